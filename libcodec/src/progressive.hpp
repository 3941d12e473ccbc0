// Internal: progressive files (FORMAT.md §4.8): a base mesh, then batches
// of vertex splits (refinement sections, id 12), each batch a set of
// independent splits coded in the decoder's vertex order.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "container.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// A grid index as a coordinate (FORMAT.md §5; defined in decode.cpp).
float grid_value(const Header& h, double step, int axis, uint32_t q);

struct BatchModels;  // progressive_split.cpp

// The ghost closing a boundary vertex's open fan into a ring (FORMAT.md
// §4.8): the last ring entry of a vertex on a border, standing for the
// outside; faces with it are not in the mesh.
constexpr uint32_t kGhost = 0xFFFFFFFEu;

// The decoder's current level of detail: the mesh, the grid index of every
// vertex and, per vertex, the faces that use it.
class LevelMesh {
 public:
  // Takes the decoded base mesh (its positions lie on the header's grid).
  void init(Mesh& mesh, const Header& h);
  // The ordered neighbours r_0 .. r_{d-1} of v when its faces are d
  // triangles forming one closed, consistently oriented fan (faces
  // (v, r_i, r_{i+1 mod d})), starting at the neighbour of least id; or,
  // when they form one open fan (v on a border), its neighbours from the
  // fan's first to its last, then kGhost; false otherwise.
  bool ring(uint32_t v, std::vector<uint32_t>& ring) const;
  bool adjacent_to_marked(uint32_t v, const std::vector<uint8_t>& marked) const;
  // Splits v (FORMAT.md §4.8): the faces (v, r_i, r_{i+1}) for i = ia ..
  // ia + dist - 1 (mod d) go to a new vertex u at grid index q, and the
  // faces (v, u, r_{ia+dist}) and (v, r_ia, u) are added. Returns u.
  uint32_t split(uint32_t v, const std::vector<uint32_t>& ring, uint32_t ia, uint32_t dist, const uint32_t q[3]);
  // Appends a vertex no face uses, at grid index q.
  void add_point(const uint32_t q[3]);
  // Appends the triangle (a, b, c).
  void add_triangle(uint32_t a, uint32_t b, uint32_t c);
  // The vertices sharing a face with v, in increasing id.
  void neighbours(uint32_t v, std::vector<uint32_t>& out) const;
  size_t vertex_count() const { return q_.size() / 3; }
  int bits() const { return h_.quantization_bits; }
  const uint32_t* q(uint32_t v) const { return &q_[3 * size_t{v}]; }
  size_t face_uses(uint32_t v) const { return vf_[v].size(); }
  // The sum over v's faces of (c1 - c0) x (c2 - c0), their first three
  // corners' grid indices (exact in int64).
  void face_normal(uint32_t v, int64_t n[3]) const;
  Mesh& mesh() { return *mesh_; }
  // The split coder's adaptive models: they carry over from batch to batch.
  std::shared_ptr<BatchModels>& models() { return models_; }

 private:
  Mesh* mesh_ = nullptr;
  Header h_;
  double step_ = 0;
  std::vector<uint32_t> q_;
  std::vector<std::vector<uint32_t>> vf_;
  std::shared_ptr<BatchModels> models_;
};

// One vertex split as the encoder hands it to encode_batch (level ids): v is
// split, the faces from y to x (in v's ring order) go to the new vertex at
// grid index q; y or x may be kGhost (the new vertex on v's border).
struct VertexSplit {
  uint32_t v = 0, y = 0, x = 0;
  uint32_t q[3] = {0, 0, 0};
};

// The ring of v from the edges opposite v in its triangles (each (a, b): the
// corners after v): the closed fan of FORMAT.md §4.8, listed from its least
// vertex, or the open fan from its first vertex then kGhost; false when the
// edges do not form one (a repeated or degenerate edge, a vertex twice,
// several cycles or paths). Sorts `edge`.
bool ring_from_edges(uint32_t v, std::vector<std::pair<uint32_t, uint32_t>>& edge, std::vector<uint32_t>& ring);

// A refinement payload (FORMAT.md §4.8): the error of the level before and
// after the batch (symmetric Hausdorff distance to the input, model units),
// the number of splits and of those putting the new vertex on a border
// (they add one face, the others two), then the range-coded splits.
struct BatchHeader {
  float error_before = 0, error_after = 0;
  uint64_t splits = 0, border = 0;
};
std::string write_batch(const BatchHeader& h, std::string_view stream);
Status read_batch(std::string_view payload, BatchHeader& h, std::string_view& stream);

// Codes a batch of splits (in any order, pairwise independent) and applies
// them to `level`; appends the new vertices' ids (in the order of `splits`)
// to `new_ids`; `border`: how many put the new vertex on a border.
Status encode_batch(LevelMesh& level, const std::vector<VertexSplit>& splits, std::string& stream,
                    std::vector<uint32_t>& new_ids, uint64_t& border);

struct BatchLimits {
  uint64_t max_vertices = 0, max_faces = 0;  // 0 = none
};
// Decodes one refinement payload and applies it to `level`.
Status decode_batch(std::string_view payload, LevelMesh& level, const BatchLimits& limits);

// The order the loose section codes vertices no face uses in (FORMAT.md
// §4.8): by their anchor (the nearest vertex of `level`), then grid index;
// q: 3 grid indices per vertex. Returns indices into q.
std::vector<uint32_t> loose_order(const LevelMesh& level, const std::vector<uint32_t>& q);
// The loose section (id 13, FORMAT.md §4.8), after the last batch: vertices
// no face uses (q: 3 grid indices per vertex, in loose_order's order, so
// they get the next ids in that order), each as a residual from its
// anchor, then the triangles the levels left out (level ids), applied to
// `level`.
Status encode_loose(LevelMesh& level, std::vector<uint32_t> q, std::vector<std::array<uint32_t, 3>> faces,
                    std::string& out);
Status decode_loose(std::string_view payload, LevelMesh& level, const BatchLimits& limits);

}  // namespace tsm
