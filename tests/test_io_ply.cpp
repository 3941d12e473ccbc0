// Tests for the PLY reader and writer (libio/src/io_ply.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "tsm/io.hpp"

namespace {

using tsm::ErrorCode;
using tsm::Mesh;
using tsm::ReadInfo;
using tsm::ReadOptions;
using tsm::Status;
using tsm::WriteOptions;
using tsm_test::bits;
using tsm_test::from_bits;
using tsm_test::contains;

using tsm_test::Faces;
using tsm_test::faces_of;

// Same vertex count, bit-identical positions, identical faces.
::testing::AssertionResult bit_identical(const Mesh& a, const Mesh& b) {
  if (a.positions.size() != b.positions.size())
    return ::testing::AssertionFailure() << "vertex counts " << a.vertex_count() << " vs " << b.vertex_count();
  for (size_t i = 0; i < a.positions.size(); ++i)
    if (bits(a.positions[i]) != bits(b.positions[i]))
      return ::testing::AssertionFailure() << "coordinate " << i << " differs: bits " << std::hex
                                           << bits(a.positions[i]) << " vs " << bits(b.positions[i]);
  if (a.face_offsets != b.face_offsets) return ::testing::AssertionFailure() << "face offsets differ";
  if (a.indices != b.indices) return ::testing::AssertionFailure() << "face indices differ";
  return ::testing::AssertionSuccess();
}

Status ply(const std::string& bytes, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_ply(bytes, "test.ply", m, o, info);
}

// Expects a parse_error naming the file and containing every part given.
void expect_parse_error(const std::string& bytes, std::initializer_list<std::string> parts,
                        const ReadOptions& o = {}) {
  Mesh m;
  m.add_triangle(0, 0, 0);  // must be cleared on failure
  Status s = ply(bytes, m, o);
  ASSERT_FALSE(s.ok()) << "accepted: " << bytes.substr(0, 200);
  EXPECT_EQ(s.code(), ErrorCode::parse_error) << s.to_string();
  EXPECT_TRUE(contains(s.message(), "test.ply: "));
  for (const std::string& p : parts) EXPECT_TRUE(contains(s.message(), p));
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_EQ(m.face_count(), 0u);
}

std::string load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Little or big endian binary body builder.
struct Body {
  bool big = false;
  std::string s;
  template <typename T>
  Body& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    const bool host_big = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
    if (big != host_big) std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
    return *this;
  }
};

// A small mesh with everything a lossless codec must keep.
Mesh awkward_mesh() {
  Mesh m;
  m.add_vertex(0.0f, 1.0f, 2.0f);
  m.add_vertex(-0.0f, 0.1f, 1e-7f);                                  // negative zero
  m.add_vertex(from_bits(0x00000001u), from_bits(0x807fffffu), 3.5f);  // smallest and largest denormals
  m.add_vertex(std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(), 1.17549435e-38f);
  m.add_vertex(1.0f / 3.0f, 123456.789f, -2.5e-30f);
  m.add_vertex(16777217.0f, -0.333333343f, 7.0f);
  m.add_vertex(42.0f, 42.0f, 42.0f);  // unreferenced
  m.add_vertex(5.0f, 6.0f, 7.0f);
  const uint32_t quad[] = {0, 1, 2, 3};
  const uint32_t pentagon[] = {1, 2, 3, 4, 5};
  const uint32_t degenerate[] = {0, 0, 1};
  const uint32_t two[] = {4, 5};
  const uint32_t one[] = {7};
  m.add_face(quad, 4);
  m.add_triangle(3, 4, 5);
  m.add_face(pentagon, 5);
  m.add_face(degenerate, 3);
  m.add_face(two, 2);
  m.add_face(one, 1);
  const uint32_t quad2[] = {5, 4, 3, 0};
  m.add_face(quad2, 4);
  return m;
}

void expect_roundtrip(const Mesh& m, bool ascii, const ReadOptions& ro = {}) {
  WriteOptions wo;
  wo.ascii = ascii;
  std::string bytes;
  ASSERT_TRUE(tsm::write_ply(m, wo, bytes).ok());
  Mesh back;
  ReadInfo info;
  Status s = ply(bytes, back, ro, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(info.format, tsm::MeshFormat::ply);
  EXPECT_EQ(info.binary, !ascii);
  EXPECT_TRUE(bit_identical(m, back)) << (ascii ? "ascii" : "binary");
}

// ---------------------------------------------------------------------------
// Round trips

TEST(PlyRoundTrip, BinaryIsBitExact) { expect_roundtrip(awkward_mesh(), false); }

TEST(PlyRoundTrip, AsciiIsBitExact) { expect_roundtrip(awkward_mesh(), true); }

TEST(PlyRoundTrip, HeaderSaysWhatWasWritten) {
  std::string bin, text;
  WriteOptions wo;
  ASSERT_TRUE(tsm::write_ply(awkward_mesh(), wo, bin).ok());
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(awkward_mesh(), wo, text).ok());
  EXPECT_EQ(bin.rfind("ply\nformat binary_little_endian 1.0\ncomment written by tsm\n", 0), 0u);
  EXPECT_EQ(text.rfind("ply\nformat ascii 1.0\ncomment written by tsm\n", 0), 0u);
  EXPECT_TRUE(contains(bin, "element vertex 8\n"));
  EXPECT_TRUE(contains(bin, "element face 7\nproperty list uchar uint vertex_indices\nend_header\n"));
  // Shortest round-trip text: 0.1f prints as 0.1, negative zero keeps its sign.
  EXPECT_TRUE(contains(text, "\n-0 0.1 1e-07\n"));
  EXPECT_TRUE(contains(text, "\n5 1 2 3 4 5\n"));
}

TEST(PlyRoundTrip, FacesOver255CornersUseUintCounts) {
  Mesh m;
  std::vector<uint32_t> big;
  for (uint32_t i = 0; i < 300; ++i) {
    m.add_vertex(std::cos(static_cast<float>(i)), std::sin(static_cast<float>(i)), 0.0f);
    big.push_back(i);
  }
  m.add_face(big.data(), big.size());
  m.add_triangle(0, 1, 2);
  std::string bytes;
  ASSERT_TRUE(tsm::write_ply(m, {}, bytes).ok());
  EXPECT_TRUE(contains(bytes, "property list uint uint vertex_indices\n"));
  expect_roundtrip(m, false);
  expect_roundtrip(m, true);
}

TEST(PlyRoundTrip, EmptyMeshAndPointCloud) {
  expect_roundtrip(Mesh(), false);
  expect_roundtrip(Mesh(), true);
  Mesh cloud;
  cloud.add_vertex(1, 2, 3);
  cloud.add_vertex(-4, 5e-3f, 6);
  expect_roundtrip(cloud, false);
  expect_roundtrip(cloud, true);
}

TEST(PlyRoundTrip, NonFiniteOnlyWithOption) {
  Mesh m;
  m.add_vertex(std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(), 1.0f);
  m.add_vertex(from_bits(0x7fc00001u), 0.0f, 0.0f);  // a NaN with a payload
  m.add_triangle(0, 1, 1);
  ReadOptions allow;
  allow.allow_nonfinite = true;
  expect_roundtrip(m, false, allow);  // binary keeps even the NaN payload
  std::string text;
  WriteOptions wo;
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(m, wo, text).ok());
  Mesh back;
  ASSERT_TRUE(ply(text, back, allow).ok());
  ASSERT_EQ(back.vertex_count(), 2u);
  EXPECT_EQ(back.positions[0], std::numeric_limits<float>::infinity());
  EXPECT_EQ(back.positions[1], -std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(back.positions[3]));
  // Refused by default, naming the option.
  Status s = ply(text, back);
  EXPECT_EQ(s.code(), ErrorCode::parse_error);
  EXPECT_TRUE(contains(s.message(), "--allow-nonfinite"));
}

TEST(PlyRoundTrip, WriterRefusesAnInvalidMesh) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_triangle(0, 0, 1);  // vertex 1 does not exist
  std::string out;
  EXPECT_EQ(tsm::write_ply(m, {}, out).code(), ErrorCode::invalid_argument);
}

// ---------------------------------------------------------------------------
// Hand-written files

const char* kTriangleHeaderTail =
    "element vertex 3\n"
    "property float x\nproperty float y\nproperty float z\n"
    "element face 1\n"
    "property list uchar int vertex_indices\n"
    "end_header\n";

Mesh triangle_mesh() {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(1, 0, 0);
  m.add_vertex(0, 1, 0.5f);
  m.add_triangle(0, 1, 2);
  return m;
}

std::string ascii_triangle() {
  return std::string("ply\nformat ascii 1.0\n") + kTriangleHeaderTail + "0 0 0\n1 0 0\n0 1 0.5\n3 0 1 2\n";
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = s.find(from, at)) != std::string::npos; at += to.size()) s.replace(at, from.size(), to);
  return s;
}

TEST(PlyRead, AsciiBasic) {
  Mesh m;
  ReadInfo info;
  Status s = ply(ascii_triangle(), m, {}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
  EXPECT_FALSE(info.binary);
  EXPECT_TRUE(info.notes.empty()) << info.notes;
}

TEST(PlyRead, CrOnlyLineEnds) {
  Mesh m;
  Status s = ply(replace_all(ascii_triangle(), "\n", "\r"), m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
  // Line numbers still count CR-only lines.
  std::string bad = replace_all(ascii_triangle(), "1 0 0\n", "1 x 0\n");
  expect_parse_error(replace_all(bad, "\n", "\r"), {"line 11:", "'x'", "vertex 1", "property 'y'"});
}

TEST(PlyRead, CrlfLineEnds) {
  Mesh m;
  Status s = ply(replace_all(ascii_triangle(), "\n", "\r\n"), m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
}

TEST(PlyRead, TabsBlankLinesAndExtraSpaces) {
  const std::string text =
      "ply\n"
      "format \t ascii\t1.0 \t\n"
      "comment\t\tx\n"
      "\t element\tvertex \t3\n"
      "property\tfloat\tx\n"
      "property  float   y \n"
      "property float\tz\n"
      "\n"
      "element face 1\t\n"
      " property list  uchar\tint vertex_indices \t\n"
      "end_header \t\n"
      "\t0 0\t0 \n"
      "  1 0 0\t\n"
      "\n"
      "0\t1  0.5\n"
      "3 0\t1 2   \n"
      "\n";
  Mesh m;
  Status s = ply(text, m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
}

TEST(PlyRead, BigEndianDoubleShortAndExtraProperties) {
  std::string header =
      "ply\nformat binary_big_endian 1.0\n"
      "comment types galore\nobj_info made by hand\n"
      "element vertex 3\n"
      "property short id\n"
      "property double x\n"
      "property short y\n"
      "property float confidence\n"
      "property int16 z\n"
      "property uchar red\n"
      "element face 2\n"
      "property int flags\n"
      "property list ushort int32 vertex_indices\n"
      "property float64 quality\n"
      "end_header\n";
  Body b;
  b.big = true;
  const double xs[3] = {0.1, -2.5, 1e300};  // 1e300 overflows float: only with the option
  const int16_t ys[3] = {-7, 300, 0};
  const int16_t zs[3] = {1, -32768, 32767};
  for (int v = 0; v < 3; ++v)
    b.put<int16_t>(static_cast<int16_t>(v)).put(xs[v]).put(ys[v]).put(0.5f).put(zs[v]).put<uint8_t>(200);
  b.put<int32_t>(-1).put<uint16_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put(9.0);
  b.put<int32_t>(77).put<uint16_t>(4).put<int32_t>(2).put<int32_t>(1).put<int32_t>(0).put<int32_t>(2).put(1.0);
  Mesh m;
  ReadOptions allow;
  allow.allow_nonfinite = true;
  ReadInfo info;
  Status s = ply(header + b.s, m, allow, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(info.binary);
  ASSERT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(bits(m.positions[0]), bits(static_cast<float>(0.1)));
  EXPECT_EQ(m.positions[1], -7.0f);
  EXPECT_EQ(m.positions[2], 1.0f);
  EXPECT_EQ(m.positions[3], -2.5f);
  EXPECT_EQ(m.positions[4], 300.0f);
  EXPECT_EQ(m.positions[5], -32768.0f);
  EXPECT_EQ(m.positions[6], std::numeric_limits<float>::infinity());
  EXPECT_EQ(m.positions[8], 32767.0f);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {2, 1, 0, 2}}));
  // Without the option the overflowed x is refused, at the third vertex.
  const size_t third_vertex = header.size() + 2 * (2 + 8 + 2 + 4 + 2 + 1);
  expect_parse_error(header + b.s, {"vertex 2", "--allow-nonfinite", "byte " + std::to_string(third_vertex) + ":"});
}

TEST(PlyRead, ListPropertyInsideVertexElement) {
  // Vertex items of varying size (a list among them): the slow vertex path.
  std::string header =
      "ply\nformat binary_little_endian 1.0\n"
      "element vertex 2\n"
      "property float x\nproperty list uchar float weights\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar uint vertex_index\nend_header\n";
  Body b;
  b.put(1.5f).put<uint8_t>(2).put(9.f).put(9.f).put(2.5f).put(3.5f);
  b.put(4.5f).put<uint8_t>(0).put(5.5f).put(6.5f);
  b.put<uint8_t>(2).put<uint32_t>(1).put<uint32_t>(0);
  Mesh m;
  Status s = ply(header + b.s, m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.positions, (std::vector<float>{1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f}));
  EXPECT_EQ(faces_of(m), (Faces{{1, 0}}));
  // Same thing in ascii.
  const std::string text =
      "ply\nformat ascii 1.0\n"
      "element vertex 2\n"
      "property float x\nproperty list uchar float weights\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
      "1.5 2 9 9 2.5 3.5\n4.5 0 5.5 6.5\n2 1 0\n";
  Mesh t;
  s = ply(text, t);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, t));
}

TEST(PlyRead, SkippedElementWithListBeforeFaces) {
  const std::string head =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element edge 2\nproperty list uchar int vertex_indices\nproperty uchar red\n"
      "element face 1\nproperty list uchar int vertex_index\nproperty list uchar float texcoord\n"
      "element material 1\nproperty double shine\n"
      "end_header\n";
  const std::string text = "ply\nformat ascii 1.0\n" + head +
                           "0 0 0\n1 0 0\n0 1 0.5\n"
                           "2 0 1 255\n3 0 1 2 7\n"
                           "3 0 1 2 6 0 0 1 0 0 1\n"
                           "0.25\n";
  Mesh m;
  ReadInfo info;
  Status s = ply(text, m, {}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
  EXPECT_TRUE(contains(info.notes, "skipped element 'edge' (2)"));
  EXPECT_TRUE(contains(info.notes, "skipped element 'material' (1)"));
  EXPECT_EQ(info.skipped_elements, 3u);

  Body b;
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(0.f).put(1.f).put(0.5f);
  b.put<uint8_t>(2).put<int32_t>(0).put<int32_t>(1).put<uint8_t>(255);
  b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put<uint8_t>(7);
  b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put<uint8_t>(6).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(1.f);
  b.put(0.25);
  Mesh mb;
  ReadInfo binfo;
  s = ply("ply\nformat binary_little_endian 1.0\n" + head + b.s, mb, {}, &binfo);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(mb, triangle_mesh()));
  EXPECT_EQ(binfo.notes, info.notes);
}

TEST(PlyRead, PointCloudWithoutFaceElement) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n1 2 3\n4 5 6\n";
  Mesh m;
  Status s = ply(text, m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.positions, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(m.face_count(), 0u);
  // And with 'element face 0'.
  Mesh m0;
  s = ply(replace_all(text, "end_header", "element face 0\nproperty list uchar int vertex_indices\nend_header"), m0);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, m0));
  // No vertices at all.
  Mesh empty;
  EXPECT_TRUE(ply("ply\nformat ascii 1.0\nend_header\n", empty).ok());
  EXPECT_EQ(empty.vertex_count(), 0u);
}

TEST(PlyRead, FacesBeforeVertices) {
  const std::string text =
      "ply\nformat ascii 1.0\n"
      "element face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0.5\n";
  Mesh m;
  Status s = ply(text, m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
}

TEST(PlyRead, BinaryBodyAfterCrOnlyAndCrlfHeaders) {
  // The body starts with a 0x0A byte: after a CR-only header it is data, not
  // the second half of a CRLF.
  Body b;
  b.put(from_bits(0x3f80000au)).put(2.f).put(3.f).put<uint8_t>(1).put<int32_t>(0);
  const std::string lf_header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (const char* eol : {"\r", "\r\n", "\n"}) {
    Mesh m;
    ReadInfo info;
    Status s = ply(replace_all(lf_header, "\n", eol) + b.s, m, {}, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    ASSERT_EQ(m.vertex_count(), 1u);
    EXPECT_EQ(bits(m.positions[0]), 0x3f80000au);
    EXPECT_EQ(m.positions[2], 3.f);
    EXPECT_EQ(faces_of(m), (Faces{{0}}));
    EXPECT_TRUE(info.notes.empty()) << info.notes;
  }
}

TEST(PlyRead, IntegerTypeNamesAndCoordinates) {
  const std::string text =
      "ply\nformat ascii 1.0\n"
      "element vertex 3\nproperty uint8 x\nproperty int32 y\nproperty uint z\nproperty char c\n"
      "element face 1\nproperty list int8 uint16 vertex_indices\nend_header\n"
      "255 -2147483648 4294967295 -128\n0 0 0 127\n1 2 3 0\n3 2 1 0\n";
  Mesh m;
  Status s = ply(text, m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.positions[0], 255.f);
  EXPECT_EQ(m.positions[1], -2147483648.f);
  EXPECT_EQ(m.positions[2], 4294967295.f);
  EXPECT_EQ(faces_of(m), (Faces{{2, 1, 0}}));
}

TEST(PlyRead, TrailingDataIsNotedNotFatal) {
  Mesh m;
  ReadInfo info;
  ASSERT_TRUE(ply(ascii_triangle() + "junk\n", m, {}, &info).ok());
  EXPECT_TRUE(contains(info.notes, "ignored"));
  Mesh b;
  ReadInfo binfo;
  std::string bytes;
  ASSERT_TRUE(tsm::write_ply(triangle_mesh(), {}, bytes).ok());
  ASSERT_TRUE(ply(bytes + "xyz", b, {}, &binfo).ok());
  EXPECT_TRUE(contains(binfo.notes, "ignored 3 bytes"));
  EXPECT_TRUE(bit_identical(b, triangle_mesh()));
}

TEST(PlyRead, EmptyFacesAreSkippedWithANote) {
  const std::string text = std::string("ply\nformat ascii 1.0\n") +
                           replace_all(kTriangleHeaderTail, "face 1", "face 2") + "0 0 0\n1 0 0\n0 1 0.5\n0\n3 0 1 2\n";
  Mesh m;
  ReadInfo info;
  Status s = ply(text, m, {}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(bit_identical(m, triangle_mesh()));
  EXPECT_TRUE(contains(info.notes, "1 face(s) with no corners"));
}

// ---------------------------------------------------------------------------
// Errors

TEST(PlyErrors, BadMagic) {
  expect_parse_error("", {"line 1:", "not a PLY file"});
  expect_parse_error("PLY\nformat ascii 1.0\nend_header\n", {"line 1:", "not a PLY file"});
  expect_parse_error("plyx\nformat ascii 1.0\nend_header\n", {"line 1:", "not a PLY file"});
  expect_parse_error("ply", {"line 1:"});
  expect_parse_error("ply \t", {"line 1:"});
  expect_parse_error("solid cube\n", {"line 1:"});
}

TEST(PlyErrors, HeaderProblems) {
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n",
                     {"line 4:", "unknown property type 'flaot'"});
  expect_parse_error("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar integer vertex_indices\nend_header\n",
                     {"line 4:", "'integer'"});
  expect_parse_error("ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
                     {"line 4:", "count type"});
  expect_parse_error("ply\nformat binary_middle_endian 1.0\nend_header\n", {"line 2:", "unknown format"});
  expect_parse_error("ply\nformat ascii 2.0\nend_header\n", {"line 2:", "version"});
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex 3\n", {"end_header"});
  expect_parse_error("ply\nelement vertex 0\nend_header\n", {"line 3:", "no 'format'"});
  expect_parse_error("ply\nformat ascii 1.0\nproperty float x\nend_header\n", {"line 3:", "before any 'element'"});
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", {"line 3:", "negative"});
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n",
                     {"line 3:", "too large"});
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex 3x\nend_header\n", {"line 3:", "not a number"});
  expect_parse_error("ply\nformat ascii 1.0\nvertices 3\nend_header\n", {"line 3:", "unknown header keyword"});
  expect_parse_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
                     {"line 3:", "no property 'z'"});
  expect_parse_error("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int corners\nend_header\n3 0 1 2\n",
                     {"line 3:", "vertex_indices"});
  expect_parse_error("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n",
                     {"line 3:", "integer"});
}

TEST(PlyErrors, TruncatedAscii) {
  std::string text = ascii_triangle();
  // Too few bytes left for the declared counts: caught before reading.
  expect_parse_error(text.substr(0, text.find("0 1 0.5")),
                     {"line 10:", "element 'vertex' declares 3 items", "bytes are left"});
  // Enough bytes for the up-front check, but the file still ends early.
  text = replace_all(text, "0 0 0\n1 0 0\n", "0.0000 0.0000 0.0000\n1.0000 0.0000 0.0000\n");
  expect_parse_error(text.substr(0, text.find("0 1 0.5")), {"line 12:", "ends after 2 of the 3 items of element 'vertex'"});
  expect_parse_error(text.substr(0, text.find("0 1 0.5") + 4), {"line 12:", "ends inside vertex 2", "property 'z'"});
  text = replace_all(text, "3 0 1 2\n", "3 00000 1 2\n");
  expect_parse_error(text.substr(0, text.size() - 3), {"line 13:", "ends inside face 0"});
  expect_parse_error(ascii_triangle().substr(0, ascii_triangle().size() - 3),
                     {"line 13:", "face 0", "list count 3 is more than the rest of the file can hold"});
  // A line short of values.
  expect_parse_error(replace_all(ascii_triangle(), "1 0 0\n", "1 0\n"), {"line 11:", "vertex 1", "property 'z'"});
  // A line with too many.
  expect_parse_error(replace_all(ascii_triangle(), "1 0 0\n", "1 0 0 4\n"), {"line 11:", "vertex 1", "'4'"});
}

TEST(PlyErrors, TruncatedBinary) {
  std::string bytes;
  ASSERT_TRUE(tsm::write_ply(awkward_mesh(), {}, bytes).ok());
  const size_t body = bytes.find("end_header\n") + 11;
  // Inside the vertex block: caught before reading, at the body start.
  expect_parse_error(bytes.substr(0, body + 50), {"byte " + std::to_string(body) + ":", "element 'vertex'"});
  // Inside the last face.
  expect_parse_error(bytes.substr(0, bytes.size() - 2), {"face 6", "the file ends"});
  // Truncated so that the early (large) faces fit but the later ones cannot.
  Mesh big;
  for (uint32_t i = 0; i < 10; ++i) big.add_vertex(static_cast<float>(i), 0, 0);
  const uint32_t ten[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  big.add_face(ten, 10);
  for (int i = 0; i < 20; ++i) big.add_triangle(0, 1, 2);
  ASSERT_TRUE(tsm::write_ply(big, {}, bytes).ok());
  for (size_t cut = 1; cut < 200; ++cut) expect_parse_error(bytes.substr(0, bytes.size() - cut), {"the file ends"});
  // Every prefix fails cleanly (or, for the whole file, succeeds).
  for (size_t n = 0; n < bytes.size(); ++n) {
    Mesh m;
    Status s = ply(bytes.substr(0, n), m);
    EXPECT_EQ(s.code(), ErrorCode::parse_error) << n;
  }
}

TEST(PlyErrors, IndexOutOfRange) {
  expect_parse_error(replace_all(ascii_triangle(), "3 0 1 2", "3 0 3 2"),
                     {"line 13:", "face 0", "index 3", "3 vertices"});
  expect_parse_error(replace_all(ascii_triangle(), "3 0 1 2", "3 0 -1 2"), {"line 13:", "index -1"});
  // Binary, fast path (uchar + int) and general path (ushort + uint).
  Body b;
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(0.f).put(1.f).put(0.5f);
  const std::string header = std::string("ply\nformat binary_little_endian 1.0\n") + kTriangleHeaderTail;
  const std::string face_at = std::to_string(header.size() + 36 + 1 + 4);
  Body f1 = b;
  f1.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(-5).put<int32_t>(2);
  expect_parse_error(header + f1.s, {"byte " + face_at + ":", "face 0", "index -5", "3 vertices"});
  Body f2 = b;
  f2.put<uint16_t>(3).put<uint32_t>(0).put<uint32_t>(3000000000u).put<uint32_t>(2);
  expect_parse_error(replace_all(header, "uchar int", "ushort uint") + f2.s, {"index 3000000000", "3 vertices"});
}

TEST(PlyErrors, NegativeListCount) {
  expect_parse_error(replace_all(ascii_triangle(), "3 0 1 2", "-3 0 1 2"), {"line 13:", "negative list count -3"});
  Body b;
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(0.f).put(1.f).put(0.5f);
  b.put<int8_t>(-1).put<int32_t>(0);
  const std::string header = replace_all(std::string("ply\nformat binary_little_endian 1.0\n") + kTriangleHeaderTail,
                                         "list uchar", "list char");
  expect_parse_error(header + b.s, {"byte " + std::to_string(header.size() + 36) + ":", "negative list count -1"});
}

TEST(PlyErrors, HugeCountsFailFast) {
  const auto start = std::chrono::steady_clock::now();
  const std::string vhead = "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n";
  expect_parse_error("ply\nformat binary_little_endian 1.0\n" + vhead + "end_header\n0123456789",
                     {"byte ", "4000000000", "10 bytes"});
  expect_parse_error("ply\nformat ascii 1.0\n" + vhead + "end_header\n1 2 3\n", {"line 8:", "4000000000"});
  const std::string fhead = "element face 4000000000\nproperty list uchar int vertex_indices\n";
  expect_parse_error("ply\nformat binary_little_endian 1.0\n" + fhead + "end_header\n\3abc", {"4000000000"});
  expect_parse_error("ply\nformat ascii 1.0\n" + fhead + "end_header\n0\n", {"4000000000"});
  // A skipped element whose count cannot fit in any file.
  expect_parse_error("ply\nformat binary_big_endian 1.0\nelement junk 18446744073709551615\nproperty double d\n"
                     "end_header\n12345678",
                     {"18446744073709551615"});
  // Huge list counts inside the body.
  Body b;
  b.put(0.f).put(0.f).put(0.f);
  b.put<uint32_t>(4000000000u).put<uint32_t>(0);
  expect_parse_error(
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uint uint vertex_indices\nend_header\n" + b.s,
      {"face 0", "ends inside"});
  expect_parse_error(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uint uint vertex_indices\nend_header\n0 0 0\n4000000000 0 0 0\n",
      {"line 11:", "list count 4000000000"});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0);
}

TEST(PlyErrors, LimitsFromOptions) {
  ReadOptions o;
  o.max_vertices = 2;
  Mesh m;
  Status s = ply(ascii_triangle(), m, o);
  EXPECT_EQ(s.code(), ErrorCode::limit_exceeded);
  EXPECT_TRUE(contains(s.message(), "test.ply"));
  EXPECT_TRUE(contains(s.message(), "max_vertices"));
  o.max_vertices = 3;
  o.max_faces = 1;
  EXPECT_TRUE(ply(ascii_triangle(), m, o).ok());
  o.max_faces = 0;
  EXPECT_TRUE(ply(ascii_triangle(), m, o).ok());
  Mesh m2;
  ReadOptions o2;
  o2.max_faces = 1;
  s = ply(replace_all(ascii_triangle(), "face 1", "face 2") + "3 2 1 0\n", m2, o2);
  EXPECT_EQ(s.code(), ErrorCode::limit_exceeded);
  EXPECT_TRUE(contains(s.message(), "max_faces"));
  // Vertex counts beyond 32-bit indices.
  s = ply("ply\nformat ascii 1.0\nelement vertex 5000000000\nproperty float x\nproperty float y\nproperty float z\n"
          "end_header\n",
          m2);
  EXPECT_EQ(s.code(), ErrorCode::limit_exceeded);
}

TEST(PlyErrors, NonFiniteRefusedUnlessAllowed) {
  for (const char* bad : {"nan", "inf", "-inf", "1e39"}) {
    const std::string text = replace_all(ascii_triangle(), "1 0 0\n", std::string("1 ") + bad + " 0\n");
    expect_parse_error(text, {"line 11:", "vertex 1", "non-finite", "--allow-nonfinite"});
    ReadOptions allow;
    allow.allow_nonfinite = true;
    Mesh m;
    Status s = ply(text, m, allow);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_FALSE(std::isfinite(m.positions[4]));
  }
  Mesh nan_mesh = triangle_mesh();
  nan_mesh.positions[7] = std::numeric_limits<float>::quiet_NaN();
  std::string bytes;
  ASSERT_TRUE(tsm::write_ply(nan_mesh, {}, bytes).ok());
  const size_t body = bytes.find("end_header\n") + 11;
  expect_parse_error(bytes, {"byte " + std::to_string(body + 24) + ":", "vertex 2", "--allow-nonfinite"});
}

TEST(PlyErrors, BadNumbersInAsciiBody) {
  expect_parse_error(replace_all(ascii_triangle(), "1 0 0\n", "1 0 zero\n"), {"line 11:", "'zero'", "property 'z'"});
  expect_parse_error(replace_all(ascii_triangle(), "3 0 1 2", "3 0 1.5 2"), {"line 13:", "'1.5'", "integer"});
  expect_parse_error(replace_all(ascii_triangle(), "3 0 1 2", "three 0 1 2"), {"line 13:", "list count"});
}

// Random damage never crashes (this runs under ASan/UBSan too) and never
// yields an invalid mesh.
TEST(PlyErrors, MutatedInputsNeverCrash) {
  std::string bin, text;
  ASSERT_TRUE(tsm::write_ply(awkward_mesh(), {}, bin).ok());
  WriteOptions wo;
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(awkward_mesh(), wo, text).ok());
  std::mt19937 rng(12345);
  int accepted = 0;
  for (const std::string* base : {&bin, &text}) {
    for (int iter = 0; iter < 3000; ++iter) {
      std::string s = *base;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const size_t at = rng() % s.size();
        switch (rng() % 4) {
          case 0: s[at] = static_cast<char>(rng()); break;
          case 1: s.erase(at, 1 + rng() % 8); break;
          case 2: s.insert(at, 1, "0123456789 \n-e."[rng() % 15]); break;
          default: s[at] = "9\n \r-"[rng() % 5]; break;
        }
        if (s.empty()) s = "p";
      }
      Mesh m;
      ReadOptions o;
      o.allow_nonfinite = (iter & 1) != 0;
      Status st = ply(s, m, o);
      if (st.ok()) {
        ++accepted;
        std::string why;
        EXPECT_TRUE(m.valid(&why)) << why;
      } else {
        EXPECT_TRUE(st.code() == ErrorCode::parse_error || st.code() == ErrorCode::limit_exceeded) << st.to_string();
        EXPECT_TRUE(contains(st.message(), "test.ply: "));
      }
    }
  }
  EXPECT_GT(accepted, 0);
}

// ---------------------------------------------------------------------------
// Corpus

void expect_file_roundtrips(const Mesh& m, const std::string& what) {
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(what + (ascii ? " via ascii" : " via binary"));
    expect_roundtrip(m, ascii);
  }
}

TEST(PlyCorpus, EdgeFiles) {
  TSM_REQUIRE_CORPUS();
  struct Expect {
    size_t vertices, faces, corners;
    bool binary;
  };
  const std::map<std::string, Expect> expected = {
      {"Box.ply", {24, 8, 28, true}},
      {"cube_att.ply", {24, 12, 36, false}},
      {"cube_quads.ply", {8, 6, 24, false}},
      {"point_cloud_test_pos.ply", {4, 0, 0, true}},
      {"test_extra_whitespace.ply", {3, 1, 3, false}},
      {"test_generic.ply", {114, 224, 672, true}},
      {"test_more_datatypes.ply", {3, 1, 3, false}},
      {"test_pos_color.ply", {114, 224, 672, true}},
      {"test_pos_color_ascii.ply", {114, 224, 672, false}},
  };
  size_t seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(tsm_test::corpus_file("edge"))) {
    if (entry.path().extension() != ".ply") continue;
    const std::string file = entry.path().filename().string();
    SCOPED_TRACE(file);
    Mesh m;
    ReadInfo info;
    Status s = tsm::read_ply(load(entry.path().string()), file, m, {}, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    auto it = expected.find(file);
    ASSERT_NE(it, expected.end()) << "new PLY file in the corpus: add its counts here";
    ++seen;
    EXPECT_EQ(m.vertex_count(), it->second.vertices);
    EXPECT_EQ(m.face_count(), it->second.faces);
    EXPECT_EQ(m.corner_count(), it->second.corners);
    EXPECT_EQ(info.binary, it->second.binary);
    if (file == "Box.ply") {
      EXPECT_TRUE(contains(info.notes, "skipped element 'material' (1)"));
    }
    expect_file_roundtrips(m, file);
  }
  EXPECT_EQ(seen, expected.size());
}

TEST(PlyCorpus, EdgeFileContents) {
  TSM_REQUIRE_CORPUS();
  Mesh quads;
  ASSERT_TRUE(tsm::read_ply(load(tsm_test::corpus_file("edge/cube_quads.ply")), "cube_quads.ply", quads, {}, nullptr).ok());
  EXPECT_EQ(faces_of(quads)[0], (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(faces_of(quads)[5], (std::vector<uint32_t>{3, 7, 4, 0}));
  EXPECT_EQ(quads.positions[3 * 6 + 0], 1.f);
  EXPECT_EQ(quads.positions[3 * 6 + 2], 1.f);

  // The binary and ascii colour files hold the same mesh.
  Mesh bin, text;
  ASSERT_TRUE(tsm::read_ply(load(tsm_test::corpus_file("edge/test_pos_color.ply")), "a", bin, {}, nullptr).ok());
  ASSERT_TRUE(tsm::read_ply(load(tsm_test::corpus_file("edge/test_pos_color_ascii.ply")), "b", text, {}, nullptr).ok());
  EXPECT_EQ(faces_of(bin), faces_of(text));
  ASSERT_EQ(bin.positions.size(), text.positions.size());
  for (size_t i = 0; i < bin.positions.size(); ++i) EXPECT_NEAR(bin.positions[i], text.positions[i], 1e-5) << i;

  // Box.ply (CR line ends, binary body, trailing 'material' element): a box
  // made of quads and triangles with every vertex used.
  Mesh box;
  ASSERT_TRUE(tsm::read_ply(load(tsm_test::corpus_file("edge/Box.ply")), "Box.ply", box, {}, nullptr).ok());
  EXPECT_EQ(box.unreferenced_vertex_count(), 0u);
  EXPECT_TRUE(box.all_finite());
  EXPECT_EQ(faces_of(box)[0], (std::vector<uint32_t>{0, 2, 3, 1}));
}

struct Scan {
  const char* file;
  size_t vertices, faces;
};

// Test names and ctest lines show the file, not the bytes of the struct.
void PrintTo(const Scan& scan, std::ostream* os) { *os << scan.file; }

class PlyScans : public ::testing::TestWithParam<Scan> {};

TEST_P(PlyScans, LoadAndRoundTrip) {
  TSM_REQUIRE_CORPUS();
  const Scan& scan = GetParam();
  const std::string bytes = load(tsm_test::corpus_file(scan.file));
  ASSERT_FALSE(bytes.empty());
  Mesh m;
  ReadInfo info;
  const auto start = std::chrono::steady_clock::now();
  Status s = tsm::read_ply(bytes, scan.file, m, {}, &info);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(s.ok()) << s.to_string();
  RecordProperty("load_ms", std::to_string(ms));
  EXPECT_EQ(m.vertex_count(), scan.vertices);
  EXPECT_EQ(m.face_count(), scan.faces);
  EXPECT_TRUE(m.all_triangles());
  EXPECT_TRUE(m.all_finite());
  EXPECT_FALSE(info.binary);
  expect_file_roundtrips(m, scan.file);
}

INSTANTIATE_TEST_SUITE_P(Corpus, PlyScans,
                         ::testing::Values(Scan{"bun_zipper.ply", 35947, 69451},
                                           Scan{"dragon_vrip.ply", 437645, 871414},
                                           Scan{"dragon_vrip_res2.ply", 100250, 202520},
                                           Scan{"dragon_vrip_res3.ply", 22998, 47794},
                                           Scan{"dragon_vrip_res4.ply", 5205, 11102}),
                         [](const ::testing::TestParamInfo<Scan>& p) {
                           std::string n = p.param.file;
                           n = n.substr(0, n.find('.'));
                           return n;
                         });

}  // namespace
