// Internal: geometry coding (seed 004 §3.2; design notes §6, §9).
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tsm/quantization.hpp"
#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

// The decoded surface as the geometry coder sees it. The connectivity encoder
// and decoder build it identically, so the predictors see the same mesh.
struct GeometryLayout {
  // Per half-edge 3k+e of triangle k (decode order, ccw; corner e -> e+1):
  // the output vertex at its origin (kNone: a virtual vertex), and the
  // half-edge across it.
  // The decoder may instead point corner_ref at the output mesh's indices
  // when they are the same list (no virtual triangles, no polygons): read
  // the corners through corners(), and keep that mesh in place meanwhile.
  std::vector<uint32_t> corner;
  const std::vector<uint32_t>* corner_ref = nullptr;
  const std::vector<uint32_t>& corners() const { return corner_ref ? *corner_ref : corner; }
  std::vector<uint32_t> twin;
  std::vector<uint32_t> parent;  // per output vertex: its vertex-tree parent (kNone at roots)
  std::vector<uint32_t> anchor;  // encoder: per output vertex on no triangle, a surface vertex near it (or kNone)
  uint32_t vertex_count = 0;     // output vertices
};

// Predictors, stored as the first byte of the geometry section.
enum class Predictor : uint8_t {
  ancestors = 0,      // seed 004 §3.2: sum lambda_i v_{n-i} over K tree ancestors, vertex-tree order
  parallelograms = 1, // march order; average of every parallelogram around the new vertex
  gate = 2,           // march order; the single parallelogram across the gate (fast)
  spread = 3,         // as parallelograms; residual contexts from the parallelograms' spread
  raw = 4,            // no prediction, every coordinate as `bits` equiprobable bits (tiny meshes)
  fan = 5,            // march order (as gate) predicted from every triangle around the new vertex,
                      // residual contexts from the parallelograms' spread (as spread): levels 1-2
};
// The predictor byte of 1, 2, 3 or 5 with this bit set says the
// parallelogram weights are all 1.0 and not stored (6 bytes less).
constexpr uint8_t kDefaultWeightsFlag = 0x80;
// The predictor byte of 1, 2, 3 or 5 (with or without 0x80) with this bit
// set says the tangent step is on; its two weights follow the
// parallelogram weights.
constexpr uint8_t kTangentFlag = 0x40;
// The predictor byte of 0, 1, 2, 3 or 5 (with the flags above) with this bit
// set says residuals are coded with two mixed models each.
constexpr uint8_t kMixFlag = 0x20;
// The predictor byte (any of the above) with this bit set says that each
// axis of two or more lattice planes codes its last plane first, as qmax
// minus it (a box's far corners: a few bits instead of ~20).
constexpr uint8_t kTopFlag = 0x10;
// The predictor byte of 0, 1, 2, 3 or 5 (any flag above but mixing) with
// this bit set says the residuals are coded with static frequency tables
// per context and rANS (rans_coder.hpp): every level without mixing.
constexpr uint8_t kTableFlag = 0x08;
// The highest encoder level that codes the connectivity's run values and
// attribute residuals, where they pay, with static prefix codes.
constexpr int kTableLevel = 2;
// The lowest encoder level that tries residual mixing (slower to decode).
constexpr int kMixLevel = 7;

// Per axis, the sorted coordinate values many vertices share (the voxel
// planes of a marching-cubes surface, a CAD grid); empty when not used.
struct Lattice {
  std::vector<uint32_t> values[3];
  bool empty() const { return values[0].empty() && values[1].empty() && values[2].empty(); }
};

struct GeometryStats {
  Predictor predictor = Predictor::parallelograms;
  int ancestors = 0;  // K for the ancestor predictor
  bool tangent = false;  // the tangent step
  bool mix = false;      // residual mixing
  bool top = false;      // lattice planes' last coded from the top
  bool tables = false;   // residuals through static tables and rANS
  Lattice lattice;
  uint32_t lattice_planes[3] = {0, 0, 0};
};

// Per output vertex on no triangle, the nearest surface vertex within two
// cells of a grid with about one surface vertex per cell (kNone if none or
// on a triangle). q: 3 quantized coordinates per output vertex.
std::vector<uint32_t> find_anchors(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits);

// Candidate lattice planes, per axis: the quantized values used far more
// often than a typical value (median + 6 sqrt(median) + 4 times); an axis is
// dropped when its planes hold under a third of the coordinates or number
// more than one per eight vertices. Depends on q only (canonical re-encode).
Lattice find_lattice(const std::vector<uint32_t>& q, uint32_t vertex_count);

// q: 3 quantized coordinates per output vertex. The encoder picks the
// predictor by level, and the lattice (if a candidate is given) by size:
// residual mixing at level kMixLevel and up, residuals through tables and
// rANS below it, the fan predictor at levels 1-2, planes
// coded from the top and the tangent step where they pay.
std::string encode_geometry(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, int level,
                            const Lattice* candidate, GeometryStats* stats = nullptr);
// One predictor, lattice and set of parallelogram weights (per class of 1,
// 2, 3+ parallelograms, 4.12 fixed point; null = 1.0), no search (tests and
// experiments). tangent: the tangent step's two weights (4.12, surface
// vertices and vertices with an anchor), null for none. mix: residual
// mixing (not with the raw predictor). top: the lattice planes' last coded
// from the top. tables: residuals through static tables and rANS (not with
// mixing or the raw predictor).
std::string encode_geometry_as(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred,
                               int ancestors, const Lattice& lattice, const int32_t* weights = nullptr,
                               const int32_t* tangent = nullptr, bool mix = false, bool top = false,
                               bool tables = false);
Status decode_geometry(std::string_view bytes, const GeometryLayout& g, int bits, std::vector<uint32_t>& q,
                       GeometryStats* stats = nullptr);

}  // namespace tsm
