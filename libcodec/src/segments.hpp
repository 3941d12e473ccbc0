// Internal: segments, for streaming and parallel coding (see segments.cpp).
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "connectivity.hpp"
#include "geometry_predict.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// Default bound on the faces of one segment (EncodeOptions::segment_faces).
constexpr uint32_t kDefaultSegmentFaces = 1u << 18;

// Encoder: the faces of each segment (input face indices, ascending), from a
// k-d split of the face centroids (quantized positions q, 3 per input
// vertex) until no part holds more than max_faces faces. One segment when
// the mesh has at most max_faces faces.
std::vector<std::vector<uint32_t>> split_faces(const Mesh& mesh, const std::vector<uint32_t>& q, uint32_t max_faces);

// Tie-breaks that a decoded file keeps (segments numbered and split alike
// on re-encoding): a 64-bit mix, and the hash of a grid cell (3 indices).
uint64_t mix64(uint64_t x);
uint64_t cell_hash(const uint32_t* cell);

// Per output vertex of a decoded part: 2 when it lies on a hole of the part's
// cut surface (next to a virtual vertex), 1 when on another triangle, 0 when
// on none. The context of its reference flag: a vertex shared with an
// earlier segment lies on that segment's border, a hole of this one.
std::vector<uint8_t> reference_contexts(const GeometryLayout& g);

// The references of a part: per output vertex, the global id of the earlier
// segment's vertex it is (kNone for the part's own vertices). Coded as a flag
// per vertex (context above and the previous flag) and, per reference, the
// difference to the previous reference's global id.
std::string encode_references(const std::vector<uint8_t>& context, const std::vector<uint32_t>& global);
// `count` references expected, each below `limit` (the vertices of the
// segments before).
Status decode_references(std::string_view bytes, const std::vector<uint8_t>& context, uint64_t count,
                         uint64_t limit, std::vector<uint32_t>& global);

// The layout the geometry coder sees when a part has references: their
// positions become virtual (they are coded in an earlier segment, and a
// segment is decoded without the others), own vertices are renumbered in
// output order, and a tree parent that is a reference ends the ancestor chain.
GeometryLayout own_layout(const GeometryLayout& g, const std::vector<uint32_t>& global);

// A segment section's payload (FORMAT.md §4.5): the part's counts, then its
// streams one after the other.
struct SegmentPayload {
  uint64_t vertex_count = 0;     // the part's vertices, own and referenced
  uint64_t face_count = 0;
  uint64_t corner_count = 0;
  uint64_t reference_count = 0;
  std::string_view vertex_tree, triangle_tree, topology, references, geometry, attributes;
};
std::string write_segment(const SegmentPayload& p);
Status read_segment(std::string_view bytes, SegmentPayload& p);

}  // namespace tsm
