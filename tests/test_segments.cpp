// Segments and streaming: a
// mesh coded as several segments decodes to the same mesh, whole or fed in
// any chunks, with the first segment's triangles out before the last bytes
// are in; the bytes do not depend on the thread count.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <random>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

using namespace tsm;
using namespace tsm_test;

namespace {

std::string encode_ok(const Mesh& m, uint32_t segment_faces, int q = 14, int threads = 1, int level = kDefaultLevel) {
  EncodeOptions eo;
  eo.quantization_bits = q;
  eo.segment_faces = segment_faces;
  eo.threads = threads;
  eo.level = level;
  std::string bytes;
  Status s = encode(m, eo, bytes);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return bytes;
}

uint32_t segments_of(const std::string& bytes) {
  FileInfo fi;
  EXPECT_TRUE(inspect(bytes, fi).ok());
  return fi.segment_count;
}

void expect_same_mesh(const Mesh& a, const Mesh& b, const std::string& what) {
  EXPECT_EQ(a.positions, b.positions) << what;
  EXPECT_EQ(a.face_offsets, b.face_offsets) << what;
  EXPECT_EQ(a.indices, b.indices) << what;
}

// Feeds `bytes` in chunks from `next_size`; checks each step's mesh is a
// prefix-closed growth (faces only use vertices already out).
Mesh stream_decode(const std::string& bytes, const std::function<size_t()>& next_size, size_t* first_out_at = nullptr) {
  StreamDecoder sd;
  size_t at = 0, faces = 0;
  if (first_out_at) *first_out_at = SIZE_MAX;
  while (at < bytes.size()) {
    size_t n = std::min(next_size(), bytes.size() - at);
    Status s = sd.feed(std::string_view(bytes).substr(at, n));
    EXPECT_TRUE(s.ok()) << s.to_string();
    if (!s.ok()) return Mesh();
    at += n;
    const Mesh& m = sd.mesh();
    EXPECT_GE(m.face_count(), faces);
    if (m.face_count() != faces) {  // a segment came out: its faces use vertices already out
      for (size_t c = m.face_offsets[faces]; c < m.indices.size(); ++c) {
        EXPECT_LT(m.indices[c], m.vertex_count());
      }
    }
    faces = m.face_count();
    if (first_out_at && faces > 0 && *first_out_at == SIZE_MAX) *first_out_at = at;
  }
  Status s = sd.finish();
  EXPECT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(sd.done());
  return sd.take_mesh();
}

void expect_segmented_round_trip(const Mesh& m, uint32_t segment_faces, const std::string& what, int q = 14) {
  const std::string bytes = encode_ok(m, segment_faces, q);
  Mesh back;
  Status s = decode(bytes, back);
  ASSERT_TRUE(s.ok()) << what << ": " << s.to_string();
  CompareResult r = compare_meshes(m, back, q);
  EXPECT_TRUE(r.equal) << what << ": " << r.difference;
  EXPECT_LE(r.max_position_error, 0.5 + 1e-3) << what;
  // Two threads decode the same mesh; two threads encode the same bytes.
  DecodeOptions d2;
  d2.threads = 2;
  Mesh back2;
  ASSERT_TRUE(decode(bytes, back2, d2).ok()) << what;
  expect_same_mesh(back, back2, what + " (2 decode threads)");
  EXPECT_TRUE(encode_ok(m, segment_faces, q, 2) == bytes) << what << ": bytes depend on the thread count";
  // Streamed whole and one byte at a time.
  expect_same_mesh(back, stream_decode(bytes, [&] { return bytes.size(); }), what + " (streamed whole)");
  expect_same_mesh(back, stream_decode(bytes, [] { return size_t{1}; }), what + " (streamed byte by byte)");
  // Canonical: the decoded mesh encodes to the same bytes (segments number
  // their vertices by position and their faces by corners, not by input id).
  EXPECT_TRUE(encode_ok(back, segment_faces, q) == bytes) << what << ": re-encoding gives other bytes";
}

}  // namespace

TEST(Segments, SmallMeshesStayOneSegment) {
  EXPECT_EQ(segments_of(encode_ok(icosphere(3), 0)), 1u);
  EXPECT_EQ(segments_of(encode_ok(icosphere(3), 1280)), 1u);
  EXPECT_EQ(segments_of(encode_ok(icosphere(3), 1279)), 2u);
}

TEST(Segments, RoundTripOfEveryFamilyInSmallSegments) {
  expect_segmented_round_trip(icosphere(4), 300, "icosphere 4 / 300");
  // Under the sanitizers the many-segment cases use a smaller sphere: each
  // segment's coders map and poison their models afresh, which took minutes.
  const int small = tsm_test::kSanitized ? 2 : 3;
  expect_segmented_round_trip(icosphere(small), 7, "icosphere / 7");
  for (int g = 1; g <= 5; ++g)
    if (!tsm_test::sanitized_skip(static_cast<size_t>(g), 1))  // genus 1, 3, 5 there
      expect_segmented_round_trip(genus_surface(g, 3), 100, "genus " + std::to_string(g));
  expect_segmented_round_trip(grid_with_holes(30, 12), 150, "grid with holes");
  expect_segmented_round_trip(fan(40, true), 5, "closed fan");
  expect_segmented_round_trip(strip(100), 16, "strip");
  expect_segmented_round_trip(moebius(24), 10, "moebius");
  expect_segmented_round_trip(book(10), 3, "book of 10 pages");
  expect_segmented_round_trip(flipped_face_sphere(3), 200, "flipped faces");
  expect_segmented_round_trip(cube_quads(), 2, "quads");
  expect_segmented_round_trip(copies(icosphere(2), 20), 100, "20 spheres");
  expect_segmented_round_trip(random_soup(300, 500, 7), 60, "random soup");
  expect_segmented_round_trip(icosphere(small - 1), 1, "one face per segment");
}

TEST(Segments, UnreferencedVerticesAndDegenerateFaces) {
  Mesh m = icosphere(3);
  for (int i = 0; i < 50; ++i) m.add_vertex(0.01f * static_cast<float>(i), 2.0f, -0.5f * static_cast<float>(i));  // on no face
  const uint32_t a = 3, b = 7;
  const uint32_t degenerate[3] = {a, a, b};
  m.add_face(degenerate, 3);
  const uint32_t pair[2] = {a, b};
  m.add_face(pair, 2);
  expect_segmented_round_trip(m, 100, "unreferenced and degenerate");
}

TEST(Segments, RandomMeshesProperty) {
  std::mt19937 rng(20261122u);
  for (int i = 0; i < tsm_test::property_runs(60); ++i) {
    Mesh m;
    switch (i % 4) {
      case 0: m = random_soup(20 + static_cast<int>(rng() % 200), 10 + static_cast<int>(rng() % 300), static_cast<uint32_t>(rng())); break;
      case 1: m = genus_surface(static_cast<int>(rng() % 4), 2); break;
      case 2: m = grid_with_holes(8 + static_cast<int>(rng() % 20), static_cast<int>(rng() % 6)); break;
      default: m = copies(icosphere(1 + static_cast<int>(rng() % 2)), 1 + static_cast<int>(rng() % 6)); break;
    }
    const uint32_t seg = 1 + static_cast<uint32_t>(rng() % 200);
    const int q = 8 + static_cast<int>(rng() % 12);
    const std::string what = "random mesh " + std::to_string(i) + " / " + std::to_string(seg);
    const std::string bytes = encode_ok(m, seg, q);
    Mesh back;
    Status s = decode(bytes, back);
    ASSERT_TRUE(s.ok()) << what << ": " << s.to_string();
    CompareResult r = compare_meshes(m, back, q);
    EXPECT_TRUE(r.equal) << what << ": " << r.difference;
    EXPECT_TRUE(encode_ok(back, seg, q) == bytes) << what << ": re-encoding gives other bytes";
    std::uniform_int_distribution<size_t> chunk(1, 97);
    expect_same_mesh(back, stream_decode(bytes, [&] { return chunk(rng); }), what + " (random chunks)");
  }
}

TEST(Segments, FirstTrianglesComeOutBeforeTheLastBytes) {
  const Mesh m = icosphere(5);  // 20,480 faces
  const std::string bytes = encode_ok(m, 2048);
  ASSERT_GE(segments_of(bytes), 8u);
  size_t first = 0;
  Mesh back = stream_decode(bytes, [] { return size_t{512}; }, &first);
  EXPECT_LT(first, bytes.size() / 4) << "first triangles after " << first << " of " << bytes.size() << " bytes";
  EXPECT_EQ(back.face_count(), m.face_count());
}

TEST(Segments, SharedVerticesAreCodedOnce) {
  const Mesh m = icosphere(5);
  FileInfo fi;
  const std::string bytes = encode_ok(m, 2048);
  ASSERT_TRUE(inspect(bytes, fi).ok());
  uint64_t vertices = 0, faces = 0;
  for (const SegmentSummary& s : fi.segments) {
    vertices += s.vertices - s.references;
    faces += s.faces;
  }
  EXPECT_EQ(vertices, m.vertex_count());
  EXPECT_EQ(faces, m.face_count());
  EXPECT_GT(fi.references, 0u);
  EXPECT_EQ(fi.segments.size(), fi.segment_count);
  // What segments cost: every segment learns its models afresh and its
  // border vertices lose parallelograms. Bounded here, measured in the bench.
  const double whole = static_cast<double>(encode_ok(m, 0).size());
  EXPECT_LT(static_cast<double>(encode_ok(m, 8192).size()), 1.10 * whole);
  EXPECT_LT(static_cast<double>(bytes.size()), 1.45 * whole);  // 10 segments of ~1,000 vertices
}

TEST(Segments, StreamErrors) {
  const std::string bytes = encode_ok(icosphere(4), 500);
  {  // truncated: finish() says so; the finished segments stay readable
    StreamDecoder sd;
    ASSERT_TRUE(sd.feed(std::string_view(bytes).substr(0, bytes.size() - 10)).ok());
    EXPECT_GT(sd.segments_done(), 0u);
    EXPECT_LT(sd.segments_done(), sd.segment_count());
    Status s = sd.finish();
    EXPECT_EQ(s.code(), ErrorCode::corrupt_data);
    EXPECT_NE(s.message().find("end"), std::string::npos) << s.message();
  }
  {  // damaged: the error sticks
    std::string bad = bytes;
    bad[bad.size() / 2] ^= 0x10;
    StreamDecoder sd;
    Status s = sd.feed(bad);
    EXPECT_FALSE(s.ok());
    EXPECT_FALSE(sd.feed("x").ok());
    EXPECT_FALSE(sd.finish().ok());
  }
  {  // bytes after the end
    StreamDecoder sd;
    ASSERT_TRUE(sd.feed(bytes).ok());
    EXPECT_FALSE(sd.feed("x").ok());
  }
  {  // not a tsm file: refused from the first byte
    StreamDecoder sd;
    EXPECT_EQ(sd.feed("P").code(), ErrorCode::corrupt_data);
  }
  {  // the caller's limits apply as soon as the header is in
    DecodeOptions d;
    d.max_vertices = 10;
    StreamDecoder sd(d);
    EXPECT_EQ(sd.feed(std::string_view(bytes).substr(0, 64)).code(), ErrorCode::limit_exceeded);
  }
}

TEST(Segments, EveryTruncationOfASegmentedFileIsAnError) {
  const std::string bytes = encode_ok(icosphere(2), 60);
  ASSERT_GE(segments_of(bytes), 4u);
  for (size_t n = 0; n < bytes.size(); ++n) {
    Mesh back;
    EXPECT_FALSE(decode(bytes.substr(0, n), back).ok()) << n;
    StreamDecoder sd;
    Status s = sd.feed(bytes.substr(0, n));
    if (s.ok()) s = sd.finish();
    EXPECT_FALSE(s.ok()) << n;
  }
}

TEST(Segments, CApiStreams) {
  const Mesh m = icosphere(4);
  const std::string bytes = encode_ok(m, 700);
  Mesh whole;
  ASSERT_TRUE(decode(bytes, whole).ok());
  tsm_stream* s = tsm_stream_new(nullptr);
  ASSERT_NE(s, nullptr);
  char err[256];
  size_t last_faces = 0;
  for (size_t at = 0; at < bytes.size(); at += 100) {
    const size_t n = std::min<size_t>(100, bytes.size() - at);
    ASSERT_EQ(tsm_stream_feed(s, reinterpret_cast<const uint8_t*>(bytes.data()) + at, n, err, sizeof err), TSM_OK)
        << err;
    const tsm_mesh* view = tsm_stream_mesh(s);
    EXPECT_GE(tsm_mesh_face_count(view), last_faces);
    last_faces = tsm_mesh_face_count(view);
  }
  ASSERT_EQ(tsm_stream_finish(s, err, sizeof err), TSM_OK) << err;
  EXPECT_EQ(tsm_stream_segments_done(s), tsm_stream_segment_count(s));
  const tsm_mesh* view = tsm_stream_mesh(s);
  ASSERT_EQ(tsm_mesh_vertex_count(view), whole.vertex_count());
  ASSERT_EQ(tsm_mesh_index_count(view), whole.corner_count());
  EXPECT_TRUE(std::equal(whole.indices.begin(), whole.indices.end(), tsm_mesh_indices(view)));
  EXPECT_TRUE(std::equal(whole.positions.begin(), whole.positions.end(), tsm_mesh_positions(view)));
  tsm_stream_free(s);
  // A truncated stream fails at finish with a message.
  s = tsm_stream_new(nullptr);
  ASSERT_EQ(tsm_stream_feed(s, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size() / 2, err, sizeof err),
            TSM_OK);
  EXPECT_EQ(tsm_stream_finish(s, err, sizeof err), TSM_CORRUPT_DATA);
  EXPECT_GT(std::strlen(err), 0u);
  tsm_stream_free(s);
}

TEST(Segments, CorpusDragonInSegments) {
  TSM_REQUIRE_CORPUS();
  Mesh m;
  ASSERT_TRUE(read_mesh(corpus_file("dragon_vrip_res3.ply"), m).ok());
  const std::string bytes = encode_ok(m, 4000, 11, 2);
  EXPECT_GE(segments_of(bytes), 8u);
  Mesh back;
  ASSERT_TRUE(decode(bytes, back).ok());
  EXPECT_TRUE(compare_meshes(m, back, 11).equal);
  EXPECT_TRUE(encode_ok(back, 4000, 11, 2) == bytes) << "res3 in segments: re-encoding gives other bytes";
  std::mt19937 rng(3);
  std::uniform_int_distribution<size_t> chunk(1, 5000);
  expect_same_mesh(back, stream_decode(bytes, [&] { return chunk(rng); }), "res3 random chunks");
}

// The test: encoded corpus meshes fed one byte at a time, in random
// chunks and whole give the same mesh, and the first segment's triangles
// come out before the last bytes went in.
TEST(Segments, CorpusMeshesStreamedByteByByteInChunksAndWhole) {
  TSM_REQUIRE_CORPUS();
  for (const char* name : {"bun_zipper.ply", "dragon_vrip_res4.ply"}) {
    Mesh m;
    ASSERT_TRUE(read_mesh(corpus_file(name), m).ok()) << name;
    const std::string bytes = encode_ok(m, static_cast<uint32_t>(m.face_count() / 6), 14, 2);
    ASSERT_GE(segments_of(bytes), 6u) << name;
    Mesh whole;
    ASSERT_TRUE(decode(bytes, whole).ok()) << name;
    EXPECT_TRUE(compare_meshes(m, whole, 14).equal) << name;
    size_t first = 0;
    expect_same_mesh(whole, stream_decode(bytes, [] { return size_t{1}; }, &first), std::string(name) + " byte by byte");
    EXPECT_LT(first, bytes.size() / 3) << name << ": first triangles after " << first << " of " << bytes.size();
    std::mt19937 rng(5);
    std::uniform_int_distribution<size_t> chunk(1, 4096);
    expect_same_mesh(whole, stream_decode(bytes, [&] { return chunk(rng); }), std::string(name) + " random chunks");
    expect_same_mesh(whole, stream_decode(bytes, [&] { return bytes.size(); }), std::string(name) + " whole");
  }
}
