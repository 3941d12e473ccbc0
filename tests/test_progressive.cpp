// Progressive files (FORMAT.md §4.8): the full file decodes to the input,
// every prefix holding the base decodes to a level of detail, levels grow
// batch by batch, and hostile refinement bytes are refused.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "container.hpp"
#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {
using namespace tsm_test;

std::string encode_progressive(const tsm::Mesh& m) {
  tsm::EncodeOptions o;
  o.progressive = true;
  std::string bytes;
  tsm::Status s = tsm::encode(m, o, bytes);
  EXPECT_TRUE(s.ok()) << s.message();
  return bytes;
}

void expect_round_trip(const tsm::Mesh& m, size_t min_batches) {
  const std::string bytes = encode_progressive(m);
  tsm::Mesh back;
  tsm::Status s = tsm::decode(bytes, back);
  ASSERT_TRUE(s.ok()) << s.message();
  const tsm::CompareResult c = tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits);
  EXPECT_TRUE(c.equal) << c.difference;
  // Canonical re-encoding: the decoded mesh (the decoder's vertex and face
  // order) encodes to the same bytes.
  const std::string again = encode_progressive(back);
  EXPECT_EQ(again.size(), bytes.size());
  EXPECT_TRUE(again == bytes) << "decode then encode changed the file";
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  EXPECT_GE(fi.batches.size(), min_batches);
  if (!fi.batches.empty()) {
    // Vertices no face uses come after the batches (but for one on the box).
    EXPECT_LE(fi.batches.back().vertices, m.vertex_count());
    EXPECT_GE(fi.batches.back().vertices + m.unreferenced_vertex_count(), m.vertex_count());
    // Faces the levels leave out (a repeat, a third at an edge) come last.
    EXPECT_EQ(fi.batches.back().faces + fi.loose_faces, m.face_count());
    EXPECT_LT(fi.vertex_count, m.vertex_count());
  }
}

tsm::Mesh merged(const tsm::Mesh& a, const tsm::Mesh& b) {
  tsm::Mesh m = a;
  const uint32_t n = static_cast<uint32_t>(a.vertex_count());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (size_t f = 0; f < b.face_count(); ++f) {
    std::vector<uint32_t> c(b.face(f), b.face(f) + b.face_size(f));
    for (uint32_t& x : c) x += n;
    m.add_face(c.data(), c.size());
  }
  return m;
}

TEST(Progressive, RoundTripSphere) { expect_round_trip(icosphere(5), 5); }
TEST(Progressive, RoundTripTorus) { expect_round_trip(genus_surface(1, 4), 3); }
TEST(Progressive, RoundTripGridWithHoles) { expect_round_trip(irregular_grid(40, 7), 1); }
TEST(Progressive, RoundTripHolesAndNonManifold) {
  // A book (pages on one edge) beside a jittered sphere, and a grid with holes.
  expect_round_trip(merged(merged(book(5), jittered(icosphere(4), 0.01f, 3)), grid_with_holes(24, 3)), 3);
}
TEST(Progressive, RoundTripPolygonsStayInTheBase) { expect_round_trip(merged(cube_quads(), icosphere(4)), 3); }

TEST(Progressive, VertexAndFaceOrderDoNotChangeTheFile) {
  // The plan depends on grid points and faces only: shuffled vertex ids,
  // face order and corner rotations give the same bytes.
  const tsm::Mesh m = icosphere(4);  // symmetric: many collapses cost the same
  const size_t n = m.vertex_count();
  std::mt19937 rng(7);
  std::vector<uint32_t> perm(n);
  for (uint32_t i = 0; i < n; ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  tsm::Mesh s;
  s.positions.resize(3 * n);
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) s.positions[3 * size_t{perm[i]} + a] = m.positions[3 * i + a];
  std::vector<size_t> faces(m.face_count());
  for (size_t f = 0; f < faces.size(); ++f) faces[f] = f;
  std::shuffle(faces.begin(), faces.end(), rng);
  for (size_t f : faces) {
    const uint32_t* c = m.face(f);
    const uint32_t r = static_cast<uint32_t>(rng() % 3);
    s.add_triangle(perm[c[r]], perm[c[(r + 1) % 3]], perm[c[(r + 2) % 3]]);
  }
  const std::string a = encode_progressive(m), b = encode_progressive(s);
  EXPECT_GT(a.size(), 0u);
  EXPECT_TRUE(a == b) << a.size() << " vs " << b.size() << " bytes";
}

TEST(Progressive, LooseVerticesAfterTheBatches) {
  tsm::Mesh m = icosphere(4);
  for (int i = 0; i < 20; ++i) m.add_vertex(0.1f * static_cast<float>(i % 7), 0.05f * static_cast<float>(i), 0.3f);
  const std::string bytes = encode_progressive(m);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  bool loose = false;
  for (const tsm::SectionInfo& s : fi.sections) loose = loose || s.name == "loose";
  EXPECT_TRUE(loose);
  expect_round_trip(m, 3);
}

// A scan's vertices no face uses lie near its surface: each is coded from
// its nearest level vertex (its anchor), in that vertex's tangent frame, so
// it costs under 24 bits (about 20 here), which its grid index alone (on
// two axes spread over the whole grid) would not.
TEST(Progressive, LooseVerticesNearTheSurfaceAreCheap) {
  tsm::Mesh m = icosphere(4);
  const size_t n = m.vertex_count();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.002f, 0.002f);
  size_t added = 0;
  for (size_t i = 0; i < n; i += 4, ++added)
    m.add_vertex(m.positions[3 * i] + jitter(rng), m.positions[3 * i + 1] + jitter(rng),
                 m.positions[3 * i + 2] + jitter(rng));
  const std::string bytes = encode_progressive(m);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  uint64_t loose = 0;
  for (const tsm::SectionInfo& s : fi.sections)
    if (s.name == "loose") loose = s.stored_bytes;
  ASSERT_GT(loose, 0u);
  EXPECT_LT(loose * 8, added * 24) << loose << " bytes for " << added << " loose vertices";
  expect_round_trip(m, 3);
}

TEST(Progressive, AttributesAreRefusedWithAReason) {
  tsm::Mesh m = icosphere(2);
  tsm::Attribute a;
  a.name = "intensity";
  a.values.assign(m.vertex_count(), 1.0f);
  m.attributes.push_back(a);
  tsm::EncodeOptions o;
  o.progressive = true;
  std::string bytes;
  tsm::Status s = tsm::encode(m, o, bytes);
  EXPECT_EQ(s.code(), tsm::ErrorCode::unsupported);
  EXPECT_TRUE(tsm_test::contains(s.message(), "attribute"));
}

TEST(Progressive, StreamGrowsBatchByBatch) {
  const tsm::Mesh m = jittered(icosphere(5), 0.02f, 11);
  const std::string bytes = encode_progressive(m);
  tsm::StreamDecoder sd;
  std::vector<size_t> faces;  // after each feed that applied a batch (one feed may apply several)
  uint32_t batches = 0;
  for (size_t at = 0; at < bytes.size(); at += 97) {
    ASSERT_TRUE(sd.feed(std::string_view(bytes).substr(at, 97)).ok());
    if (sd.batches_done() > batches) {
      batches = sd.batches_done();
      std::string why;
      ASSERT_TRUE(sd.mesh().valid(&why)) << why;
      faces.push_back(sd.mesh().face_count());
    }
  }
  ASSERT_TRUE(sd.finish().ok());
  ASSERT_GE(faces.size(), 3u);
  for (size_t k = 1; k < faces.size(); ++k) EXPECT_GT(faces[k], faces[k - 1]);
  EXPECT_TRUE(tsm::compare_meshes(m, sd.mesh(), tsm::kDefaultQuantizationBits).equal);
}

TEST(Progressive, PrefixesDecodeToGrowingLevels) {
  const tsm::Mesh m = jittered(icosphere(5), 0.02f, 5);
  const std::string bytes = encode_progressive(m);
  size_t last_faces = 0;
  bool base_seen = false;
  for (size_t cut = 0; cut <= bytes.size(); cut += 211) {
    tsm::Mesh level;
    tsm::PartialReport rep;
    tsm::Status s = tsm::decode_partial(std::string_view(bytes).substr(0, cut), level, {}, &rep);
    if (!s.ok()) {
      EXPECT_FALSE(base_seen) << "a longer prefix failed after a shorter one decoded: " << s.message();
      continue;
    }
    base_seen = true;
    std::string why;
    ASSERT_TRUE(level.valid(&why)) << why;
    EXPECT_GE(level.face_count(), last_faces);
    EXPECT_FALSE(rep.complete);
    last_faces = level.face_count();
  }
  EXPECT_TRUE(base_seen);
  tsm::Mesh full;
  tsm::PartialReport rep;
  ASSERT_TRUE(tsm::decode_partial(bytes, full, {}, &rep).ok());
  EXPECT_TRUE(rep.complete);
  EXPECT_EQ(full.face_count(), m.face_count());
}

// The border loops of a triangle mesh (edges no face has the other way
// round), or -1 when a vertex has several border edges leaving it.
int border_loops(const tsm::Mesh& m, size_t* border_vertices) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t k = 0; k < 3; ++k) ++directed[{m.face(f)[k], m.face(f)[(k + 1) % 3]}];
  std::map<uint32_t, uint32_t> next;
  for (const auto& e : directed)
    if (!directed.count({e.first.second, e.first.first}) && !next.emplace(e.first.first, e.first.second).second)
      return -1;
  *border_vertices = next.size();
  int loops = 0;
  std::set<uint32_t> seen;
  for (const auto& e : next) {
    if (seen.count(e.first)) continue;
    ++loops;
    for (uint32_t v = e.first; seen.insert(v).second;) {
      auto it = next.find(v);
      if (it == next.end()) return -1;
      v = it->second;
    }
  }
  return loops;
}

TEST(Progressive, BordersCoarsenAndHolesStay) {
  const tsm::Mesh m = jittered(grid_with_holes(40, 3), 0.005f, 11);
  size_t input_border = 0, border = 0;
  const int loops = border_loops(m, &input_border);
  ASSERT_GE(loops, 4);  // the outline and the holes
  const std::string bytes = encode_progressive(m);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  ASSERT_FALSE(fi.batches.empty());
  // Every level has the input's borders: none closed, opened or pinched.
  size_t levels = 0, base_border = 0;
  for (size_t cut = 0; cut <= bytes.size(); cut += 97) {
    tsm::Mesh level;
    if (!tsm::decode_partial(std::string_view(bytes).substr(0, cut), level, {}, nullptr).ok()) continue;
    EXPECT_EQ(border_loops(level, &border), loops) << "at byte " << cut;
    if (levels++ == 0) base_border = border;
  }
  EXPECT_GE(levels, 3u);
  // The borders are coarsened too (they stayed whole in the base before).
  EXPECT_LT(base_border * 3, input_border);
  expect_round_trip(m, 3);
}

TEST(Progressive, RepeatedAndFinFacesWaitForTheLooseSection) {
  // A sphere whose faces are all there twice (once reversed: a zero-thickness
  // sheet), some three times, and fins on some edges: no vertex has a fan,
  // so without the loose section's faces the whole mesh would be the base.
  const tsm::Mesh sphere = jittered(icosphere(4), 0.01f, 5);
  tsm::Mesh m = double_sided(sphere);
  size_t extra = sphere.face_count();
  for (size_t f = 0; f < sphere.face_count(); f += 9, ++extra)
    m.add_triangle(sphere.face(f)[0], sphere.face(f)[1], sphere.face(f)[2]);
  for (size_t f = 4; f < sphere.face_count(); f += 13, ++extra) {
    const uint32_t* c = sphere.face(f);
    const uint32_t tip = static_cast<uint32_t>(m.vertex_count());
    float p[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[a] += 0.5f * sphere.positions[3 * size_t{c[k]} + a];
    m.add_vertex(p[0], p[1], p[2]);  // outside the sphere, over the face
    m.add_triangle(c[1], c[0], tip);
  }
  const std::string bytes = encode_progressive(m);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  ASSERT_FALSE(fi.batches.empty());
  EXPECT_EQ(fi.loose_faces, extra);
  EXPECT_LT(fi.vertex_count * 4, sphere.vertex_count());
  // The levels are the sphere without its repeats and fins.
  EXPECT_EQ(fi.batches.back().faces, sphere.face_count());
  expect_round_trip(m, 3);
}

TEST(Progressive, StopsAtMaxBytesAndMaxError) {
  const tsm::Mesh m = jittered(icosphere(5), 0.02f, 9);
  const std::string bytes = encode_progressive(m);
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  ASSERT_GE(fi.batches.size(), 3u);
  const size_t k = fi.batches.size() / 2;
  tsm::PartialOptions po;
  po.max_error = fi.batches[k].error;
  tsm::Mesh level;
  tsm::PartialReport rep;
  ASSERT_TRUE(tsm::decode_partial(bytes, level, po, &rep).ok());
  EXPECT_LE(rep.error, po.max_error);
  EXPECT_LE(rep.batches, k + 1);
  EXPECT_LT(level.face_count(), m.face_count());
  tsm::PartialOptions pb;
  pb.max_bytes = bytes.size() / 2;
  ASSERT_TRUE(tsm::decode_partial(bytes, level, pb, &rep).ok());
  EXPECT_LE(rep.bytes_used, pb.max_bytes);
  EXPECT_GT(rep.batches, 0u);
  EXPECT_LT(level.face_count(), m.face_count());
}

// Refinement sections with valid framing and checksums but random or
// mutated payloads: refused or decoded, never a crash or hang.
TEST(Progressive, HostileRefinementsAreRefused) {
  const tsm::Mesh m = icosphere(4);
  const std::string bytes = encode_progressive(m);
  tsm::Header h;
  std::vector<tsm::Section> sections;
  ASSERT_TRUE(tsm::read_container(bytes, h, sections).ok());
  std::string base;
  size_t first_refinement = 0;
  for (const tsm::Section& s : sections)
    if (s.id == tsm::kSectionRefinement) {
      first_refinement = s.offset;
      break;
    }
  ASSERT_GT(first_refinement, 0u);
  std::mt19937 rng(7);
  int refused = 0;
  for (int run = 0; run < tsm_test::property_runs(300); ++run) {
    std::string file = bytes.substr(0, first_refinement);
    for (const tsm::Section& s : sections) {
      if (s.id != tsm::kSectionRefinement) continue;
      std::string payload = s.data;
      if (run % 2) {
        payload = tsm_test::random_bytes(rng, rng() % 64);
      } else {
        for (int k = 0; k < 3 && !payload.empty(); ++k)
          payload[rng() % payload.size()] ^= static_cast<char>(1 + rng() % 255);
      }
      tsm::append_raw_section(file, tsm::kSectionRefinement, payload);
    }
    file += std::string(2, '\0');
    tsm::Mesh out;
    tsm::DecodeOptions o;
    o.max_vertices = 1u << 20;
    tsm::Status s = tsm::decode(file, out, o);
    if (!s.ok()) {
      ++refused;
      EXPECT_TRUE(s.code() == tsm::ErrorCode::corrupt_data || s.code() == tsm::ErrorCode::limit_exceeded)
          << s.message();
    } else {
      std::string why;
      EXPECT_TRUE(out.valid(&why)) << why;
    }
  }
  EXPECT_GT(refused, 0);
}

TEST(Progressive, CorpusBunnyRoundTrip) {
  if (tsm_test::kSanitized) GTEST_SKIP() << "the full bunny is for the plain build";
  TSM_REQUIRE_CORPUS();
  tsm::Mesh m;
  ASSERT_TRUE(tsm::read_mesh(tsm_test::corpus_file("bun_zipper.ply"), m).ok());
  m.attributes.clear();
  expect_round_trip(m, 10);
}

}  // namespace
