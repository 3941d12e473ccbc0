// Internal: the connectivity side of Topological Surgery (seed 004 §3-4,
// design notes §3-5), split by pipeline stage:
//   mesh_cut.cpp       every mesh -> closed oriented manifold components
//   vertex_tree.cpp    the vertex spanning tree (layered spiral) and its runs
//   bounding_loop.cpp  jump edges, rotation system and the bounding loop walk
//   triangle_tree.cpp  triangle tree runs and marching pattern
//   connectivity_encode.cpp  the coded streams (connectivity_coding.hpp:
//                      the models and stitch candidates both sides share)
//   connectivity_decode.cpp  the decoder: the streams read, the faces reassembled
//
// Half-edge h = 3*t + i of triangle t runs from corner i to corner (i+1)%3;
// the triangle lies on its left. Faces are counter-clockwise seen from
// outside, so around a vertex, cw_next(h) = next(twin(h)).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "geometry_predict.hpp"
#include "range_coder.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

constexpr uint32_t kNone = 0xFFFFFFFFu;

// As tests of divisibility by 3 (a multiply and a compare, no remainder).
inline uint32_t he_next(uint32_t h) { return (h + 1) % 3 == 0 ? h - 2 : h + 1; }
inline uint32_t he_prev(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

// Union-find over dense ids; unite() keeps the smaller id as the set's root,
// so the root of a set is its smallest member.
struct UnionFind {
  std::vector<uint32_t> p;
  explicit UnionFind(size_t n) : p(n) {
    for (size_t i = 0; i < n; ++i) p[i] = static_cast<uint32_t>(i);
  }
  uint32_t find(uint32_t x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  bool unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (a < b) p[b] = a;
    else p[a] = b;
    return true;
  }
};

// The connectivity's run values (vertex-run lengths, march counts, the
// positions of virtual and stitched vertices and the stitch distances;
// FORMAT.md §8.3.1): adaptive: their adaptive models, behind a mode byte 0
// at the start of the topology stream; tables: mode byte 1, static prefix
// codes per context in a bit stream (the fast levels: one table lookup per
// value instead of about eight adaptive decisions).
enum class RunCoding : uint8_t { adaptive = 1, tables = 2 };
constexpr int kRunContexts = 8;   // 2 vertex-run lengths, 4 march counts, position, distance
constexpr int kRunMapBytes = 1;   // the run tables' used-context map

enum class VertexKind : uint8_t { real = 0, duplicate = 1, virtual_ = 2 };

// Stage 1 output: closed, oriented, manifold triangle components.
struct CutMesh {
  uint32_t vertex_count = 0;            // real + duplicates + virtual
  std::vector<uint32_t> tri;            // 3 per triangle, cut-mesh vertex ids
  std::vector<uint32_t> twin;           // 3 per triangle, always paired
  std::vector<VertexKind> kind;         // per vertex
  std::vector<uint32_t> source;         // per vertex: input vertex id (kNone for virtual)
  std::vector<uint32_t> tri_source;     // per triangle: input triangle index, kNone for virtual
  std::vector<uint8_t> diagonal;        // per half-edge: 1 if it is an interior edge of an input polygon
  // Components: vertices grouped, in a canonical order; each lists its root.
  std::vector<uint32_t> component_root; // per component, the vertex the tree starts from
  std::vector<uint32_t> vertex_component;
  uint32_t component_count() const { return static_cast<uint32_t>(component_root.size()); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(tri.size() / 3); }
  // Statistics.
  uint32_t holes = 0, duplicates = 0, cut_edges = 0;
  // CutHints::root_rule > 0: two vertices shared the extreme position, so
  // the roots depend on vertex ids (the caller then drops that rule).
  bool root_tie = false;
};

// The input split into what the manifold coder takes and side lists.
struct PreparedInput {
  std::vector<uint32_t> tri;             // triangles for the manifold coder (input vertex ids)
  std::vector<uint8_t> tri_diagonal;     // 3 per triangle: edge i is a polygon diagonal
  std::vector<uint32_t> side_faces;      // faces kept verbatim (degenerate ones): face index list
  uint32_t polygon_count = 0;            // polygons (n > 3) triangulated
};

PreparedInput prepare_input(const Mesh& mesh);
// What the encoder may know beyond the faces (all optional, per input vertex).
struct CutHints {
  // For a vertex on no triangle: the output id of a nearby surface vertex
  // (kNone if none); orders those vertices and predicts them.
  const std::vector<uint32_t>* anchor = nullptr;
  // Quantized positions (3 per vertex): the uses of an edge with more than
  // two faces are paired in the order of their third corner's position, so
  // a decoded mesh cuts the same way again (canonical re-encoding).
  const std::vector<uint32_t>* qpos = nullptr;
  // The vertex tree: the midpoint-distance Kruskal variant (needs qpos)
  // instead of the layered spiral.
  bool midpoint_tree = false;
  // Where each component's tree starts. 0: at its smallest vertex id, the
  // reference edge to its neighbour of smallest id. 1..6 (needs qpos): at
  // the vertex with the smallest (odd rule) or largest (even rule) quantized
  // position, compared lexicographically from axis (rule - 1) / 2 on; the
  // reference edge to the neighbour with the smallest position. A decoded
  // mesh has the same positions, so a rule picks the same roots and edges
  // there (the encoder tries several and keeps the smallest file).
  int root_rule = 0;
  // How the run values are coded (FORMAT.md §8.3.1; tables: where they pay).
  RunCoding runs = RunCoding::adaptive;
  // false: the cut surface only (vertex order, layout, stats) where the
  // decoded faces are its triangles; code_connectivity_streams codes the
  // streams later (the encoder's canonical rounds need them for one round).
  bool streams = true;
};

// Lexicographic order of quantized positions (3 per input vertex), from
// axis `first` on: -1, 0 or 1.
inline int compare_positions(const std::vector<uint32_t>& qpos, uint32_t a, uint32_t b, int first) {
  for (int i = 0; i < 3; ++i) {
    const int axis = (first + i) % 3;
    const uint32_t x = qpos[3 * size_t{a} + axis], y = qpos[3 * size_t{b} + axis];
    if (x != y) return x < y ? -1 : 1;
  }
  return 0;
}

// Of the candidates offered (an id and its input vertex), the one whose
// position comes first in compare_positions (sign 1) or last (sign -1), and
// whether another had the same position (a tie).
struct PositionExtreme {
  const std::vector<uint32_t>* qpos = nullptr;
  int first = 0, sign = 1;
  uint32_t best = kNone, best_input = kNone;
  bool tie = false;
  void offer(uint32_t id, uint32_t input) {
    const int order = best == kNone ? -1 : sign * compare_positions(*qpos, input, best_input, first);
    if (order < 0) {
      best = id;
      best_input = input;
      tie = false;
    } else if (order == 0) {
      tie = true;
    }
  }
};

// Takes in.tri and in.tri_diagonal over (they are left empty).
CutMesh cut_mesh(PreparedInput& in, uint32_t input_vertex_count, const CutHints& hints = CutHints());

// Stage 2: the vertex spanning forest, in pre-order.
struct VertexForest {
  std::vector<uint32_t> order;          // pre-order position -> cut-mesh vertex
  std::vector<uint32_t> parent;         // per pre-order position, parent position (kNone at roots)
  std::vector<uint32_t> child_count;    // per pre-order position
  std::vector<uint32_t> component_start;  // pre-order position where each component starts (+ end)
  // Per cut-mesh vertex: the half-edge to its parent (kNone at roots), and
  // for roots the reference half-edge the children are ordered from.
  std::vector<uint32_t> parent_he;
  std::vector<uint32_t> root_ref_he;
  std::vector<uint8_t> tree_he;         // per half-edge: 1 if it is a tree edge (both directions)
};

// midpoint: the Kruskal variant over edges by their midpoint's distance from
// the root (needs qpos, quantized positions per input vertex); else the
// layered spiral.
// geometric_ref: a root's reference edge goes to its neighbour with the
// smallest position (CutHints::root_rule > 0; a tie sets *tie), else to
// its neighbour of smallest id.
// m is renumbered on the way (vertices in ring order, triangles after
// them): the later stages walk it in memory order.
VertexForest build_vertex_tree(CutMesh& m, const std::vector<uint32_t>* qpos = nullptr, bool midpoint = false,
                               bool geometric_ref = false, bool* tie = nullptr);

// Stage 3: bounding loop of one component (encoder side: with half-edges).
struct JumpEndpoint {
  uint32_t corner;   // tour position (within the component's tree tour)
  uint32_t order;    // clockwise order within that corner
  uint32_t partner;  // index of the other endpoint in the sorted endpoint list
};

struct ComponentLoop {
  std::vector<uint32_t> loop;           // loop position -> cut-mesh vertex
  std::vector<uint32_t> loop_he;        // loop position p -> half-edge loop[p] -> loop[p+1]
  std::vector<JumpEndpoint> jumps;      // sorted by (corner, order)
};

// Encoder: choose jump edges for component c (its triangles listed in
// `triangles`), mark them in `cut_he` (which holds the tree edges), and walk
// the loop. `local` is scratch of one entry per triangle of the mesh.
ComponentLoop encoder_loop(const CutMesh& m, const VertexForest& f, uint32_t c,
                           const std::vector<uint32_t>& triangles, std::vector<uint8_t>& cut_he,
                           std::vector<uint32_t>& local);

// Decoder: the loop of a component from its tree (parent positions, local to
// the component) and jump endpoints; loop_twin[p] is the loop position that
// walks loop edge p the other way (the two sides of a cut edge). Returns
// false on inconsistent input.
bool decoder_loop(const std::vector<uint32_t>& parent, const std::vector<JumpEndpoint>& jumps,
                  std::vector<uint32_t>& loop, std::vector<uint32_t>& loop_twin);
// The tree's Euler tour alone (vertices in pre-order; the loop without jump
// edges), the first step of decoder_loop.
bool tree_tour(const std::vector<uint32_t>& parent, std::vector<uint32_t>& loop, std::vector<uint32_t>& loop_twin);

// Stage 4: the triangle tree (seed 004 §4).
struct TriangleRuns {
  uint32_t root = 0;                    // loop position r
  std::vector<uint32_t> march;          // per run: march count
  std::vector<uint8_t> branch;          // per run: 1 = ends in a branching triangle, 0 = leaf
  std::vector<uint8_t> bits;            // marching bits (0 right, 1 left)
  std::vector<uint32_t> triangle_order; // encoder: cut-mesh triangles in decode order
  std::vector<uint8_t> parent_slot;     // per triangle in decode order: which edge faces its parent
};

// `corner_pos` is scratch with one entry per half-edge of the mesh.
Status encode_triangle_tree(const CutMesh& m, const ComponentLoop& cl, std::vector<uint32_t>& corner_pos,
                            TriangleRuns& out);
// The marching bits, asked for during the walk with their context: the
// numbers of triangles already emitted around the gate's two vertices
// (valence so far, capped at 7), the previous bit of the run, and how often
// each of the two candidate vertices (the loop vertex after b, for a right
// march, and the one before a, for a left march) occurs on the loop (its
// degree in the cut, capped at 3). The encoder answers from its bits, the
// decoder from the range coder.
constexpr int kMarchContexts = 8 * 8 * 3 * 3 * 3;
// The two sources of marching bits (concrete types, so that the walk
// inlines the range coder: a virtual call per bit cost 4% of a fast-level
// decode). Both adapt probs[ctx].
struct MarchBitDecoder {
  RangeDecoder& d;
  Prob* probs;
  int bit(int ctx) { return d.bit(probs[ctx]); }
};
struct MarchBitEncoder {  // answers from the encoder's bits, coding each
  RangeEncoder& e;
  Prob* probs;
  const std::vector<uint8_t>& bits;
  size_t next = 0;
  int bit(int ctx) {
    const int b = next < bits.size() ? bits[next] : 0;
    ++next;
    e.bit(probs[ctx], b);
    return b;
  }
};

// Where decode_triangle_tree writes the triangles it walks, in decode order
// k = 0..T-1 (T = loop length - 2); half-edge 3k + e of the tree is global
// half-edge he_base + 3k + e. Each non-root triangle's edge 0 is the one it
// shares with its parent.
//   corner[3k + e]   vertex_base + loop[loop position of corner e]
//   twin[he_base + 3k] and the parent's shared edge: paired (global ids);
//                    loop edges are left alone (loop_he pairs them)
//   loop_he[p]       the global half-edge that is loop edge p (loop[p] ->
//                    loop[p+1]); kNone on entry (a position claimed twice is
//                    refused)
//   parent, slot     optional (null: not written): per triangle its parent's
//                    decode index (kNone at the root) and the parent's edge
struct TriangleTreeOut {
  uint32_t* corner = nullptr;
  uint32_t* twin = nullptr;
  uint32_t* loop_he = nullptr;
  uint32_t vertex_base = 0, he_base = 0;
  uint32_t* parent = nullptr;
  uint8_t* slot = nullptr;
};
// Decoder (and encoder, to share the contexts): the walk of the triangle
// tree. runs.bits is unused: bits come from `bits`; loop maps loop positions
// to the component's local vertices (n of them), for the valence contexts.
// Instantiated for MarchBitDecoder and MarchBitEncoder.
template <class Bits>
Status decode_triangle_tree(uint32_t loop_length, const TriangleRuns& runs, const std::vector<uint32_t>& loop,
                            uint32_t n, Bits& bits, const TriangleTreeOut& out, uint64_t& bit_count);

// Stage 5: the whole connectivity, coded.
struct ConnectivityStats {
  uint64_t components = 0, vertex_runs = 0, triangle_runs = 0, jump_edges = 0, stitches = 0,
           virtual_vertices = 0, side_faces = 0, polygons = 0, marching_bits = 0;
  uint64_t run_tables = 0;  // 1 when the run values were table-coded (mode bit 0)
  uint64_t welded = 0;      // 1 when the faces are on welded points (mode bit 1, FORMAT.md §8.13)
  uint64_t points = 0;      // then the number of points
  uint64_t bytes = 0;
};

// The three connectivity streams (container sections).
struct ConnectivityStreams {
  std::string vertex_tree;    // VST runs per component
  std::string triangle_tree;  // root, runs, marching bits, polygon-edge flags per component
  // The run coding's mode byte (0 adaptive, 1 tables; FORMAT.md §8.3.1),
  // then components, jumps, virtual vertices, stitches (all positions, then
  // each target by its rank among candidates, §8.3.2), side faces.
  std::string topology;
};

struct PendingStreams;  // connectivity_encode.cpp

struct ConnectivityEncoding {
  ConnectivityStreams streams;
  // Output vertex id (vertex-tree pre-order) -> input vertex id.
  std::vector<uint32_t> vertex_order;
  // The cut surface as the decoder will rebuild it, for the geometry coder.
  GeometryLayout layout;
  ConnectivityStats stats;
  // With stitches: the topology stream as it would be with every stitch
  // target coded as a distance after its position instead of by candidates
  // (empty without stitches). Not a stream of the file: the canonical rounds
  // (encode.cpp) order the codings of a cycle by it.
  std::string distance_topology;
  bool root_tie = false;  // CutHints::root_rule > 0 and a root or reference edge tied on position
  // Set while the streams are not coded yet (CutHints::streams false).
  std::shared_ptr<PendingStreams> pending;
};

Status encode_connectivity(const Mesh& mesh, ConnectivityEncoding& out, const CutHints& hints = CutHints());
// Codes the streams of an encoding made with CutHints::streams false (does
// nothing when they are coded).
Status code_connectivity_streams(ConnectivityEncoding& ce);
// Fills out.face_offsets / out.indices (positions are the geometry stage's
// job) and the layout the geometry decoder walks. The counts come from the
// header and are checked against what the streams say.
Status decode_connectivity(const ConnectivityStreams& in, uint64_t vertex_count, uint64_t face_count,
                           uint64_t corner_count, Mesh& out, GeometryLayout& layout,
                           ConnectivityStats* stats = nullptr);

}  // namespace tsm
