// The encoder's faster steps keep its choices: fit_alpha (geometry_predict.cpp),
// whose SSE2 and AVX2 paths must pick the weight that one sum per weight over
// the samples in order picks, whatever the samples (inside the log table,
// across its end, far outside it, more than its sampling stride);
// find_anchors, whose scan for a few vertices off the surface must pick
// the anchor its sorted cells pick.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "connectivity.hpp"
#include "geometry_predict.hpp"

namespace tsm {
int32_t fit_alpha(const std::vector<std::pair<int64_t, int64_t>>& samples, bool wide);
}

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

}  // namespace
