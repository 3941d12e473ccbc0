// Internal: the split layout of a welded mesh (FORMAT.md §8.13): which
// corners of a point were one vertex of the input. See split_layout.cpp.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// The walk (split_layout.cpp) numbers the vertices as the corners make
// them, then one per point on no corner: the order vertex attributes are
// coded in. The output ids go point by point.
//
// Encoder. `faces`: the welded faces as the decoder gives them (corners are
// output point ids, `points` of them; `q` their grid positions, 3 each);
// `corner_vertex`: per corner, the input vertex it was; `point_vertex`: per
// point, an input vertex of it (for a point on no corner, its only vertex).
// `value_class`: per input vertex, the same number for vertices at one
// point whose vertex attribute values are equal on their grids (a new
// vertex with an earlier one's values is coded as its copy). Returns the
// split stream and fills per walk vertex its input vertex, its output id,
// its point and its original (the vertex whose values it has: itself, or
// the one it copies), and `indices` (the corners as walk vertices).
std::string encode_split_layout(const Mesh& faces, uint32_t points, const std::vector<uint32_t>& q,
                                const std::vector<uint32_t>& corner_vertex, const std::vector<uint32_t>& point_vertex,
                                const std::vector<uint32_t>& value_class, std::vector<uint32_t>& walk_input,
                                std::vector<uint32_t>& walk_out, std::vector<uint32_t>& walk_point,
                                std::vector<uint32_t>& walk_orig, std::vector<uint32_t>& indices);

// Decoder: rewrites `faces.indices` from points to walk vertices and fills
// per walk vertex its output id, its point and its original; the stream must give
// exactly `vertex_count` vertices.
Status decode_split_layout(std::string_view stream, uint64_t vertex_count, uint32_t points,
                           const std::vector<uint32_t>& q, Mesh& faces, std::vector<uint32_t>& walk_out,
                           std::vector<uint32_t>& walk_point, std::vector<uint32_t>& walk_orig);

// Corner attributes with one value per vertex (FORMAT.md §8.12, predictor
// bit 4), bit i for attribute i: the attribute has as many values as the
// mesh has vertices, each corner uses its vertex's value and no two vertices
// use one (an OBJ or PLY export of per-vertex values). Such an attribute is
// coded as a vertex attribute, so a vertex copying another's values (§8.13)
// costs one decision.
uint64_t per_vertex_corner_attributes(const Mesh& mesh);

// The mesh with each attribute of `mask` turned into a vertex attribute:
// vertex v gets the value its corners use; the vertices on no face take the
// values no corner uses, both in order.
Mesh corner_attributes_on_vertices(const Mesh& mesh, uint64_t mask);

// Points out (FORMAT.md §8.13): per output vertex, the output vertices an
// edge of a face joins it to (either way; `faces` on output ids below n).
struct RankNeighbours {
  std::vector<uint32_t> start, list;  // vertex o's are list[start[o] .. start[o + 1])
};
RankNeighbours rank_neighbours(const Mesh& faces, size_t n);

// The model of output vertex o's point rank: 0 when no neighbour's rank is
// coded yet (`coded`: per output vertex its point rank, or 0xFFFFFFFF), 1
// when those are all 0, 2 when one is above 0 (the input vertices of one
// part come in the same order at each of their points).
int neighbours_say(const RankNeighbours& nb, uint32_t o, const std::vector<uint32_t>& coded);

}  // namespace tsm
