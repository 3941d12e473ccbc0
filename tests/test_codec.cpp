// tsm::encode / tsm::decode / tsm::inspect through the public API only: round
// trips over every generated family, option and argument errors, and hostile
// input (truncation, corruption, forged headers, caller limits).
//
// The section layout will change when the Topological Surgery streams land;
// these tests only rely on the container header (format-spec/FORMAT.md), which
// stays.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::ErrorCode;
using tsm::Mesh;

struct Named {
  const char* name;
  Mesh mesh;
};

Mesh point_set(int n) {
  Mesh m;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> d(-5, 7);
  for (int i = 0; i < n; ++i) m.add_vertex(d(rng), d(rng), d(rng));
  return m;
}

std::vector<Named> families() {
  std::vector<Named> out;
  out.push_back({"icosphere(3)", tsm_test::icosphere(3)});
  out.push_back({"genus_surface(2)", tsm_test::genus_surface(2)});
  out.push_back({"grid_with_holes(12,3)", tsm_test::grid_with_holes(12, 3)});
  out.push_back({"fan(9,open)", tsm_test::fan(9, false)});
  out.push_back({"fan(9,closed)", tsm_test::fan(9, true)});
  out.push_back({"strip(21)", tsm_test::strip(21)});
  out.push_back({"moebius(16)", tsm_test::moebius(16)});
  out.push_back({"book(5)", tsm_test::book(5)});
  out.push_back({"bowtie", tsm_test::bowtie()});
  out.push_back({"flipped_face_sphere(2)", tsm_test::flipped_face_sphere(2)});
  out.push_back({"random_soup(300,500)", tsm_test::random_soup(300, 500, 17)});
  out.push_back({"cube_quads", tsm_test::cube_quads()});
  out.push_back({"ngon(11)", tsm_test::ngon(11)});
  out.push_back({"copies(icosphere(1),4)", tsm_test::copies(tsm_test::icosphere(1), 4)});
  out.push_back({"copies(cube_quads,3)", tsm_test::copies(tsm_test::cube_quads(), 3)});
  out.push_back({"empty", Mesh()});
  out.push_back({"point_set(50)", point_set(50)});
  Mesh one;
  one.add_vertex(1.5f, -2.0f, 3.25f);
  out.push_back({"single_point", one});
  return out;
}

// The largest position error a correct codec can have, in grid steps: half a
// step for the quantization, plus the rounding of the dequantized value
// (computed in double) to the nearest float, at most half a float ulp of the
// largest coordinate magnitude.
double error_bound(const Mesh& original, const Mesh& decoded, int q) {
  tsm::Grid g = tsm::Grid::for_mesh(original, q);
  if (g.step <= 0) return 0.5 + 1e-6;
  float big = 0;
  for (const Mesh* m : {&original, &decoded})
    for (float x : m->positions) big = std::max(big, std::fabs(x));
  double half_ulp = 0.5 * static_cast<double>(std::nextafter(big, std::numeric_limits<float>::infinity()) - big);
  return 0.5 + half_ulp / g.step + 1e-6;
}

std::string encode_ok(const Mesh& m, int q = 14, int level = 6) {
  std::string bytes;
  tsm::Status s = tsm::encode(m, tsm::EncodeOptions{q, level}, bytes);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return bytes;
}

// --- Round trips ----------------------------------------------------------

TEST(Codec, RoundTripEveryFamily) {
  for (const Named& n : families()) {
    for (int q : {1, 8, 14, 30}) {
      for (int level : {0, 9}) {
        if (tsm_test::sanitized_skip(q == 1 || q == 14, level == 9)) continue;
        SCOPED_TRACE(std::string(n.name) + " q=" + std::to_string(q) + " level=" + std::to_string(level));
        std::string bytes;
        tsm::Status s = tsm::encode(n.mesh, tsm::EncodeOptions{q, level}, bytes);
        ASSERT_TRUE(s.ok()) << s.to_string();
        Mesh back;
        s = tsm::decode(bytes, back);
        ASSERT_TRUE(s.ok()) << s.to_string();
        EXPECT_TRUE(back.valid());
        EXPECT_TRUE(back.all_finite());
        tsm::CompareResult r = tsm::compare_meshes(n.mesh, back, q);
        EXPECT_TRUE(r.equal) << r.difference;
        EXPECT_LE(r.max_position_error, error_bound(n.mesh, back, q));
      }
    }
  }
}

TEST(Codec, RoundTripDefaultOptionsAndAllLevels) {
  Mesh m = tsm_test::genus_surface(1);
  Mesh first;
  for (int level = 0; level <= 9; ++level) {
    std::string bytes = encode_ok(m, tsm::kDefaultQuantizationBits, level);
    Mesh back;
    ASSERT_TRUE(tsm::decode(bytes, back).ok());
    EXPECT_TRUE(tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits).equal) << "level " << level;
    // The level trades size for speed; the decoded mesh is the same.
    if (level == 0) first = back;
    EXPECT_EQ(back.positions, first.positions) << "level " << level;
    EXPECT_EQ(back.indices, first.indices) << "level " << level;
    EXPECT_EQ(back.face_offsets, first.face_offsets) << "level " << level;
  }
  std::string bytes;
  ASSERT_TRUE(tsm::encode(m, tsm::EncodeOptions{}, bytes).ok());
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  EXPECT_EQ(fi.quantization_bits, tsm::kDefaultQuantizationBits);
  EXPECT_EQ(fi.level, tsm::kDefaultLevel);
}

// A mesh whose bounding box is nearly a cube: on an axis shorter than the
// extent, the float nearest the last grid point could lie just past origin
// + extent, so the decoded mesh had a larger extent and coding it again took
// another grid (a jittered sphere at 12 bits drifted on every re-encoding).
// The decoder keeps every coordinate within origin + extent (FORMAT.md §5).
TEST(Codec, CanonicalWhenAShorterAxisNearlyReachesTheExtent) {
  int checked = 0;
  for (uint32_t seed = 1; seed <= 12; ++seed)
    for (int q : {8, 12, 16}) {
      const Mesh m = tsm_test::jittered(tsm_test::icosphere(3), 0.0002f, seed);
      const std::string bytes = encode_ok(m, q, 0);
      Mesh back;
      ASSERT_TRUE(tsm::decode(bytes, back).ok());
      // The decoded mesh has the extent it was coded with (the largest
      // axis's ends decode exactly; no other axis may end beyond them).
      auto extent = [](const Mesh& x) {
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, e = 0;
        for (size_t i = 0; i < x.positions.size(); ++i) {
          lo[i % 3] = std::min(lo[i % 3], static_cast<double>(x.positions[i]));
          hi[i % 3] = std::max(hi[i % 3], static_cast<double>(x.positions[i]));
        }
        for (int a = 0; a < 3; ++a) e = std::max(e, hi[a] - lo[a]);
        return e;
      };
      EXPECT_EQ(extent(back), extent(m)) << "seed " << seed << " q " << q;
      EXPECT_TRUE(encode_ok(back, q, 0) == bytes) << "seed " << seed << " q " << q;
      ++checked;
    }
  EXPECT_EQ(checked, 36);
}

// A minimum of -0 (a position coordinate, a texture coordinate) decodes
// as +0 (origin + 0 x step): the encoder takes +0 as the origin, so the
// decoded mesh re-encodes to the same bytes.
TEST(Codec, CanonicalWithNegativeZeroMinimum) {
  Mesh m = tsm_test::icosphere(1);
  for (size_t i = 0; i < m.positions.size(); ++i)
    m.positions[i] = m.positions[i] <= 0 ? -0.0f : m.positions[i];  // every minimum a -0
  tsm::Attribute uv;
  uv.name = "texcoord";
  uv.kind = tsm::AttributeKind::texcoord;
  uv.components = 2;
  for (size_t v = 0; v < m.vertex_count(); ++v)
    uv.values.insert(uv.values.end(), {v % 3 ? 0.25f * static_cast<float>(v % 5) : -0.0f, 0.5f});
  m.attributes = {uv};
  for (int level : {0, 6}) {
    const std::string bytes = encode_ok(m, 12, level);
    Mesh back;
    ASSERT_TRUE(tsm::decode(bytes, back).ok());
    EXPECT_TRUE(encode_ok(back, 12, level) == bytes) << "level " << level;
  }
}

TEST(Codec, RoundTripAwkwardCoordinates) {
  // Extents that are not exact in float, far from the origin, tiny and huge.
  std::vector<Named> cases;
  Mesh far = tsm_test::icosphere(2);
  for (size_t i = 0; i < far.positions.size(); i += 3) far.positions[i] = far.positions[i] * 0.37f + 1000.3f;
  cases.push_back({"far from origin", far});
  Mesh tiny = tsm_test::random_soup(100, 150, 5);
  for (float& x : tiny.positions) x *= 1e-30f;
  cases.push_back({"tiny", tiny});
  Mesh huge = tsm_test::random_soup(100, 150, 6);
  for (float& x : huge.positions) x *= 1e37f;
  cases.push_back({"huge", huge});
  Mesh flat = tsm_test::grid_with_holes(8, 1);  // zero extent on one axis
  cases.push_back({"flat", flat});
  Mesh line;
  for (int i = 0; i < 10; ++i) line.add_vertex(0.1f * static_cast<float>(i), 0.3f, -0.2f);
  line.add_triangle(0, 5, 9);
  cases.push_back({"collinear", line});
  Mesh same;
  for (int i = 0; i < 4; ++i) same.add_vertex(0.25f, 0.5f, 0.75f);
  same.add_triangle(0, 1, 2);
  same.add_triangle(3, 2, 1);
  cases.push_back({"all coincident", same});
  // max - min (1.01405269...) is not a float; rounded to the nearest float it
  // is smaller than the true extent, so the vertex at max x lands one grid
  // point beyond the last (2^q - 1) for q >= 24 unless the grid allows for it.
  Mesh rounded;
  rounded.add_vertex(-0x1.e3f482p-1f, 0.0f, 0.0f);  // -0.945224822
  rounded.add_vertex(0x1.19eb4p-4f, 0.0f, 0.0f);    // 0.0688278675
  rounded.add_vertex(0x1.19eb4p-4f, 0.5f, 0.0f);
  rounded.add_triangle(0, 1, 2);
  cases.push_back({"extent rounds down in float", rounded});
  // The whole float range: the extent (2 * FLT_MAX) is only finite in double.
  const float fmax = std::numeric_limits<float>::max();
  Mesh range;
  range.add_vertex(-fmax, 0.0f, 1.0f);
  range.add_vertex(fmax, -fmax, 0.0f);
  range.add_vertex(0.0f, fmax, -3e38f);
  range.add_vertex(1e-30f, 1.0f, fmax);
  range.add_triangle(0, 1, 2);
  range.add_triangle(0, 2, 3);
  cases.push_back({"whole float range", range});
  // One axis near the top of the float range with a smaller extent than the
  // largest: its grid points run past FLT_MAX.
  Mesh high;
  high.add_vertex(0.0f, 0.0f, 3e38f);
  high.add_vertex(3.4e38f, 0.0f, 3.4e38f);
  high.add_vertex(0.0f, 1.0f, 3.4e38f);
  high.add_triangle(0, 1, 2);
  cases.push_back({"near FLT_MAX", high});
  // Refusing a mesh up front would be allowed (invalid_argument), accepting
  // it and writing a file that does not decode to it is not; and every one
  // of these is in fact accepted at every q (counted, so that an encoder
  // that refused them all would not pass).
  std::vector<std::string> refused;
  size_t accepted = 0;
  for (const Named& n : cases)
    for (int q : {1, 4, 8, 14, 24, 27, 30}) {
      SCOPED_TRACE(std::string(n.name) + " q=" + std::to_string(q));
      std::string bytes;
      tsm::Status s = tsm::encode(n.mesh, tsm::EncodeOptions{q, 6}, bytes);
      if (!s.ok()) {
        EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << s.to_string();
        refused.push_back(std::string(n.name) + " q=" + std::to_string(q));
        continue;
      }
      ++accepted;
      Mesh back;
      s = tsm::decode(bytes, back);
      if (!s.ok()) {
        ADD_FAILURE() << "the encoder's output does not decode: " << s.to_string();
        continue;
      }
      EXPECT_TRUE(back.all_finite());
      tsm::CompareResult r = tsm::compare_meshes(n.mesh, back, q);
      EXPECT_TRUE(r.equal) << r.difference;
      EXPECT_LE(r.max_position_error, error_bound(n.mesh, back, q));
    }
  std::string list;
  for (const std::string& r : refused) list += "\n  " + r;
  EXPECT_EQ(accepted, 7 * cases.size()) << "refused:" << list;
  EXPECT_EQ(cases.size(), 9u);
}

TEST(Codec, EmptyAndPointSetOnly) {
  Mesh empty;
  std::string bytes = encode_ok(empty);
  EXPECT_FALSE(bytes.empty());
  Mesh back = tsm_test::icosphere(1);  // decode must clear what was there
  ASSERT_TRUE(tsm::decode(bytes, back).ok());
  EXPECT_EQ(back.vertex_count(), 0u);
  EXPECT_EQ(back.face_count(), 0u);
  EXPECT_TRUE(back.valid());

  Mesh pts = point_set(40);
  bytes = encode_ok(pts, 12);
  ASSERT_TRUE(tsm::decode(bytes, back).ok());
  EXPECT_EQ(back.vertex_count(), 40u);
  EXPECT_EQ(back.face_count(), 0u);
  EXPECT_TRUE(tsm::compare_meshes(pts, back, 12).equal);
}

TEST(Codec, Deterministic) {
  const std::vector<Named> all = families();
  for (size_t i = 0; i < all.size(); ++i) {
    if (tsm_test::sanitized_skip(i, 0)) continue;
    const Named& n = all[i];
    std::string a = encode_ok(n.mesh, 11, 9);
    Mesh copy = n.mesh;
    std::string b = encode_ok(copy, 11, 9);
    EXPECT_EQ(a, b) << n.name;
  }
}

TEST(Codec, InspectReportsHeader) {
  Mesh m = tsm_test::copies(tsm_test::cube_quads(), 2);
  std::string bytes = encode_ok(m, 10, 3);
  tsm::FileInfo fi;
  tsm::Status s = tsm::inspect(bytes, fi);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(fi.format_version, 12u);
  EXPECT_EQ(fi.vertex_count, m.vertex_count());
  EXPECT_EQ(fi.face_count, m.face_count());
  EXPECT_EQ(fi.corner_count, m.corner_count());
  EXPECT_EQ(fi.quantization_bits, 10);
  EXPECT_EQ(fi.level, 3);
  EXPECT_EQ(fi.segment_count, 1u);
  EXPECT_EQ(fi.file_bytes, bytes.size());
  tsm::BoundingBox box = tsm::bounding_box(m);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(fi.bbox_min[a], box.min[a]);
  EXPECT_DOUBLE_EQ(fi.step, static_cast<double>(box.largest_extent()) / 1023.0);
  ASSERT_FALSE(fi.sections.empty());
  uint64_t stored = 0;
  for (const tsm::SectionInfo& si : fi.sections) {
    EXPECT_FALSE(si.name.empty());
    EXPECT_TRUE(si.codec == "raw" || si.codec == "zstd") << si.codec;
    if (si.codec == "raw") {
      EXPECT_EQ(si.raw_bytes, si.stored_bytes);
    }
    stored += si.stored_bytes;
  }
  EXPECT_LT(stored, bytes.size());
}

// --- Argument errors -------------------------------------------------------

TEST(Codec, InvalidOptionsRefused) {
  Mesh m = tsm_test::icosphere(1);
  std::string bytes = "untouched";
  for (int q : {-1, 0, 31, 64}) {
    tsm::Status s = tsm::encode(m, tsm::EncodeOptions{q, 6}, bytes);
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << "q=" << q;
    EXPECT_NE(s.message().find("quantization"), std::string::npos) << s.message();
  }
  for (int level : {-1, 10, 100}) {
    tsm::Status s = tsm::encode(m, tsm::EncodeOptions{14, level}, bytes);
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << "level=" << level;
    EXPECT_NE(s.message().find("level"), std::string::npos) << s.message();
  }
}

TEST(Codec, NonFinitePositionsRefused) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    Mesh m = tsm_test::icosphere(1);
    m.positions[7] = bad;
    std::string bytes;
    tsm::Status s = tsm::encode(m, tsm::EncodeOptions{}, bytes);
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << bad;
    EXPECT_FALSE(s.message().empty());
  }
  // Finite coordinates whose extent overflows a float: refused up front, or
  // an exact round trip.
  Mesh m;
  m.add_vertex(-3e38f, 0, 0);
  m.add_vertex(3e38f, 1e38f, 0);
  m.add_vertex(0, -2e38f, 3e38f);
  m.add_triangle(0, 1, 2);
  std::string bytes;
  tsm::Status s = tsm::encode(m, tsm::EncodeOptions{}, bytes);
  if (!s.ok()) {
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << s.to_string();
  } else {
    Mesh back;
    s = tsm::decode(bytes, back);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_TRUE(back.all_finite());
    auto r = tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits);
    EXPECT_TRUE(r.equal) << r.difference;
  }
}

TEST(Codec, InvalidMeshRefused) {
  std::string bytes;
  Mesh out_of_range = tsm_test::icosphere(1);
  out_of_range.indices[5] = static_cast<uint32_t>(out_of_range.vertex_count());
  EXPECT_EQ(tsm::encode(out_of_range, tsm::EncodeOptions{}, bytes).code(), ErrorCode::invalid_argument);

  Mesh ragged = tsm_test::icosphere(1);
  ragged.positions.push_back(1.0f);
  EXPECT_EQ(tsm::encode(ragged, tsm::EncodeOptions{}, bytes).code(), ErrorCode::invalid_argument);

  Mesh offsets = tsm_test::icosphere(1);
  offsets.face_offsets.back() += 1;
  EXPECT_EQ(tsm::encode(offsets, tsm::EncodeOptions{}, bytes).code(), ErrorCode::invalid_argument);

  Mesh start = tsm_test::icosphere(1);
  start.face_offsets[0] = 1;
  EXPECT_EQ(tsm::encode(start, tsm::EncodeOptions{}, bytes).code(), ErrorCode::invalid_argument);

  Mesh decreasing = tsm_test::cube_quads();
  std::swap(decreasing.face_offsets[2], decreasing.face_offsets[3]);
  EXPECT_EQ(tsm::encode(decreasing, tsm::EncodeOptions{}, bytes).code(), ErrorCode::invalid_argument);
}

TEST(Codec, FaceWithNoCornersRefusedOrRoundTrips) {
  // Mesh::valid() accepts a face with zero corners (equal offsets). The
  // encoder must either refuse it up front or give back a file that decodes.
  Mesh m = tsm_test::cube_quads();
  m.face_offsets.push_back(m.face_offsets.back());
  ASSERT_TRUE(m.valid());
  std::string bytes;
  tsm::Status s = tsm::encode(m, tsm::EncodeOptions{}, bytes);
  if (!s.ok()) {
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument) << s.to_string();
    return;
  }
  Mesh back;
  s = tsm::decode(bytes, back);
  ASSERT_TRUE(s.ok()) << "encode accepted an empty face but its output does not decode: " << s.to_string();
  auto r = tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits);
  EXPECT_TRUE(r.equal) << r.difference;
}

// --- Hostile input ---------------------------------------------------------

TEST(Codec, GarbageRefused) {
  Mesh back;
  EXPECT_EQ(tsm::decode("", back).code(), ErrorCode::corrupt_data);
  EXPECT_EQ(tsm::decode("ply\nformat ascii 1.0\n", back).code(), ErrorCode::corrupt_data);
  EXPECT_EQ(tsm::decode(std::string(100, '\0'), back).code(), ErrorCode::corrupt_data);
  tsm::FileInfo fi;
  EXPECT_EQ(tsm::inspect("TSM", fi).code(), ErrorCode::corrupt_data);
}

TEST(Codec, EveryTruncationRefused) {
  Mesh m = tsm_test::cube_quads();
  m.add_vertex(9, 9, 9);  // and an unreferenced vertex
  std::string bytes = encode_ok(m, 8, 6);
  ASSERT_LT(bytes.size(), 4096u);
  for (size_t n = 0; n < bytes.size(); ++n) {
    std::string cut = bytes.substr(0, n);
    Mesh back;
    tsm::Status s = tsm::decode(cut, back);
    EXPECT_FALSE(s.ok()) << "prefix of " << n << " of " << bytes.size() << " bytes decoded";
    EXPECT_FALSE(s.message().empty());
    tsm::FileInfo fi;
    EXPECT_FALSE(tsm::inspect(cut, fi).ok()) << "prefix " << n;
  }
  // Trailing bytes are refused as well.
  Mesh back;
  EXPECT_EQ(tsm::decode(bytes + '\0', back).code(), ErrorCode::corrupt_data);
  EXPECT_EQ(tsm::decode(bytes + bytes, back).code(), ErrorCode::corrupt_data);
  ASSERT_TRUE(tsm::decode(bytes, back).ok());
}

TEST(Codec, RandomSingleByteCorruptionNeverCrashes) {
  Mesh m = tsm_test::icosphere(2);
  std::string bytes = encode_ok(m, 12, 6);
  std::mt19937 rng(2024);
  std::uniform_int_distribution<size_t> at(0, bytes.size() - 1);
  std::uniform_int_distribution<int> flip(1, 255);
  int refused = 0;
  for (int i = 0; i < 2000; ++i) {
    std::string bad = bytes;
    size_t p = at(rng);
    bad[p] = static_cast<char>(static_cast<uint8_t>(bad[p]) ^ static_cast<uint8_t>(flip(rng)));
    Mesh back;
    tsm::Status s = tsm::decode(bad, back);
    if (s.ok()) {
      std::string why;
      EXPECT_TRUE(back.valid(&why)) << "byte " << p << ": decoded an invalid mesh: " << why;
    } else {
      ++refused;
      EXPECT_NE(s.code(), ErrorCode::internal) << s.message();
      EXPECT_FALSE(s.message().empty());
    }
    tsm::FileInfo fi;
    (void)tsm::inspect(bad, fi);
  }
  // Checksums (header and section payloads) and the length checks catch
  // nearly every change.
  EXPECT_GT(refused, 1900);
}

// An encoded file split into its header fields (format-spec/FORMAT.md §2-3)
// and its sections, so a test can change a header field and rebuild a file
// with a valid checksum (the first section's, which covers the header).
struct Parsed {
  uint64_t version = 0;
  uint64_t vertices = 0, faces = 0, corners = 0;
  uint8_t grid = 0, level = 0;  // grid: quantization bits | 0x20 exact | axis << 6; level | 0x10 segmented
  float origin[3] = {0, 0, 0};
  float top = 0;  // the bounding box's maximum on the grid byte's axis
  uint64_t segments = 0;
  std::string first;  // the first section up to its checksum
  std::string rest;   // everything after the first section's checksum
};

void put_varint(std::string& s, uint64_t v) {
  while (v >= 0x80) {
    s.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  s.push_back(static_cast<char>(v));
}
void put_le(std::string& s, uint64_t v, size_t n) {
  for (size_t i = 0; i < n; ++i) s.push_back(static_cast<char>(v >> (8 * i)));
}
uint64_t get_le(const std::string& s, size_t& p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(s.at(p + i))) << (8 * i);
  p += n;
  return v;
}
uint64_t get_varint(const std::string& s, size_t& p) {
  uint64_t v = 0;
  for (int shift = 0;; shift += 7) {
    uint8_t b = static_cast<uint8_t>(s.at(p++));
    v |= static_cast<uint64_t>(b & 0x7f) << shift;
    if (!(b & 0x80)) return v;
  }
}
float get_f32(const std::string& s, size_t& p) {
  const uint32_t b = static_cast<uint32_t>(get_le(s, p, 4));
  float f;
  std::memcpy(&f, &b, 4);
  return f;
}
void put_f32(std::string& s, float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  put_le(s, b, 4);
}

Parsed parse(const std::string& file) {
  Parsed h;
  size_t p = 4;
  h.version = get_varint(file, p);
  h.vertices = get_varint(file, p);
  h.faces = get_varint(file, p);
  h.corners = get_varint(file, p);
  h.grid = static_cast<uint8_t>(file.at(p++));
  h.level = static_cast<uint8_t>(file.at(p++));
  for (float& o : h.origin) o = get_f32(file, p);
  h.top = get_f32(file, p);
  h.segments = (h.level & 0x10) ? get_varint(file, p) : 1;
  const size_t first = p;
  const uint64_t tag = get_varint(file, p);
  const uint64_t stored = get_varint(file, p);
  if (tag & 1) get_varint(file, p);
  p += static_cast<size_t>(stored);
  h.first = file.substr(first, p - first);
  h.rest = file.substr(p + 4);
  return h;
}

std::string build(const Parsed& h) {
  std::string s = "TSM\x1a";
  put_varint(s, h.version);
  put_varint(s, h.vertices);
  put_varint(s, h.faces);
  put_varint(s, h.corners);
  s.push_back(static_cast<char>(h.grid));
  s.push_back(static_cast<char>(h.level));
  for (float o : h.origin) put_f32(s, o);
  put_f32(s, h.top);
  if (h.level & 0x10) put_varint(s, h.segments);
  s += h.first;
  put_le(s, XXH32(s.data(), s.size(), 0), 4);
  return s + h.rest;
}

TEST(Codec, ForgingHelpersRebuildTheEncodersBytes) {
  // Guards the helpers the tests below use.
  Mesh m = tsm_test::icosphere(1);
  std::string bytes = encode_ok(m, 9, 4);
  Parsed h = parse(bytes);
  EXPECT_EQ(h.version, 12u);
  EXPECT_EQ(h.vertices, m.vertex_count());
  EXPECT_EQ(h.faces, m.face_count());
  EXPECT_EQ(h.corners, m.corner_count());
  EXPECT_EQ(h.grid & 0x1f, 9);
  EXPECT_EQ(h.level, 4);
  EXPECT_EQ(h.segments, 1u);
  tsm::BoundingBox box = tsm::bounding_box(m);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(h.origin[a], box.min[a]);
  const int axis = h.grid >> 6;
  ASSERT_LT(axis, 3);
  EXPECT_EQ(static_cast<double>(h.top) - static_cast<double>(h.origin[axis]), box.largest_extent());
  EXPECT_EQ(build(h), bytes);
}

TEST(Codec, ForgedHugeCountsRefusedQuickly) {
  Mesh m = tsm_test::icosphere(1);
  const Parsed good = parse(encode_ok(m, 9, 4));
  for (int which = 0; which < 3; ++which) {
    Parsed h = good;
    (which == 0 ? h.vertices : which == 1 ? h.faces : h.corners) = 4000000000ull;
    std::string forged = build(h);
    auto t0 = std::chrono::steady_clock::now();
    Mesh back;
    tsm::Status s = tsm::decode(forged, back);
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(s.code(), ErrorCode::corrupt_data) << which << ": " << s.to_string();
    EXPECT_LT(ms, 250.0) << which << ": took long enough to have allocated for the claimed counts";
    EXPECT_LT(back.positions.capacity(), 100000u);
    EXPECT_LT(back.indices.capacity(), 100000u);
    // Inspect either refuses it or shows the claim, quickly.
    tsm::FileInfo fi;
    t0 = std::chrono::steady_clock::now();
    tsm::Status si = tsm::inspect(forged, fi);
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(ms, 250.0) << which;
    if (si.ok()) {
      EXPECT_EQ(which == 0 ? fi.vertex_count : which == 1 ? fi.face_count : fi.corner_count, 4000000000ull);
    } else {
      EXPECT_EQ(si.code(), ErrorCode::corrupt_data) << si.to_string();
    }
  }
  // 2^64 - 1 of everything.
  Parsed h = good;
  h.vertices = h.faces = h.corners = ~uint64_t{0};
  Mesh back;
  EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data);
}

TEST(Codec, ForgedHeaderFieldsRefused) {
  Mesh m = tsm_test::icosphere(1);
  const Parsed good = parse(encode_ok(m, 9, 4));
  Mesh back;
  ASSERT_TRUE(tsm::decode(build(good), back).ok());
  // Any other version than 12 (one format until 1.0): unsupported, with a
  // message that says which version is read.
  for (int version : {0, 1, 3, 11, 13, 0xFFFF}) {
    Parsed h = good;
    h.version = static_cast<uint16_t>(version);
    const tsm::Status s = tsm::decode(build(h), back);
    EXPECT_EQ(s.code(), ErrorCode::unsupported) << version;
    const std::string expected =
        "format version " + std::to_string(version) + ": this decoder reads only format version 12";
    EXPECT_NE(s.message().find(expected), std::string::npos) << s.to_string();
    tsm::StreamDecoder sd;
    EXPECT_EQ(sd.feed(build(h)).code(), ErrorCode::unsupported) << version;
  }
  {  // the exact-grid flag without the exact grid's fields
    Parsed h = good;
    h.grid |= 0x20;
    EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data);
  }
  for (int bits : {0, 31}) {
    Parsed h = good;
    h.grid = static_cast<uint8_t>((h.grid & ~0x1f) | bits);
    EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data) << bits;
  }
  {  // axis 3
    Parsed h = good;
    h.grid |= 0xc0;
    EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data);
  }
  for (uint64_t segments : {0, 1}) {  // a segment count follows only for 2 or more
    Parsed h = good;
    h.level |= 0x10;
    h.segments = segments;
    EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data) << segments;
  }
  for (int bit : {0x20, 0x40, 0x80}) {  // the level byte's bits 5-7
    Parsed h = good;
    h.level = static_cast<uint8_t>(h.level | bit);
    EXPECT_EQ(tsm::decode(build(h), back).code(), ErrorCode::corrupt_data) << bit;
  }
  {
    // The header is covered by the first section's checksum.
    std::string f = build(good);
    f[10] = static_cast<char>(f[10] ^ 1);
    EXPECT_EQ(tsm::decode(f, back).code(), ErrorCode::corrupt_data);
  }
  for (int which = 0; which < 3; ++which) {
    // One vertex, face or corner fewer or more than the streams hold.
    for (int delta : {-1, 1}) {
      Parsed h = good;
      uint64_t& c = which == 0 ? h.vertices : which == 1 ? h.faces : h.corners;
      c = static_cast<uint64_t>(static_cast<int64_t>(c) + delta);
      tsm::Status s = tsm::decode(build(h), back);
      EXPECT_EQ(s.code(), ErrorCode::corrupt_data) << which << " " << delta << ": " << s.to_string();
    }
  }
}

TEST(Codec, ForgedNonFiniteGridRefused) {
  // The encoder never writes a non-finite or negative grid; a decoder given
  // one must not hand back NaN or infinite positions as a valid mesh.
  Mesh m = tsm_test::icosphere(1);
  const Parsed good = parse(encode_ok(m, 9, 4));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float fmax = std::numeric_limits<float>::max();
  const int axis = good.grid >> 6;
  for (int which = 0; which < 7; ++which) {
    Parsed h = good;
    if (which == 0) h.top = nan;
    if (which == 1) h.top = inf;
    if (which == 2) h.origin[1] = nan;
    if (which == 3) h.origin[2] = -inf;
    if (which == 4) {  // the largest extent a float box has
      h.origin[axis] = -fmax;
      h.top = fmax;
    }
    if (which == 5) {  // each finite, but a grid step past the top overflows a float
      h.origin[axis] = 3e38f;
      h.top = fmax;
    }
    if (which == 6) h.top = h.origin[axis] - 1.0f;
    Mesh back;
    tsm::Status s = tsm::decode(build(h), back);
    EXPECT_TRUE(!s.ok() || back.all_finite()) << "case " << which << ": decoded non-finite positions";
    if (!s.ok()) {
      EXPECT_EQ(s.code(), ErrorCode::corrupt_data) << s.to_string();
    }
  }
}

TEST(Codec, DecodeLimits) {
  Mesh m = tsm_test::icosphere(2);
  std::string bytes = encode_ok(m);
  Mesh back;
  tsm::DecodeOptions o;
  o.max_vertices = m.vertex_count() - 1;
  tsm::Status s = tsm::decode(bytes, back, o);
  EXPECT_EQ(s.code(), ErrorCode::limit_exceeded) << s.to_string();
  EXPECT_NE(s.message().find(std::to_string(m.vertex_count())), std::string::npos) << s.message();
  o.max_vertices = m.vertex_count();
  EXPECT_TRUE(tsm::decode(bytes, back, o).ok());

  o = tsm::DecodeOptions();
  o.max_faces = m.face_count() - 1;
  s = tsm::decode(bytes, back, o);
  EXPECT_EQ(s.code(), ErrorCode::limit_exceeded) << s.to_string();
  o.max_faces = m.face_count();
  EXPECT_TRUE(tsm::decode(bytes, back, o).ok());
  EXPECT_TRUE(tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits).equal);

  // A limit is checked against the header before the payload matters: a
  // forged huge claim reports the limit.
  Parsed h = parse(bytes);
  h.vertices = 4000000000ull;
  o = tsm::DecodeOptions();
  o.max_vertices = 1000000;
  EXPECT_EQ(tsm::decode(build(h), back, o).code(), ErrorCode::limit_exceeded);
}

}  // namespace

namespace {

// The bytes of the worked example in FORMAT.md §11: the hex pairs at the
// start of each line of its first code block.
std::string spec_example_bytes() {
  std::ifstream in(TSM_FORMAT_SPEC);
  std::string line, bytes;
  bool in_section = false, in_block = false;
  while (std::getline(in, line)) {
    if (line.rfind("## 11.", 0) == 0) in_section = true;
    if (!in_section) continue;
    if (line.rfind("```", 0) == 0) {
      if (in_block) break;
      in_block = true;
      continue;
    }
    if (!in_block) continue;
    size_t i = 0;
    for (;;) {
      while (i < line.size() && line[i] == ' ') ++i;
      if (i + 2 > line.size() || !std::isxdigit(static_cast<unsigned char>(line[i])) ||
          !std::isxdigit(static_cast<unsigned char>(line[i + 1])) || (i + 2 < line.size() && line[i + 2] != ' '))
        break;
      bytes.push_back(static_cast<char>(std::stoi(line.substr(i, 2), nullptr, 16)));
      i += 2;
    }
  }
  return bytes;
}

}  // namespace

// The spec's worked example is what the encoder writes for its triangle and
// decodes to that triangle (it once went stale because nothing checked
// it).
TEST(Codec, FormatSpecWorkedExampleIsCurrent) {
  const std::string example = spec_example_bytes();
  ASSERT_EQ(example.size(), 57u) << "could not read the example from " << TSM_FORMAT_SPEC;
  tsm::Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(2, 0, 0);
  m.add_vertex(0, 1, 0.5f);
  m.add_triangle(0, 1, 2);
  tsm::EncodeOptions o;
  o.quantization_bits = 8;
  o.level = 0;
  std::string bytes;
  ASSERT_TRUE(tsm::encode(m, o, bytes).ok());
  EXPECT_EQ(bytes, example) << "FORMAT.md §11 no longer shows what `tsm encode tri.obj -q 8 -l 0` writes";
  tsm::Mesh back;
  const tsm::Status s = tsm::decode(example, back);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(back.indices, m.indices);
  EXPECT_EQ(back.positions[3 * 2 + 1], 128.0f * 2.0f / 255.0f);
}
