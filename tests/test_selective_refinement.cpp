// Selective refinement of a progressive file (seed 003): refined everywhere
// it is the full mesh exactly, coarsened everywhere the base, refined by
// batches the decoder's levels; any predicate gives a valid mesh, and
// illegal single steps are refused.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <utility>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/selective_refinement.hpp"
#include "tsm/tsm.hpp"

namespace {
using namespace tsm_test;

std::string encode_progressive(const tsm::Mesh& m) {
  tsm::EncodeOptions o;
  o.progressive = true;
  o.threads = 1;
  std::string bytes;
  tsm::Status s = tsm::encode(m, o, bytes);
  EXPECT_TRUE(s.ok()) << s.message();
  return bytes;
}

void expect_same(const tsm::Mesh& a, const tsm::Mesh& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.indices, b.indices);
}

// Every face has distinct corners, every directed edge occurs once, and (a
// closed input) its reverse too; returns V - E + F.
long euler_of_valid_surface(const tsm::Mesh& m, bool closed) {
  std::string why;
  EXPECT_TRUE(m.valid(&why)) << why;
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    const uint32_t n = m.face_size(f);
    for (uint32_t k = 0; k < n; ++k) {
      for (uint32_t j = k + 1; j < n; ++j) EXPECT_NE(c[k], c[j]) << "face " << f;
      const int uses = ++edges[std::make_pair(c[k], c[(k + 1) % n])];
      EXPECT_EQ(uses, 1) << "directed edge " << c[k] << "-" << c[(k + 1) % n] << " twice";
    }
  }
  size_t undirected = 0;
  for (const auto& e : edges) {
    const bool twin = edges.count({e.first.second, e.first.first}) != 0;
    if (closed) {
      EXPECT_TRUE(twin) << "edge " << e.first.first << "-" << e.first.second << " on a hole";
    }
    undirected += twin ? (e.first.first < e.first.second ? 1 : 0) : 1;
  }
  std::vector<uint8_t> used(m.vertex_count(), 0);
  for (uint32_t v : m.indices) used[v] = 1;
  for (size_t v = 0; v < used.size(); ++v) EXPECT_TRUE(used[v]) << "vertex " << v << " on no face";
  return static_cast<long>(m.vertex_count()) - static_cast<long>(undirected) + static_cast<long>(m.face_count());
}

struct Built {
  std::string bytes;
  tsm::ProgressiveHierarchy h;
};

void build(Built& b, const tsm::Mesh& m) {
  b.bytes = encode_progressive(m);
  tsm::Status s = b.h.build(b.bytes);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_GT(b.h.batch_count(), 2u);
}

}  // namespace

TEST(SelectiveRefinement, RefinedEverywhereIsTheFullMeshCoarsenedTheBase) {
  Built b;
  build(b, icosphere(5));
  if (HasFatalFailure()) return;
  tsm::Mesh full, base;
  ASSERT_TRUE(tsm::decode(b.bytes, full).ok());
  tsm::PartialOptions p;
  p.max_error = 1e30;  // the first level: the base
  tsm::PartialReport r;
  ASSERT_TRUE(tsm::decode_partial(b.bytes, base, p, &r).ok());
  ASSERT_EQ(r.batches, 0u);

  EXPECT_EQ(b.h.applied_count(), b.h.split_count());
  expect_same(b.h.current_mesh(), full);
  b.h.adapt([](const tsm::SplitView&) { return false; });
  EXPECT_EQ(b.h.applied_count(), 0u);
  expect_same(b.h.current_mesh(), base);
  b.h.adapt([](const tsm::SplitView&) { return true; });
  expect_same(b.h.current_mesh(), full);
  EXPECT_EQ(b.h.split_count(), full.vertex_count() - base.vertex_count());
}

TEST(SelectiveRefinement, RefinedByBatchesGivesTheDecodersLevels) {
  Built b;
  build(b, genus_surface(1, 4));
  if (HasFatalFailure()) return;
  tsm::StreamDecoder dec;
  dec.stop_at_levels(true);
  ASSERT_TRUE(dec.feed(b.bytes).ok());
  uint32_t seen = 0, last = ~0u;
  for (;;) {
    if (dec.progressive() && dec.batches_done() != last) {
      const uint32_t k = last = dec.batches_done();
      b.h.adapt([k](const tsm::SplitView& s) { return s.batch < k; });
      expect_same(b.h.current_mesh(), dec.mesh());
      ++seen;
    }
    if (!dec.level_pending()) break;
    ASSERT_TRUE(dec.feed({}).ok());
  }
  ASSERT_TRUE(dec.finish().ok());
  EXPECT_EQ(seen, b.h.batch_count() + 1);
}

TEST(SelectiveRefinement, HalfSpaceHasDetailOnlyThere) {
  Built b;
  build(b, icosphere(5));  // unit sphere around the origin
  if (HasFatalFailure()) return;
  tsm::Mesh full;
  ASSERT_TRUE(tsm::decode(b.bytes, full).ok());
  b.h.adapt([](const tsm::SplitView& s) { return s.position[0] > 0; });
  const tsm::Mesh& m = b.h.current_mesh();
  EXPECT_EQ(euler_of_valid_surface(m, true), 2);
  const std::vector<uint32_t>& ids = b.h.current_vertex_ids();
  ASSERT_EQ(ids.size(), m.vertex_count());
  std::vector<uint8_t> active(full.vertex_count(), 0);
  for (uint32_t v : ids) active[v] = 1;
  size_t far_in = 0, far_in_active = 0, far_out = 0, far_out_active = 0;
  for (uint32_t v = 0; v < full.vertex_count(); ++v) {
    const float x = full.positions[3 * size_t{v}];
    if (x > 0.2f) far_in++, far_in_active += active[v];
    if (x < -0.2f) far_out++, far_out_active += active[v];
  }
  // Inside, the full detail (but for children on the other side of their parent: none this far in).
  EXPECT_EQ(far_in_active, far_in);
  // Outside, about the base's density.
  EXPECT_LT(far_out_active * 4, far_out) << far_out_active << " of " << far_out;
  EXPECT_LT(m.vertex_count(), full.vertex_count() * 3 / 4);
  EXPECT_GT(m.vertex_count(), full.vertex_count() / 3);
}

TEST(SelectiveRefinement, AnyPredicateGivesAValidMesh) {
  for (int kind = 0; kind < 2; ++kind) {
    Built b;
    build(b, kind == 0 ? genus_surface(2, 3) : grid_with_holes(30, 3));
    if (HasFatalFailure()) return;
    const bool closed = kind == 0;
    tsm::Mesh full;
    ASSERT_TRUE(tsm::decode(b.bytes, full).ok());
    const long euler = euler_of_valid_surface(full, closed);
    EXPECT_EQ(euler, -2);  // genus 2; a disk with 3 holes
    std::mt19937 rng(7);
    for (int trial = 0; trial < 12; ++trial) {
      const double p = (trial % 4 + 1) / 5.0;
      std::vector<uint8_t> want(b.h.split_count());
      for (auto& w : want) w = std::bernoulli_distribution(p)(rng) ? 1 : 0;
      b.h.adapt([&](const tsm::SplitView& s) { return want[s.index] != 0; });
      for (uint32_t s = 0; s < b.h.split_count(); ++s) {
        if (want[s]) {
          EXPECT_TRUE(b.h.applied(s)) << "split " << s << " asked for";
        }
        if (b.h.applied(s)) {
          for (uint32_t d : b.h.dependencies(s)) EXPECT_TRUE(b.h.applied(d));
        }
      }
      EXPECT_EQ(euler_of_valid_surface(b.h.current_mesh(), closed), euler) << "kind " << kind << " trial " << trial;
      if (HasFailure()) return;
    }
  }
}

TEST(SelectiveRefinement, IllegalStepsAreRefused) {
  Built b;
  build(b, icosphere(4));
  if (HasFatalFailure()) return;
  // A split with a dependency: from the full mesh its dependency cannot be undone first.
  uint32_t s = 0;
  while (s < b.h.split_count() && b.h.dependencies(s).empty()) ++s;
  ASSERT_LT(s, b.h.split_count());
  const uint32_t d = b.h.dependencies(s).back();
  tsm::Status st = b.h.coarsen(d);
  EXPECT_EQ(st.code(), tsm::ErrorCode::invalid_argument);
  EXPECT_TRUE(contains(st.message(), "cannot be undone")) << st.message();
  // From the base, s cannot come before d; in dependency order it can.
  b.h.adapt([](const tsm::SplitView&) { return false; });
  st = b.h.refine(s);
  EXPECT_EQ(st.code(), tsm::ErrorCode::invalid_argument);
  EXPECT_TRUE(contains(st.message(), "needs split")) << st.message();
  EXPECT_FALSE(b.h.applied(s));
  std::vector<uint32_t> order;
  std::vector<uint8_t> seen(b.h.split_count(), 0);
  std::function<void(uint32_t)> visit = [&](uint32_t x) {
    if (seen[x]) return;
    seen[x] = 1;
    for (uint32_t y : b.h.dependencies(x)) visit(y);
    order.push_back(x);
  };
  visit(s);
  for (uint32_t x : order) ASSERT_TRUE(b.h.refine(x).ok()) << x;
  EXPECT_TRUE(b.h.applied(s));
  EXPECT_EQ(euler_of_valid_surface(b.h.current_mesh(), true), 2);
  // Undone in reverse order: the base again.
  for (size_t i = order.size(); i-- > 0;) ASSERT_TRUE(b.h.coarsen(order[i]).ok()) << order[i];
  EXPECT_EQ(b.h.applied_count(), 0u);
  EXPECT_EQ(b.h.refine(b.h.split_count()).code(), tsm::ErrorCode::invalid_argument);

  // A single-rate file has no hierarchy.
  std::string single;
  ASSERT_TRUE(tsm::encode(icosphere(3), tsm::EncodeOptions{}, single).ok());
  tsm::ProgressiveHierarchy h;
  st = h.build(single);
  EXPECT_EQ(st.code(), tsm::ErrorCode::invalid_argument);
  EXPECT_TRUE(contains(st.message(), "--progressive")) << st.message();
  // A damaged one: the decoder's error.
  std::string bad = b.bytes;
  bad[bad.size() / 2] ^= 0x40;
  EXPECT_FALSE(h.build(bad).ok());
}
