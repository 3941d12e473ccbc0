// The encoder's faster steps keep its choices: fit_alpha (geometry_predict.cpp),
// whose SSE2 and AVX2 paths must pick the weight that one sum per weight over
// the samples in order picks, whatever the samples (inside the log table,
// across its end, far outside it, more than its sampling stride);
// find_anchors, whose scan for a few vertices off the surface must pick
// the anchor its sorted cells pick; find_lattice, whose counted values must
// give the planes sorted values give; the tangent step's samples, which a
// coding pass without the step gathers as fit_betas' own pass would; the
// cut's order of components that share vertices, which a decoded mesh must
// give again (one canonical round, not two).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "connectivity.hpp"
#include "geometry_predict.hpp"
#include "mesh_gen.hpp"

namespace tsm {
int32_t fit_alpha(const std::vector<std::pair<int64_t, int64_t>>& samples, bool wide);
void tangent_samples_both_ways(const GeometryLayout& g, const std::vector<uint32_t>& q, int bits, Predictor pred,
                               const Lattice& lattice, const int32_t weights[3],
                               std::array<std::vector<std::pair<int64_t, int64_t>>, 2>& own,
                               std::array<std::vector<std::pair<int64_t, int64_t>>, 2>& gathered);
}  // namespace tsm

namespace {

using Samples = std::vector<std::pair<int64_t, int64_t>>;

// fit_alpha as it was written first: per weight a16 = 0 .. 24 (of 16ths),
// the sum of log2(1 + |y - round(alpha d)|) over every stride-th sample,
// in sample order; the first smallest wins (4.12 fixed point).
int32_t plain_fit_alpha(const Samples& samples) {
  if (samples.empty()) return 1 << 12;
  const size_t stride = std::max<size_t>(1, samples.size() / 200000);
  double cost[25] = {};
  for (size_t i = 0; i < samples.size(); i += stride) {
    const int64_t d = samples[i].first, y = samples[i].second;
    for (int a16 = 0; a16 < 25; ++a16) {
      const int64_t alpha = int64_t{a16} << 8;
      const int64_t r = y - ((alpha * d + 2048) >> 12);
      cost[a16] += std::log2(1.0 + static_cast<double>(r < 0 ? -r : r));
    }
  }
  int best = 0;
  for (int a16 = 1; a16 < 25; ++a16)
    if (cost[a16] < cost[best]) best = a16;
  return best << 8;
}

// fit_alpha by its SSE2 sums and by its AVX2 sums (where the processor has
// it; else the SSE2 sums again): the same weight, else -1.
int32_t fit_both(const Samples& s) {
  const int32_t narrow = tsm::fit_alpha(s, false), wide = tsm::fit_alpha(s, true);
  return narrow == wide ? narrow : -1;
}

// y near alpha * d for a random alpha in 0 .. 1.5, plus noise of the
// given size: the weights' costs are close, as on a scan.
Samples make_samples(std::mt19937_64& rng, size_t n, int64_t dmax, int64_t noise) {
  std::uniform_int_distribution<int64_t> dd(-dmax, dmax), nn(-noise, noise);
  std::uniform_real_distribution<double> aa(0.0, 1.5);
  const double alpha = aa(rng);
  Samples s(n);
  for (auto& [d, y] : s) {
    d = dd(rng);
    y = static_cast<int64_t>(std::llround(alpha * static_cast<double>(d))) + nn(rng);
  }
  return s;
}

TEST(EncoderSpeed, FitAlphaPicksThePlainSumsWeight) {
  std::mt19937_64 rng(37);
  int cases = 0;
  // Small residuals (the table), residuals across the table's end (4096),
  // far beyond it (the slow path), and each mixed in one sample set.
  const std::pair<int64_t, int64_t> regimes[] = {{40, 3},      {300, 40},          {3000, 200},    {6000, 3000},
                                                 {4000, 4100}, {1 << 20, 1 << 12}, {1 << 28, 100}, {5461, 0}};
  for (auto [dmax, noise] : regimes)
    for (size_t n : {size_t{1}, size_t{7}, size_t{100}, size_t{5000}}) {
      const Samples s = make_samples(rng, n, dmax, noise);
      EXPECT_EQ(fit_both(s), plain_fit_alpha(s)) << "dmax " << dmax << " noise " << noise << " n " << n;
      ++cases;
    }
  Samples mixed;
  for (auto [dmax, noise] : regimes) {
    const Samples s = make_samples(rng, 3000, dmax, noise);
    mixed.insert(mixed.end(), s.begin(), s.end());
  }
  EXPECT_EQ(fit_both(mixed), plain_fit_alpha(mixed));
  // More samples than the stride's 200,000: every second one is summed.
  const Samples many = make_samples(rng, 450001, 500, 60);
  EXPECT_EQ(fit_both(many), plain_fit_alpha(many));
  EXPECT_EQ(cases, 32);
}

// A set where two weights cost exactly the same: the first (smaller)
// weight wins, as in the plain sums.
TEST(EncoderSpeed, FitAlphaTieKeepsTheSmallerWeight) {
  const Samples zero_d(50, {0, 5});  // every weight predicts 0: all costs equal
  EXPECT_EQ(fit_both(zero_d), 0);
  EXPECT_EQ(plain_fit_alpha(zero_d), 0);
  const Samples exact = {{16, 16}, {-32, -32}, {160, 160}};  // alpha 1.0 exactly
  EXPECT_EQ(fit_both(exact), 1 << 12);
  EXPECT_EQ(plain_fit_alpha(exact), 1 << 12);
}

// find_anchors by its definition: per vertex on no triangle, the surface
// vertex nearest to it (squared distance, then smaller id) among those
// whose cell of 2^shift steps is at most one cell away on every axis, else
// at most two; the cells as find_anchors sizes them.
std::vector<uint32_t> plain_anchors(const tsm::GeometryLayout& g, const std::vector<uint32_t>& q, int bits) {
  const uint32_t n = g.vertex_count;
  std::vector<uint32_t> anchor(n, tsm::kNone);
  std::vector<uint8_t> on(n, 0);
  for (uint32_t v : g.corner) on[v] = 1;
  uint32_t surface = 0;
  for (uint8_t x : on) surface += x;
  if (surface == 0 || surface == n) return anchor;
  int shift = bits - static_cast<int>(std::log2(std::sqrt(static_cast<double>(surface)) + 1.0));
  shift = std::clamp(shift, std::max(0, bits - 20), 30);
  for (uint32_t v = 0; v < n; ++v) {
    if (on[v]) continue;
    for (int64_t reach = 1; reach <= 2 && anchor[v] == tsm::kNone; ++reach) {
      uint64_t best = UINT64_MAX;
      for (uint32_t u = 0; u < n; ++u) {
        if (!on[u]) continue;
        uint64_t d = 0;
        bool near = true;
        for (int a = 0; a < 3; ++a) {
          const int64_t x = q[3 * size_t{v} + a], y = q[3 * size_t{u} + a];
          near = near && std::abs((x >> shift) - (y >> shift)) <= reach;
          d += static_cast<uint64_t>((x - y) * (x - y));
        }
        if (near && d < best) best = d, anchor[v] = u;
      }
    }
  }
  return anchor;
}

// Random surface triangles and points off the surface, some near it,
// some two cells away and some far from every cell of it: with a few off-surface points (the scan
// path) and with many (the sorted cells), with ties on distance.
TEST(EncoderSpeed, FindAnchorsPicksTheNearestWithinTwoCells) {
  std::mt19937_64 rng(371);
  int checked = 0;
  for (uint32_t off : {1u, 3u, 8u, 9u, 40u})
    for (int bits : {6, 11, 14}) {
      const uint32_t surface = 600, n = surface + off;
      const uint32_t qmax = (1u << bits) - 1;
      std::uniform_int_distribution<uint32_t> coord(0, qmax), jitter(0, 3);
      std::vector<uint32_t> q(3 * size_t{n});
      // The surface on the lower half of x, the points off it anywhere:
      // some with no surface cell near, some with one only two cells away.
      for (uint32_t& x : q) x = coord(rng);
      for (uint32_t v = 0; v < surface; ++v) q[3 * size_t{v}] /= 2;
      // Off-surface points 0..off-1 at the end: half of them beside a
      // surface vertex (a tie when the jitter is 0 and two coincide).
      for (uint32_t k = 0; k < off; k += 2)
        for (int a = 0; a < 3; ++a)
          q[3 * size_t{surface + k} + a] = std::min(qmax, q[3 * size_t{k % 7} + a] + jitter(rng));
      for (int a = 0; a < 3; ++a) q[3 * size_t{5} + a] = q[3 * size_t{2} + a];  // two surface vertices coincide
      tsm::GeometryLayout g;
      g.vertex_count = n;
      for (uint32_t v = 0; v < surface; ++v) g.corner.push_back(v);
      g.twin.assign(g.corner.size(), tsm::kNone);
      const std::vector<uint32_t> got = tsm::find_anchors(g, q, bits), want = plain_anchors(g, q, bits);
      EXPECT_EQ(got, want) << "off " << off << " bits " << bits;
      checked += std::count_if(want.begin(), want.end(), [](uint32_t a) { return a != tsm::kNone; }) > 0;
    }
  EXPECT_EQ(checked, 15);
}

// find_lattice as first written: per axis the values sorted, counted by
// runs, the planes those used at least median + 6 sqrt(median) + 4 times,
// dropped when they hold under a third of the coordinates or number more
// than one per eight vertices.
tsm::Lattice plain_lattice(const std::vector<uint32_t>& q, uint32_t n) {
  tsm::Lattice out;
  for (int a = 0; a < 3; ++a) {
    std::vector<uint32_t> vals(n);
    for (uint32_t v = 0; v < n; ++v) vals[v] = q[3 * size_t{v} + a];
    std::sort(vals.begin(), vals.end());
    std::vector<std::pair<uint32_t, uint32_t>> runs;
    for (size_t i = 0, j; i < vals.size(); i = j) {
      for (j = i; j < vals.size() && vals[j] == vals[i];) ++j;
      runs.push_back({vals[i], static_cast<uint32_t>(j - i)});
    }
    if (runs.empty()) continue;
    std::vector<uint32_t> counts;
    for (auto [value, count] : runs) counts.push_back(count);
    std::sort(counts.begin(), counts.end());
    const double median = counts[counts.size() / 2];
    size_t covered = 0;
    for (auto [value, count] : runs)
      if (count >= median + 6.0 * std::sqrt(median) + 4.0) out.values[a].push_back(value), covered += count;
    if (3 * covered < n || 8 * out.values[a].size() > n) out.values[a].clear();
  }
  return out;
}

// Scan-like coordinates with a few planes that many vertices share, over
// ranges below and above 8 values per vertex (find_lattice counts the
// former in a table and sorts the latter).
TEST(EncoderSpeed, FindLatticeCountsAsItSorts) {
  std::mt19937_64 rng(372);
  int with_planes = 0, cases = 0;
  for (uint32_t n : {1u, 40u, 3000u})
    for (uint32_t range : {4u, 1000u, 30000u, 1u << 22})
      for (int planes : {0, 3, 20}) {
        std::uniform_int_distribution<uint32_t> coord(0, range - 1), pick(0, 2);
        std::vector<uint32_t> plane_at(static_cast<size_t>(planes));
        for (uint32_t& x : plane_at) x = coord(rng);
        std::vector<uint32_t> q(3 * size_t{n});
        for (size_t i = 0; i < q.size(); ++i)
          q[i] = planes && i % 3 != 1 && pick(rng) ? plane_at[coord(rng) % plane_at.size()] : coord(rng);
        const tsm::Lattice got = tsm::find_lattice(q, n), want = plain_lattice(q, n);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(got.values[a], want.values[a]) << "n " << n << " range " << range;
        with_planes += !want.values[0].empty();
        ++cases;
      }
  EXPECT_EQ(cases, 36);
  EXPECT_GE(with_planes, 4);
}

// The tangent step's samples on a jittered sphere with holes cut in it
// and points off it (some with an anchor, tangent set 1): as gathered by
// the first coding pass, and by fit_betas' own pass with the step on, for
// the parallelogram and spread predictors, with and without planes.
// With CutHints::streams false and the streams coded afterwards, the
// encoding is the one coded at once: on a surface with stitches (shared
// vertices), and on one with polygons and degenerate faces (whose streams
// are coded at once anyway).
TEST(EncoderSpeed, StreamsCodedLaterAreTheSame) {
  tsm::Mesh stitched = tsm_test::icosphere(2);
  for (uint32_t f = 0; f < 6; ++f) {  // the first faces again, reversed: edges of four uses
    const uint32_t* c = stitched.face(f);
    const uint32_t r[3] = {c[0], c[2], c[1]};
    stitched.add_face(r, 3);
  }
  tsm::Mesh mixed = tsm_test::icosphere(2);
  const uint32_t quad[4] = {0, 1, 2, 3}, degenerate[3] = {4, 4, 5};
  mixed.add_face(quad, 4);
  mixed.add_face(degenerate, 3);
  for (const tsm::Mesh* m : {&stitched, &mixed}) {
    tsm::ConnectivityEncoding now, later;
    ASSERT_TRUE(tsm::encode_connectivity(*m, now).ok());
    if (m == &stitched) {
      EXPECT_GT(now.stats.stitches, 0u);
    } else {
      EXPECT_GT(now.stats.polygons * now.stats.side_faces, 0u);
    }
    tsm::CutHints hints;
    hints.streams = false;
    ASSERT_TRUE(tsm::encode_connectivity(*m, later, hints).ok());
    EXPECT_EQ(later.vertex_order, now.vertex_order);
    EXPECT_EQ(later.layout.corners(), now.layout.corners());
    ASSERT_TRUE(tsm::code_connectivity_streams(later).ok());
    EXPECT_FALSE(later.pending);
    EXPECT_EQ(later.streams.vertex_tree, now.streams.vertex_tree);
    EXPECT_EQ(later.streams.triangle_tree, now.streams.triangle_tree);
    EXPECT_EQ(later.streams.topology, now.streams.topology);
    EXPECT_EQ(later.distance_topology, now.distance_topology);
    EXPECT_EQ(later.stats.vertex_runs, now.stats.vertex_runs);
    EXPECT_EQ(later.stats.bytes, now.stats.bytes);
  }
}

TEST(EncoderSpeed, TangentSamplesGatheredOnTheFirstPass) {
  tsm::Mesh m = tsm_test::jittered(tsm_test::icosphere(4), 0.02f, 5);
  // Holes: every 7th face dropped.
  tsm::Mesh cut;
  cut.positions = m.positions;
  for (uint32_t f = 0; f < m.face_count(); ++f)
    if (f % 7 != 3) cut.add_face(m.face(f), 3);
  const uint32_t surface = static_cast<uint32_t>(cut.vertex_count());
  for (uint32_t k = 0; k < 6; ++k)  // points off the surface, near vertex 11 k
    for (int a = 0; a < 3; ++a) cut.positions.push_back(m.positions[3 * size_t{11 * k} + a] * 1.05f);
  const int bits = 12;
  std::vector<uint32_t> qin(cut.positions.size());
  for (size_t i = 0; i < qin.size(); ++i)
    qin[i] = static_cast<uint32_t>(std::lround((cut.positions[i] + 1.2) / 2.4 * ((1 << bits) - 1)));
  tsm::ConnectivityEncoding ce;
  ASSERT_TRUE(tsm::encode_connectivity(cut, ce).ok());
  tsm::GeometryLayout& g = ce.layout;
  std::vector<uint32_t> q(3 * size_t{g.vertex_count}), out_of(cut.vertex_count());
  for (uint32_t v = 0; v < g.vertex_count; ++v) {
    out_of[ce.vertex_order[v]] = v;
    for (int a = 0; a < 3; ++a) q[3 * size_t{v} + a] = qin[3 * size_t{ce.vertex_order[v]} + a];
  }
  for (uint32_t k = 0; k < 6; k += 2) g.anchor[out_of[surface + k]] = out_of[11 * k];  // half of them anchored
  tsm::Lattice planes;
  planes.values[1] = {100, 2000, 4000};
  const int32_t weights[2][3] = {{4096, 4096, 4096}, {2600, 3100, 2900}};
  int sets = 0;
  for (tsm::Predictor pred : {tsm::Predictor::parallelograms, tsm::Predictor::spread})
    for (const tsm::Lattice& lattice : {tsm::Lattice(), planes})
      for (const auto& w : weights) {
        std::array<std::vector<std::pair<int64_t, int64_t>>, 2> own, gathered;
        tsm::tangent_samples_both_ways(g, q, bits, pred, lattice, w, own, gathered);
        EXPECT_EQ(own[0], gathered[0]);
        EXPECT_EQ(own[1], gathered[1]);
        EXPECT_GT(own[0].size(), 500u);
        EXPECT_GE(own[1].size(), 1u);
        ++sets;
      }
  EXPECT_EQ(sets, 8);
}

// A sphere with holes, and components that share vertices with it (no
// edges: those pair by position) listed before it, so that in the input
// their copies of the shared vertices come first: tetrahedra on one or two
// sphere vertices and new ones, and double-sided triangles on three sphere
// vertices only (every vertex an earlier component's). Coding the decoded
// mesh must give back the same faces: the fixed point after one round.
TEST(EncoderSpeed, SharedVertexComponentsSettleInOneRound) {
  const tsm::Mesh sphere = tsm_test::icosphere(2);
  tsm::Mesh m;
  m.positions = sphere.positions;
  const uint32_t nv = static_cast<uint32_t>(sphere.vertex_count());
  auto add = [&](std::initializer_list<uint32_t> c) { m.add_face(std::data(c), c.size()); };
  auto fresh = [&](float x) {
    for (int a = 0; a < 3; ++a) m.positions.push_back(x + 0.1f * static_cast<float>(a));
    return static_cast<uint32_t>(m.vertex_count() - 1);
  };
  // Sphere vertices far apart (no edge between any two of them).
  const uint32_t far[] = {3, 17, 29, 40, 11, 36};
  for (int k = 0; k < 3; ++k) {  // tetrahedra on sphere vertex far[k] (and far[k + 3] for k = 0)
    const uint32_t a = far[k], b = fresh(2.0f + static_cast<float>(k)), c = fresh(3.0f + static_cast<float>(k)),
                   d = k == 0 ? far[3] : fresh(4.0f + static_cast<float>(k));
    add({a, b, c});
    add({a, c, d});
    add({a, d, b});
    add({b, d, c});
  }
  add({far[4], far[5], far[1]});  // double-sided, on sphere vertices only
  add({far[4], far[1], far[5]});
  for (uint32_t f = 0; f < sphere.face_count(); ++f)
    if (f % 9 != 4) m.add_face(sphere.face(f), 3);  // holes
  for (uint32_t i = 0; i + 1 < 6; ++i)
    for (uint32_t j = i + 1; j < 6; ++j)
      for (uint32_t f = 0; f < sphere.face_count(); ++f) {
        const uint32_t* c = sphere.face(f);
        int hits = 0;
        for (int e = 0; e < 3; ++e) hits += c[e] == far[i] || c[e] == far[j];
        ASSERT_LT(hits, 2) << "sphere vertices " << far[i] << " and " << far[j] << " share an edge";
      }
  ASSERT_GT(m.vertex_count(), nv);
  tsm::Mesh decoded[2];
  const tsm::Mesh* coded = &m;
  for (tsm::Mesh& d : decoded) {
    tsm::ConnectivityEncoding ce;
    ASSERT_TRUE(tsm::encode_connectivity(*coded, ce).ok());
    EXPECT_GT(ce.stats.stitches, 0u);
    tsm::GeometryLayout scratch;
    ASSERT_TRUE(tsm::decode_connectivity(ce.streams, coded->vertex_count(), coded->face_count(), coded->corner_count(),
                                         d, scratch)
                    .ok());
    d.positions.assign(m.positions.size(), 0.0f);
    coded = &d;
  }
  EXPECT_EQ(decoded[1].indices, decoded[0].indices);
  EXPECT_EQ(decoded[1].face_offsets, decoded[0].face_offsets);
}

}  // namespace
