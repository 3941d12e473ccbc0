// Attributes: normals, colours, texture coordinates and generic values per
// vertex, face or corner, coded after the connectivity and the geometry, in
// the order the decoder rebuilds them (seed 004 §5, "Kodierung der Photometrie
// Daten": colours, normals and texture coordinates follow the vertex tree, and
// per-corner values are split where they are discontinuous; design notes §7).
//
// Vertex values follow the output vertex order (the vertex tree's pre-order,
// so consecutive values are usually neighbours); normals may instead be
// predicted from the decoded geometry (the area-weighted normal of the faces
// around the vertex). Face values follow the decoded face order. Corner
// values keep their own value list, as OBJ's vt/vn and glTF seams do: per
// corner the stream says whether it reuses a value already met at the same
// vertex (smooth), starts a new one (a seam or crease), or reuses a value from
// elsewhere; values no corner uses are kept at the end. Quantization: integer
// types exactly, floats on a grid over the attribute's bounding box, normals
// octahedrally. Residuals are range coded (FORMAT.md §8.12).
#include "attributes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "range_coder.hpp"
#include "table_coder.hpp"

namespace tsm {

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, "attributes: " + what); }

constexpr int kMaxAttributes = 64;

// FORMAT.md §8.12.1: an attribute's residuals through static
// prefix codes, one per residual model res[cls][c][z], at context
// 24 i + 8 cls + 2 c + z of attribute i (bit 3 of its predictor byte).
constexpr uint8_t kAttributeTableFlag = 0x08;
// Predictor bit 5: vertex values may name one of the last 64 distinct values
// (values that repeat across a model, as a CAD part's axis normals do, where
// the prediction misses them).
constexpr uint8_t kAttributeRecentFlag = 0x20;
constexpr size_t kRecentValues = 64;
// Predictor bit 6: a vertex value may name the value of an earlier vertex at
// the same grid position (its point's wedges, FORMAT.md §8.12: a split
// vertex of a welded mesh usually repeats the UV, colour or skin weights of
// its point's other vertices where only the normal changes, and the normal
// where only the UV does). Up to 32 such vertices, the latest first.
constexpr uint8_t kAttributeSiblingFlag = 0x40;
constexpr uint32_t kSiblingVertices = 32;
// Predictor bit 7: every component's residuals in the models of component 0
// (res[cls][0][z]): a small attribute (a textured box, a low-poly model's
// texture coordinates) learns one set of models instead of two to four.
constexpr uint8_t kAttributeSharedFlag = 0x80;

// Predictor bit 4: a corner attribute coded as a vertex attribute, one value
// per own vertex, each corner using its vertex's value (an OBJ/PLY export of
// per-vertex values keeps one list entry per vertex).
constexpr uint8_t kAttributePerVertexFlag = 0x10;

// The header an attribute is coded with: a corner attribute coded per vertex
// as a vertex attribute.
AttributeHeader coded_header(const AttributeHeader& h, bool per_vertex) {
  AttributeHeader c = h;
  if (per_vertex) c.domain = AttributeDomain::vertex;
  return c;
}
constexpr int kAttributeTableContexts = 24;  // per attribute
int table_context(int cls, uint32_t c, int zero) { return 8 * cls + 2 * static_cast<int>(c) + zero; }

// Octahedral mapping of a direction onto [0, 2^bits - 1]^2.
void oct_encode(double x, double y, double z, int bits, int32_t out[2]) {
  const double s = std::fabs(x) + std::fabs(y) + std::fabs(z);
  if (!(s > 0)) {
    x = 0;
    y = 0;
    z = 1;
  } else {
    x /= s;
    y /= s;
    z /= s;
  }
  if (z < 0) {
    const double ox = x, oy = y;
    x = (1 - std::fabs(oy)) * (ox >= 0 ? 1 : -1);
    y = (1 - std::fabs(ox)) * (oy >= 0 ? 1 : -1);
  }
  const double m = std::ldexp(1.0, bits) - 1;
  int32_t u = static_cast<int32_t>(std::floor((x * 0.5 + 0.5) * m + 0.5));
  int32_t v = static_cast<int32_t>(std::floor((y * 0.5 + 0.5) * m + 0.5));
  // The square's border is folded onto itself: (u, 0) and (m - u, 0) are one
  // direction, so are (0, v) and (0, m - v) (and the corners are (0, 0, -1)).
  // One representative, so that a decoded normal keys as it was coded.
  const int32_t top = static_cast<int32_t>(m);
  if (v == 0 || v == top) u = std::min(u, top - u);
  if (u == 0 || u == top) v = std::min(v, top - v);
  out[0] = u;
  out[1] = v;
}

void oct_decode(int32_t u, int32_t v, int bits, float out[3]) {
  const double m = std::ldexp(1.0, bits) - 1;
  double x = u / m * 2 - 1, y = v / m * 2 - 1;
  const double z = 1 - std::fabs(x) - std::fabs(y);
  if (z < 0) {
    const double ox = x, oy = y;
    x = (1 - std::fabs(oy)) * (ox >= 0 ? 1 : -1);
    y = (1 - std::fabs(ox)) * (oy >= 0 ? 1 : -1);
  }
  const double n = std::sqrt(x * x + y * y + z * z);
  out[0] = static_cast<float>(x / n);
  out[1] = static_cast<float>(y / n);
  out[2] = static_cast<float>(z / n);
}

double grid_step(const AttributeHeader& h) { return h.extent > 0 ? h.extent / (std::ldexp(1.0, h.bits) - 1.0) : 0.0; }

// Integers per value: 2 for octahedral, else the components.
uint32_t int_components(const AttributeHeader& h) { return h.quant == AttributeQuant::octahedral ? 2 : h.components; }

void to_ints(const AttributeHeader& h, const float* v, int32_t* out) {
  if (h.quant == AttributeQuant::octahedral) {
    oct_encode(v[0], v[1], v[2], h.bits, out);
    return;
  }
  for (uint32_t c = 0; c < h.components; ++c) {
    if (h.quant == AttributeQuant::exact) {
      out[c] = static_cast<int32_t>(v[c]);
    } else {
      const double step = grid_step(h);
      const int64_t top = (int64_t{1} << h.bits) - 1;
      int64_t q =
          step > 0 ? static_cast<int64_t>(std::floor((static_cast<double>(v[c]) - h.origin[c]) / step + 0.5)) : 0;
      out[c] = static_cast<int32_t>(std::clamp<int64_t>(q, 0, top));
    }
  }
}

void from_ints(const AttributeHeader& h, const int32_t* x, float* out) {
  if (h.quant == AttributeQuant::octahedral) {
    oct_decode(x[0], x[1], h.bits, out);
    return;
  }
  for (uint32_t c = 0; c < h.components; ++c)
    out[c] = h.quant == AttributeQuant::exact ? static_cast<float>(x[c])
                                              : attribute_grid_value(h, static_cast<int>(c), x[c]);
}

// The integer range of one component (decoder checks).
bool in_range(const AttributeHeader& h, int64_t x) {
  if (h.quant == AttributeQuant::exact) return x >= -(int64_t{1} << 30) && x <= (int64_t{1} << 30);
  return x >= 0 && x < (int64_t{1} << h.bits);
}

struct Models {
  SIntModelT<4> res[3][4][2];  // [prediction class][component][previous residual of the component was 0]
  UIntModel symbol[6];
  UIntModel far;
  UIntModel unused;
  UIntModel imported[2];        // [the corner's vertex is a reference]: is a new value one of an earlier segment
  SIntModelT<4> import_id;      // its id in the file's value list, from the previous one
  UIntModel recent_hit[2];      // [the previous vertex's was one]: the value is one of the recent values
  UIntModel recent_index;       // which, most recent first
  UIntModel sibling_hit[2][2];  // [the previous was a hit][more than one wedge value]: an earlier sibling's value
  UIntModel sibling_index;      // which of the siblings' distinct values, latest first
  UIntModel transfer;           // predictor 2, across a seam: which turn or mirror of the edge
};

// Residual coding of one value against a prediction; contexts: the
// prediction's class (predictor 2: 0 no triangle, 1 one, 2 several; else 0)
// and per component whether its previous residual was zero.
template <class Coder>
struct ValueCoder {
  Coder& io;
  Models m;
  int last_zero[4] = {1, 1, 1, 1};
  bool shared = false;  // predictor bit 7: component 0's models for every component
  bool value(const AttributeHeader& h, const int32_t* pred, int32_t* x, int cls = 0) {
    if (h.quant == AttributeQuant::octahedral) return octahedral_value(h, pred, x, cls);
    const uint32_t n = int_components(h);
    for (uint32_t c = 0; c < n; ++c) {
      int32_t r = io.residual(m.res[cls][shared ? 0 : c][last_zero[c]], table_context(cls, c, last_zero[c]),
                              static_cast<int64_t>(x[c]) - pred[c]);
      const int64_t v = static_cast<int64_t>(pred[c]) + r;
      if (!in_range(h, v)) return false;
      x[c] = static_cast<int32_t>(v);
      last_zero[c] = r == 0;
    }
    return true;
  }
  // An octahedral value (FORMAT.md §8.12, "Octahedral residuals"): the square
  // continues across each edge as its mirror image (the edge u = m is glued
  // to itself with v -> m - v), so pred + residual may lie up to one square
  // beyond an edge and is folded back. A normal near the square's border (a
  // CAD part's -z, the lower hemisphere's rim) then costs the small step
  // across the fold, not the width of the square.
  bool octahedral_value(const AttributeHeader& h, const int32_t* pred, int32_t* x, int cls) {
    const int64_t top = (int64_t{1} << h.bits) - 1;
    int64_t want[2] = {0, 0};
    if constexpr (Coder::kEncoder) octahedral_residual(top, pred, x, want);
    int64_t v[2];
    for (uint32_t c = 0; c < 2; ++c) {
      const int32_t r =
          io.residual(m.res[cls][shared ? 0 : c][last_zero[c]], table_context(cls, c, last_zero[c]), want[c]);
      v[c] = static_cast<int64_t>(pred[c]) + r;
      if (v[c] < -top || v[c] > 2 * top) return false;
      last_zero[c] = r == 0;
    }
    octahedral_fold(top, v);
    x[0] = static_cast<int32_t>(v[0]);
    x[1] = static_cast<int32_t>(v[1]);
    return true;
  }
  // Folds a point of [-m, 2m]^2 into the square [0, m]^2.
  static void octahedral_fold(int64_t m, int64_t* v) {
    if (v[0] > m) {
      v[0] = 2 * m - v[0];
      v[1] = m - v[1];
    } else if (v[0] < 0) {
      v[0] = -v[0];
      v[1] = m - v[1];
    }
    if (v[1] > m) {
      v[1] = 2 * m - v[1];
      v[0] = m - v[0];
    } else if (v[1] < 0) {
      v[1] = -v[1];
      v[0] = m - v[0];
    }
  }
  // The encoder's residual: of the value's mirror images (up to two
  // reflections across the square's edges) that fold back to it, the one
  // nearest the prediction (the smallest larger component, then the
  // smallest sum, then the first in the order tried).
  static void octahedral_residual(int64_t m, const int32_t* pred, const int32_t* x, int64_t* out) {
    // Across u = m, u = 0, v = m, v = 0.
    auto reflect = [m](int e, int64_t* p) {
      const int a = e < 2 ? 0 : 1;
      p[a] = (e % 2 == 0 ? 2 * m : 0) - p[a];
      p[1 - a] = m - p[1 - a];
    };
    out[0] = int64_t{x[0]} - pred[0];
    out[1] = int64_t{x[1]} - pred[1];
    auto cost = [](const int64_t* r) {
      const int64_t a = r[0] < 0 ? -r[0] : r[0], b = r[1] < 0 ? -r[1] : r[1];
      return std::make_pair(std::max(a, b), a + b);
    };
    for (int e1 = -1; e1 < 4; ++e1)
      for (int e2 = -1; e2 < 4; ++e2) {
        int64_t p[2] = {x[0], x[1]};
        if (e1 >= 0) reflect(e1, p);
        if (e2 >= 0) reflect(e2, p);
        if (p[0] < -m || p[0] > 2 * m || p[1] < -m || p[1] > 2 * m) continue;
        int64_t f[2] = {p[0], p[1]};
        octahedral_fold(m, f);
        if (f[0] != x[0] || f[1] != x[1]) continue;
        const int64_t r[2] = {p[0] - pred[0], p[1] - pred[1]};
        if (cost(r) < cost(out)) {
          out[0] = r[0];
          out[1] = r[1];
        }
      }
  }
};

// The encoder's table-coded residuals of one attribute: counted in a first
// pass, coded with the codes built from the counts in a second.
struct TableResiduals {
  TableEncoder tables{kAttributeTableContexts};
  bool fits = true;           // every residual within the symbols' range (|r| < 2^30)
  BitWriter* bits = nullptr;  // null: counting (the first pass)
  void put(int ctx, int64_t v) {
    if (v <= -(int64_t{1} << 30) || v >= (int64_t{1} << 30)) {
      fits = false;
    } else if (bits) {
      tables.put(*bits, ctx, v);
    } else {
      tables.count(ctx, v);
    }
  }
};

struct Enc {
  RangeEncoder e;
  TableResiduals* tables = nullptr;  // this attribute's residuals through tables
  int32_t sint(SIntModelT<4>& m, int64_t v) {
    m.encode(e, static_cast<int32_t>(v));
    return static_cast<int32_t>(v);
  }
  int32_t residual(SIntModelT<4>& m, int ctx, int64_t v) {
    if (tables) {
      tables->put(ctx, v);
      return static_cast<int32_t>(v);
    }
    return sint(m, v);
  }
  uint32_t uint(UIntModel& m, uint32_t v) {
    m.encode(e, v);
    return v;
  }
  static constexpr bool kEncoder = true;
};

struct Dec {
  RangeDecoder d;
  // The attribute tables and their bit stream; `base` is the
  // current attribute's first context, -1 when its residuals are range coded.
  const TableSet* tables = nullptr;
  BitReader bits;
  int base = -1;
  bool bad_code = false;  // a code word no table has: the attribute is refused
  int32_t sint(SIntModelT<4>& m, int64_t) { return m.decode(d); }
  int32_t residual(SIntModelT<4>& m, int ctx, int64_t) {
    if (base < 0) return m.decode(d);
    int32_t r = 0;
    if (!tables->decode(bits, base + ctx, r)) bad_code = true;
    return r;
  }
  uint32_t uint(UIntModel& m, uint32_t) { return m.decode(d); }
  static constexpr bool kEncoder = false;
};

// How the faces around a vertex weigh in its geometry normal (predictors
// 1, 3 and 4): by area; each face alike (its unit normal: what most
// modelling tools write for smooth shading); by the corner's angle (the
// face's vector over the lengths of the corner's two edges: its sine).
enum class NormalWeights { area = 0, face = 1, angle = 2 };

NormalWeights normal_weights(int predictor) {
  return predictor == 3 ? NormalWeights::face : predictor == 4 ? NormalWeights::angle : NormalWeights::area;
}

// The squared length of b - a (grid positions).
double squared_distance(const uint32_t* a, const uint32_t* b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += (double(b[k]) - a[k]) * (double(b[k]) - a[k]);
  return s;
}

// A face's vector (FORMAT.md §8.12 "Geometry normals"): the cross
// products of its fan from corner 0 summed; false unless every corner is
// an own vertex and it has 3 or more.
bool face_vector(const Mesh& faces, size_t f, const std::vector<uint32_t>& rank, const std::vector<uint32_t>& q,
                 double out[3]) {
  const uint32_t k = faces.face_size(f);
  const uint32_t* c = faces.face(f);
  bool own = k >= 3;
  for (uint32_t i = 0; i < k && own; ++i) own = rank[c[i]] != kNone;
  if (!own) return false;
  const uint32_t* p0 = &q[3 * static_cast<size_t>(rank[c[0]])];
  out[0] = out[1] = out[2] = 0;
  for (uint32_t i = 1; i + 1 < k; ++i) {
    const uint32_t* p1 = &q[3 * static_cast<size_t>(rank[c[i]])];
    const uint32_t* p2 = &q[3 * static_cast<size_t>(rank[c[i + 1]])];
    const double a[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
    const double b[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
    out[0] += a[1] * b[2] - a[2] * b[1];
    out[1] += a[2] * b[0] - a[0] * b[2];
    out[2] += a[0] * b[1] - a[1] * b[0];
  }
  return true;
}

// Normals of the own vertices from the faces whose corners are all own
// (fans for polygons), weighted as `weights` says, as octahedral indices.
// has[r]: 0 where the sum is zero, else 1 + how far the vertex's faces
// stray from the sum (the residuals' class): 0 every face within about
// 0.26 degrees (a flat region: the prediction is near exact), 1 within
// 0.8, 2 farther (a curved region or a crease).
void geometry_normals(const Mesh& faces, const std::vector<uint32_t>& rank, const std::vector<uint32_t>& q, int bits,
                      NormalWeights weights, std::vector<int32_t>& oct, std::vector<uint8_t>& has) {
  const size_t n = q.size() / 3;
  std::vector<double> sum(3 * n, 0.0);
  // The face vectors, kept for the stray pass (has_vector: 1 where there is one).
  std::vector<double> vectors(3 * faces.face_count());
  std::vector<uint8_t> has_vector(faces.face_count(), 0);
  std::vector<double> edge;  // per corner of a face: the squared length of its edge to the next
  for (size_t f = 0; f < faces.face_count(); ++f) {
    double* v = &vectors[3 * f];
    if (!face_vector(faces, f, rank, q, v)) continue;
    has_vector[f] = 1;
    const uint32_t k = faces.face_size(f);
    const uint32_t* c = faces.face(f);
    const double len = std::sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]);
    if (weights == NormalWeights::angle) {
      // Each edge's squared length once (the same either way round: the
      // differences of grid integers are exact).
      edge.resize(k);
      for (uint32_t i = 0; i < k; ++i)
        edge[i] = squared_distance(&q[3 * static_cast<size_t>(rank[c[i]])],
                                   &q[3 * static_cast<size_t>(rank[c[(i + 1) % k]])]);
    }
    for (uint32_t i = 0; i < k; ++i) {
      double w = 1;
      if (weights == NormalWeights::face) {
        w = len > 0 ? 1 / len : 0;
      } else if (weights == NormalWeights::angle) {
        const double e = edge[i] * edge[(i + k - 1) % k];
        w = e > 0 ? 1 / std::sqrt(e) : 0;
      }
      double* s = &sum[3 * static_cast<size_t>(rank[c[i]])];
      s[0] += v[0] * w;
      s[1] += v[1] * w;
      s[2] += v[2] * w;
    }
  }
  oct.assign(2 * n, 0);
  has.assign(n, 0);
  for (size_t r = 0; r < n; ++r) {
    const double* s = &sum[3 * r];
    if (s[0] == 0 && s[1] == 0 && s[2] == 0) continue;
    has[r] = 1;
    oct_encode(s[0], s[1], s[2], bits, &oct[2 * r]);
  }
  // The stray: per face with a non-zero vector, against each corner's sum,
  // cos^2 >= 0.99998 keeps class 0, >= 0.9998 class 1 (10^5 dot^2 against
  // 99998 |v|^2 |s|^2, 10^4 dot^2 against 9998, dot > 0), else class 2; a
  // vertex takes its faces' largest.
  for (size_t f = 0; f < faces.face_count(); ++f) {
    if (!has_vector[f]) continue;
    const double* v = &vectors[3 * f];
    const double vv = (v[0] * v[0] + v[1] * v[1]) + v[2] * v[2];
    if (vv == 0) continue;
    const uint32_t k = faces.face_size(f);
    const uint32_t* c = faces.face(f);
    for (uint32_t i = 0; i < k; ++i) {
      const uint32_t r = rank[c[i]];
      if (!has[r]) continue;
      const double* s = &sum[3 * static_cast<size_t>(r)];
      const double dot = (v[0] * s[0] + v[1] * s[1]) + v[2] * s[2];
      const double nn = vv * ((s[0] * s[0] + s[1] * s[1]) + s[2] * s[2]);
      const int cls = dot > 0 && 100000 * (dot * dot) >= 99998 * nn ? 0
                      : dot > 0 && 10000 * (dot * dot) >= 9998 * nn ? 1
                                                                    : 2;
      has[r] = static_cast<uint8_t>(std::max(int{has[r]}, 1 + cls));
    }
  }
}

// Texture coordinates from the geometry (predictor 2, FORMAT.md §8.12): the
// triangle (a, b, w), in the cyclic order of its face, has its texture
// coordinates at a and b; w is placed in the texture plane as it lies in
// space relative to the edge a-b: at the same fraction t along the edge, and
// across it by its distance h from the edge's line. When the triangle across
// the edge, (b, a, c), has its texture coordinates too, the texture vector of
// a unit step away from the edge is c's (an affine map, so stretched and
// sheared charts are followed) and w goes the other way; otherwise it is the
// edge's texture vector turned a quarter (a conformal map) to the side
// `sigma` says (the sign of the texture triangle's area, which a chart keeps
// from face to face). Positions are grid indices.
void uv_from_triangle(const uint32_t* pw, const uint32_t* pa, const uint32_t* pb, const int32_t* ua, const int32_t* ub,
                      const uint32_t* pc, const int32_t* uc, int sigma, double out[2]) {
  const double ex = double(pb[0]) - pa[0], ey = double(pb[1]) - pa[1], ez = double(pb[2]) - pa[2];
  const double l2 = ex * ex + ey * ey + ez * ez;
  const double dx = double(ub[0]) - ua[0], dy = double(ub[1]) - ua[1];
  if (l2 == 0) {
    out[0] = ua[0];
    out[1] = ua[1];
    return;
  }
  const double wx = double(pw[0]) - pa[0], wy = double(pw[1]) - pa[1], wz = double(pw[2]) - pa[2];
  const double t = (wx * ex + wy * ey + wz * ez) / l2;
  const double px = wx - t * ex, py = wy - t * ey, pz = wz - t * ez;
  const double hw = std::sqrt(px * px + py * py + pz * pz);
  if (pc) {
    const double cx = double(pc[0]) - pa[0], cy = double(pc[1]) - pa[1], cz = double(pc[2]) - pa[2];
    const double tc = (cx * ex + cy * ey + cz * ez) / l2;
    const double qx = cx - tc * ex, qy = cy - tc * ey, qz = cz - tc * ez;
    const double hc = std::sqrt(qx * qx + qy * qy + qz * qz);
    if (hc > 0) {
      const double mx = (double(uc[0]) - ua[0] - tc * dx) / hc, my = (double(uc[1]) - ua[1] - tc * dy) / hc;
      out[0] = ua[0] + t * dx - hw * mx;
      out[1] = ua[1] + t * dy - hw * my;
      return;
    }
  }
  const double h = hw / std::sqrt(l2) * sigma;
  out[0] = ua[0] + t * dx - h * dy;
  out[1] = ua[1] + t * dy + h * dx;
}

// The sign of the texture-space area of a face's corners (shoelace), 0 if none.
int uv_orientation(const int32_t* const* uv, uint32_t k) {
  // Each product is below 2^48 (24-bit grids); the sum wraps modulo 2^64
  // (a polygon of tens of thousands of corners could exceed int64).
  uint64_t area = 0;
  for (uint32_t i = 0; i < k; ++i) {
    const int32_t* a = uv[i];
    const int32_t* b = uv[(i + 1) % k];
    area += static_cast<uint64_t>(int64_t{a[0]} * b[1]) - static_cast<uint64_t>(int64_t{b[0]} * a[1]);
  }
  const int64_t signed_area = static_cast<int64_t>(area);
  return signed_area > 0 ? 1 : signed_area < 0 ? -1 : 0;
}

// Rounds an averaged prediction to the attribute's integer range.
int32_t round_to_grid(double x, int bits) {
  const double top = std::ldexp(1.0, bits) - 1;
  const double r = std::floor(x + 0.5);
  return static_cast<int32_t>(r < 0 ? 0 : r > top ? top : r);
}

// Predictor 6, tangents (FORMAT.md §8.12 "Tangents"): a glTF TANGENT (xyz
// a unit vector along the texture's u direction on the surface, w = +-1 the
// handedness of the bitangent) follows from the positions, the texture
// coordinates and the normal, as MikkTSpace makes it: per triangle the
// directions of increasing u and v (dP/du, dP/dv), summed at its corners,
// dP/du projected orthogonal to the vertex's normal, and w the side of
// n x t that dP/dv lies on. The attribute's values follow all others'
// (its sources', which may come after it in header order).
constexpr int kTangentPredictor = 6;

// The attributes a tangent is predicted from (header indices, -1: none).
struct TangentSources {
  int normal = -1;    // the first attribute coded per vertex with octahedral normals
  int texcoord = -1;  // the first attribute coded per vertex of kind texcoord
};

// `coded`: the headers as coded (a corner attribute coded per vertex with
// domain vertex). Sources are never tangents themselves (3 or 2 components).
TangentSources tangent_sources(const std::vector<AttributeHeader>& coded) {
  TangentSources s;
  for (size_t j = 0; j < coded.size(); ++j) {
    const AttributeHeader& h = coded[j];
    if (h.domain != AttributeDomain::vertex) continue;
    if (s.normal < 0 && h.quant == AttributeQuant::octahedral) s.normal = static_cast<int>(j);
    if (s.texcoord < 0 && h.kind == AttributeKind::texcoord) s.texcoord = static_cast<int>(j);
  }
  return s;
}

// Whether an attribute may be a tangent: 4 grid components per vertex.
bool tangent_shaped(const AttributeHeader& h) {
  return h.domain == AttributeDomain::vertex && h.quant == AttributeQuant::grid && h.components == 4;
}

// Grid index of value v on component c (the encoder's rounding, clamped),
// for a grid of `step` (0: every value is index 0) and largest index `top`.
int32_t tangent_grid_index(const AttributeHeader& h, double step, double top, uint32_t c, double v) {
  if (!(step > 0)) return 0;
  const double x = std::floor((v - static_cast<double>(h.origin[c])) / step + 0.5);
  return static_cast<int32_t>(x < 0 ? 0 : x > top ? top : x);
}

// Per own rank the normal of a tangent's normal source (decoded, binary64).
std::vector<double> source_normals(const AttributeHeader& nh, const std::vector<int32_t>& normal) {
  std::vector<double> n(3 * (normal.size() / 2));
  for (size_t r = 0; r < normal.size() / 2; ++r) {
    float f[3];
    oct_decode(normal[2 * r], normal[2 * r + 1], nh.bits, f);
    for (int a = 0; a < 3; ++a) n[3 * r + a] = f[a];
  }
  return n;
}

// The angle between edges a and b of a corner, its weight in a tangent:
// acos of their cosine through Abramowitz and Stegun's 4.4.45 (within
// 7e-5 of it), only +, -, x, / and sqrt, so that every decoder computes the
// same bits; 0 for an edge of length 0.
double corner_angle(const double* a, const double* b) {
  const double aa = (a[0] * a[0] + a[1] * a[1]) + a[2] * a[2], bb = (b[0] * b[0] + b[1] * b[1]) + b[2] * b[2];
  if (!(aa > 0 && bb > 0)) return 0;
  double c = ((a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]) / std::sqrt(aa * bb);
  c = c < -1 ? -1 : c > 1 ? 1 : c;
  const double x = std::fabs(c);
  const double t = std::sqrt(1 - x) * (((-0.0187293 * x + 0.0742610) * x - 0.2121144) * x + 1.5707288);
  return c < 0 ? 3.141592653589793 - t : t;
}

// Adds vector d, projected orthogonal to unit-ish n and normalized, times w, to s.
void add_projected(const double* d, const double* n, double w, double* s) {
  const double k = (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2];
  const double t[3] = {d[0] - n[0] * k, d[1] - n[1] * k, d[2] - n[2] * k};
  const double l2 = (t[0] * t[0] + t[1] * t[1]) + t[2] * t[2];
  if (!(l2 > 0)) return;
  const double f = w / std::sqrt(l2);
  for (int a = 0; a < 3; ++a) s[a] += t[a] * f;
}

// The triangles of the fans of the faces whose corners are all own: at
// each corner, their dP/du and dP/dv (oriented by the sign of the texture
// triangle's area; a degenerate one adds nothing), projected orthogonal to
// the corner's normal and normalized, times the corner's angle, add to the
// sums `tu`, `tv` of its vertex (own rank).
void tangent_sums(const Mesh& faces, const std::vector<uint32_t>& rank, const std::vector<uint32_t>& q,
                  const std::vector<double>& normal, const std::vector<int32_t>& uv, std::vector<double>& tu,
                  std::vector<double>& tv) {
  tu.assign(q.size(), 0.0);
  tv.assign(q.size(), 0.0);
  for (size_t f = 0; f < faces.face_count(); ++f) {
    const uint32_t k = faces.face_size(f);
    const uint32_t* c = faces.face(f);
    bool own = k >= 3;
    for (uint32_t i = 0; i < k && own; ++i) own = rank[c[i]] != kNone;
    if (!own) continue;
    for (uint32_t i = 1; i + 1 < k; ++i) {
      const uint32_t r[3] = {rank[c[0]], rank[c[i]], rank[c[i + 1]]};
      const uint32_t* p[3] = {&q[3 * size_t{r[0]}], &q[3 * size_t{r[1]}], &q[3 * size_t{r[2]}]};
      const int32_t *u0 = &uv[2 * size_t{r[0]}], *u1 = &uv[2 * size_t{r[1]}], *u2 = &uv[2 * size_t{r[2]}];
      const double s1 = double(u1[0]) - u0[0], t1 = double(u1[1]) - u0[1];
      const double s2 = double(u2[0]) - u0[0], t2 = double(u2[1]) - u0[1];
      const double det = s1 * t2 - s2 * t1;
      if (det == 0) continue;
      const double sign = det > 0 ? 1 : -1;
      double du[3], dv[3];
      for (int a = 0; a < 3; ++a) {
        const double e1 = double(p[1][a]) - p[0][a], e2 = double(p[2][a]) - p[0][a];
        du[a] = (e1 * t2 - e2 * t1) * sign;
        dv[a] = (e2 * s1 - e1 * s2) * sign;
      }
      for (int j = 0; j < 3; ++j) {
        const uint32_t *pj = p[j], *pn = p[(j + 1) % 3], *pp = p[(j + 2) % 3];
        const double ea[3] = {double(pn[0]) - pj[0], double(pn[1]) - pj[1], double(pn[2]) - pj[2]};
        const double eb[3] = {double(pp[0]) - pj[0], double(pp[1]) - pj[1], double(pp[2]) - pj[2]};
        const double w = corner_angle(ea, eb);
        const double* n = &normal[3 * size_t{r[j]}];
        add_projected(du, n, w, &tu[3 * size_t{r[j]}]);
        add_projected(dv, n, w, &tv[3 * size_t{r[j]}]);
      }
    }
  }
}

// Per own rank the predicted integers (4 each) of a tangent attribute `h`
// from the normals' and texture coordinates' integers (own-rank order) and
// the positions; has[r] = 0 where there is none (no texture area around the
// vertex, or dP/du along the normal).
void tangent_predictions(const AttributeHeader& h, const Mesh& faces, const std::vector<uint32_t>& rank,
                         const std::vector<uint32_t>& q, const AttributeHeader& nh, const std::vector<int32_t>& normal,
                         const std::vector<int32_t>& uv, std::vector<int32_t>& pred, std::vector<uint8_t>& has) {
  const std::vector<double> normals = source_normals(nh, normal);
  std::vector<double> tu, tv;
  tangent_sums(faces, rank, q, normals, uv, tu, tv);
  const size_t own = q.size() / 3;
  pred.assign(4 * own, 0);
  has.assign(own, 0);
  const double step = grid_step(h), top = std::ldexp(1.0, h.bits) - 1;
  for (size_t r = 0; r < own; ++r) {
    const double* n = &normals[3 * r];
    const double* u = &tu[3 * r];
    const double* v = &tv[3 * r];
    const double d = (n[0] * u[0] + n[1] * u[1]) + n[2] * u[2];
    const double t[3] = {u[0] - n[0] * d, u[1] - n[1] * d, u[2] - n[2] * d};
    const double l2 = (t[0] * t[0] + t[1] * t[1]) + t[2] * t[2];
    if (!(l2 > 0)) continue;
    const double len = std::sqrt(l2);
    const double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
    const double side = (b[0] * v[0] + b[1] * v[1]) + b[2] * v[2];
    has[r] = 1;
    for (uint32_t c = 0; c < 3; ++c) pred[4 * r + c] = tangent_grid_index(h, step, top, c, t[c] / len);
    pred[4 * r + 3] = tangent_grid_index(h, step, top, 3, side < 0 ? -1.0 : 1.0);
  }
}

// Faces around each part vertex (a face once per corner at the vertex).
struct VertexFaces {
  std::vector<uint32_t> start, face, corner;  // corner: position in the face
  void build(const Mesh& faces, size_t V) {
    start.assign(V + 1, 0);
    for (uint32_t v : faces.indices) ++start[v + 1];
    for (size_t v = 0; v < V; ++v) start[v + 1] += start[v];
    face.resize(faces.indices.size());
    corner.resize(faces.indices.size());
    std::vector<uint32_t> at(start.begin(), start.end() - 1);
    for (uint32_t f = 0; f < faces.face_count(); ++f)
      for (uint32_t i = 0; i < faces.face_size(f); ++i) {
        const uint32_t v = faces.face(f)[i];
        face[at[v]] = f;
        corner[at[v]++] = i;
      }
  }
};

// Names the readers give (FORMAT.md §8.12): a header names one of them by
// its index (one byte), and any other name by its length + 10 and its bytes.
constexpr const char* kCommonNames[] = {"normal",  "texcoord", "color",     "texcoord0",   "texcoord1",
                                        "TANGENT", "JOINTS_0", "WEIGHTS_0", "_gltf_group", "_gltf_primitive"};
constexpr uint64_t kCommonNameCount = sizeof(kCommonNames) / sizeof(kCommonNames[0]);

// A grid's origins and top (FORMAT.md §8.12) that are multiples of 1/64
// in -2 .. 2 - 1/64 (0, 0.25, 1, -1: texture coordinates and colours in
// 0..1) take one byte, an i8 of the value times 64; the grid byte says
// which (bit 2 + c for origin[c], bit 6 for top) besides the axis (bits
// 0-1). A writer uses the short form for exactly those values (-0 is not
// one), so a decoded file re-encodes to the same bytes.
constexpr float kGridShortScale = 64.0f;
constexpr int kGridTopShortBit = 6;

bool short_grid_value(float v, int8_t& k) {
  const float scaled = v * kGridShortScale;  // exact: a power of two, no overflow in range
  if (!(scaled >= -128.0f && scaled <= 127.0f) || scaled != std::floor(scaled) || (v == 0.0f && std::signbit(v)))
    return false;
  k = static_cast<int8_t>(scaled);
  return true;
}

void write_grid_value(ByteWriter& w, float v, bool is_short) {
  int8_t k = 0;
  if (is_short && short_grid_value(v, k)) {
    w.u8(static_cast<uint8_t>(k));
  } else {
    w.f32(v);
  }
}

// The header's layout byte: kind, domain, type, components - 1 (2 bits
// each); its coding byte: quant (2 bits), then bits (5 bits; 0 for exact).
void write_header(ByteWriter& w, const AttributeHeader& h) {
  uint64_t common = kCommonNameCount;
  for (uint64_t k = 0; k < kCommonNameCount; ++k)
    if (h.name == kCommonNames[k]) common = k;
  if (common < kCommonNameCount) {
    w.varint(common);
  } else {
    w.varint(kCommonNameCount + h.name.size());
    w.bytes(h.name);
  }
  w.u8(static_cast<uint8_t>(static_cast<uint32_t>(h.kind) | static_cast<uint32_t>(h.domain) << 2 |
                            static_cast<uint32_t>(h.type) << 4 | (h.components - 1) << 6));
  const int bits = h.quant == AttributeQuant::exact ? 0 : h.bits;
  w.u8(static_cast<uint8_t>(static_cast<uint32_t>(h.quant) | static_cast<uint32_t>(bits) << 2));
  if (h.quant == AttributeQuant::grid) {
    float top = 0;
    const int axis = extent_axis(h.origin, static_cast<int>(h.components), h.extent, top);
    uint32_t grid = static_cast<uint32_t>(axis);
    int8_t k = 0;
    for (uint32_t c = 0; c < h.components; ++c)
      grid |= static_cast<uint32_t>(short_grid_value(h.origin[c], k)) << (2 + c);
    grid |= static_cast<uint32_t>(short_grid_value(top, k)) << kGridTopShortBit;
    w.u8(static_cast<uint8_t>(grid));
    for (uint32_t c = 0; c < h.components; ++c) write_grid_value(w, h.origin[c], grid >> (2 + c) & 1);
    write_grid_value(w, top, grid >> kGridTopShortBit & 1);
  }
}

// A grid value, short (an i8, the value times 64) or an f32.
bool read_grid_value(ByteReader& r, bool is_short, float& v) {
  uint8_t k = 0;
  if (!is_short) return r.f32(v);
  if (!r.u8(k)) return false;
  v = static_cast<float>(static_cast<int8_t>(k)) / kGridShortScale;
  return true;
}

Status read_header(ByteReader& r, AttributeHeader& h) {
  uint64_t len = 0;
  std::string_view name;
  uint8_t layout = 0, coding = 0;
  if (!r.varint(len)) return corrupt("truncated attribute header");
  if (len < kCommonNameCount) {
    name = kCommonNames[len];
  } else if (len - kCommonNameCount > kMaxAttributeNameBytes) {
    return corrupt("bad attribute name length");
  } else if (!r.bytes(static_cast<size_t>(len - kCommonNameCount), name)) {
    return corrupt("truncated attribute header");
  }
  if (!r.u8(layout) || !r.u8(coding)) return corrupt("truncated attribute header");
  h.name.assign(name);
  const uint32_t domain = layout >> 2 & 3, quant = coding & 3, bits = coding >> 2;
  if (domain > 2 || quant > 2 || bits > 24) return corrupt("bad attribute header");
  h.kind = static_cast<AttributeKind>(layout & 3);
  h.domain = static_cast<AttributeDomain>(domain);
  h.type = static_cast<AttributeType>(layout >> 4 & 3);
  h.components = (layout >> 6) + 1u;
  h.quant = static_cast<AttributeQuant>(quant);
  h.bits = static_cast<int>(bits);
  const uint32_t comps = h.components;
  if ((h.quant == AttributeQuant::exact) != (bits == 0)) return corrupt("bad quantization bits");
  if ((h.type == AttributeType::f32) == (h.quant == AttributeQuant::exact))
    return corrupt(h.quant == AttributeQuant::exact ? "an f32 attribute coded as exact integers"
                                                    : "an integer attribute not coded as exact integers");
  if (h.quant == AttributeQuant::octahedral && comps != 3) return corrupt("octahedral needs 3 components");
  if (h.kind == AttributeKind::normal && comps != 3) return corrupt("a normal has 3 components");
  if (h.kind == AttributeKind::texcoord && comps != 2) return corrupt("a texture coordinate has 2 components");
  if (h.kind == AttributeKind::color && comps < 3) return corrupt("a colour has 3 or 4 components");
  if (h.quant == AttributeQuant::grid) {
    uint8_t grid = 0;
    float top = 0;
    if (!r.u8(grid)) return corrupt("truncated attribute header");
    const uint32_t axis = grid & 3;
    if (axis >= comps || grid >> 7 || (grid >> (2 + comps) & ((1u << (kGridTopShortBit - 2 - comps)) - 1)))
      return corrupt("bad grid byte");
    for (uint32_t c = 0; c < comps; ++c)
      if (!read_grid_value(r, grid >> (2 + c) & 1, h.origin[c]) || !std::isfinite(h.origin[c]))
        return corrupt("bad grid origin");
    if (!read_grid_value(r, grid >> kGridTopShortBit & 1, top) || !std::isfinite(top))
      return corrupt("bad grid maximum");
    h.extent = static_cast<double>(top) - static_cast<double>(h.origin[axis]);
    if (!(h.extent >= 0)) return corrupt("bad grid maximum (below the origin)");
  }
  return Status::Ok();
}

// The walk shared by the encoder (Coder = Enc, values known) and the decoder
// (Coder = Dec): vertex, face and corner values of one attribute.
// Predictor 2 without a placement (FORMAT.md §8.12, "Across a seam"): the
// value of a known corner of the vertex's faces (`base`) and, when an
// earlier vertex at the same position has a neighbour at that corner's
// position, the texture edge between those two (`edge`): the same edge on
// the other side of the seam, turned or mirrored as a chart of a texture
// atlas is (kTurns of them, named by the `transfer` model).
struct SeamTransfer {
  bool have = false;
  int32_t base[2] = {0, 0};
  int32_t edge[2] = {0, 0};
};
constexpr uint32_t kTurns = 8;

// The edge turned or mirrored as turn `k` says: identity, mirror in u, in
// v, half turn, quarter turns, the diagonals' mirrors.
void turned_edge(const int32_t* e, uint32_t k, int64_t* out) {
  const int64_t x = e[0], y = e[1];
  const int64_t t[kTurns][2] = {{x, y}, {-x, y}, {x, -y}, {-x, -y}, {-y, x}, {y, -x}, {y, x}, {-y, -x}};
  out[0] = t[k][0];
  out[1] = t[k][1];
}

void transfer_prediction(const SeamTransfer& t, uint32_t k, int bits, int32_t* pred) {
  int64_t e[2];
  turned_edge(t.edge, k, e);
  const int64_t top = (int64_t{1} << bits) - 1;
  for (int c = 0; c < 2; ++c) pred[c] = static_cast<int32_t>(std::clamp<int64_t>(t.base[c] + e[c], 0, top));
}

template <class Coder>
struct AttributeWalk {
  const AttributeHeader& h;
  ValueCoder<Coder>& vc;
  Coder& io;
  const Mesh& faces;                    // part output faces
  const std::vector<uint32_t>& rank;    // per part vertex: own rank or kNone
  const std::vector<int32_t>* gnormal;  // per own rank: geometry normal (octahedral)
  const std::vector<uint8_t>* ghas;
  const std::vector<uint32_t>* q = nullptr;  // own vertices' grid positions (predictor 2)
  const VertexFaces* around = nullptr;       // faces around each vertex (predictor 2)
  // Predictor 5: the recent misses of the affine and of the
  // conformal placements (FORMAT.md §8.12 "Affine or conformal").
  int64_t err_affine = 0, err_conformal = 0;
  static int64_t miss(const int32_t* x, const int32_t* p) {
    return std::abs(int64_t{x[0]} - p[0]) + std::abs(int64_t{x[1]} - p[1]);
  }
  const std::vector<int32_t>* tangent = nullptr;      // predictor 6: per own rank the predicted integers
  const std::vector<uint8_t>* tangent_has = nullptr;  // predictor 6: per own rank, 1 where predicted

  // Predictor 6 at own rank r: the tangent predicted there (class 0), else
  // the previous value (class 1).
  int tangent_prediction(uint32_t r, int32_t* pred) const {
    if (!(*tangent_has)[r]) return 1;
    std::copy_n(&(*tangent)[4 * size_t{r}], 4, pred);
    return 0;
  }

  // Predictor 2 for the value at position i of face f (vertex w): the mean
  // of the texture-space placements from the face's triangles (w, i+1, i+2)
  // and, for polygons, (i-2, i-1, w) whose other two corners are known
  // (`known(position)` gives their integers or nullptr) and own vertices.
  // For each, the first face around a (in `around` order) other than f that
  // has the edge a-b and a third corner c, an own vertex other than w, whose
  // value `across(F, position of a, of b, of c in F, ia, ib)` gives, is the
  // triangle across the edge. sum[0..1] gets the placements with c where
  // found (affine), sum[2..3] the placements without c (conformal).
  template <class Known, class Across>
  int uv_triangles(uint32_t f, uint32_t i, int sigma, Known known, Across across, double sum[4]) const {
    const uint32_t k = faces.face_size(f);
    const uint32_t* c = faces.face(f);
    int count = 0;
    const uint32_t w = c[i];
    if (k < 3 || rank[w] == kNone) return 0;
    for (uint32_t side = 0; side < (k > 3 ? 2u : 1u); ++side) {
      const uint32_t ia = side == 0 ? (i + 1) % k : (i + k - 2) % k;
      const uint32_t ib = side == 0 ? (i + 2) % k : (i + k - 1) % k;
      const uint32_t a = c[ia], b = c[ib];
      if (a == w || b == w || a == b || rank[a] == kNone || rank[b] == kNone) continue;
      const int32_t* ua = known(ia);
      const int32_t* ub = known(ib);
      if (!ua || !ub) continue;
      const uint32_t* pc = nullptr;
      const int32_t* uc = nullptr;
      for (uint32_t j = around->start[a]; j < around->start[a + 1] && !uc; ++j) {
        const uint32_t F = around->face[j], pa = around->corner[j], kf = faces.face_size(F);
        if (F == f || kf < 3) continue;
        const uint32_t* fc = faces.face(F);
        uint32_t pb, pcf;
        if (fc[(pa + 1) % kf] == b) {
          pb = (pa + 1) % kf;
          pcf = (pa + 2) % kf;
        } else if (fc[(pa + kf - 1) % kf] == b) {
          pb = (pa + kf - 1) % kf;
          pcf = (pa + kf - 2) % kf;
        } else {
          continue;
        }
        const uint32_t cv = fc[pcf];
        if (cv == w || cv == a || cv == b || rank[cv] == kNone) continue;
        uc = across(F, pa, pb, pcf, ia, ib);
        if (uc) pc = &(*q)[3 * static_cast<size_t>(rank[cv])];
      }
      double p[2];
      const uint32_t* pw = &(*q)[3 * static_cast<size_t>(rank[w])];
      const uint32_t* pa = &(*q)[3 * static_cast<size_t>(rank[a])];
      const uint32_t* pb = &(*q)[3 * static_cast<size_t>(rank[b])];
      uv_from_triangle(pw, pa, pb, ua, ub, pc, uc, sigma, p);
      sum[0] += p[0];
      sum[1] += p[1];
      if (pc) uv_from_triangle(pw, pa, pb, ua, ub, nullptr, nullptr, sigma, p);
      sum[2] += p[0];
      sum[3] += p[1];
      ++count;
    }
    return count;
  }

  // The mean of `count` placements summed in `sum` becomes the prediction
  // (when there is one); returns the residuals' class.
  int placed(const double sum[2], int count, int32_t* pred) const {
    if (count > 0) {
      pred[0] = round_to_grid(sum[0] / count, h.bits);
      pred[1] = round_to_grid(sum[1] / count, h.bits);
    }
    return std::min(count, 2);
  }

  // Predictors 2 and 5 place texture coordinates from the geometry; 5
  // chooses per vertex between the affine and the conformal placement.
  static bool placement(int predictor) { return predictor == 2 || predictor == 5; }

  // Vertex values, own vertices in output order. `x`: 'ints' per own vertex.
  // With `recent` (predictor bit 5), a value may instead name one of the
  // last 64 distinct values (the encoder does when the prediction misses it).
  bool vertices(int predictor, bool recent, bool siblings, std::vector<int32_t>& x) {
    const uint32_t n = int_components(h);
    int32_t prev[4] = {0, 0, 0, 0};
    int sigma = 1;
    std::vector<const int32_t*> uv;
    std::vector<std::array<int32_t, 4>> list;  // recent values, most recent first
    uint32_t hit_before = 0, sibling_before = 0;
    std::vector<uint32_t> earlier;  // per own rank: the previous own vertex at its grid position, or kNone
    if (siblings || placement(predictor)) earlier_at_same_position(earlier);
    std::vector<uint32_t> vertex_of;  // per own rank: its part vertex
    for (uint32_t v = 0; v < rank.size(); ++v)
      if (rank[v] != kNone) vertex_of.push_back(v);
    for (size_t v = 0; v < rank.size(); ++v) {
      const uint32_t r = rank[v];
      if (r == kNone) continue;
      if (siblings && !earlier.empty() && earlier[r] != kNone) {
        uint32_t hit = 0;
        if (!sibling_value(earlier, r, sibling_before, x, hit)) return false;
        sibling_before = hit;
        if (hit) {
          const int32_t* xv = &x[n * static_cast<size_t>(r)];
          std::copy(xv, xv + n, prev);
          if (recent) touch_recent(list, xv);
          if (placement(predictor)) update_sigma(v, r, sigma, uv, x);
          continue;
        }
      }
      int32_t pred[4] = {prev[0], prev[1], prev[2], prev[3]};
      int32_t affine[2] = {0, 0}, conformal[2] = {0, 0};  // predictor 2's two placements
      int placements = 0;
      int cls = 0;
      if (predictor == 1 || predictor == 3 || predictor == 4) {
        cls = (*ghas)[r] ? (*ghas)[r] - 1 : 2;  // how far its faces stray (geometry_normals)
        if ((*ghas)[r]) {
          pred[0] = (*gnormal)[2 * r];
          pred[1] = (*gnormal)[2 * r + 1];
        }
      }
      if (placement(predictor)) {
        double sum[4] = {0, 0, 0, 0};
        int count = 0;
        for (uint32_t j = around->start[v]; j < around->start[v + 1]; ++j) {
          const uint32_t f = around->face[j];
          const uint32_t* c = faces.face(f);
          count += uv_triangles(
              f, around->corner[j], sigma,
              [&](uint32_t at) -> const int32_t* {
                const uint32_t ra = rank[c[at]];
                return ra < r ? &x[2 * static_cast<size_t>(ra)] : nullptr;
              },
              [&](uint32_t F, uint32_t, uint32_t, uint32_t pc, uint32_t, uint32_t) -> const int32_t* {
                const uint32_t rc = rank[faces.face(F)[pc]];
                return rc < r ? &x[2 * static_cast<size_t>(rc)] : nullptr;
              },
              sum);
        }
        if (count == 0 && predictor == 5) count = pair_placement(v, r, sigma, x, sum, vertex_of);
        cls = placed(sum, count, pred);
        if (predictor == 5 && count > 0) {  // the placement whose recent misses are smaller
          placed(sum + 2, count, conformal);
          std::copy_n(pred, 2, affine);
          if (err_conformal < err_affine) std::copy_n(conformal, 2, pred);
        }
        placements = count;
      }
      if (predictor == kTangentPredictor) cls = tangent_prediction(r, pred);
      SeamTransfer transfer;
      if (placement(predictor) && cls == 0) {
        seam_transfer(v, r, earlier, vertex_of, x, pred, transfer);
        if (transfer.have) cls = 1;
      }
      int32_t* xv = &x[n * static_cast<size_t>(r)];
      if (!recent) {
        if (!transferred_value(transfer, pred, cls, xv)) return false;
      } else if (!recent_value(list, hit_before, pred, cls, transfer, xv)) {
        return false;
      }
      std::copy(xv, xv + n, prev);
      if (predictor == 5 && placements > 0) {
        err_affine += miss(xv, affine) - (err_affine >> 3);
        err_conformal += miss(xv, conformal) - (err_conformal >> 3);
      }
      if (placement(predictor)) update_sigma(v, r, sigma, uv, x);
    }
    return true;
  }
  // Predictor 5 where no triangle of a face places vertex w = v (own rank
  // r), FORMAT.md §8.12 "Placement from two neighbours": a = the first
  // corner of w's faces (faces-around order, positions in order) decoded
  // before it, b = the first such corner after a not on the line w-a (in
  // w's faces, then in a's), and w is placed as the face (w, a, b) would
  // place it, or (w, b, a): the order whose normal agrees with w's (the
  // sum over its faces of (next - w) x (previous - w)). At the start of a
  // chart, where a vertex has one decoded neighbour, this replaces the
  // neighbour's value as the prediction. Adds the placement to `sum`;
  // returns 1, or 0 when there is none.
  int pair_placement(size_t v, uint32_t r, int sigma, const std::vector<int32_t>& x, double sum[4],
                     const std::vector<uint32_t>& vertex_of) const {
    const uint32_t* pw = &(*q)[3 * size_t{r}];
    double n[3] = {0, 0, 0}, cross[3] = {0, 0, 0};
    uint32_t ra = kNone, rb = kNone;
    for (uint32_t j = around->start[v]; j < around->start[v + 1]; ++j) {
      const uint32_t f = around->face[j], k = faces.face_size(f), i = around->corner[j];
      const uint32_t* c = faces.face(f);
      if (k < 3) continue;
      const uint32_t rn = rank[c[(i + 1) % k]], rp = rank[c[(i + k - 1) % k]];
      if (rn != kNone && rp != kNone) {
        double t[3];
        corner_cross(rn, rp, pw, t);
        for (int d = 0; d < 3; ++d) n[d] += t[d];
      }
      for (uint32_t m = 0; m < k && rb == kNone; ++m) {
        const uint32_t rc = rank[c[m]];
        if (c[m] == v || rc == kNone || rc >= r || rc == ra) continue;
        if (ra == kNone) {
          ra = rc;
        } else {
          corner_cross(ra, rc, pw, cross);
          if (cross[0] != 0 || cross[1] != 0 || cross[2] != 0) rb = rc;
        }
      }
    }
    if (ra == kNone) return 0;
    const uint32_t va = vertex_of[ra];
    for (uint32_t j = around->start[va]; j < around->start[va + 1] && rb == kNone; ++j) {
      const uint32_t f = around->face[j], k = faces.face_size(f);
      const uint32_t* c = faces.face(f);
      for (uint32_t m = 0; m < k && rb == kNone; ++m) {
        const uint32_t rc = rank[c[m]];
        if (c[m] == v || rc == kNone || rc >= r || rc == ra) continue;
        corner_cross(ra, rc, pw, cross);
        if (cross[0] != 0 || cross[1] != 0 || cross[2] != 0) rb = rc;
      }
    }
    if (rb == kNone) return 0;
    const double s = cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2];
    if (s == 0) return 0;
    if (s < 0) std::swap(ra, rb);
    double p[2];
    uv_from_triangle(pw, &(*q)[3 * size_t{ra}], &(*q)[3 * size_t{rb}], &x[2 * size_t{ra}], &x[2 * size_t{rb}], nullptr,
                     nullptr, sigma, p);
    for (int k = 0; k < 4; ++k) sum[k] += p[k % 2];
    return 1;
  }
  // (q[ra] - pw) x (q[rb] - pw), binary64 in the order FORMAT.md gives.
  void corner_cross(uint32_t ra, uint32_t rb, const uint32_t* pw, double* out) const {
    const uint32_t* pa = &(*q)[3 * size_t{ra}];
    const uint32_t* pb = &(*q)[3 * size_t{rb}];
    const double e[3] = {double(pa[0]) - pw[0], double(pa[1]) - pw[1], double(pa[2]) - pw[2]};
    const double g[3] = {double(pb[0]) - pw[0], double(pb[1]) - pw[1], double(pb[2]) - pw[2]};
    out[0] = e[1] * g[2] - e[2] * g[1];
    out[1] = e[2] * g[0] - e[0] * g[2];
    out[2] = e[0] * g[1] - e[1] * g[0];
  }
  // Predictor 2 where no triangle places vertex v (own rank r): the value
  // of the first corner of its faces (faces-around order, positions in
  // order) decoded before it becomes the prediction, and the transfer's
  // edge is looked for: along the chain of earlier vertices at v's position
  // (latest first, at most kSiblingVertices), the first corner decoded
  // before v of their faces (same order) at that corner's position.
  void seam_transfer(size_t v, uint32_t r, const std::vector<uint32_t>& earlier, const std::vector<uint32_t>& vertex_of,
                     const std::vector<int32_t>& x, int32_t* pred, SeamTransfer& t) const {
    const uint32_t ra = first_known_corner(v, r, nullptr);
    if (ra == kNone) return;
    std::copy_n(&x[2 * size_t{ra}], 2, pred);
    std::copy_n(&x[2 * size_t{ra}], 2, t.base);
    if (earlier.empty()) return;
    uint32_t seen = 0;
    for (uint32_t s = earlier[r]; s != kNone && seen < kSiblingVertices; s = earlier[s], ++seen) {
      const uint32_t rb = first_known_corner(vertex_of[s], r, &(*q)[3 * size_t{ra}]);
      if (rb == kNone) continue;
      t.have = true;
      for (int c = 0; c < 2; ++c) t.edge[c] = x[2 * size_t{s} + c] - x[2 * size_t{rb} + c];
      return;
    }
  }
  // The own rank of the first corner of vertex v's faces (faces-around
  // order, positions in order) decoded before rank r and, with `at`, at
  // that grid position; kNone if none.
  uint32_t first_known_corner(size_t v, uint32_t r, const uint32_t* at) const {
    for (uint32_t j = around->start[v]; j < around->start[v + 1]; ++j) {
      const uint32_t f = around->face[j], k = faces.face_size(f);
      const uint32_t* c = faces.face(f);
      for (uint32_t i = 0; i < k; ++i) {
        const uint32_t rc = rank[c[i]];
        if (rc == kNone || rc >= r) continue;
        if (!at || std::equal(at, at + 3, &(*q)[3 * size_t{rc}])) return rc;
      }
    }
    return kNone;
  }
  // A value coded against `pred`, or with a seam transfer first the turn
  // (the encoder's: the smallest larger residual, then the smallest sum,
  // then the first) that makes the prediction.
  bool transferred_value(const SeamTransfer& t, int32_t* pred, int cls, int32_t* xv) {
    if (t.have) {
      uint32_t k = 0;
      if constexpr (Coder::kEncoder) {
        int64_t best[2] = {INT64_MAX, INT64_MAX};
        for (uint32_t j = 0; j < kTurns; ++j) {
          int32_t p[2];
          transfer_prediction(t, j, h.bits, p);
          const int64_t d0 = std::abs(int64_t{xv[0]} - p[0]), d1 = std::abs(int64_t{xv[1]} - p[1]);
          const int64_t cost[2] = {std::max(d0, d1), d0 + d1};
          if (std::lexicographical_compare(cost, cost + 2, best, best + 2)) {
            std::copy_n(cost, 2, best);
            k = j;
          }
        }
      }
      k = io.uint(vc.m.transfer, k);
      if (k >= kTurns) return false;
      transfer_prediction(t, k, h.bits, pred);
    }
    return vc.value(h, pred, xv, cls);
  }
  // Faces completed by vertex v (own rank r) give the chart's orientation.
  void update_sigma(size_t v, uint32_t r, int& sigma, std::vector<const int32_t*>& uv,
                    const std::vector<int32_t>& x) const {
    for (uint32_t j = around->start[v]; j < around->start[v + 1]; ++j) {
      const uint32_t f = around->face[j], k = faces.face_size(f);
      const uint32_t* c = faces.face(f);
      bool complete = k >= 3;
      uv.clear();
      for (uint32_t i = 0; i < k && complete; ++i) {
        complete = rank[c[i]] <= r;
        if (complete) uv.push_back(&x[2 * static_cast<size_t>(rank[c[i]])]);
      }
      if (!complete) continue;
      const int o = uv_orientation(uv.data(), k);
      if (o != 0) sigma = o;
    }
  }
  // Per own rank, the previous own rank with the same grid position (kNone:
  // none); empty without positions. One pass in rank order over an open
  // addressing table of positions, each slot holding the latest rank there.
  void earlier_at_same_position(std::vector<uint32_t>& earlier) const {
    earlier.clear();
    if (!q || q->empty()) return;
    const size_t own = q->size() / 3;
    size_t slots = 16;
    while (slots < 2 * own) slots *= 2;
    const size_t mask = slots - 1;
    std::vector<uint32_t> latest(slots, kNone);
    const uint32_t* p = q->data();
    earlier.assign(own, kNone);
    for (uint32_t r = 0; r < own; ++r) {
      const uint32_t* x = p + 3 * size_t{r};
      const uint64_t hash = (uint64_t{x[0]} * 0x9E3779B97F4A7C15ull) ^ (uint64_t{x[1]} * 0xC2B2AE3D27D4EB4Full) ^
                            (uint64_t{x[2]} * 0x165667B19E3779F9ull);
      size_t i = static_cast<size_t>(hash >> 32) & mask;
      while (latest[i] != kNone && !std::equal(x, x + 3, p + 3 * size_t{latest[i]})) i = (i + 1) & mask;
      earlier[r] = latest[i];
      latest[i] = r;
    }
  }
  // The siblings' step (predictor bit 6) for own rank r, which has an
  // earlier vertex at its position: whether its value is one of the
  // distinct values of the up to kSiblingVertices latest such vertices
  // (latest first) and which. `hit` = 1 when it is (x[r] then holds it).
  bool sibling_value(const std::vector<uint32_t>& earlier, uint32_t r, uint32_t before, std::vector<int32_t>& x,
                     uint32_t& hit) {
    const uint32_t n = int_components(h);
    uint32_t distinct[kSiblingVertices];
    uint32_t count = 0, seen = 0;
    for (uint32_t s = earlier[r]; s != kNone && seen < kSiblingVertices; s = earlier[s], ++seen) {
      const int32_t* xs = &x[n * static_cast<size_t>(s)];
      bool dup = false;
      for (uint32_t j = 0; j < count && !dup; ++j)
        dup = std::equal(xs, xs + n, &x[n * static_cast<size_t>(distinct[j])]);
      if (!dup) distinct[count++] = s;
    }
    uint32_t j = 0;
    hit = 0;
    if constexpr (Coder::kEncoder) {
      const int32_t* xv = &x[n * static_cast<size_t>(r)];
      for (j = 0; j < count; ++j)
        if (std::equal(xv, xv + n, &x[n * static_cast<size_t>(distinct[j])])) break;
      hit = j < count;
      if (!hit) j = 0;
    }
    hit = io.uint(vc.m.sibling_hit[before][count > 1], hit);
    if (hit > 1) return false;
    if (!hit) return true;
    if (count > 1) j = io.uint(vc.m.sibling_index, j);
    if (j >= count) return false;
    const int32_t* xs = &x[n * static_cast<size_t>(distinct[j])];
    std::copy(xs, xs + n, &x[n * static_cast<size_t>(r)]);
    return true;
  }
  // A value taken without the recent values' step moves to the front of
  // their list as one coded with it would.
  void touch_recent(std::vector<std::array<int32_t, 4>>& list, const int32_t* xv) const {
    const uint32_t n = int_components(h);
    std::array<int32_t, 4> v{};
    std::copy(xv, xv + n, v.begin());
    const size_t at = find_recent(list, xv, n);
    if (at < list.size()) {
      std::move_backward(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(at),
                         list.begin() + static_cast<std::ptrdiff_t>(at) + 1);
      list[0] = v;
      return;
    }
    list.insert(list.begin(), v);
    if (list.size() > kRecentValues) list.pop_back();
  }
  // One vertex value with the recent values: a hit (and which) or the value
  // coded against `pred`; then the value moves to the front of `list`.
  bool recent_value(std::vector<std::array<int32_t, 4>>& list, uint32_t& hit_before, int32_t* pred, int cls,
                    const SeamTransfer& transfer, int32_t* xv) {
    const uint32_t n = int_components(h);
    size_t at = list.size();  // the value's place in the list, if there
    uint32_t hit = 0, j = 0;
    if constexpr (Coder::kEncoder) {
      at = find_recent(list, xv, n);
      if (at < list.size() && !std::equal(xv, xv + n, pred)) {
        hit = 1;
        j = static_cast<uint32_t>(at);
      }
    }
    hit = io.uint(vc.m.recent_hit[hit_before], hit);
    if (hit > 1) return false;
    if (hit) {
      j = io.uint(vc.m.recent_index, j);
      if (j >= list.size()) return false;
      std::copy(list[j].begin(), list[j].begin() + n, xv);
      at = j;
    } else {
      if (!transferred_value(transfer, pred, cls, xv)) return false;
      if constexpr (!Coder::kEncoder) at = find_recent(list, xv, n);
    }
    hit_before = hit;
    std::array<int32_t, 4> v{};
    std::copy(xv, xv + n, v.begin());
    if (at < list.size()) {
      std::move_backward(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(at),
                         list.begin() + static_cast<std::ptrdiff_t>(at) + 1);
      list[0] = v;
      return true;
    }
    list.insert(list.begin(), v);
    if (list.size() > kRecentValues) list.pop_back();
    return true;
  }
  static size_t find_recent(const std::vector<std::array<int32_t, 4>>& list, const int32_t* x, uint32_t n) {
    for (size_t k = 0; k < list.size(); ++k) {
      bool same = true;
      for (uint32_t c = 0; c < n && same; ++c) same = list[k][c] == x[c];
      if (same) return k;
    }
    return list.size();
  }
  bool face_values(std::vector<int32_t>& x) {
    const uint32_t n = int_components(h);
    int32_t prev[4] = {0, 0, 0, 0};
    for (size_t f = 0; f < x.size() / n; ++f) {
      if (!vc.value(h, prev, &x[n * f])) return false;
      std::copy(&x[n * f], &x[n * f] + n, prev);
    }
    return true;
  }
  // Corner values. Encoder: `in_value` per output corner (the input value
  // index), `in_ints` the input values; out: the part's value list in
  // first-use order (then the unused ones), `index` per corner.
  // max_unused: a bound from the stream's size (each value costs at least
  // one coded decision). With predictor 2 the corners of a face are visited
  // known vertices first (those with candidates when the face starts), so
  // that a new value has its face's other values to be predicted from.
  //
  // In a segment (`segmented`), each new value says whether it is a value of
  // an earlier segment (`imported`, per input value: its id in the file's
  // value list, or kNone) and then which; `alias` gets per output value that
  // id or kNone. `in_of`: per output value its input value (encoder).
  bool corners(int predictor, bool segmented, const std::vector<uint32_t>* imported,
               const std::vector<uint32_t>& in_value, const std::vector<int32_t>& in_ints, size_t in_count,
               uint64_t max_unused, std::vector<int32_t>& values, std::vector<uint32_t>& index,
               std::vector<uint32_t>& alias, std::vector<uint32_t>& in_of) {
    const uint32_t n = int_components(h);
    const size_t K = faces.indices.size();
    const size_t V = rank.size();
    std::vector<uint32_t> cand(4 * V, kNone);
    std::vector<uint8_t> ncand(V, 0);
    std::vector<uint32_t> out_of(Coder::kEncoder ? in_count : 0, kNone);  // encoder: input value -> output id
    in_of.clear();
    alias.clear();
    int64_t last_import = 0;
    index.assign(K, 0);
    values.clear();
    int32_t prev[4] = {0, 0, 0, 0};
    int sigma = 1;
    std::vector<uint32_t> visit;     // positions of the face in visiting order
    std::vector<uint8_t> done;       // per position: value known
    std::vector<const int32_t*> uv;  // per position: its value's integers
    for (uint32_t g = 0; g < faces.face_count(); ++g) {
      const uint32_t fk = faces.face_size(g);
      const uint32_t* fc = faces.face(g);
      visit.clear();
      if (predictor == 2) {
        for (uint32_t i = 0; i < fk; ++i)
          if (ncand[fc[i]] > 0) visit.push_back(i);
        for (uint32_t i = 0; i < fk; ++i)
          if (ncand[fc[i]] == 0) visit.push_back(i);
      } else {
        for (uint32_t i = 0; i < fk; ++i) visit.push_back(i);
      }
      done.assign(fk, 0);
      for (uint32_t i : visit) {
        const size_t k = faces.face_offsets[g] + i;
        const uint32_t w = fc[i];
        const uint32_t nc = ncand[w];
        uint32_t s = 0, id = kNone;
        if constexpr (Coder::kEncoder) {
          id = out_of[in_value[k]];
          if (id == kNone) {
            s = nc;
          } else {
            s = nc + 1;
            for (uint32_t j = 0; j < nc; ++j)
              if (cand[4 * w + j] == id) s = j;
          }
        }
        s = io.uint(vc.m.symbol[std::min<uint32_t>(nc, 5)], s);
        const uint32_t have = static_cast<uint32_t>(values.size() / n);
        if (s < nc) {
          id = cand[4 * w + s];
        } else if (s == nc) {  // a new value
          id = have;
          int32_t pred[4] = {prev[0], prev[1], prev[2], prev[3]};
          int cls = 0;
          const uint32_t r = rank[w];
          if (gnormal && r != kNone && (*ghas)[r]) {
            pred[0] = (*gnormal)[2 * r];
            pred[1] = (*gnormal)[2 * r + 1];
          }
          if (predictor == 2) {
            double sum[4] = {0, 0, 0, 0};
            const uint32_t* off = faces.face_offsets.data();
            const int count = uv_triangles(
                g, i, sigma,
                [&](uint32_t at) -> const int32_t* {
                  return done[at] ? &values[n * static_cast<size_t>(index[off[g] + at])] : nullptr;
                },
                [&](uint32_t F, uint32_t pa, uint32_t pb, uint32_t pc, uint32_t ia, uint32_t ib) -> const int32_t* {
                  if (F >= g || index[off[F] + pa] != index[off[g] + ia] || index[off[F] + pb] != index[off[g] + ib])
                    return nullptr;
                  return &values[n * static_cast<size_t>(index[off[F] + pc])];
                },
                sum);
            cls = placed(sum, count, pred);
            if (count == 0) {
              for (uint32_t j : visit)
                if (done[j]) {
                  const int32_t* u = &values[n * static_cast<size_t>(index[faces.face_offsets[g] + j])];
                  std::copy(u, u + n, pred);
                  break;
                }
            }
          }
          uint32_t from = kNone;
          if (segmented) {
            uint32_t flag = 0;
            if constexpr (Coder::kEncoder) flag = (*imported)[in_value[k]] != kNone;
            flag = io.uint(vc.m.imported[r == kNone], flag);
            if (flag > 1) return false;
            if (flag) {
              int64_t delta = 0;
              if constexpr (Coder::kEncoder) delta = int64_t{(*imported)[in_value[k]]} - last_import;
              const int64_t gid = last_import + io.sint(vc.m.import_id, delta);
              if (gid < 0 || gid >= int64_t{kNone}) return false;
              last_import = gid;
              from = static_cast<uint32_t>(gid);
            }
          }
          alias.push_back(from);
          values.resize(values.size() + n);
          int32_t* x = &values[n * static_cast<size_t>(id)];
          if constexpr (Coder::kEncoder) {
            std::copy(&in_ints[n * static_cast<size_t>(in_value[k])],
                      &in_ints[n * static_cast<size_t>(in_value[k])] + n, x);
            out_of[in_value[k]] = id;
            in_of.push_back(in_value[k]);
          }
          if (!vc.value(h, pred, x, cls)) return false;
          std::copy(x, x + n, prev);
        } else if (s == nc + 1) {  // a value met elsewhere
          uint32_t back = 0;
          if constexpr (Coder::kEncoder) back = have - 1 - id;
          back = io.uint(vc.m.far, back);
          if (back >= have) return false;
          id = have - 1 - back;
        } else {
          return false;
        }
        index[k] = id;
        done[i] = 1;
        if (s >= nc && nc < 4) {
          bool seen = false;
          for (uint32_t j = 0; j < nc; ++j) seen = seen || cand[4 * w + j] == id;
          if (!seen) {
            cand[4 * w + nc] = id;
            ncand[w] = static_cast<uint8_t>(nc + 1);
          }
        }
      }
      if (predictor == 2 && fk >= 3) {
        uv.clear();
        for (uint32_t i = 0; i < fk; ++i)
          uv.push_back(&values[n * static_cast<size_t>(index[faces.face_offsets[g] + i])]);
        const int o = uv_orientation(uv.data(), fk);
        if (o != 0) sigma = o;
      }
    }
    // The values no corner uses, in input order.
    uint32_t unused = 0;
    if constexpr (Coder::kEncoder) unused = static_cast<uint32_t>(in_count - in_of.size());
    unused = io.uint(vc.m.unused, unused);
    if (unused == 0xFFFFFFFFu || unused > max_unused) return false;
    size_t next_in = 0;
    for (uint32_t u = 0; u < unused; ++u) {
      const size_t at = values.size();
      values.resize(at + n);
      alias.push_back(kNone);
      if constexpr (Coder::kEncoder) {
        while (out_of[next_in] != kNone) ++next_in;
        std::copy(&in_ints[n * next_in], &in_ints[n * next_in] + n, &values[at]);
        in_of.push_back(static_cast<uint32_t>(next_in));
        ++next_in;
      }
      if (!vc.value(h, prev, &values[at])) return false;
      std::copy(&values[at], &values[at] + n, prev);
    }
    return true;
  }
};

}  // namespace

uint32_t attribute_key_size(const AttributeHeader& h) { return int_components(h); }
void attribute_key(const AttributeHeader& h, const float* value, int32_t* out) { to_ints(h, value, out); }

Attribute described_like(const Attribute& a) {
  Attribute b;
  b.name = a.name;
  b.kind = a.kind;
  b.domain = a.domain;
  b.type = a.type;
  b.components = a.components;
  return b;
}

bool same_description(const Attribute& a, const Attribute& b) {
  return a.name == b.name && a.kind == b.kind && a.domain == b.domain && a.type == b.type &&
         a.components == b.components;
}

// FORMAT.md §8.12: the float nearest the grid point, or the float below it
// while it lies past origin + extent (as positions, §5): each component of
// the decoded values then spans at most the extent, so coding them again
// takes the same grid (a component other than the one that set the extent
// could round up past it, and the grid grew by an ulp each round).
float attribute_grid_value(const AttributeHeader& h, int c, int64_t x) {
  const double o = static_cast<double>(h.origin[c]);
  const double v = o + static_cast<double>(x) * grid_step(h);
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  float f = static_cast<float>(v > kMax ? kMax : v < -kMax ? -kMax : v);
  while (static_cast<double>(f) - o > h.extent) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

std::vector<AttributeHeader> attribute_headers(const Mesh& mesh, const AttributeBits& bits) {
  std::vector<AttributeHeader> out;
  for (const Attribute& a : mesh.attributes) {
    AttributeHeader h;
    h.name = a.name;
    h.kind = a.kind;
    h.domain = a.domain;
    h.type = a.type;
    h.components = a.components;
    if (a.type != AttributeType::f32) {
      h.quant = AttributeQuant::exact;
    } else if (a.kind == AttributeKind::normal) {
      h.quant = AttributeQuant::octahedral;
      h.bits = bits.normal;
    } else {
      h.quant = AttributeQuant::grid;
      h.bits = a.kind == AttributeKind::texcoord ? bits.texcoord
               : a.kind == AttributeKind::color  ? bits.color
                                                 : bits.generic;
      float mn[4], mx[4];
      for (uint32_t c = 0; c < a.components; ++c) mn[c] = mx[c] = a.values.empty() ? 0.0f : a.values[c];
      for (size_t i = 0; i < a.values.size(); ++i) {
        const uint32_t c = static_cast<uint32_t>(i % a.components);
        mn[c] = std::min(mn[c], a.values[i]);
        mx[c] = std::max(mx[c], a.values[i]);
      }
      for (uint32_t c = 0; c < a.components; ++c) {
        h.origin[c] = mn[c] + 0.0f;  // a -0 minimum as +0, as it decodes (canonical re-encoding)
        h.extent = std::max(h.extent, static_cast<double>(mx[c]) - static_cast<double>(mn[c]));
      }
    }
    out.push_back(h);
  }
  return out;
}

namespace {

// The predictors an attribute may use, as bits (1 << predictor): 0 previous
// value; 1, 3 and 4 geometry normal weighted by area, by face, by angle
// (octahedral vertex normals; 3 and 4 also corner normals, whose new values
// predictor 0 predicts by area); 2 texture placement from the geometry
// (two-component grid values per vertex or corner); 5 the same placement,
// affine or conformal per vertex (two-component grid values per vertex).
unsigned predictors_for(const AttributeHeader& h) {
  unsigned p = 1;
  if (h.domain == AttributeDomain::vertex && h.quant == AttributeQuant::octahedral) p |= 2 | 8 | 16;
  if (h.domain == AttributeDomain::corner && h.quant == AttributeQuant::octahedral) p |= 8 | 16;
  if (h.domain != AttributeDomain::face && h.quant == AttributeQuant::grid && h.components == 2) p |= 4;
  if (h.domain == AttributeDomain::vertex && h.quant == AttributeQuant::grid && h.components == 2) p |= 32;
  if (tangent_shaped(h)) p |= 1u << kTangentPredictor;  // with sources (tangent_sources)
  return p;
}

}  // namespace

uint32_t smallest_rotation(const uint32_t* c, uint32_t n) {
  uint32_t best = 0;
  for (uint32_t r = 1; r < n; ++r)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = c[(r + i) % n], b = c[(best + i) % n];
      if (a != b) {
        if (a < b) best = r;
        break;
      }
    }
  return best;
}

Status encode_attributes(const std::vector<AttributeHeader>& headers, const AttributeInput& in, std::string& out) {
  out.clear();
  if (headers.empty()) return Status::Ok();
  const Mesh& part = *in.part;
  const Mesh& faces = *in.faces;
  const std::vector<uint32_t>& order = *in.order;
  const size_t V = order.size();
  std::vector<uint32_t> rank(V, kNone);
  uint32_t own = 0;
  for (size_t v = 0; v < V; ++v)
    if (!in.is_ref || in.is_ref->empty() || !(*in.is_ref)[v]) rank[v] = own++;
  // Output faces -> input faces and the rotation of their corners.
  std::vector<uint32_t> face_of(faces.face_count(), kNone), shift(faces.face_count(), 0);
  bool need_faces = false;
  for (const AttributeHeader& h : headers) need_faces = need_faces || h.domain != AttributeDomain::vertex;
  if (need_faces) {
    std::vector<uint32_t> out_id(part.vertex_count(), kNone);
    for (size_t v = 0; v < V; ++v) out_id[order[v]] = static_cast<uint32_t>(v);
    // Key of a face: its corner cycle (output ids) from its smallest rotation.
    auto key = [](const uint32_t* c, uint32_t k, uint32_t& best) {
      best = smallest_rotation(c, k);
      std::vector<uint32_t> cycle(k);
      for (uint32_t i = 0; i < k; ++i) cycle[i] = c[(best + i) % k];
      return cycle;
    };
    std::vector<std::pair<std::vector<uint32_t>, uint32_t>> in_keys;  // (key, input face)
    std::vector<uint32_t> rot_in(part.face_count());
    std::vector<uint32_t> tmp;
    for (uint32_t f = 0; f < part.face_count(); ++f) {
      tmp.assign(part.face(f), part.face(f) + part.face_size(f));
      for (uint32_t& x : tmp) x = out_id[x];
      in_keys.push_back({key(tmp.data(), static_cast<uint32_t>(tmp.size()), rot_in[f]), f});
    }
    std::sort(in_keys.begin(), in_keys.end());
    std::vector<uint8_t> used(in_keys.size(), 0);
    for (uint32_t g = 0; g < faces.face_count(); ++g) {
      uint32_t rot_out = 0;
      std::pair<std::vector<uint32_t>, uint32_t> probe{key(faces.face(g), faces.face_size(g), rot_out), 0};
      auto it = std::lower_bound(in_keys.begin(), in_keys.end(), probe);
      while (it != in_keys.end() && it->first == probe.first && used[static_cast<size_t>(it - in_keys.begin())]) ++it;
      if (it == in_keys.end() || it->first != probe.first)
        return Status(ErrorCode::internal, "attributes: a decoded face matches no input face");
      used[static_cast<size_t>(it - in_keys.begin())] = 1;
      const uint32_t f = it->second, k = faces.face_size(g);
      face_of[g] = f;
      // Output corner i is key corner (i - rot_out), input corner (i - rot_out + rot_in).
      shift[g] = (rot_in[f] + k - rot_out % (k ? k : 1)) % (k ? k : 1);
    }
  }
  std::vector<int32_t> gnormal;
  std::vector<uint8_t> ghas;
  VertexFaces around;
  bool need_around = false;
  for (size_t i = 0; i < headers.size(); ++i)
    need_around = need_around || predictors_for(coded_header(headers[i], in.per_vertex >> i & 1)) & (4 | 32);
  if (need_around) around.build(faces, V);
  // Predictor 6: the sources' integers per own rank, from the part's values.
  std::vector<AttributeHeader> coded(headers.size());
  for (size_t i = 0; i < headers.size(); ++i) coded[i] = coded_header(headers[i], in.per_vertex >> i & 1);
  const TangentSources sources = tangent_sources(coded);
  auto own_ints = [&](int j) {
    const AttributeHeader& h = coded[static_cast<size_t>(j)];
    const uint32_t n = int_components(h);
    std::vector<int32_t> x(n * static_cast<size_t>(own));
    for (size_t v = 0; v < V; ++v)
      if (rank[v] != kNone)
        to_ints(h, &part.attributes[static_cast<size_t>(j)].values[h.components * static_cast<size_t>(order[v])],
                &x[n * rank[v]]);
    return x;
  };
  std::vector<int32_t> tangent_pred;
  std::vector<uint8_t> tangent_has;
  // One attribute's values into `enc` with `predictor`.
  std::vector<uint32_t>* own_values = nullptr;
  bool siblings = false;  // the attribute being coded names its siblings' values (predictor bit 6)
  bool shared = false;    // its components share the residual models (predictor bit 7)
  auto code = [&](Enc& enc, size_t i, int predictor, bool recent) {
    const AttributeHeader h = coded_header(headers[i], in.per_vertex >> i & 1);
    const Attribute& a = part.attributes[i];
    const uint32_t n = int_components(h);
    ValueCoder<Enc> vc{enc, {}};
    vc.shared = shared;
    const bool oct = h.quant == AttributeQuant::octahedral;
    if (oct) geometry_normals(faces, rank, *in.q, h.bits, normal_weights(predictor), gnormal, ghas);
    AttributeWalk<Enc> walk{h, vc, enc, faces, rank, oct ? &gnormal : nullptr, oct ? &ghas : nullptr, in.q, &around};
    if (predictor == kTangentPredictor) {
      tangent_predictions(h, faces, rank, *in.q, coded[static_cast<size_t>(sources.normal)], own_ints(sources.normal),
                          own_ints(sources.texcoord), tangent_pred, tangent_has);
      walk.tangent = &tangent_pred;
      walk.tangent_has = &tangent_has;
    }
    if (h.domain == AttributeDomain::vertex) {
      std::vector<int32_t> x(n * static_cast<size_t>(own));
      for (size_t v = 0; v < V; ++v)
        if (rank[v] != kNone) to_ints(h, &a.values[h.components * static_cast<size_t>(order[v])], &x[n * rank[v]]);
      return walk.vertices(predictor, recent, siblings, x);
    }
    if (h.domain == AttributeDomain::face) {
      std::vector<int32_t> x(n * faces.face_count());
      for (size_t g = 0; g < faces.face_count(); ++g)
        to_ints(h, &a.values[h.components * static_cast<size_t>(face_of[g])], &x[n * g]);
      return walk.face_values(x);
    }
    const size_t count = a.value_count();
    std::vector<int32_t> ints(n * count);
    for (size_t j = 0; j < count; ++j) to_ints(h, &a.values[h.components * j], &ints[n * j]);
    std::vector<uint32_t> in_value(faces.indices.size());
    for (uint32_t g = 0; g < faces.face_count(); ++g) {
      const uint32_t k = faces.face_size(g), f = face_of[g];
      for (uint32_t c = 0; c < k; ++c)
        in_value[faces.face_offsets[g] + c] = a.indices[part.face_offsets[f] + (c + shift[g]) % k];
    }
    std::vector<int32_t> values;
    std::vector<uint32_t> index, alias, in_of;
    const std::vector<uint32_t>* imported = in.imported ? &(*in.imported)[i] : nullptr;
    if (!walk.corners(predictor, in.segmented, imported, in_value, ints, count, UINT64_MAX, values, index, alias,
                      in_of))
      return false;
    if (own_values) {  // the values this part adds to the file's list, in its order
      own_values->clear();
      for (size_t j = 0; j < in_of.size(); ++j)
        if (alias[j] == kNone) own_values->push_back(in_of[j]);
    }
    return true;
  };
  std::string body;
  ByteWriter w(body);
  w.varint(headers.size());
  for (const AttributeHeader& h : headers) write_header(w, h);
  // Per attribute: the predictor that codes it smallest (each tried alone),
  // at the fast levels whether tables pay (§8.12.1), its byte in the header,
  // then its values into the one stream (and its residuals into the bit
  // stream of the tables).
  Enc enc;
  BitWriter table_bits;
  std::vector<CodeLengths> table_lengths;  // every attribute's contexts once one has tables
  if (in.own_values) in.own_values->assign(headers.size(), {});
  struct Deferred {
    size_t i;
    bool recent, siblings, shared;
  };
  std::vector<Deferred> deferred;  // predictor 6: coded after the other attributes
  for (size_t i = 0; i < headers.size(); ++i) {
    const bool per_vertex = in.per_vertex >> i & 1;
    const AttributeHeader h = coded_header(headers[i], per_vertex);
    const unsigned choices = predictors_for(h);
    int predictor = 0;
    size_t best = SIZE_MAX;
    own_values = nullptr;
    bool recent = false;
    siblings = h.domain == AttributeDomain::vertex;
    shared = false;
    auto adaptive_size = [&](int p, size_t& size) {
      Enc trial;
      if (!code(trial, i, p, recent)) return false;
      size = trial.e.finish().size();
      return true;
    };
    for (int p = 0; p <= kTangentPredictor && choices != 1; ++p) {
      size_t size = 0;
      if (!(choices >> p & 1)) continue;
      if (p == kTangentPredictor && (sources.normal < 0 || sources.texcoord < 0)) continue;
      if (!adaptive_size(p, size)) return Status(ErrorCode::internal, "attributes: values out of range");
      if (size < best) {
        best = size;
        predictor = p;
      }
    }
    if (h.domain == AttributeDomain::vertex) {  // the recent values where they pay (predictor bit 5)
      size_t with = 0;
      if (best == SIZE_MAX && !adaptive_size(predictor, best))
        return Status(ErrorCode::internal, "attributes: values out of range");
      recent = true;
      if (!adaptive_size(predictor, with)) return Status(ErrorCode::internal, "attributes: values out of range");
      recent = with < best;
      best = std::min(best, with);
      siblings = false;  // the siblings' values where they pay (predictor bit 6)
      if (!adaptive_size(predictor, with)) return Status(ErrorCode::internal, "attributes: values out of range");
      siblings = with >= best;
      best = std::min(best, with);
    }
    if (int_components(h) > 1) {  // the components' shared models where they pay (predictor bit 7)
      size_t with = 0;
      if (best == SIZE_MAX && !adaptive_size(predictor, best))
        return Status(ErrorCode::internal, "attributes: values out of range");
      shared = true;
      if (!adaptive_size(predictor, with)) return Status(ErrorCode::internal, "attributes: values out of range");
      shared = with <= best;
      best = std::min(best, with);
    }
    TableResiduals residuals;
    bool tables = false;
    if (in.tables && predictor != kTangentPredictor) {  // a tangent's values come last, range coded
      Enc trial;
      trial.tables = &residuals;
      if (!code(trial, i, predictor, recent)) return Status(ErrorCode::internal, "attributes: values out of range");
      if (residuals.fits) {
        residuals.tables.build();
        if (best == SIZE_MAX && !adaptive_size(predictor, best))
          return Status(ErrorCode::internal, "attributes: values out of range");
        // At most 1/8 more than the models (the bunny's scalars 1.01-1.05,
        // spherical texture coordinates 1.05; its geometry-predicted
        // normals, small residuals the models learn well, 1.19 keep them).
        tables = trial.e.finish().size() + residuals.tables.coded_bytes() <= best + best / 8;
      }
    }
    w.u8(static_cast<uint8_t>(predictor | (tables ? kAttributeTableFlag : 0) |
                              (per_vertex ? kAttributePerVertexFlag : 0) | (recent ? kAttributeRecentFlag : 0) |
                              (siblings ? kAttributeSiblingFlag : 0) | (shared ? kAttributeSharedFlag : 0)));
    own_values = in.own_values ? &(*in.own_values)[i] : nullptr;
    if (predictor == kTangentPredictor) {  // coded after the others, with its choices
      deferred.push_back({i, recent, siblings, shared});
      continue;
    }
    if (tables) {
      residuals.bits = &table_bits;
      enc.tables = &residuals;
      table_lengths.resize(kAttributeTableContexts * headers.size());
      const std::vector<CodeLengths>& lengths = residuals.tables.lengths();
      std::copy(lengths.begin(), lengths.end(), table_lengths.begin() + kAttributeTableContexts * i);
    }
    if (!code(enc, i, predictor, recent)) return Status(ErrorCode::internal, "attributes: values out of range");
    enc.tables = nullptr;
  }
  for (const Deferred& d : deferred) {
    siblings = d.siblings;
    shared = d.shared;
    own_values = nullptr;
    if (!code(enc, d.i, kTangentPredictor, d.recent))
      return Status(ErrorCode::internal, "attributes: values out of range");
  }
  if (!table_lengths.empty())  // §8.12.1: the bit stream's length, the tables, the bit stream
    body += write_table_block(table_lengths, 3 * static_cast<int>(headers.size()), table_bits.finish());
  out = body + enc.e.finish();
  return Status::Ok();
}

Status decode_attributes(std::string_view bytes, const AttributePart& in, std::vector<Attribute>& out,
                         std::vector<std::vector<uint32_t>>* alias) {
  out.clear();
  if (alias) alias->clear();
  if (bytes.empty()) return Status::Ok();
  const Mesh& faces = *in.faces;
  const std::vector<uint32_t>& global = *in.global;
  ByteReader r(bytes);
  uint64_t count = 0;
  if (!r.varint(count) || count > kMaxAttributes) return corrupt("bad attribute count");
  std::vector<AttributeHeader> headers(static_cast<size_t>(count));
  for (AttributeHeader& h : headers) TSM_RETURN_IF_ERROR(read_header(r, h));
  std::vector<int> predictor(headers.size());
  std::vector<uint8_t> tabled(headers.size(), 0);
  uint64_t per_vertex = 0, recent = 0, siblings = 0, shared = 0;
  for (size_t i = 0; i < headers.size(); ++i) {
    uint8_t p = 0;
    if (!r.u8(p)) return corrupt("bad predictor");
    if (p & kAttributeTableFlag) {
      tabled[i] = 1;
      p = static_cast<uint8_t>(p & ~kAttributeTableFlag);
    }
    if (p & kAttributePerVertexFlag) {
      if (headers[i].domain != AttributeDomain::corner || in.segmented)
        return corrupt("'" + headers[i].name + "' is coded per vertex but is not a corner attribute of a whole mesh");
      per_vertex |= uint64_t{1} << i;
      p = static_cast<uint8_t>(p & ~kAttributePerVertexFlag);
      headers[i] = coded_header(headers[i], true);
    }
    if (p & kAttributeRecentFlag) {
      if (headers[i].domain != AttributeDomain::vertex)
        return corrupt("'" + headers[i].name + "' names recent values but is not coded per vertex");
      recent |= uint64_t{1} << i;
      p = static_cast<uint8_t>(p & ~kAttributeRecentFlag);
    }
    if (p & kAttributeSiblingFlag) {
      if (headers[i].domain != AttributeDomain::vertex)
        return corrupt("'" + headers[i].name + "' names its siblings' values but is not coded per vertex");
      siblings |= uint64_t{1} << i;
      p = static_cast<uint8_t>(p & ~kAttributeSiblingFlag);
    }
    if (p & kAttributeSharedFlag) {
      shared |= uint64_t{1} << i;
      p = static_cast<uint8_t>(p & ~kAttributeSharedFlag);
    }
    if (p > kTangentPredictor || !(predictors_for(headers[i]) >> p & 1)) return corrupt("bad predictor");
    predictor[i] = p;
  }
  // Predictor 6: its sources, and the attributes in the order their values
  // come (a tangent's after all the others').
  const TangentSources sources = tangent_sources(headers);
  std::vector<size_t> coding_order;
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < headers.size(); ++i)
      if ((predictor[i] == kTangentPredictor) == (pass == 1)) coding_order.push_back(i);
  if (std::find(predictor.begin(), predictor.end(), kTangentPredictor) != predictor.end() &&
      (sources.normal < 0 || sources.texcoord < 0))
    return corrupt("a tangent predicted without a normal and texture coordinates per vertex");
  std::vector<std::vector<int32_t>> source_ints(headers.size());  // the sources' integers, own-rank order
  std::vector<int32_t> tangent_pred;
  std::vector<uint8_t> tangent_has;
  if (in.per_vertex) *in.per_vertex = per_vertex;
  // §8.12.1: with a table-coded attribute, the bit stream's
  // length, the tables of every attribute's contexts, the bit stream.
  Dec dec;
  TableSet tables;
  uint32_t table_bytes = 0;  // the bit stream's
  if (std::find(tabled.begin(), tabled.end(), 1) != tabled.end()) {
    std::string why;
    if (!read_table_block(r, kAttributeTableContexts * static_cast<int>(count), 3 * static_cast<int>(count), tables,
                          dec.bits, why, &table_bytes))
      return corrupt(why);
    dec.tables = &tables;
  }
  if (in.table_coded) *in.table_coded = static_cast<uint32_t>(std::count(tabled.begin(), tabled.end(), 1));
  if (in.header_bytes) *in.header_bytes = bytes.size() - r.remaining() - table_bytes;
  if (in.costs) in.costs->assign(headers.size(), {});
  std::string_view coded;
  r.bytes(r.remaining(), coded);
  const size_t V = global.size();
  std::vector<uint32_t> rank(V, kNone);
  uint32_t own = 0;
  for (size_t v = 0; v < V; ++v)
    if (global[v] == kNone) rank[v] = own++;
  VertexFaces around;
  for (size_t i = 0; i < headers.size(); ++i)
    if ((predictor[i] == 2 || predictor[i] == 5) && around.start.empty()) around.build(faces, V);
  dec.d.init(coded);
  out.resize(headers.size());
  for (size_t i : coding_order) {
    const AttributeHeader& h = headers[i];
    dec.base = tabled[i] ? kAttributeTableContexts * static_cast<int>(i) : -1;
    const uint64_t bits_before = 8 * dec.d.bytes_read() + dec.bits.bits_read();
    const uint32_t n = int_components(h);
    std::vector<int32_t> gn;
    std::vector<uint8_t> gh;
    if (h.quant == AttributeQuant::octahedral)
      geometry_normals(faces, rank, *in.q, h.bits, normal_weights(predictor[i]), gn, gh);
    ValueCoder<Dec> vc{dec, {}};
    vc.shared = shared >> i & 1;
    AttributeWalk<Dec> walk{h,
                            vc,
                            dec,
                            faces,
                            rank,
                            h.quant == AttributeQuant::octahedral ? &gn : nullptr,
                            h.quant == AttributeQuant::octahedral ? &gh : nullptr,
                            in.q,
                            &around};
    if (predictor[i] == kTangentPredictor) {
      tangent_predictions(h, faces, rank, *in.q, headers[static_cast<size_t>(sources.normal)],
                          source_ints[static_cast<size_t>(sources.normal)],
                          source_ints[static_cast<size_t>(sources.texcoord)], tangent_pred, tangent_has);
      walk.tangent = &tangent_pred;
      walk.tangent_has = &tangent_has;
    }
    Attribute a;
    a.name = h.name;
    a.kind = h.kind;
    a.domain = per_vertex >> i & 1 ? AttributeDomain::corner : h.domain;
    a.type = h.type;
    a.components = h.components;
    std::vector<int32_t> x;
    if (h.domain == AttributeDomain::vertex) {
      x.assign(n * static_cast<size_t>(own), 0);
      if (!walk.vertices(predictor[i], recent >> i & 1, siblings >> i & 1, x))
        return corrupt("vertex values of '" + h.name + "' out of range");
      if (per_vertex >> i & 1) {  // each corner uses its vertex's value
        a.indices.resize(faces.indices.size());
        for (size_t k = 0; k < faces.indices.size(); ++k) a.indices[k] = rank[faces.indices[k]];
      }
    } else if (h.domain == AttributeDomain::face) {
      x.assign(n * faces.face_count(), 0);
      if (!walk.face_values(x)) return corrupt("face values of '" + h.name + "' out of range");
    } else {
      std::vector<uint32_t> none, aliases, in_of;
      std::vector<int32_t> no_ints;
      // Each unused value costs a decision in the range-coded stream or,
      // table-coded, at least a bit in the bit stream.
      const uint64_t budget = max_decisions(coded.size()) + 8 * uint64_t{table_bytes};
      if (!walk.corners(predictor[i], in.segmented, nullptr, none, no_ints, 0, budget, x, a.indices, aliases, in_of))
        return corrupt("corner values of '" + h.name + "' are invalid");
      if (alias) {
        alias->resize(headers.size());
        (*alias)[i] = std::move(aliases);
      }
    }
    if (dec.d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("stream is truncated");
    if (dec.bad_code) return corrupt("a residual of '" + h.name + "' is a code word no table has");
    if (dec.bits.overrun()) return corrupt("the table-coded bit stream is truncated");
    if (in.costs) {
      (*in.costs)[i] = {h, tabled[i] != 0, 8 * dec.d.bytes_read() + dec.bits.bits_read() - bits_before};
      (*in.costs)[i].header.domain = a.domain;
    }
    if (static_cast<int>(i) == sources.normal || static_cast<int>(i) == sources.texcoord) source_ints[i] = x;
    a.values.resize(static_cast<size_t>(h.components) * (x.size() / n));
    for (size_t j = 0; j < x.size() / n; ++j) from_ints(h, &x[n * j], &a.values[h.components * j]);
    out[i] = std::move(a);
  }
  return Status::Ok();
}

}  // namespace tsm
