// Geometry prediction and residual coding (seed 004 §3.2; design notes §6
// and §9). Positions are quantized on the Draco grid; each vertex is
// predicted from vertices decoded before it and the residual is range coded.
//
// Predictors (the first byte of the geometry section says which):
//  - parallelograms: vertices in march order (first appearance in the
//    triangle tree's decode order). The connectivity is decoded first, so a
//    new vertex p sees every triangle around it: each triangle (p, u, w) whose
//    neighbour across u-w has a decoded far corner o gives u + w - o; the
//    prediction is their average (Draco's multi-parallelogram, without
//    flags). With none, the average of p's decoded neighbours.
//  - gate: the same order, only the parallelogram across the gate (the edge
//    the march entered by); cheaper to decode.
//  - spread: as parallelograms, but a vertex with two or more parallelograms
//    takes its residual context per axis from their spread (the largest
//    minus the smallest of the single parallelogram predictions on that
//    axis) instead of the activity: where the parallelograms disagree the
//    vertex is usually near one of them, so far from their average (on
//    scanned grids, say; on marching-cubes surfaces the activity does
//    better, and the encoder keeps whichever is smaller).
//  - ancestors: the paper's predictor, vertex-tree order, P = sum lambda_i
//    v_{n-i} over the K nearest tree ancestors, lambda fitted per mesh by
//    least squares (Eigen) and stored as 16.16 fixed point.
//  - raw: no prediction; every coordinate as plain bits
//    (a plane index where its axis has lattice planes). On a mesh of a few
//    vertices fresh adaptive models cost more than they save.
// Residuals: per axis an adaptive signed-integer model chosen by the
// prediction class (how much was known) and an activity context (the bit
// length of the residuals of the neighbours, and of this vertex's earlier
// axes).
#include "geometry_predict.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <type_traits>
#if defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__))
#define TSM_FIT_SSE2 1
#include <emmintrin.h>
#if defined(__x86_64__) && defined(__GNUC__)
#define TSM_FIT_AVX2 1  // chosen at run time (fit_alpha)
#include <immintrin.h>
#endif
#endif

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "range_coder.hpp"
#include "rans_coder.hpp"
#include "table_coder.hpp"
#include "tsm/quantization.hpp"

namespace tsm {

namespace {

constexpr int kClasses = 5;    // 0 nothing known, 1 neighbour average, 2..4: 1, 2, 3+ parallelograms
constexpr int kActivity = 14;  // activity contexts
constexpr uint8_t kUnknown = 0xFF;
constexpr int kMaxAncestors = 4;
constexpr int kLambdaShift = 16;
constexpr int kAlphaShift = 12;
constexpr int32_t kAlphaOne = 1 << kAlphaShift;
// Meshes up to this many vertices also try the default weights and no prediction.
constexpr uint32_t kSmallMesh = 4096;
constexpr int32_t kMaxBeta = 2 * kAlphaOne;  // the tangent step's weights: 0 .. 2.0

constexpr int kMantissa = 6;  // modelled mantissa bits of a residual
using ResidualModel = SIntModelT<kMantissa>;
constexpr int kMixCtx = 8;    // weight sets of residual mixing per coding position and decision

// Predictors 1, 2, 3 and 5, which predict from the triangles around a vertex
// (parallelogram weights, the tangent step).
bool surface_predictor(Predictor p) {
  return p == Predictor::parallelograms || p == Predictor::gate || p == Predictor::spread || p == Predictor::fan;
}
// Predictors 1 and 3 visit the vertices in greedy order, 2 and 5 in march
// order; 3 and 5 take residual contexts from the parallelograms' spread.
bool greedy_order(Predictor p) { return p == Predictor::parallelograms || p == Predictor::spread; }
bool spread_contexts(Predictor p) { return p == Predictor::spread || p == Predictor::fan; }

// floor(x / 2^s): an arithmetic shift (GCC, Clang and MSVC shift signed
// values arithmetically; C++20 requires it). No branch on the sign, which
// the residuals' predictions have at random.
static_assert((int64_t{-5} >> 1) == -3, "signed right shift must be arithmetic (floor)");
inline int64_t floor_shift(int64_t x, int s) { return x >> s; }

// floor(x / d) for 0 <= x < 2^57 and 2 <= d <= kSmallDivisor by a multiply:
// with m = floor((2^64 - 1) / d) + 1, m d = 2^64 + e with 0 <= e <= d, so
// x m / 2^64 exceeds x / d by x e / (d 2^64) < 1 / d, which never crosses
// the next integer. The prediction's averages divide by 2..128 once per
// axis and vertex, where a 64-bit division costs tens of cycles.
constexpr int64_t kSmallDivisor = 128;
struct Reciprocals {
  uint64_t m[kSmallDivisor + 1] = {};
  constexpr Reciprocals() {
    for (int d = 2; d <= kSmallDivisor; ++d) m[d] = ~uint64_t{0} / static_cast<uint64_t>(d) + 1;
  }
};
inline constexpr Reciprocals kReciprocal{};

// wasm32 has __int128 but emulates its product with a call (__multi3),
// slower than its native 64-bit division: there the division is used.
#if defined(__SIZEOF_INT128__) && !defined(__wasm__)
#define TSM_RECIPROCAL_DIV 1
__extension__ typedef unsigned __int128 uint128;  // GCC and Clang (64-bit targets)
#endif
// div_round's quotient floor(num / den) for |num| < 2^40 and den <= 128,
// without a branch on the sign: num + 2^40 den is positive and below 2^48.
__attribute__((always_inline)) inline bool floor_div_small(int64_t num, int64_t den, int64_t& q) {
#ifdef TSM_RECIPROCAL_DIV
  constexpr int64_t kLimit = int64_t{1} << 40;
  if (den > kSmallDivisor || num >= kLimit || num <= -kLimit) return false;
  const uint64_t x = static_cast<uint64_t>(num + (den << 40));
  q = static_cast<int64_t>((static_cast<uint128>(x) * kReciprocal.m[den]) >> 64) - kLimit;
  return true;
#else
  (void)num, (void)den, (void)q;
  return false;
#endif
}

__attribute__((always_inline)) inline int64_t div_round(int64_t sum, int64_t n) {  // round half up, any sign; n >= 1
  const int64_t num = 2 * sum + n, den = 2 * n;
  int64_t q;
  if (floor_div_small(num, den, q)) return q;
  return num >= 0 ? num / den : -((-num + den - 1) / den);
}

// N residual models, each set up on the first use of its context: a set
// of many contexts (about 8.7 KB each) then costs nothing to create, so a
// small mesh, a segment or one of the encoder's trial codings pays only for
// the contexts it codes. Allocated on the heap by its owner (not zeroed).
template <int N>
class LazyModels {
 public:
  LazyModels() {}
  ResidualModel& operator[](int i) {
    const uint64_t bit = uint64_t{1} << (i & 63);
    if (!(ready_[i >> 6] & bit)) {
      new (&slot_[i].m) ResidualModel;  // default-initialized: the mantissa rows set themselves up lazily
      ready_[i >> 6] |= bit;
    }
    return slot_[i].m;
  }

 private:
  union Slot {
    Slot() {}  // not constructed until first used
    ResidualModel m;
  };
  uint64_t ready_[(N + 63) / 64] = {};
  Slot slot_[N];
};

// Residual contexts: (coding position i * kClasses + predictor class) *
// kActivity + activity context, as the tables number them.
constexpr int kTableContexts = 3 * kClasses * kActivity;

// Residual mixing (kMixFlag): the second model of each residual
// decision, by the second context (numbered as the surface models), and the
// mixing weights by coding position and first context (capped at
// kMixCtx - 1). Only allocated for a mixed stream.
struct MixModels {
  MixModels() {}  // user-provided: make_unique does not zero the models first
  LazyModels<kTableContexts> m2;
  MixWeights w[3][kMixCtx][kMixKinds<kMantissa>];
};

// The surface residuals' adaptive models, one per context. Not allocated
// when the residuals go through tables.
using SurfaceModels = LazyModels<kTableContexts>;

// Lattice coding: on-lattice flag by [axis][axes on the lattice so far],
// then the lattice index offset from the plane nearest the prediction, by
// (axis * 3 + axes on the lattice so far) * kActivity + activity context.
// Allocated on the first lattice decision.
struct LatticeModels {
  LatticeModels() {}  // as MixModels
  Prob on[3][3];
  LazyModels<3 * 3 * kActivity> index;
};

// The encoder's and decoder's view of the coded symbols; everything else in
// the traversals below is shared, so both sides make the same predictions.
// The value passed in is the encoder's; the decoder ignores it.
struct EncodeSink {
  static constexpr bool kEncoder = true;
  RangeEncoder e;
  int bit(Prob& p, int b) {
    e.bit(p, b);
    return b;
  }
  int32_t sint(ResidualModel& m, int64_t v) {
    m.encode(e, static_cast<int32_t>(v));
    return static_cast<int32_t>(v);
  }
  // A surface residual (context: Coder::vertex's, numbered for the tables).
  int32_t residual(SurfaceModels* m, int ctx, int64_t v) { return sint((*m)[ctx], v); }
  int32_t sint_mixed(ResidualModel& a, ResidualModel& b, MixWeights* w, int64_t v) {
    MixEncodeOp op{e};
    return code_mixed_sint(op, a, b, w, static_cast<int32_t>(v));
  }
  uint32_t uint(UIntModel& m, uint32_t v) {
    m.encode(e, v);
    return v;
  }
  bool truncated() const { return false; }
};

// The encoder's first pass: the same walk, nothing coded (statistics only).
struct CollectSink {
  static constexpr bool kEncoder = true;
  int bit(Prob&, int b) { return b; }
  int32_t sint(ResidualModel&, int64_t v) { return static_cast<int32_t>(v); }
  int32_t residual(SurfaceModels*, int, int64_t v) { return static_cast<int32_t>(v); }
  int32_t sint_mixed(ResidualModel&, ResidualModel&, MixWeights*, int64_t v) { return static_cast<int32_t>(v); }
  uint32_t uint(UIntModel&, uint32_t v) { return v; }
  bool truncated() const { return false; }
};

// Tables (kTableFlag): the surface residuals through static frequency
// tables per context and rANS (rans_coder.hpp), everything else through the
// range coder as before. One pass: the encoder counts and keeps the
// residuals, then builds the tables and codes them (rANS runs backwards).
struct TableEncodeSink : EncodeSink {
  RansEncoder& tables;
  BitWriter bits;
  explicit TableEncodeSink(RansEncoder& t) : tables(t) {}
  int32_t residual(SurfaceModels*, int ctx, int64_t v) {
    tables.count_and_put(bits, ctx, v);
    return static_cast<int32_t>(v);
  }
};

struct DecodeSink {
  static constexpr bool kEncoder = false;
  RangeDecoder d;
  int bit(Prob& p, int) { return d.bit(p); }
  int32_t sint(ResidualModel& m, int64_t) { return m.decode(d); }
  int32_t residual(SurfaceModels* m, int ctx, int64_t) { return (*m)[ctx].decode(d); }
  int32_t sint_mixed(ResidualModel& a, ResidualModel& b, MixWeights* w, int64_t) {
    MixDecodeOp op{d};
    return code_mixed_sint(op, a, b, w, 0);
  }
  uint32_t uint(UIntModel& m, uint32_t) { return m.decode(d); }
  bool truncated() const { return d.overrun() > RangeDecoder::kMaxOverrun; }
  // Why truncated() holds, for the error message.
  const char* truncation() const { return "stream is truncated"; }
};

struct TableDecodeSink : DecodeSink {
  RansDecoder tables;
  BitReader bits;
  bool bad_code = false;  // a context without a table
  __attribute__((always_inline)) int32_t residual(SurfaceModels*, int ctx, int64_t) {
    int32_t r = 0;
    if (!tables.decode(bits, ctx, r)) bad_code = true;  // also a context without a table
    return r;
  }
  bool truncated() const { return DecodeSink::truncated() || bits.overrun() || tables.overrun() || bad_code; }
  const char* truncation() const {
    return bad_code           ? "a residual's context has no table"
           : bits.overrun()   ? "residual bit stream is truncated"
           : tables.overrun() ? "rANS stream is truncated"
                              : DecodeSink::truncation();
  }
};

struct Coder {
  // surface_models: false when the surface residuals go through tables (or
  // there are none: the raw predictor).
  Coder(uint32_t vertex_count, int bits, bool surface_models)
      : act(vertex_count, kUnknown), qmax((int64_t{1} << bits) - 1) {
    if (surface_models) surface = std::make_unique<SurfaceModels>();
  }
  std::unique_ptr<SurfaceModels> surface;
  std::unique_ptr<LatticeModels> lattice_models;  // made on the first lattice decision
  LatticeModels& lat() {
    if (!lattice_models) lattice_models = std::make_unique<LatticeModels>();
    return *lattice_models;
  }
  // Vertices on no triangle: predicted from an anchor surface vertex.
  Prob has_anchor;
  UIntModel anchor_gap;
  std::vector<uint8_t> act;  // per output vertex: bit length of its residuals' sum, kUnknown until coded
  int64_t qmax;
  Lattice lattice;
  bool planes_from_top = false;  // each axis's last plane coded first, from the top (code_lattice)
  // Per parallelogram class (1, 2, 3+ parallelograms): the weight of the
  // parallelogram average against the neighbour average, 4.12 fixed point
  // (4096 = parallelograms only), fitted per mesh by least squares.
  int32_t alpha[3] = {kAlphaOne, kAlphaOne, kAlphaOne};
  // Residual mixing: each residual from two models, the second by
  // the largest residual of this vertex's axes coded so far (the first axis:
  // the neighbours' activity where the first context is the spread, else the
  // previous vertex's activity), mixed (range_coder.hpp).
  std::unique_ptr<MixModels> mix;  // null: no mixing
  int prev_act = 0;  // activity of the vertex coded last (0 before the first)
  bool spread_ctx = false;  // predictor spread: contexts from the parallelograms' spread
  // Tangent step (kTangentFlag): a vertex with a local normal codes
  // the two axes across the normal first, then the axis nearest it, predicted
  // through the tangent plane from the first two residuals with the weight
  // beta[set] (4.12; set 0: surface vertices, 1: vertices with an anchor).
  // Residual models are then chosen by coding position instead of axis.
  bool tangent = false;
  int32_t beta[2] = {kAlphaOne, kAlphaOne};
  std::vector<std::pair<int64_t, int64_t>> tan_samples[2];  // encoder's fit: (correction at weight 1, x - p)
  bool collect = false;
  std::vector<std::pair<int64_t, int64_t>> samples[3];  // encoder's fit: (P - N, x - N) per coordinate
  // Encoder: a coding pass without the tangent step also gathers the
  // tangent samples (tan_samples) that a collect pass with it would, for
  // fit_betas (tangent_sample below).
  bool tangent_samples = false;
  std::vector<uint32_t> nearest[3];  // per axis, per grid value: nearest plane (when qmax < 2^18)

  // Nearest plane to a grid value (the lower one on a tie).
  size_t nearest_plane(int a, uint32_t p) const {
    if (!nearest[a].empty()) return nearest[a][p];
    const std::vector<uint32_t>& L = lattice.values[a];
    size_t j = static_cast<size_t>(std::lower_bound(L.begin(), L.end(), p) - L.begin());
    if (j == L.size() || (j > 0 && p - L[j - 1] <= L[j] - p)) j = j == 0 ? 0 : j - 1;
    return j;
  }
  // The table takes qmax + 1 entries per axis: only where the vertices
  // look up more often than that (a mesh of a few vertices at 14 bits spent
  // most of its decode building it); the binary search gives the same plane.
  void build_nearest() {
    for (int a = 0; a < 3; ++a) {
      const std::vector<uint32_t>& L = lattice.values[a];
      nearest[a].clear();
      if (L.empty() || qmax >= (int64_t{1} << 18) || qmax + 1 > 16 * static_cast<int64_t>(act.size())) continue;
      nearest[a].resize(static_cast<size_t>(qmax) + 1);
      size_t j = 0;
      for (uint32_t p = 0; p <= qmax; ++p) {
        while (j + 1 < L.size() && L[j + 1] <= p) ++j;  // L[j] <= p < L[j+1], or p below L[0]
        size_t k = j;
        if (j + 1 < L.size() && L[j] <= p && L[j + 1] - p < p - L[j]) k = j + 1;
        nearest[a][p] = static_cast<uint32_t>(k);
      }
    }
  }

  // spread: per axis the spread of the parallelogram predictions (>= 0),
  // the context instead of the activity; null to use the activity.
  // normal: for the tangent step (scaled below 2^16 by tangent_normal), or
  // null; tan_set: which beta.
  // kPlain: the caller knows there is no lattice, no tangent step (normal
  // null), no spread context and no mixing (plain() below), so those
  // branches are compiled out (the fast levels' gate predictor).
  // kLattice false: the caller knows no axis has lattice planes.
  bool plain() const {
    return !tangent && !mix && !spread_ctx && lattice.empty();
  }
  // Encoder, after vertex v is coded without the tangent step: the sample
  // vertex() collects with the tangent step on the axis nearest `normal`
  // (null: none), from the same prediction and coordinates (the sample
  // reads neither the residual contexts, the lattice nor the weight beta).
  void tangent_sample(const std::vector<uint32_t>& q, uint32_t v, const int64_t pred[3], const int64_t* normal,
                      int tan_set) {
    if (!normal) return;
    int kn = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(normal[a]) > std::abs(normal[kn])) kn = a;
    if (normal[kn] == 0) return;
    const int o0 = kn == 0 ? 1 : 0, o1 = kn == 2 ? 1 : 2;
    int64_t res[3];
    for (int a = 0; a < 3; ++a)
      res[a] = int64_t{q[3 * static_cast<size_t>(v) + a]} - std::clamp<int64_t>(pred[a], 0, qmax);
    const int64_t sgn = normal[kn] < 0 ? -1 : 1;
    const int64_t num = -sgn * (normal[o0] * res[o0] + normal[o1] * res[o1]);
    tan_samples[tan_set].push_back({div_round(num, sgn * normal[kn]), res[kn]});
  }
  template <bool kPlain = false, bool kLattice = true, class Sink>
  bool vertex(Sink& s, std::vector<uint32_t>& q, uint32_t v, const int64_t pred[3], int cls, int activity,
              const int64_t* spread = nullptr, const int64_t* normal = nullptr, int tan_set = 0) {
    uint64_t sum = 0, top = 0;
    int on_count = 0;
    int order[3] = {0, 1, 2};
    int kn = -1;  // the axis nearest the normal, coded last
    if (!kPlain && normal) {
      kn = 0;
      for (int a = 1; a < 3; ++a)
        if (std::abs(normal[a]) > std::abs(normal[kn])) kn = a;
      if (normal[kn] == 0) kn = -1;
      else order[0] = kn == 0 ? 1 : 0, order[1] = kn == 2 ? 1 : 2, order[2] = kn;
    }
    int64_t res[3] = {0, 0, 0};  // x minus the clamped prediction, per axis coded so far
    for (int i = 0; i < 3; ++i) {
      const int a = order[i];
      int ctx = !kPlain && spread ? bit_length(static_cast<uint64_t>(spread[a]))
                                  : i == 0 ? activity : (activity + bit_length(top) + 1) / 2;
      ctx = std::min(ctx, kActivity - 1);
      const int64_t p0 = std::clamp<int64_t>(pred[a], 0, qmax);  // clamped, before the tangent step
      int64_t p = p0;
      if (!kPlain && a == kn) {
        // Through the tangent plane: n . (x - p) = 0 solved for this axis.
        const int64_t sgn = normal[kn] < 0 ? -1 : 1;
        const int64_t num = -sgn * (normal[order[0]] * res[order[0]] + normal[order[1]] * res[order[1]]);
        const int64_t den = sgn * normal[kn];
        if constexpr (Sink::kEncoder)
          if (collect)
            tan_samples[tan_set].push_back({div_round(num, den), int64_t{q[3 * static_cast<size_t>(v) + a]} - p0});
        p = std::clamp<int64_t>(pred[a] + div_round(beta[tan_set] * num, int64_t{kAlphaOne} * den), 0, qmax);
      }
      uint32_t& x = q[3 * static_cast<size_t>(v) + a];
      const std::vector<uint32_t>& L = lattice.values[a];
      bool coded = false;
      if (!kPlain && kLattice && !L.empty()) {
        const size_t j = nearest_plane(a, static_cast<uint32_t>(p));
        size_t jx = 0;
        int on = 0;
        if constexpr (Sink::kEncoder) {
          // A value on a plane is nearest that plane (the table, when built,
          // saves the search).
          jx = nearest_plane(a, x);
          on = L[jx] == x;
        }
        LatticeModels& lm = lat();
        on = s.bit(lm.on[a][on_count], on);
        if (on) {
          int64_t d = s.sint(lm.index[(a * 3 + on_count) * kActivity + ctx],
                             static_cast<int64_t>(jx) - static_cast<int64_t>(j));
          int64_t k = static_cast<int64_t>(j) + d;
          if (k < 0 || k >= static_cast<int64_t>(L.size())) return false;
          x = L[static_cast<size_t>(k)];
          ++on_count;
          coded = true;
        }
      }
      if (!coded) {
        int64_t r;
        const int rctx = (i * kClasses + cls) * kActivity + ctx;  // SurfaceModels' and the tables' numbering
        if (!kPlain && mix) {
          const int ctx2 = std::min(i ? bit_length(top) : spread ? activity : prev_act, kActivity - 1);
          r = s.sint_mixed((*surface)[rctx], mix->m2[(i * kClasses + cls) * kActivity + ctx2],
                           mix->w[i][std::min(ctx, kMixCtx - 1)], static_cast<int64_t>(x) - p);
        } else {
          r = s.residual(surface.get(), rctx, static_cast<int64_t>(x) - p);
        }
        if (p + r < 0 || p + r > qmax) return false;
        x = static_cast<uint32_t>(p + r);
      }
      const int64_t r = static_cast<int64_t>(x) - p;
      res[a] = static_cast<int64_t>(x) - p0;
      uint64_t ar = static_cast<uint64_t>(r < 0 ? -r : r);
      sum += ar;
      top = std::max(top, ar);
    }
    const uint8_t activity_v = static_cast<uint8_t>(std::min(bit_length(sum), 254));
    act[v] = activity_v;
    prev_act = activity_v;
    return true;
  }
};

// The tangent step's normal at a centre c (a prediction, or an anchor):
// the sum over triangles (c, u, w) of cross(u - c, w - c), then scaled so
// that its largest coordinate is below 2^16. Unusable (no tangent step) if
// there are no triangles, more than 4096, or a coordinate difference of
// 2^20 or more (which keeps every product and sum in 64 bits).
struct NormalSum {
  static constexpr int kMaxTriangles = 4096;
  static constexpr int64_t kMaxDiff = int64_t{1} << 20;
  int64_t n[3] = {0, 0, 0};
  int count = 0;
  bool ok = true;
  void add(const uint32_t* u, const uint32_t* w, const int64_t c[3]) {
    if (!ok || ++count > kMaxTriangles) {
      ok = false;
      return;
    }
    int64_t d1[3], d2[3];
    for (int a = 0; a < 3; ++a) {
      d1[a] = int64_t{u[a]} - c[a];
      d2[a] = int64_t{w[a]} - c[a];
      if (std::abs(d1[a]) >= kMaxDiff || std::abs(d2[a]) >= kMaxDiff) ok = false;
    }
    if (!ok) return;
    cross(d1, d2);
  }
  // add() when every coordinate difference from c is known to be below
  // kMaxDiff (near() for corners on the grid of qmax).
  void add_near(const uint32_t* u, const uint32_t* w, const int64_t c[3]) {
    if (!ok || ++count > kMaxTriangles) {
      ok = false;
      return;
    }
    const int64_t d1[3] = {u[0] - c[0], u[1] - c[1], u[2] - c[2]};
    const int64_t d2[3] = {w[0] - c[0], w[1] - c[1], w[2] - c[2]};
    cross(d1, d2);
  }
  // Whether every point of the grid 0..qmax per axis lies within kMaxDiff
  // of c on each axis (then add_near() equals add() for decoded corners).
  static bool near(int64_t qmax, const int64_t c[3]) {
    for (int a = 0; a < 3; ++a)
      if (c[a] <= qmax - kMaxDiff || c[a] >= kMaxDiff) return false;
    return true;
  }
  void cross(const int64_t d1[3], const int64_t d2[3]) {
    n[0] += d1[1] * d2[2] - d1[2] * d2[1];
    n[1] += d1[2] * d2[0] - d1[0] * d2[2];
    n[2] += d1[0] * d2[1] - d1[1] * d2[0];
  }
  const int64_t* finish() {
    if (!ok || count == 0) return nullptr;
    const int64_t m = std::max({std::abs(n[0]), std::abs(n[1]), std::abs(n[2])});
    const int sh = std::max(0, bit_length(static_cast<uint64_t>(m)) - 16);
    for (int64_t& x : n) x = x < 0 ? -((-x) >> sh) : x >> sh;
    return n;
  }
};

// The blend of FORMAT.md §8.5.4 from the sums a walk around a vertex found:
// the parallelograms' average against the neighbours' with the class's
// weight, else the neighbours' average, else the last vertex. Returns the
// class; with parallelograms, d and n get P - N and N per axis (the
// encoder's weight fit).
__attribute__((always_inline)) inline int blend_prediction(const int32_t alpha[3], const int64_t para[3], int npara,
                                                           const int64_t nb[3], int nnb, const int64_t last[3],
                                                           int64_t pred[3], int64_t d[3], int64_t n[3]) {
  if (npara) {
    const int cls = 1 + std::min(npara, 3);
    // One parallelogram and one neighbour (the gate predictor's usual
    // case): the averages are the sums themselves (div_round(x, 1) == x).
    const bool single = npara == 1 && nnb == 1;
    for (int a = 0; a < 3; ++a) {
      const int64_t P = single ? para[a] : div_round(para[a], npara), N = single ? nb[a] : div_round(nb[a], nnb);
      d[a] = P - N;
      n[a] = N;
      pred[a] = N + floor_shift(alpha[cls - 2] * (P - N) + (int64_t{1} << (kAlphaShift - 1)), kAlphaShift);
    }
    return cls;
  }
  for (int a = 0; a < 3; ++a) pred[a] = nnb ? div_round(nb[a], nnb) : last[a];
  return nnb ? 1 : 0;
}

// What the walk around a vertex found (SurfaceCoder::code with multi):
// the encoder's passes in one greedy order see the same decoded vertices
// around each vertex at the same positions, so the first pass keeps its
// walks and the others read them instead of walking again.
struct FanWalk {
  int64_t para[3], nb[3], spread[3];
  int npara, nnb, npair;
  uint32_t ids;  // FanWalks::ids[ids ..]: the nnb neighbours, then min(npair, 16) (u, w) pairs
};
struct FanWalks {
  std::vector<FanWalk> fans;  // per vertex in coding order
  std::vector<uint32_t> ids;
  bool ready = false;
};

// Prediction from the triangles around a vertex (march, greedy and gate
// orders share it).
template <class Sink>
struct SurfaceCoder {
  const GeometryLayout& g;
  Coder& c;
  Sink& s;
  std::vector<uint32_t>& q;
  int64_t last[3];
  int last_act = 0;
  const std::vector<uint32_t>& cv;  // per half-edge: the output vertex at its origin (kNone: virtual)
  FanWalks* walks = nullptr;        // the encoder's walks in greedy order: kept on its first pass, then read
  size_t walk_step = 0;

  SurfaceCoder(const GeometryLayout& layout, Coder& coder, Sink& sink, std::vector<uint32_t>& qs)
      : g(layout), c(coder), s(sink), q(qs), cv(layout.corners()) {
    for (int a = 0; a < 3; ++a) last[a] = (c.qmax + 1) / 2;
  }
  uint32_t known(uint32_t h) const {  // output vertex at the origin of half-edge h if decoded, else kNone
    uint32_t v = cv[h];
    return v != kNone && c.act[v] != kUnknown ? v : kNone;
  }
  const uint32_t* at(uint32_t v) const { return &q[3 * static_cast<size_t>(v)]; }
  // Calls f(h) for each half-edge h of the fan of h0 (leaving the same
  // position), h0 first.
  template <class F>
  void fan(uint32_t h0, F&& f) const {
    uint32_t h = h0;
    size_t guard = 0;
    do {
      f(h);
      h = he_next(g.twin[h]);
    } while (h != h0 && ++guard < cv.size());
  }
  // Per output vertex, its smallest half-edge (kNone for one on no
  // triangle); built on first use.
  const std::vector<uint32_t>& first_half_edges() {
    if (first_he.empty()) {
      first_he.assign(g.vertex_count, kNone);
      for (uint32_t h = static_cast<uint32_t>(cv.size()); h-- > 0;)
        if (cv[h] != kNone) first_he[cv[h]] = h;
    }
    return first_he;
  }
  std::vector<uint32_t> first_he;
  // The tangent step's normal: adds half-edge h's triangle (centre, u, w)
  // if its two other corners u, w are decoded.
  void add_normal_triangle(NormalSum& ns, uint32_t h, const int64_t centre[3]) const {
    const uint32_t u = known(he_next(h)), w = known(he_prev(h));
    if (u != kNone && w != kNone) ns.add(at(u), at(w), centre);
  }

  // Codes the vertex at the origin of half-edge h0 (undecoded, not virtual);
  // multi: every triangle around it, else only h0's triangle.
  template <bool kPlain = false>
  bool code(uint32_t h0, bool multi) {
    const uint32_t v = cv[h0];
    int64_t para[3] = {0, 0, 0}, nb[3] = {0, 0, 0}, pred[3];
    int64_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // per axis, the smallest and largest parallelogram
    int npara = 0, nnb = 0, actsum = 0;
    constexpr int kPairs = 16;  // triangles with u and w decoded, kept for the tangent step's normal
    uint32_t pu[kPairs], pw[kPairs];
    int npair = 0;
    FanWalks* const kept = multi ? walks : nullptr;
    auto neighbour = [&](uint32_t u) {
      for (int a = 0; a < 3; ++a) nb[a] += at(u)[a];
      ++nnb;
      actsum += c.act[u];
      if (kept) kept->ids.push_back(u);  // (only while the first pass walks)
    };
    auto visit = [&](uint32_t h) {
      uint32_t u = known(he_next(h));
      if (u == kNone) return;
      neighbour(u);
      uint32_t w = known(he_prev(h));
      if (w == kNone) return;
      if (npair < kPairs) pu[npair] = u, pw[npair] = w;
      ++npair;
      uint32_t o = known(he_prev(g.twin[he_next(h)]));
      if (o == kNone) return;
      for (int a = 0; a < 3; ++a) {
        const int64_t x = int64_t{at(u)[a]} + at(w)[a] - at(o)[a];
        para[a] += x;
        lo[a] = npara ? std::min(lo[a], x) : x;
        hi[a] = npara ? std::max(hi[a], x) : x;
      }
      ++npara;
    };
    auto walk = [&](auto&& f) {
      if (multi)
        fan(h0, f);
      else
        f(h0);
    };
    int64_t spread[3];
    if (kept && kept->ready) {  // this vertex's walk on the first pass
      const FanWalk& f = kept->fans[walk_step++];
      std::copy(f.para, f.para + 3, para);
      std::copy(f.nb, f.nb + 3, nb);
      std::copy(f.spread, f.spread + 3, spread);
      npara = f.npara, nnb = f.nnb, npair = f.npair;
      if (nnb > 0 || npair > 0) {  // (a walk that found nothing kept no ids: f.ids may be the end)
        const uint32_t* id = kept->ids.data() + f.ids;
        for (int i = 0; i < nnb; ++i) actsum += c.act[id[i]];
        id += nnb;
        for (int i = 0; i < std::min(npair, kPairs); ++i) pu[i] = id[2 * i], pw[i] = id[2 * i + 1];
      }
    } else {
      const size_t first_id = kept ? kept->ids.size() : 0;
      walk(visit);
      if (!multi) {
        uint32_t w = known(he_prev(h0));  // the root triangle's third corner sees two
        if (w != kNone && npara == 0) neighbour(w);
      }
      for (int a = 0; a < 3; ++a) spread[a] = hi[a] - lo[a];
      if (kept) {
        for (int i = 0; i < std::min(npair, kPairs); ++i) kept->ids.push_back(pu[i]), kept->ids.push_back(pw[i]);
        FanWalk f;
        std::copy(para, para + 3, f.para);
        std::copy(nb, nb + 3, f.nb);
        std::copy(spread, spread + 3, f.spread);
        f.npara = npara, f.nnb = nnb, f.npair = npair;
        f.ids = static_cast<uint32_t>(first_id);
        kept->fans.push_back(f);
      }
    }
    int64_t d[3], n[3];
    const int cls = blend_prediction(c.alpha, para, npara, nb, nnb, last, pred, d, n);
    if constexpr (Sink::kEncoder)
      if (c.collect && npara)
        for (int a = 0; a < 3; ++a) c.samples[cls - 2].push_back({d[a], static_cast<int64_t>(at(v)[a]) - n[a]});
    const int64_t* normal = nullptr;
    NormalSum ns;
    auto find_normal = [&] {
      if (npair <= kPairs) {
        for (int i = 0; i < npair; ++i) ns.add(at(pu[i]), at(pw[i]), pred);
      } else {  // a wide fan: walk it again
        walk([&](uint32_t h) { add_normal_triangle(ns, h, pred); });
      }
      return ns.finish();
    };
    if (!kPlain && c.tangent && npara > 0) normal = find_normal();
    if constexpr (Sink::kEncoder)
      if (c.tangent_samples && !c.tangent && npara > 0) {  // (the tangent step off: normal is null)
        const int64_t* sample_normal = find_normal();  // (before v is decoded, as on a pass with the step)
        if (!point<kPlain>(v, pred, cls, nnb ? (actsum + nnb / 2) / nnb : last_act,
                           !kPlain && c.spread_ctx && npara >= 2 ? spread : nullptr))
          return false;
        c.tangent_sample(q, v, pred, sample_normal, 0);
        return true;
      }
    return point<kPlain>(v, pred, cls, nnb ? (actsum + nnb / 2) / nnb : last_act,
                         !kPlain && c.spread_ctx && npara >= 2 ? spread : nullptr, normal);
  }
  template <bool kPlain = false>
  bool point(uint32_t v, const int64_t pred[3], int cls, int activity, const int64_t* spread = nullptr,
             const int64_t* normal = nullptr, int tan_set = 0) {
    if (!c.template vertex<kPlain>(s, q, v, pred, cls, activity, spread, normal, tan_set)) return false;
    for (int a = 0; a < 3; ++a) last[a] = at(v)[a];
    last_act = c.act[v];
    return true;
  }
  // Vertices on no triangle (isolated points), in output order: from their
  // anchor (a surface vertex near them; anchors ascend, coded as gaps), or
  // without one from the previous point.
  bool isolated() {
    uint32_t prev_anchor = 0;
    for (uint32_t v = 0; v < g.vertex_count; ++v) {
      if (c.act[v] != kUnknown) continue;
      uint32_t anchor = kNone;
      if constexpr (Sink::kEncoder) {
        uint32_t x = g.anchor.empty() ? kNone : g.anchor[v];
        if (x != kNone && x >= prev_anchor && c.act[x] != kUnknown) anchor = x;
      }
      int64_t pred[3];
      if (s.bit(c.has_anchor, anchor != kNone)) {
        uint32_t gap = s.uint(c.anchor_gap, anchor - prev_anchor);
        anchor = prev_anchor + gap;
        if (gap == 0xFFFFFFFFu || anchor < prev_anchor || anchor >= g.vertex_count || c.act[anchor] == kUnknown)
          return false;
        prev_anchor = anchor;
        for (int a = 0; a < 3; ++a) pred[a] = at(anchor)[a];
      } else {
        for (int a = 0; a < 3; ++a) pred[a] = last[a];
      }
      // The tangent step about the anchor's first fan (every corner but
      // virtual ones is decoded by now).
      NormalSum ns;
      bool sample = false;
      if constexpr (Sink::kEncoder) sample = c.tangent_samples && !c.tangent;
      if ((c.tangent || sample) && anchor != kNone) {
        const uint32_t h0 = first_half_edges()[anchor];  // kNone: an anchor on no triangle (only in a forged file)
        if (h0 != kNone)
          fan(h0, [&](uint32_t h) { add_normal_triangle(ns, h, pred); });
      }
      const int64_t* normal = ns.finish();
      if (!point(v, pred, 0, last_act, nullptr, sample ? nullptr : normal, 1)) return false;
      if (sample) c.tangent_sample(q, v, pred, normal, 1);
      if ((v & 4095) == 0 && s.truncated()) return false;
    }
    return true;
  }
};

// The fast levels' decoder: the gate predictor in march order without a
// tangent step or mixing, residuals from tables (FORMAT.md §8.5.12). It is
// SurfaceCoder::code with multi false followed by Coder::vertex, written
// out for that one case: the gate's three corners looked up once, the
// averages of one or two values as sums and shifts, the table lookup
// inline. kLattice: some axis has lattice planes (a scan's or a
// marching-cubes surface's), whose on-plane flags and plane offsets go
// through the range coder as in Coder::vertex. Same arithmetic as the
// general walk, which the encoder runs (every level-0 round trip in the
// tests compares the two). first: the half-edges to code, in order.
template <bool kLattice>
bool decode_gate_tables(const GeometryLayout& g, Coder& c, TableDecodeSink& s, std::vector<uint32_t>& q,
                        const uint32_t* first, uint32_t nfirst, int64_t last[3], int& last_act) {
  const uint32_t* cv = g.corners().data();
  const uint32_t* twin = g.twin.data();
  uint8_t* act = c.act.data();
  uint32_t* Q = q.data();
  const int64_t qmax = c.qmax, alpha = c.alpha[0];
  LatticeModels* lm = kLattice ? &c.lat() : nullptr;
  auto known = [&](uint32_t h) {
    const uint32_t v = cv[h];
    return v != kNone && act[v] != kUnknown ? v : kNone;
  };
  for (uint32_t i = 0; i < nfirst; ++i) {
    const uint32_t h0 = first[i], v = cv[h0], hn = he_next(h0);
    const uint32_t u = known(hn), w = known(he_prev(h0));
    int64_t pred[3];
    int cls = 1, activity;
    if (u != kNone) {
      const uint32_t* U = Q + 3 * size_t{u};
      const uint32_t o = w != kNone ? known(he_prev(twin[hn])) : kNone;
      if (o != kNone) {  // the parallelogram u + w - o against the neighbour u
        const uint32_t *W = Q + 3 * size_t{w}, *O = Q + 3 * size_t{o};
        for (int a = 0; a < 3; ++a)
          pred[a] = U[a] + floor_shift(alpha * (int64_t{W[a]} - O[a]) + (int64_t{1} << (kAlphaShift - 1)), kAlphaShift);
        cls = 2;
        activity = act[u];
      } else if (w != kNone) {  // the average of u and w, rounded half up
        const uint32_t* W = Q + 3 * size_t{w};
        for (int a = 0; a < 3; ++a) pred[a] = (int64_t{U[a]} + W[a] + 1) >> 1;
        activity = (act[u] + act[w] + 1) >> 1;
      } else {
        for (int a = 0; a < 3; ++a) pred[a] = U[a];
        activity = act[u];
      }
    } else if (w != kNone) {
      const uint32_t* W = Q + 3 * size_t{w};
      for (int a = 0; a < 3; ++a) pred[a] = W[a];
      activity = act[w];
    } else {
      for (int a = 0; a < 3; ++a) pred[a] = last[a];
      cls = 0;
      activity = last_act;
    }
    uint64_t sum = 0, top = 0;
    int on_count = 0;
    uint32_t* X = Q + 3 * size_t{v};
    for (int a = 0; a < 3; ++a) {
      const int ctx = std::min(a == 0 ? activity : (activity + bit_length(top) + 1) / 2, kActivity - 1);
      const int64_t p = std::clamp<int64_t>(pred[a], 0, qmax);
      int64_t r;
      const std::vector<uint32_t>* L = kLattice ? &c.lattice.values[a] : nullptr;
      if (kLattice && !L->empty() && s.d.bit(lm->on[a][on_count])) {  // on a plane: its offset from the nearest
        const int64_t k = static_cast<int64_t>(c.nearest_plane(a, static_cast<uint32_t>(p))) +
                          lm->index[(a * 3 + on_count) * kActivity + ctx].decode(s.d);
        if (k < 0 || k >= static_cast<int64_t>(L->size())) return false;
        X[a] = (*L)[static_cast<size_t>(k)];
        ++on_count;
        r = int64_t{X[a]} - p;
      } else {
        int32_t t;
        if (!s.tables.decode(s.bits, (a * kClasses + cls) * kActivity + ctx, t)) {
          s.bad_code = true;
          return false;
        }
        r = t;
        if (p + r < 0 || p + r > qmax) return false;
        X[a] = static_cast<uint32_t>(p + r);
      }
      const uint64_t ar = static_cast<uint64_t>(r < 0 ? -r : r);
      sum += ar;
      top = std::max(top, ar);
    }
    act[v] = static_cast<uint8_t>(std::min(bit_length(sum), 254));
    for (int a = 0; a < 3; ++a) last[a] = X[a];
    last_act = act[v];
    if ((i & 4095) == 0 && s.truncated()) return false;
  }
  c.prev_act = last_act;
  return true;
}

// The greedy order's state (greedy_vertices below): per vertex kDone once
// ordered, else its priority 4 min(parallelograms, 3) + min(neighbours, 3);
// bucket b (1..15) lists the vertices in the order they reached priority b,
// the next vertex is the first of the highest bucket still at that
// priority. A vertex whose priority rises is appended to its new bucket and
// left in the old one, where it is skipped (priorities only rise, so a
// vertex enters a bucket at most once): no unlinking. A drained bucket is
// emptied, so its storage stays the size of the front.
struct GreedyQueue {
  static constexpr uint8_t kDone = 0xFF;
  explicit GreedyQueue(uint32_t n) : prio(n, 0) {}
  std::vector<uint8_t> prio;
  std::vector<uint32_t> bucket[16];
  size_t taken[16] = {};   // per bucket: entries already taken or skipped
  uint32_t nonempty = 0;  // bit b: bucket b may hold a vertex still at priority b

  bool done(uint32_t x) const { return x != kNone && prio[x] == kDone; }
  // Adds a parallelogram (dp = 1) and/or a neighbour (dn = 1) to the
  // vertex x (not ordered yet).
  void raise(uint32_t x, int dp, int dn) {
    const int p = prio[x];
    const int np = std::min((p >> 2) + dp, 3) * 4 + std::min((p & 3) + dn, 3);
    if (np == p) return;
    prio[x] = static_cast<uint8_t>(np);
    bucket[np].push_back(x);
    nonempty |= 1u << np;
  }
  // The next vertex (marked done), or kNone when every bucket is empty.
  uint32_t pop() {
    while (nonempty) {
      const int b = 31 - __builtin_clz(nonempty);
      std::vector<uint32_t>& list = bucket[b];
      while (taken[b] < list.size()) {
        const uint32_t v = list[taken[b]++];
        if (prio[v] == b) {
          prio[v] = kDone;
          return v;
        }
      }
      list.clear();
      taken[b] = 0;
      nonempty &= ~(1u << b);
    }
    return kNone;
  }
  // After vertex v (done) at the origin of half-edge h: the counts that
  // its triangle (v, u, w) completes (u at hn = he_next(h), w at hp).
  __attribute__((always_inline)) void count(const uint32_t* cv, const uint32_t* twin, uint32_t h, uint32_t hn,
                                            uint32_t hp) {
    const uint32_t xu = cv[hn], xw = cv[hp];
    const bool u = done(xu), w = done(xw);
    count(cv, twin, h, hp, xu, xw, u, w, u && w ? cv[he_prev(twin[hn])] : kNone);
  }
  // The same with u = cv[hn] and w = cv[hp] given, whether each is done,
  // and (when both are) x, the corner across u-w.
  __attribute__((always_inline)) void count(const uint32_t* cv, const uint32_t* twin, uint32_t h, uint32_t hp,
                                            uint32_t xu, uint32_t xw, bool u, bool w, uint32_t x) {
    // v as a neighbour of u, and the parallelogram of u across w-v.
    if (!u && xu != kNone) raise(xu, w && done(cv[he_prev(twin[hp])]), 1);
    // The parallelogram of w across v-u.
    if (!w && xw != kNone && u && done(cv[he_prev(twin[h])])) raise(xw, 1, 0);
    // v as the far corner of the vertex across u-w.
    if (u && w && x != kNone && prio[x] != kDone) raise(x, 1, 0);
  }
};

// The decoder of the predictors that walk every triangle around the vertex
// (fan in march order: levels 1-2; parallelograms and spread in greedy
// order: levels 3-6) without mixing, residuals from tables: SurfaceCoder::
// code with multi true, the fan walk written out as one loop (the general
// walk calls a lambda per half-edge), then the general Coder::vertex. Same
// arithmetic as the general walk, which the encoder runs (the round trips
// in the tests at levels 1-6 compare the two).
struct FanTableDecoder {
  const uint32_t* cv;
  const uint32_t* twin;
  const uint8_t* act;
  size_t H;
  Coder& c;
  TableDecodeSink& s;
  std::vector<uint32_t>& q;
  int64_t* last;
  int& last_act;
  bool lattice;  // some axis has lattice planes

  FanTableDecoder(const GeometryLayout& g, Coder& coder, TableDecodeSink& sink, std::vector<uint32_t>& qs,
                  int64_t* last_, int& last_act_)
      : cv(g.corners().data()),
        twin(g.twin.data()),
        act(coder.act.data()),
        H(g.corners().size()),
        c(coder),
        s(sink),
        q(qs),
        last(last_),
        last_act(last_act_),
        lattice(!c.lattice.empty()) {}
  uint32_t known(uint32_t h) const {
    const uint32_t v = cv[h];
    return v != kNone && act[v] != kUnknown ? v : kNone;
  }
  const uint32_t* at(uint32_t v) const { return &q[3 * size_t{v}]; }

  // Decodes the vertex at the origin of half-edge h0; greedy: the order's
  // counts around it are updated in the same walk (null in march order).
  __attribute__((always_inline)) bool vertex(uint32_t h0, GreedyQueue* greedy) {
    constexpr int kPairs = 16;
    const uint32_t v = cv[h0];
    constexpr int64_t kMax = std::numeric_limits<int64_t>::max(), kMin = std::numeric_limits<int64_t>::min();
    int64_t para[3] = {0, 0, 0}, nb[3] = {0, 0, 0}, lo[3] = {kMax, kMax, kMax}, hi[3] = {kMin, kMin, kMin}, pred[3];
    int npara = 0, nnb = 0, actsum = 0, npair = 0;
    uint32_t pu[kPairs], pw[kPairs];
    uint32_t h = h0;
    size_t guard = 0;
    do {
      const uint32_t hn = he_next(h), hp = he_prev(h), xu = cv[hn], xw = cv[hp];
      auto decoded = [&](uint32_t x) { return x != kNone && act[x] != kUnknown; };
      const uint32_t u = decoded(xu) ? xu : kNone;
      uint32_t xo = kNone;  // the corner across u-w, once looked up
      bool have_xo = false;
      if (u != kNone) {
        const uint32_t* U = at(u);
        for (int a = 0; a < 3; ++a) nb[a] += U[a];
        ++nnb;
        actsum += act[u];
        const uint32_t w = decoded(xw) ? xw : kNone;
        if (w != kNone) {
          if (npair < kPairs) pu[npair] = u, pw[npair] = w;
          ++npair;
          xo = cv[he_prev(twin[hn])];
          have_xo = true;
          if (decoded(xo)) {
            const uint32_t *W = at(w), *O = at(xo);
            for (int a = 0; a < 3; ++a) {
              const int64_t x = int64_t{U[a]} + W[a] - O[a];
              para[a] += x;
              lo[a] = std::min(lo[a], x);
              hi[a] = std::max(hi[a], x);
            }
            ++npara;
          }
        }
      }
      // (v counts as done there: decoded before the next vertex is chosen)
      if (greedy) {
        const bool ud = u != kNone || xu == v, wd = decoded(xw) || xw == v;
        if (ud && wd && !have_xo) xo = cv[he_prev(twin[hn])];
        greedy->count(cv, twin, h, hp, xu, xw, ud, wd, xo);
      }
      h = he_next(twin[h]);
    } while (h != h0 && ++guard < H);
    int64_t d[3], n[3];
    const int cls = blend_prediction(c.alpha, para, npara, nb, nnb, last, pred, d, n);
    int64_t spread[3] = {0, 0, 0};
    if (npara >= 2)
      for (int a = 0; a < 3; ++a) spread[a] = hi[a] - lo[a];
    const int64_t* normal = nullptr;
    NormalSum ns;
    if (c.tangent && npara > 0) {
      if (npair <= kPairs) {
        // Every decoded coordinate is within 0..qmax (residuals are checked,
        // lattice planes too: code_lattice).
        if (NormalSum::near(c.qmax, pred)) {
          for (int j = 0; j < npair; ++j) ns.add_near(at(pu[j]), at(pw[j]), pred);
        } else {
          for (int j = 0; j < npair; ++j) ns.add(at(pu[j]), at(pw[j]), pred);
        }
      } else {  // a wide fan: walk it again
        uint32_t hh = h0;
        size_t gg = 0;
        do {
          const uint32_t u = known(he_next(hh)), w = known(he_prev(hh));
          if (u != kNone && w != kNone) ns.add(at(u), at(w), pred);
          hh = he_next(twin[hh]);
        } while (hh != h0 && ++gg < H);
      }
      normal = ns.finish();
    }
    const int activity = nnb ? (actsum + nnb / 2) / nnb : last_act;
    const int64_t* sp = c.spread_ctx && npara >= 2 ? spread : nullptr;
    if (!(lattice ? c.vertex<false, true>(s, q, v, pred, cls, activity, sp, normal)
                  : c.vertex<false, false>(s, q, v, pred, cls, activity, sp, normal)))
      return false;
    for (int a = 0; a < 3; ++a) last[a] = at(v)[a];
    last_act = act[v];
    return true;
  }
};

// March order. first: the half-edges to code, in order.
bool decode_fan_tables(const GeometryLayout& g, Coder& c, TableDecodeSink& s, std::vector<uint32_t>& q,
                       const uint32_t* first, uint32_t nfirst, int64_t last[3], int& last_act) {
  FanTableDecoder fd(g, c, s, q, last, last_act);
  for (uint32_t i = 0; i < nfirst; ++i) {
    if (!fd.vertex(first[i], nullptr)) return false;
    if ((i & 4095) == 0 && s.truncated()) return false;
  }
  return true;
}

// Per vertex its smallest half-edge (first_he, kNone for a vertex on no
// triangle), and the vertices in the order of their smallest half-edges
// (march order), in one pass over the corners.
void first_half_edges_in_order(const std::vector<uint32_t>& cv, uint32_t vertex_count, std::vector<uint32_t>& first_he,
                               std::vector<uint32_t>& march) {
  first_he.assign(vertex_count, kNone);
  march.resize(vertex_count);
  uint32_t* f = first_he.data();
  uint32_t* out = march.data();
  size_t n = 0;
  for (uint32_t h = 0, H = static_cast<uint32_t>(cv.size()); h < H; ++h) {
    const uint32_t x = cv[h];
    if (x != kNone && f[x] == kNone) {
      f[x] = h;
      out[n++] = x;
    }
  }
  march.resize(n);
}

// Greedy order (greedy_vertices below), found as the vertices are decoded:
// the walk that predicts a vertex also counts what it completes.
// first_he, march: as first_half_edges_in_order gives them.
bool decode_greedy_tables(const GeometryLayout& g, Coder& c, TableDecodeSink& s, std::vector<uint32_t>& q,
                          const std::vector<uint32_t>& first_he, const std::vector<uint32_t>& march, int64_t last[3],
                          int& last_act) {
  FanTableDecoder fd(g, c, s, q, last, last_act);
  GreedyQueue greedy(g.vertex_count);
  const size_t M = march.size();
  size_t scan = 0;
  for (uint32_t i = 0;; ++i) {
    uint32_t v = greedy.pop();
    if (v == kNone) {
      // A new component: the first undecoded corner in march order, which
      // is the first half-edge of the first undecoded vertex in `march`.
      while (scan < M && greedy.prio[march[scan]] == GreedyQueue::kDone) ++scan;
      if (scan == M) return true;
      v = march[scan];
      greedy.prio[v] = GreedyQueue::kDone;
    }
    if (!fd.vertex(first_he[v], &greedy)) return false;
    if ((i & 4095) == 0 && s.truncated()) return false;
  }
}

// March order: vertices as the triangle tree first reaches them.
template <class Sink>
bool code_march_order(const GeometryLayout& g, bool multi, Coder& c, Sink& s, std::vector<uint32_t>& q) {
  SurfaceCoder<Sink> sc(g, c, s, q);
  const uint32_t H = static_cast<uint32_t>(sc.cv.size());
  // Coding the vertex at h makes exactly that vertex known, so the half-edges
  // to code are the first occurrences of each vertex in the corner list:
  // listed first without branches (virtual corners map to the extra entry V,
  // marked seen), so the coding loop below does not mispredict on them.
  const uint32_t V = g.vertex_count;
  // Not zero-filled (the loop writes every entry it later reads).
  std::unique_ptr<uint32_t[]> first(new uint32_t[H]);
  uint32_t nfirst = 0;
  {
    std::vector<uint8_t> seen(size_t{V} + 1, 0);
    seen[V] = 1;
    const uint32_t* cv = sc.cv.data();
    for (uint32_t h = 0; h < H; ++h) {
      const uint32_t x = std::min(cv[h], V);
      first[nfirst] = h;
      nfirst += seen[x] ^ 1u;
      seen[x] = 1;
    }
  }
  if constexpr (std::is_same_v<Sink, TableDecodeSink>) {
    const bool no_lattice = c.lattice.empty();
    if (!multi && !c.tangent && !c.mix && !c.spread_ctx) {
      if (!(no_lattice ? decode_gate_tables<false>(g, c, s, q, first.get(), nfirst, sc.last, sc.last_act)
                       : decode_gate_tables<true>(g, c, s, q, first.get(), nfirst, sc.last, sc.last_act)))
        return false;
      return sc.isolated();
    }
    if (multi && c.spread_ctx && !c.mix) {
      if (!decode_fan_tables(g, c, s, q, first.get(), nfirst, sc.last, sc.last_act)) return false;
      return sc.isolated();
    }
  }
  auto walk = [&](auto plain) {
    for (uint32_t i = 0; i < nfirst; ++i) {
      if (!sc.template code<decltype(plain)::value>(first[i], multi)) return false;
      if ((i & 4095) == 0 && s.truncated()) return false;
    }
    return true;
  };
  if (!(c.plain() ? walk(std::true_type{}) : walk(std::false_type{}))) return false;
  return sc.isolated();
}

// Greedy order: next the vertex with the most complete parallelograms (then
// the most decoded neighbours), each counted up to 3; ties first-in
// first-out. Counts are kept incrementally: a parallelogram completes when
// the last of its three known corners is decoded. A new component starts at
// the first undecoded corner in march order. The order depends on the
// connectivity alone, so the encoder finds it once per layout, before
// coding (the table decoder as it decodes: decode_greedy_tables): the
// vertices in order into `out`. first_he: per vertex, its smallest
// half-edge (the fan the coder walks).
void greedy_vertices(const GeometryLayout& g, const std::vector<uint32_t>& first_he, std::vector<uint32_t>& out) {
  const uint32_t* cv = g.corners().data();
  const uint32_t* twin = g.twin.data();
  const uint32_t H = static_cast<uint32_t>(g.corners().size());
  out.clear();
  out.reserve(g.vertex_count);
  GreedyQueue greedy(g.vertex_count);
  uint32_t scan = 0;
  for (;;) {
    uint32_t v = greedy.pop();
    if (v == kNone) {  // a new component (every vertex not ordered has priority 0)
      while (scan < H && (cv[scan] == kNone || greedy.prio[cv[scan]] == GreedyQueue::kDone)) ++scan;
      if (scan == H) break;
      v = cv[scan];
      greedy.prio[v] = GreedyQueue::kDone;
    }
    out.push_back(v);
    // The counts around v: each triangle (v, u, w) of its fan.
    const uint32_t h0 = first_he[v];
    uint32_t h = h0;
    size_t guard = 0;
    do {
      greedy.count(cv, twin, h, he_next(h), he_prev(h));
      h = he_next(twin[h]);
    } while (h != h0 && ++guard < H);
  }
}

// The greedy order is the same for every pass over one layout: the
// encoder's passes (fits and trial encodes) find it once.
struct GreedyOrder {
  std::vector<uint32_t> vertices;
  bool found = false;
  FanWalks walks;  // what the first pass's walks found (SurfaceCoder::code)
  // The coordinates the encoder's passes code: each pass writes back the
  // values it reads (prediction plus residual, or the plane coded), so
  // one copy of q serves them all.
  std::vector<uint32_t> coords;
  std::vector<uint32_t>& work(const std::vector<uint32_t>& q) {
    if (coords.empty()) coords = q;
    return coords;
  }
};

// Codes the vertices in greedy order (order: the encoder's, found on the
// first pass; null: found here).
template <class Sink>
bool code_greedy(const GeometryLayout& g, Coder& c, Sink& s, std::vector<uint32_t>& q, GreedyOrder* order = nullptr) {
  SurfaceCoder<Sink> sc(g, c, s, q);
  if constexpr (std::is_same_v<Sink, TableDecodeSink>) {
    if (!c.mix) {
      std::vector<uint32_t> march;
      first_half_edges_in_order(sc.cv, g.vertex_count, sc.first_he, march);  // (isolated() reuses first_he)
      return decode_greedy_tables(g, c, s, q, sc.first_he, march, sc.last, sc.last_act) && sc.isolated();
    }
  }
  const std::vector<uint32_t>& first_he = sc.first_half_edges();
  GreedyOrder own;
  if (!order) order = &own;
  if (!order->found) {
    greedy_vertices(g, first_he, order->vertices);
    order->found = true;
  }
  const std::vector<uint32_t>& vs = order->vertices;
  const uint32_t nv = static_cast<uint32_t>(vs.size());
  if (order != &own) {  // the encoder's passes share them
    sc.walks = &order->walks;
    if (!sc.walks->ready) sc.walks->fans.reserve(nv);
  }
  // (As code_march_order: without a lattice, tangent step, spread contexts
  // or mixing, their branches compiled out.)
  auto walk = [&](auto plain) {
    for (uint32_t i = 0; i < nv; ++i) {
      if (!sc.template code<decltype(plain)::value>(first_he[vs[i]], true)) return false;
      if ((i & 4095) == 0 && s.truncated()) return false;
    }
    return true;
  };
  if (!(c.plain() ? walk(std::true_type{}) : walk(std::false_type{}))) return false;
  if (sc.walks) sc.walks->ready = true;
  return sc.isolated();
}

// Vertex-tree order (output ids are tree pre-order), the paper's predictor.
template <class Sink>
bool code_ancestors(const GeometryLayout& g, int K, const int32_t* lambda, Coder& c, Sink& s,
                    std::vector<uint32_t>& q) {
  const uint32_t n = g.vertex_count;
  int64_t root[3];
  for (int a = 0; a < 3; ++a) root[a] = (c.qmax + 1) / 2;
  for (uint32_t v = 0; v < n; ++v) {
    uint32_t anc[kMaxAncestors];
    int d = 0;
    for (uint32_t x = g.parent[v]; x != kNone && d < K; x = g.parent[x]) anc[d++] = x;
    int64_t pred[3];
    int cls, activity = 0;
    if (d == 0) {
      for (int a = 0; a < 3; ++a) pred[a] = root[a];
      cls = 0;
    } else {
      activity = c.act[anc[0]];
      if (d < K) {
        for (int a = 0; a < 3; ++a) pred[a] = q[3 * static_cast<size_t>(anc[0]) + a];
        cls = 1;
      } else {
        for (int a = 0; a < 3; ++a) {
          int64_t sum = int64_t{1} << (kLambdaShift - 1);
          for (int i = 0; i < K; ++i) sum += int64_t{lambda[i]} * q[3 * static_cast<size_t>(anc[i]) + a];
          pred[a] = sum >= 0 ? sum >> kLambdaShift : -((-sum + (int64_t{1} << kLambdaShift) - 1) >> kLambdaShift);
        }
        cls = 2;
      }
    }
    if (!c.vertex(s, q, v, pred, cls, activity)) return false;
    if (d == 0)
      for (int a = 0; a < 3; ++a) root[a] = q[3 * static_cast<size_t>(v) + a];
    if ((v & 4095) == 0 && s.truncated()) return false;
  }
  return true;
}

// Least-squares lambda over all vertices with K ancestors (seed 004 §3.2).
void fit_lambda(const GeometryLayout& g, const std::vector<uint32_t>& q, int K, int32_t* lambda) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(K);
  for (uint32_t v = 0; v < g.vertex_count; ++v) {
    uint32_t anc[kMaxAncestors];
    int d = 0;
    for (uint32_t x = g.parent[v]; x != kNone && d < K; x = g.parent[x]) anc[d++] = x;
    if (d < K) continue;
    for (int a = 0; a < 3; ++a) {
      double y[kMaxAncestors];
      for (int i = 0; i < K; ++i) y[i] = q[3 * static_cast<size_t>(anc[i]) + a];
      for (int i = 0; i < K; ++i) {
        for (int j = 0; j < K; ++j) M(i, j) += y[i] * y[j];
        b(i) += y[i] * q[3 * static_cast<size_t>(v) + a];
      }
    }
  }
  Eigen::VectorXd l = M.ldlt().solve(b);
  for (int i = 0; i < K; ++i) {
    double x = std::isfinite(l(i)) ? l(i) : (i == 0 ? 1.0 : 0.0);
    x = std::clamp(x, -256.0, 256.0);
    lambda[i] = static_cast<int32_t>(std::lround(x * (1 << kLambdaShift)));
  }
}

// The lattice values per axis: count, then increasing values as gaps; with
// `top` (kTopFlag) an axis of two or more planes codes its last
// plane first, as qmax minus it, and then the others as gaps below it.
template <class Sink>
bool code_lattice(Sink& s, Lattice& lattice, int64_t qmax, size_t vertex_count, bool top) {
  ResidualModel count, gap;
  for (int a = 0; a < 3; ++a) {
    std::vector<uint32_t>& L = lattice.values[a];
    int64_t n = s.sint(count, static_cast<int64_t>(L.size()));
    if (n < 0 || n > qmax + 1 || n > static_cast<int64_t>(vertex_count)) return false;
    if constexpr (!Sink::kEncoder) L.resize(static_cast<size_t>(n));
    int64_t end = qmax + 1;  // the planes coded as gaps lie below it
    if (top && n >= 2) {
      end = qmax - s.sint(gap, qmax - L.back());  // L has n entries (decoder: resized)
      if (end < 0 || end > qmax || s.truncated()) return false;
      L.back() = static_cast<uint32_t>(end);
      --n;
    }
    int64_t prev = -1;
    for (int64_t i = 0; i < n; ++i) {
      int64_t x = prev + 1 + s.sint(gap, i < static_cast<int64_t>(L.size()) ? L[static_cast<size_t>(i)] - prev - 1 : 0);
      if (x <= prev || x >= end || s.truncated()) return false;
      L[static_cast<size_t>(i)] = static_cast<uint32_t>(x);
      prev = x;
    }
  }
  return true;
}
template <class Sink>
bool code_lattice(Sink& s, Coder& c) {
  return code_lattice(s, c.lattice, c.qmax, c.act.size(), c.planes_from_top);
}

// Whether the planes cost fewer bytes with each axis's last plane coded
// from the top (the planes alone, fresh models; a tie keeps them all
// from the bottom).
bool top_pays(const Lattice& lattice, int bits, uint32_t vertex_count) {
  auto size = [&](bool top) {
    EncodeSink s;
    Lattice copy = lattice;
    code_lattice(s, copy, (int64_t{1} << bits) - 1, vertex_count, top);
    return s.e.finish().size();
  };
  for (int a = 0; a < 3; ++a)
    if (lattice.values[a].size() >= 2) return size(true) < size(false);
  return false;
}

}  // namespace

namespace {

// fit_alpha's sums of log2(1 + |residual|), one per weight a16 = 0 ..
// kLanes - 1 (the last 3 unused: 4 lanes a step), each added in sample
// order. With SSE2 (x86 GCC or Clang), 4 residuals and 2 sums a step.
struct AlphaCosts {
  static constexpr int kLanes = 28;
#ifdef TSM_FIT_SSE2
  __m128d acc[kLanes / 2];
  AlphaCosts() {
    for (__m128d& x : acc) x = _mm_setzero_pd();
  }
  void add(const double* term) {
    for (int j = 0; j < kLanes / 2; ++j) acc[j] = _mm_add_pd(acc[j], _mm_loadu_pd(term + 2 * j));
  }
  // A sample whose residuals |y - floor((a16 d + 8) / 16)| are all below
  // the table's end (so |d| < 2^13: 32 bits hold a16 d).
  void add_small(const double* table, int32_t d, int32_t y) {
    alignas(16) int32_t index[kLanes];
    __m128i t = _mm_setr_epi32(8, 8 + d, 8 + 2 * d, 8 + 3 * d);
    const __m128i step = _mm_set1_epi32(4 * d), yv = _mm_set1_epi32(y);
#pragma GCC unroll 7
    for (int k = 0; k < kLanes; k += 4) {
      const __m128i r = _mm_sub_epi32(yv, _mm_srai_epi32(t, 4));
      const __m128i sign = _mm_srai_epi32(r, 31);
      _mm_store_si128(reinterpret_cast<__m128i*>(index + k), _mm_sub_epi32(_mm_xor_si128(r, sign), sign));
      t = _mm_add_epi32(t, step);
    }
    // The indices are read back from memory (one load each) rather than
    // taken out of the vector registers lane by lane (three instructions).
    __asm__ volatile("" : : "r"(index) : "memory");
#pragma GCC unroll 14
    for (int j = 0; j < kLanes / 2; ++j) {
      const __m128d v = _mm_loadh_pd(_mm_load_sd(table + index[2 * j]), table + index[2 * j + 1]);
      acc[j] = _mm_add_pd(acc[j], v);
    }
  }
  void get(double* cost) const {
    for (int j = 0; j < kLanes / 2; ++j) _mm_storeu_pd(cost + 2 * j, acc[j]);
  }
#else
  static constexpr int kUsed = 25;  // without SIMD, only the weights fit_alpha reads
  double acc[kLanes] = {};
  void add(const double* term) {
    for (int a = 0; a < kUsed; ++a) acc[a] += term[a];
  }
  void add_small(const double* table, int32_t d, int32_t y) {
    int32_t t = 8;
    for (int a = 0; a < kUsed; ++a, t += d) {
      const int32_t r = y - (t >> 4);
      acc[a] += table[r < 0 ? -r : r];
    }
  }
  void get(double* cost) const { std::copy(acc, acc + kLanes, cost); }
#endif
};

constexpr int64_t kAlphaTable = 4096;  // fit_alpha's table of log2(1 + r), r < 4096

#ifdef TSM_FIT_AVX2
// fit_alpha's sums with AVX2 (where the processor has it): as AlphaCosts
// with 8 residuals and 4 sums a step and the small terms gathered from the
// table 4 at a time; every lane adds the same terms in the same order, so
// the sums are AlphaCosts' to the bit. `term_of(d, y, term)` gives a
// sample's terms outside the table.
template <class Terms>
__attribute__((target("avx2"))) void alpha_costs_avx2(const std::vector<std::pair<int64_t, int64_t>>& samples,
                                                      size_t stride, const double* table, Terms term_of, double* cost) {
  constexpr int kLanes = AlphaCosts::kLanes;
  __m256d acc[kLanes / 4];
  for (__m256d& x : acc) x = _mm256_setzero_pd();
  for (size_t i = 0; i < samples.size(); i += stride) {
    const int64_t d = samples[i].first, y = samples[i].second;
    const int64_t r_last = y - floor_shift((kLanes - 1) * d + 8, 4);
    if (y > -kAlphaTable && y < kAlphaTable && r_last > -kAlphaTable && r_last < kAlphaTable) {
      // |d| < 2^13 here: 32 bits hold a16 d. Lanes 28-31 are computed but
      // not read.
      const int32_t d32 = static_cast<int32_t>(d);
      __m256i t =
          _mm256_setr_epi32(8, 8 + d32, 8 + 2 * d32, 8 + 3 * d32, 8 + 4 * d32, 8 + 5 * d32, 8 + 6 * d32, 8 + 7 * d32);
      const __m256i step = _mm256_set1_epi32(8 * d32), yv = _mm256_set1_epi32(static_cast<int32_t>(y));
      // (The masked gather: the plain one starts from an undefined vector,
      // which GCC 12 warns about.)
      const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1)), zero = _mm256_setzero_pd();
#pragma GCC unroll 4
      for (int k = 0; k < kLanes / 8 + 1; ++k) {
        const __m256i r = _mm256_abs_epi32(_mm256_sub_epi32(yv, _mm256_srai_epi32(t, 4)));
        acc[2 * k] =
            _mm256_add_pd(acc[2 * k], _mm256_mask_i32gather_pd(zero, table, _mm256_castsi256_si128(r), all, 8));
        if (2 * k + 1 < kLanes / 4)
          acc[2 * k + 1] = _mm256_add_pd(acc[2 * k + 1],
                                         _mm256_mask_i32gather_pd(zero, table, _mm256_extracti128_si256(r, 1), all, 8));
        t = _mm256_add_epi32(t, step);
      }
      continue;
    }
    double term[kLanes];
    term_of(d, y, term);
    for (int j = 0; j < kLanes / 4; ++j) acc[j] = _mm256_add_pd(acc[j], _mm256_loadu_pd(term + 4 * j));
  }
  for (int j = 0; j < kLanes / 4; ++j) _mm256_storeu_pd(cost + 4 * j, acc[j]);
}
#endif

}  // namespace

// The weight (of 16ths, 0 .. 1.5) that minimizes an estimate of the coded
// size, sum log2(1 + |residual|), over a sample of the coordinates. `wide`:
// AVX2 where the processor has it (the same sums; false for tests).
int32_t fit_alpha(const std::vector<std::pair<int64_t, int64_t>>& samples, bool wide = true) {
  if (samples.empty()) return kAlphaOne;
  // log2(1 + r) for small r from a table (the same values, 5x faster).
  static const std::vector<double> small_log = [] {
    std::vector<double> t(4096);
    for (size_t r = 0; r < t.size(); ++r) t[r] = std::log2(1.0 + static_cast<double>(r));
    return t;
  }();
  const size_t stride = std::max<size_t>(1, samples.size() / 200000);
  // Every weight's cost in one pass over the samples (each sum still adds
  // its terms in sample order, so the costs are those of a pass per weight).
  // The weight's residual y - floor((a16 d + 8) / 16) (alpha d rounded at
  // 4.12, alpha = a16 / 16) is monotone in a16: when it is inside the
  // table at a16 = 0 and at the last lane it is at every lane, and those
  // samples (nearly all) go through fast_terms.
  constexpr int kWeights = 25;  // a16 = 0 .. 24
  auto term_of = [&](int64_t d, int64_t y, double* term) {
    for (int a16 = 0; a16 < AlphaCosts::kLanes; ++a16) {
      const int64_t r = y - floor_shift(a16 * d + 8, 4);
      const int64_t m = r < 0 ? -r : r;
      term[a16] = m < kAlphaTable ? small_log[static_cast<size_t>(m)] : std::log2(1.0 + static_cast<double>(m));
    }
  };
  double cost[AlphaCosts::kLanes];
  bool summed = false;
#ifdef TSM_FIT_AVX2
  if (wide && __builtin_cpu_supports("avx2")) {
    alpha_costs_avx2(samples, stride, small_log.data(), term_of, cost);
    summed = true;
  }
#else
  (void)wide;
#endif
  if (!summed) {
    AlphaCosts costs;
    for (size_t i = 0; i < samples.size(); i += stride) {
      const int64_t d = samples[i].first, y = samples[i].second;
      const int64_t r_last = y - floor_shift((AlphaCosts::kLanes - 1) * d + 8, 4);
      if (y > -kAlphaTable && y < kAlphaTable && r_last > -kAlphaTable && r_last < kAlphaTable) {
        costs.add_small(small_log.data(), static_cast<int32_t>(d), static_cast<int32_t>(y));
        continue;
      }
      double term[AlphaCosts::kLanes];
      term_of(d, y, term);
      costs.add(term);
    }
    costs.get(cost);
  }
  int best = 0;
  for (int a16 = 1; a16 < kWeights; ++a16)
    if (cost[a16] < cost[best]) best = a16;
  return best << (kAlphaShift - 4);
}

// A statistics pass in a surface predictor's order: nothing coded, the
// fitting samples collected in `fit`.
void collect_pass(const GeometryLayout& g, const std::vector<uint32_t>& q, Predictor pred, Coder& fit,
                  GreedyOrder* order) {
  fit.collect = true;
  CollectSink cs;
  std::vector<uint32_t> own;
  std::vector<uint32_t>& work = order ? order->work(q) : (own = q);
  if (greedy_order(pred))
    code_greedy(g, fit, cs, work, order);
  else
    code_march_order(g, pred == Predictor::fan, fit, cs, work);
}

// The parallelogram weights for a predictor: fitted per class by least
// squares and by the size estimate (fit_alpha); the caller codes both.
void fit_alphas(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred, int32_t lsq[3],
                int32_t est[3], GreedyOrder* order) {
  Coder fit(g.vertex_count, bits, false);
  collect_pass(g, q, pred, fit, order);
  for (int k = 0; k < 3; ++k) {
    est[k] = fit_alpha(fit.samples[k]);
    double num = 0, den = 0;
    for (auto [d, e] : fit.samples[k]) {
      num += static_cast<double>(d) * static_cast<double>(e);
      den += static_cast<double>(d) * static_cast<double>(d);
    }
    lsq[k] = den > 0 ? static_cast<int32_t>(std::clamp(std::round(kAlphaOne * num / den), 0.0, 2.0 * kAlphaOne))
                     : kAlphaOne;
  }
}

// The tangent step's weights (surface vertices, vertices with an anchor)
// for a predictor, lattice and parallelogram weights, by fit_alpha's size
// estimate (0 .. 1.5).
void fit_betas(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred,
               const Lattice& lattice, const int32_t* weights, int32_t beta[2], GreedyOrder* order) {
  Coder fit(g.vertex_count, bits, false);
  fit.tangent = true;
  fit.lattice = lattice;
  fit.build_nearest();
  if (weights)
    for (int k = 0; k < 3; ++k) fit.alpha[k] = weights[k];
  collect_pass(g, q, pred, fit, order);
  for (int i = 0; i < 2; ++i) beta[i] = fit.tan_samples[i].empty() ? 0 : fit_alpha(fit.tan_samples[i]);
}

// Predictor raw: the lattice planes, then every coordinate of
// every vertex in output order as equiprobable bits: the index of its plane
// when its axis has planes (every value of the axis is one), else its grid
// value. No models to train: on a mesh of a few vertices this beats any
// prediction from the grid centre with fresh models.
int index_bits(size_t planes) {
  int n = 0;
  while ((size_t{1} << n) < planes) ++n;
  return n;
}

std::string encode_geometry_raw(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits,
                                const Lattice& lattice, bool top) {
  EncodeSink s;
  Coder c(g.vertex_count, bits, false);
  c.lattice = lattice;
  c.planes_from_top = top;
  code_lattice(s, c);
  for (size_t i = 0; i < 3 * size_t{g.vertex_count}; ++i) {
    const std::vector<uint32_t>& L = lattice.values[i % 3];
    if (L.empty()) {
      s.e.direct(q[i], bits);
    } else {
      const auto it = std::lower_bound(L.begin(), L.end(), q[i]);
      assert(it != L.end() && *it == q[i]);
      s.e.direct(static_cast<uint32_t>(it - L.begin()), index_bits(L.size()));
    }
  }
  return std::string(1, static_cast<char>(static_cast<uint8_t>(Predictor::raw) | (top ? kTopFlag : 0))) +
         s.e.finish();
}

bool decode_geometry_raw(DecodeSink& s, Coder& c, uint32_t vertex_count, int bits, std::vector<uint32_t>& q) {
  if (!code_lattice(s, c)) return false;
  int nbits[3];
  for (int a = 0; a < 3; ++a) nbits[a] = c.lattice.values[a].empty() ? bits : index_bits(c.lattice.values[a].size());
  for (uint32_t v = 0; v < vertex_count; ++v) {
    for (int a = 0; a < 3; ++a) {
      const std::vector<uint32_t>& L = c.lattice.values[a];
      const uint32_t x = s.d.direct(nbits[a]);
      if (L.empty()) {
        q[3 * size_t{v} + a] = x;
      } else {
        if (x >= L.size()) return false;
        q[3 * size_t{v} + a] = L[x];
      }
    }
    if ((v & 4095) == 0 && s.truncated()) return false;
  }
  return !s.truncated();
}

// Whether every coordinate of an axis with planes is on one of them (what
// the raw predictor needs).
bool covers(const Lattice& lattice, const std::vector<uint32_t>& q, uint32_t vertex_count) {
  for (int a = 0; a < 3; ++a) {
    const std::vector<uint32_t>& L = lattice.values[a];
    if (L.empty()) continue;
    for (uint32_t v = 0; v < vertex_count; ++v)
      if (!std::binary_search(L.begin(), L.end(), q[3 * size_t{v} + a])) return false;
  }
  return true;
}

// fit_betas' samples (Coder::tan_samples) as a coding pass without the
// tangent step gathers them.
using TangentSamples = std::array<std::vector<std::pair<int64_t, int64_t>>, 2>;

// encode_geometry_as with the greedy order shared between passes (null:
// found on each). tangent_out: where a pass of a surface predictor without
// the tangent step leaves the samples fit_betas would collect for its
// predictor and weights (null: none gathered).
std::string encode_geometry_with(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred,
                                 int K, const Lattice& lattice, const int32_t* weights, const int32_t* tangent,
                                 bool mix, bool top, bool tables, GreedyOrder* order,
                                 TangentSamples* tangent_out = nullptr) {
  if (pred == Predictor::raw) {
    const bool all_on = covers(lattice, q, g.vertex_count);
    return encode_geometry_raw(g, q, bits, all_on ? lattice : Lattice(), top && all_on);
  }
  if (mix) tables = false;
  std::string head;
  ByteWriter w(head);
  const bool default_weights =
      pred != Predictor::ancestors && (!weights || (weights[0] == kAlphaOne && weights[1] == kAlphaOne &&
                                                    weights[2] == kAlphaOne));
  if (!surface_predictor(pred)) tangent = nullptr;
  w.u8(static_cast<uint8_t>(static_cast<uint8_t>(pred) | (default_weights ? kDefaultWeightsFlag : 0) |
                            (tangent ? kTangentFlag : 0) | (mix ? kMixFlag : 0) | (top ? kTopFlag : 0) |
                            (tables ? kTableFlag : 0)));
  int32_t lambda[kMaxAncestors] = {0, 0, 0, 0};
  if (pred == Predictor::ancestors) {
    fit_lambda(g, q, K, lambda);
    w.u8(static_cast<uint8_t>(K));
    for (int i = 0; i < K; ++i) w.u32(static_cast<uint32_t>(lambda[i]));
  }
  int32_t alpha[3] = {kAlphaOne, kAlphaOne, kAlphaOne}, beta[2] = {kAlphaOne, kAlphaOne};
  if (pred != Predictor::ancestors && !default_weights)
    for (int k = 0; k < 3; ++k) {
      alpha[k] = weights[k];
      w.u16(static_cast<uint16_t>(static_cast<int16_t>(alpha[k])));
    }
  if (tangent)
    for (int i = 0; i < 2; ++i) {
      beta[i] = std::clamp<int32_t>(tangent[i], 0, kMaxBeta);
      w.u16(static_cast<uint16_t>(beta[i]));
    }
  // One coding pass with a given sink (the table encoder makes two).
  auto pass = [&](auto& s) {
    Coder c(g.vertex_count, bits, !tables);
    c.spread_ctx = spread_contexts(pred);
    if (mix) c.mix = std::make_unique<MixModels>();
    std::copy(alpha, alpha + 3, c.alpha);
    if (tangent) {
      c.tangent = true;
      std::copy(beta, beta + 2, c.beta);
    }
    c.lattice = lattice;
    c.planes_from_top = top;
    code_lattice(s, c);
    c.build_nearest();
    c.tangent_samples = tangent_out && !tangent && surface_predictor(pred);
    std::vector<uint32_t> own;
    std::vector<uint32_t>& work = order ? order->work(q) : (own = q);
    if (pred == Predictor::ancestors)
      code_ancestors(g, K, lambda, c, s, work);
    else if (greedy_order(pred))
      code_greedy(g, c, s, work, order);
    else
      code_march_order(g, pred == Predictor::fan, c, s, work);
    if (c.tangent_samples)
      for (int i = 0; i < 2; ++i) (*tangent_out)[i] = std::move(c.tan_samples[i]);
  };
  if (!tables) {
    EncodeSink s;
    pass(s);
    return head + s.e.finish();
  }
  // Tables (FORMAT.md §8.5.12): code (the residuals counted and kept),
  // build the tables; then the tables' range-coded stream, the rANS stream
  // and the bit stream, each after its length, and the range stream.
  RansEncoder codes(kTableContexts);
  TableEncodeSink s(codes);
  pass(s);
  codes.build();
  RangeEncoder table_coder;
  codes.write_tables(table_coder);
  ByteWriter tail(head);
  for (const std::string& part : {table_coder.finish(), codes.finish(), s.bits.finish()}) {
    tail.u32(static_cast<uint32_t>(part.size()));
    tail.bytes(part);
  }
  return head + s.e.finish();
}

// Tests (test_encode_speed.cpp): fit_betas' samples for a greedy
// predictor `pred` with the given weights and lattice, from its own pass
// (`own`), and as the first coding pass of encode_geometry gathers them
// (`gathered`: the parallelogram predictor, no lattice, after a pass that
// keeps the walks).
void tangent_samples_both_ways(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred,
                               const Lattice& lattice, const int32_t weights[3], TangentSamples& own,
                               TangentSamples& gathered) {
  Coder fit(g.vertex_count, bits, false);
  fit.tangent = true;
  fit.lattice = lattice;
  fit.build_nearest();
  std::copy(weights, weights + 3, fit.alpha);
  collect_pass(g, q, pred, fit, nullptr);
  for (int i = 0; i < 2; ++i) own[i] = fit.tan_samples[i];
  GreedyOrder order;
  int32_t lsq[3], est[3];
  fit_alphas(g, q, bits, Predictor::parallelograms, lsq, est, &order);
  encode_geometry_with(g, q, bits, Predictor::parallelograms, 0, Lattice(), weights, nullptr, false, false, true,
                       &order, &gathered);
}

std::string encode_geometry_as(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred, int K,
                               const Lattice& lattice, const int32_t* weights, const int32_t* tangent, bool mix,
                               bool top, bool tables) {
  return encode_geometry_with(g, q, bits, pred, K, lattice, weights, tangent, mix, top, tables, nullptr);
}

namespace {

constexpr uint32_t kFewOffSurface = 8;

// find_anchors for one vertex v off the surface, by a scan of the surface
// vertices: the nearest whose cell (2^shift steps a side) is at most one
// cell from v's on every axis, else at most two; kNone if none is.
uint32_t nearest_in_cells(const std::vector<uint32_t>& q, const std::vector<uint8_t>& on_surface, uint32_t v,
                          int shift) {
  const uint32_t* p = &q[3 * size_t{v}];
  const int64_t c[3] = {p[0] >> shift, p[1] >> shift, p[2] >> shift};
  uint64_t best[3] = {UINT64_MAX, UINT64_MAX, UINT64_MAX};  // per cell distance 1, 2
  uint32_t at[3] = {kNone, kNone, kNone};
  for (uint32_t u = 0; u < on_surface.size(); ++u) {
    if (!on_surface[u]) continue;
    const uint32_t* o = &q[3 * size_t{u}];
    int64_t cells = 0;
    uint64_t d = 0;
    for (int a = 0; a < 3; ++a) {
      const int64_t k = (o[a] >> shift) - c[a];
      cells = std::max(cells, k < 0 ? -k : k);
      const int64_t e = int64_t{p[a]} - o[a];
      d += static_cast<uint64_t>(e * e);
    }
    if (cells > 2) continue;
    for (int64_t r = std::max<int64_t>(cells, 1); r <= 2; ++r)
      if (d < best[r]) {  // (ids ascending: the first of equal distances stays)
        best[r] = d;
        at[r] = u;
      }
  }
  return at[1] != kNone ? at[1] : at[2];
}

}  // namespace

std::vector<uint32_t> find_anchors(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits) {
  const uint32_t n = g.vertex_count;
  std::vector<uint32_t> anchor(n, kNone);
  std::vector<uint8_t> on_surface(n, 0);
  for (uint32_t v : g.corners())
    if (v != kNone) on_surface[v] = 1;
  uint32_t surface = 0;
  for (uint32_t v = 0; v < n; ++v) surface += on_surface[v];
  if (surface == 0 || surface == n) return anchor;
  // Cells of 2^shift steps, about one surface vertex per occupied cell.
  int shift = bits - static_cast<int>(std::log2(std::sqrt(static_cast<double>(surface)) + 1.0));
  shift = std::clamp(shift, std::max(0, bits - 20), 30);  // cell coordinates fit the 21-bit fields of the key
  auto cell = [&](uint32_t v, int dx, int dy, int dz) -> uint64_t {
    int64_t c[3] = {(q[3 * size_t{v}] >> shift) + dx, (q[3 * size_t{v} + 1] >> shift) + dy,
                    (q[3 * size_t{v} + 2] >> shift) + dz};
    return (static_cast<uint64_t>(c[0] + 4) << 42) ^ (static_cast<uint64_t>(c[1] + 4) << 21) ^
           static_cast<uint64_t>(c[2] + 4);
  };
  // A few vertices off the surface (a scan's stray points): each compared
  // with every surface vertex, the same nearest (by squared distance, then
  // id) within one cell, else two, without sorting the cells.
  if (n - surface <= kFewOffSurface) {
    for (uint32_t v = 0; v < n; ++v)
      if (!on_surface[v]) anchor[v] = nearest_in_cells(q, on_surface, v, shift);
    return anchor;
  }
  std::vector<std::pair<uint64_t, uint32_t>> cells;
  cells.reserve(surface);
  for (uint32_t v = 0; v < n; ++v)
    if (on_surface[v]) cells.push_back({cell(v, 0, 0, 0), v});
  std::sort(cells.begin(), cells.end());
  for (uint32_t v = 0; v < n; ++v) {
    if (on_surface[v]) continue;
    uint64_t best = UINT64_MAX;
    // The cells dz = -r .. r of a column (dx, dy) are consecutive keys: one
    // search, then the column's run of keys (any order of the candidates
    // gives the same nearest, then smallest id). Below cell 0 on an axis
    // there is none (the key would wrap).
    const int z0 = static_cast<int>(q[3 * size_t{v} + 2] >> shift);
    for (int r = 1; r <= 2 && best == UINT64_MAX; ++r)
      for (int dx = -r; dx <= r; ++dx)
        for (int dy = -r; dy <= r; ++dy) {
          const uint64_t last = cell(v, dx, dy, r);
          const uint64_t first = cell(v, dx, dy, std::max(-r, -z0));
          auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(first, uint32_t{0}));
          for (; it != cells.end() && it->first <= last; ++it) {
            uint64_t d = 0;
            for (int a = 0; a < 3; ++a) {
              int64_t e = int64_t{q[3 * size_t{v} + a]} - q[3 * size_t{it->second} + a];
              d += static_cast<uint64_t>(e * e);
            }
            if (d < best || (d == best && it->second < anchor[v])) {
              best = d;
              anchor[v] = it->second;
            }
          }
        }
  }
  return anchor;
}

Lattice find_lattice(const std::vector<uint32_t>& q, uint32_t n) {
  Lattice out;
  std::vector<uint32_t> vals(n), counts;
  std::vector<std::pair<uint32_t, uint32_t>> runs;  // value, count, by value
  for (int a = 0; a < 3; ++a) {
    uint32_t top = 0;
    for (uint32_t v = 0; v < n; ++v) top = std::max(top, vals[v] = q[3 * static_cast<size_t>(v) + a]);
    runs.clear();
    if (n > 0 && top / 8 < n) {
      // Values below 8 per vertex: counted in a table, not sorted.
      counts.assign(size_t{top} + 1, 0);
      for (uint32_t x : vals) ++counts[x];
      for (uint32_t x = 0; x <= top; ++x)
        if (counts[x]) runs.push_back({x, counts[x]});
    } else {
      std::sort(vals.begin(), vals.end());
      for (size_t i = 0; i < vals.size();) {
        size_t j = i;
        while (j < vals.size() && vals[j] == vals[i]) ++j;
        runs.push_back({vals[i], static_cast<uint32_t>(j - i)});
        i = j;
      }
    }
    if (runs.empty()) continue;
    counts.resize(runs.size());
    for (size_t i = 0; i < runs.size(); ++i) counts[i] = runs[i].second;
    std::nth_element(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(counts.size() / 2), counts.end());
    // A value off the planes is used about `median` times (Poisson-like);
    // a plane far more often.
    const double median = counts[counts.size() / 2];
    const double threshold = median + 6.0 * std::sqrt(median) + 4.0;
    std::vector<uint32_t>& L = out.values[a];
    size_t covered = 0;
    for (auto [value, count] : runs)
      if (count >= threshold) {
        L.push_back(value);
        covered += count;
      }
    if (3 * covered < n || 8 * L.size() > n) L.clear();
  }
  return out;
}

std::string encode_geometry(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, int level,
                            const Lattice* candidate, GeometryStats* stats) {
  // Levels 0-6: residuals through static tables and rANS; but the mixing
  // levels, and at levels 3-6 a small mesh (where the tables may cost more
  // than they save, and decoding takes no time), search with the adaptive
  // models and try tables on the winner last.
  const bool adaptive_search = level >= kMixLevel || (level >= 3 && g.vertex_count <= kSmallMesh);
  bool tables = !adaptive_search;
  GeometryStats st;
  st.predictor = level <= 2 ? Predictor::gate : Predictor::parallelograms;
  st.tables = tables;
  GreedyOrder order;  // every greedy pass below walks this layout in one order
  int32_t lsq[3], est[3];
  fit_alphas(g, q, bits, st.predictor, lsq, est, &order);
  const int32_t* weights = est;
  // At levels 3 and up the first pass also gathers the tangent step's
  // samples, which hold for the spread predictor and any lattice too (the
  // same prediction in the same order): the step's weights are fitted on
  // them (also when the least-squares weights win, which predict nearly
  // alike) and need no pass of their own.
  TangentSamples est_samples;
  TangentSamples* const gather_est = level >= 3 ? &est_samples : nullptr;
  std::string best = encode_geometry_with(g, q, bits, st.predictor, 0, st.lattice, est, nullptr, false, false, tables,
                                          &order, gather_est);
  // `lattice` may be st.lattice itself (the assignment below is then a
  // self-assignment, which std::vector handles).
  int32_t beta[2];
  auto consider = [&](Predictor pred, int K, const Lattice& lattice, const int32_t* w, const int32_t* tan = nullptr,
                      bool mixed = false, TangentSamples* tangent_out = nullptr) {
    const bool top = top_pays(lattice, bits, g.vertex_count);
    std::string alt =
        encode_geometry_with(g, q, bits, pred, K, lattice, w, tan, mixed, top, tables, &order, tangent_out);
    if (alt.size() >= best.size()) return false;
    best.swap(alt);
    st.predictor = pred;
    st.ancestors = K;
    st.lattice = lattice;
    st.tangent = tan != nullptr;
    st.mix = mixed;
    st.top = static_cast<uint8_t>(best[0]) & kTopFlag;  // raw drops planes that miss a vertex, and the flag
    st.tables = static_cast<uint8_t>(best[0]) & kTableFlag;  // raw and mixing have none
    weights = w;
    return true;
  };
  if ((level >= 3 || tables) && candidate) {
    // Shared coordinate planes: keep them where they make the file smaller
    // (all candidate axes at once, then at high levels each axis alone).
    const Lattice& found = *candidate;
    if (!found.empty()) {
      consider(st.predictor, 0, found, weights);
      if (level >= 8)
        for (int a = 0; a < 3; ++a) {
          Lattice trial = st.lattice;
          if (trial.values[a].empty()) continue;
          trial.values[a].clear();
          consider(st.predictor, 0, trial, weights);
        }
    }
  }
  // Levels 1-2: the prediction from every triangle around the
  // new vertex, still in march order (predictor fan), and at level 2 the
  // tangent step on whichever of gate and fan is smaller; each kept only
  // where it makes the file smaller.
  int32_t fan_lsq[3], fan_est[3];
  if (level == 1 || level == 2) {
    fit_alphas(g, q, bits, Predictor::fan, fan_lsq, fan_est, &order);
    consider(Predictor::fan, 0, st.lattice, fan_est);
    if (level == 2) {
      fit_betas(g, q, bits, st.predictor, st.lattice, weights, beta, &order);
      consider(st.predictor, 0, st.lattice, weights, beta);
    }
  }
  // The least-squares weights instead of the size estimate's.
  if (level >= 3 && std::memcmp(lsq, est, sizeof lsq) != 0) consider(st.predictor, 0, st.lattice, lsq);
  // Residual contexts from the parallelograms' spread instead of the activity.
  if (level >= 3) consider(Predictor::spread, 0, st.lattice, weights);
  // Averaging every parallelogram loses where some of them are poor (across
  // the rows of a latitude-longitude grid, say): the gate's alone, in march
  // order, with its own weights. Tried where the search is adaptive (the
  // mixing levels, small meshes) and on meshes with lattice planes (CAD
  // parts: 2CylinderEngine's 8,618-vertex primitives, 3% smaller with it);
  // on the scans it won nowhere (5-10% larger than the surface predictors)
  // and costs a pass of its own for the weights.
  int32_t gate_lsq[3], gate_est[3];
  if (level >= 3 && (adaptive_search || !st.lattice.empty())) {
    fit_alphas(g, q, bits, Predictor::gate, gate_lsq, gate_est, &order);
    consider(Predictor::gate, 0, st.lattice, gate_est);
  }
  if (level >= 7)
    for (int K = 1; K <= kMaxAncestors; ++K) consider(Predictor::ancestors, K, st.lattice, nullptr);
  // On small meshes the stored weights may cost more than they save, and
  // (a few vertices) no prediction may beat every predictor: both are cheap
  // to try there.
  if (g.vertex_count <= kSmallMesh) {
    if (st.predictor != Predictor::ancestors) consider(st.predictor, 0, st.lattice, nullptr);
    // Every value an axis repeats as planes, when the vertices share few
    // values (the 8 corners of a box: 2 per axis); find_lattice's statistical
    // test needs more vertices than that.
    Lattice shared;
    std::vector<uint32_t> vals(g.vertex_count);
    for (int a = 0; a < 3; ++a) {
      for (uint32_t v = 0; v < g.vertex_count; ++v) vals[v] = q[3 * size_t{v} + a];
      std::sort(vals.begin(), vals.end());
      vals.erase(std::unique(vals.begin(), vals.end()), vals.end());
      if (2 * vals.size() <= g.vertex_count) shared.values[a] = vals;
      vals.resize(g.vertex_count);
    }
    if (!shared.empty()) {
      for (Predictor pred : {Predictor::gate, Predictor::parallelograms}) consider(pred, 0, shared, nullptr);
      consider(Predictor::raw, 0, shared, nullptr);
    }
    consider(Predictor::raw, 0, Lattice(), nullptr);
  }
  // The tangent step on whatever surface predictor won.
  if (level >= 3 && surface_predictor(st.predictor)) {
    if (greedy_order(st.predictor) && weights)
      for (int i = 0; i < 2; ++i) beta[i] = est_samples[i].empty() ? 0 : fit_alpha(est_samples[i]);
    else
      fit_betas(g, q, bits, st.predictor, st.lattice, weights, beta, &order);
    consider(st.predictor, 0, st.lattice, weights, beta);
  }
  // Residual mixing on whatever won: smaller, slower to decode.
  if (level >= kMixLevel && st.predictor != Predictor::raw)
    consider(st.predictor, st.ancestors, st.lattice, weights, st.tangent ? beta : nullptr, true);
  if (adaptive_search && st.predictor != Predictor::raw) {
    tables = true;
    consider(st.predictor, st.ancestors, st.lattice, weights, st.tangent ? beta : nullptr);
  }
  for (int a = 0; a < 3; ++a) st.lattice_planes[a] = static_cast<uint32_t>(st.lattice.values[a].size());
  if (stats) *stats = st;
  return best;
}

Status decode_geometry(std::string_view bytes, const GeometryLayout& g, int bits, std::vector<uint32_t>& q,
                       GeometryStats* stats) {
  auto corrupt = [](const std::string& what) { return Status(ErrorCode::corrupt_data, "geometry: " + what); };
  ByteReader r(bytes);
  GeometryStats st;
  uint8_t kind;
  if (!r.u8(kind)) return corrupt("empty section");
  bool default_weights = false;
  if (kind & kTableFlag) {
    kind = static_cast<uint8_t>(kind & ~kTableFlag);
    st.tables = true;
  }
  if (kind & kTopFlag) {
    kind = static_cast<uint8_t>(kind & ~kTopFlag);
    st.top = true;
  }
  if (kind & kMixFlag) {
    kind = static_cast<uint8_t>(kind & ~kMixFlag);
    st.mix = true;
    const int base = kind & ~(kDefaultWeightsFlag | kTangentFlag);
    if (base > static_cast<int>(Predictor::spread) && base != static_cast<int>(Predictor::fan))
      return corrupt("predictor " + std::to_string(base) + " has no residual models to mix");
  }
  if (kind & kTangentFlag) {
    kind = static_cast<uint8_t>(kind & ~kTangentFlag);
    st.tangent = true;
    const uint8_t base = static_cast<uint8_t>(kind & ~kDefaultWeightsFlag);
    if (!surface_predictor(static_cast<Predictor>(base)))
      return corrupt("predictor " + std::to_string(base) + " has no tangent step");
  }
  if ((kind & kDefaultWeightsFlag) && kind != kDefaultWeightsFlag) {
    kind = static_cast<uint8_t>(kind & ~kDefaultWeightsFlag);
    default_weights = true;
    if (kind > static_cast<uint8_t>(Predictor::spread) && kind != static_cast<uint8_t>(Predictor::fan))
      return corrupt("predictor " + std::to_string(kind) + " has no weights to leave out");
  }
  if (kind > static_cast<uint8_t>(Predictor::fan)) return corrupt("unknown predictor " + std::to_string(kind));
  st.predictor = static_cast<Predictor>(kind);
  if (st.tables && (st.predictor == Predictor::raw || st.mix))
    return corrupt(st.mix ? "residual mixing and tables at once" : "the raw predictor has no residuals for tables");
  if (st.predictor == Predictor::raw) {
    q.assign(3 * static_cast<size_t>(g.vertex_count), 0);
    Coder c(g.vertex_count, bits, false);
    c.planes_from_top = st.top;
    DecodeSink ds;
    ds.d.init(bytes.substr(1));
    if (!decode_geometry_raw(ds, c, g.vertex_count, bits, q))
      return corrupt(ds.truncated() ? "stream is truncated" : "bad lattice or plane index");
    for (int a = 0; a < 3; ++a) st.lattice_planes[a] = static_cast<uint32_t>(c.lattice.values[a].size());
    if (stats) *stats = st;
    return Status::Ok();
  }
  int32_t lambda[kMaxAncestors] = {0, 0, 0, 0};
  if (st.predictor == Predictor::ancestors) {
    uint8_t K;
    if (!r.u8(K)) return corrupt("truncated predictor header");
    if (K < 1 || K > kMaxAncestors) return corrupt("ancestor count " + std::to_string(K) + " out of range 1..4");
    st.ancestors = K;
    for (int i = 0; i < K; ++i) {
      uint32_t x;
      if (!r.u32(x)) return corrupt("truncated predictor header");
      lambda[i] = static_cast<int32_t>(x);
      if (lambda[i] < -(256 << kLambdaShift) || lambda[i] > (256 << kLambdaShift))
        return corrupt("ancestor weight out of range");
    }
  }
  int32_t alpha[3] = {kAlphaOne, kAlphaOne, kAlphaOne};
  if (st.predictor != Predictor::ancestors && !default_weights)
    for (int k = 0; k < 3; ++k) {
      uint16_t x;
      if (!r.u16(x)) return corrupt("truncated predictor header");
      alpha[k] = static_cast<int16_t>(x);
    }
  Coder c(g.vertex_count, bits, !st.tables);
  if (st.tangent) {
    c.tangent = true;
    for (int i = 0; i < 2; ++i) {
      uint16_t x;
      if (!r.u16(x)) return corrupt("truncated predictor header");
      if (x > kMaxBeta)
        return corrupt("tangent weight " + std::to_string(x) + " out of range 0.." + std::to_string(kMaxBeta));
      c.beta[i] = x;
    }
  }
  for (int k = 0; k < 3; ++k) c.alpha[k] = alpha[k];
  c.spread_ctx = spread_contexts(st.predictor);
  if (st.mix) c.mix = std::make_unique<MixModels>();
  c.planes_from_top = st.top;
  if (st.predictor == Predictor::ancestors)
    for (uint32_t v = 0; v < g.vertex_count; ++v)
      if (g.parent[v] != kNone && g.parent[v] >= v) return corrupt("bad vertex tree parent");
  auto run = [&](auto& s) -> Status {
    if (!code_lattice(s, c)) return corrupt("bad lattice");
    c.build_nearest();
    for (int a = 0; a < 3; ++a) st.lattice_planes[a] = static_cast<uint32_t>(c.lattice.values[a].size());
    q.assign(3 * static_cast<size_t>(g.vertex_count), 0);
    bool ok;
    if (st.predictor == Predictor::ancestors)
      ok = code_ancestors(g, st.ancestors, lambda, c, s, q);
    else
      ok = greedy_order(st.predictor) ? code_greedy(g, c, s, q)
                                      : code_march_order(g, st.predictor == Predictor::fan, c, s, q);
    if (!ok || s.truncated()) return corrupt(s.truncated() ? s.truncation() : "coordinate outside the grid");
    if constexpr (std::is_same_v<std::decay_t<decltype(s)>, TableDecodeSink>)
      if (!s.tables.finished()) return corrupt("rANS states do not end where they started");
    if (stats) *stats = st;
    return Status::Ok();
  };
  if (!st.tables) {
    DecodeSink s;
    s.d.init(bytes.substr(r.offset()));
    return run(s);
  }
  // With tables (§8.5.12): the tables' range-coded stream, the rANS stream
  // and the bit stream, each after its length, then the range-coded stream.
  auto s = std::make_unique<TableDecodeSink>();
  uint32_t n;
  std::string_view table_bytes, rans, raw;
  if (!r.u32(n) || !r.bytes(n, table_bytes)) return corrupt("residual tables are cut off");
  if (!r.u32(n) || !r.bytes(n, rans)) return corrupt("rANS stream is cut off");
  if (!s->tables.init(rans)) return corrupt("rANS stream too short or with a bad state");
  if (!r.u32(n) || !r.bytes(n, raw)) return corrupt("residual bit stream is cut off");
  s->bits.init(raw);
  s->d.init(bytes.substr(r.offset()));
  RangeDecoder table_decoder(table_bytes);
  std::string why;
  if (!s->tables.read_tables(table_decoder, kTableContexts, why)) return corrupt(why);
  return run(*s);
}

}  // namespace tsm
