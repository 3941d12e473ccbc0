// Tests for the OBJ, STL and OFF readers and the OBJ, STL and OFF writers.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/io.hpp"

namespace {

using tsm::ErrorCode;
using tsm::Mesh;
using tsm::ReadInfo;
using tsm::ReadOptions;
using tsm::Status;

using tsm_test::Faces;
using tsm_test::faces_of;

std::vector<float> positions_of(const Mesh& m) { return m.positions; }

// Same vertex count, bit-identical positions, identical faces.
::testing::AssertionResult bit_identical(const Mesh& a, const Mesh& b) {
  if (a.positions.size() != b.positions.size())
    return ::testing::AssertionFailure() << "vertex counts " << a.vertex_count() << " vs " << b.vertex_count();
  if (!a.positions.empty() &&
      std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(float)) != 0)
    return ::testing::AssertionFailure() << "positions differ in their bits";
  if (a.face_offsets != b.face_offsets) return ::testing::AssertionFailure() << "face offsets differ";
  if (a.indices != b.indices) return ::testing::AssertionFailure() << "face indices differ";
  return ::testing::AssertionSuccess();
}

Status obj(const std::string& text, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_obj(text, "test.obj", m, o, info);
}
Status stl(const std::string& bytes, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_stl(bytes, "test.stl", m, o, info);
}
Status off(const std::string& text, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_off(text, "test.off", m, o, info);
}

void expect_roundtrip(const Mesh& m) {
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  Mesh back;
  ReadOptions o;
  o.allow_nonfinite = true;
  Status st = tsm::read_obj(text, "written.obj", back, o, nullptr);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(bit_identical(m, back));
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---------------------------------------------------------------- OBJ

TEST(ObjRead, EveryFaceForm) {
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
      "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nvn 1 0 0\n"
      "f 1 2 3\n"
      "f 1/1 2/2 4/3\n"
      "f 1//1 3//2 4//1\n"
      "f 2/1/1 3/2/2 4/3/1\n";
  Mesh m;
  Status st = obj(text, m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}}));
  EXPECT_EQ(positions_of(m), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
}

TEST(ObjRead, NegativeIndicesAreRelativeToVerticesSoFar) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -1 -2/-1/-1 -4//-2\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {3, 2, 0}}));
}

TEST(ObjRead, NegativeIndexBeforeFirstVertexIsAnError) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nf -1 -2 -3\n", m);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("test.obj: line 3"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("-3"), std::string::npos) << st.message();
}

TEST(ObjRead, PolygonsAndShortFacesKeptAsRead) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 2 2\n"
                  "f 1 2 3 4 5\nf 1 2 3 4\nf 1 2\nf 3\nf 1 1 2\n",
                  m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2, 3, 4}, {0, 1, 2, 3}, {0, 1}, {2}, {0, 0, 1}}));
  EXPECT_FALSE(m.all_triangles());
}

TEST(ObjRead, LinesAndPointsSkippedAndNoted) {
  Mesh m;
  ReadInfo info;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3 1\np 1\nf 1 2 3\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.face_count(), 1u);
  EXPECT_EQ(info.skipped_elements, 3u);
  EXPECT_EQ(info.format, tsm::MeshFormat::obj);
  EXPECT_NE(info.notes.find("skipped 2 'l' records and 1 'p' records"), std::string::npos) << info.notes;
}

TEST(ObjRead, IgnoredAndUnknownRecords) {
  Mesh m;
  ReadInfo info;
  Status st = obj("# comment\nmtllib a.mtl\no thing\ng group\ns off\nusemtl red\nvp 0.5\n"
                  "v 0 0 0 1 0.5 0.5 0.5\n\n   \t\nv 1 0 0\nv 0 1 0\n"
                  "cstype bezier\nfoo bar baz\nfoo\nf 1 2 3 # trailing comment\n",
                  m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}}));
  EXPECT_EQ(m.positions[0], 0.0f);
  EXPECT_NE(info.notes.find("skipped 2 records with unknown keyword 'foo'"), std::string::npos) << info.notes;
  EXPECT_NE(info.notes.find("'cstype'"), std::string::npos) << info.notes;
  EXPECT_EQ(info.skipped_elements, 0u);
}

TEST(ObjRead, LineEndsCrCrlfAndMissingFinalNewline) {
  const Faces want{{0, 1, 2}};
  for (const char* text : {"v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n",
                           "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3", "v 0 0 0\r\nv 1 0 0\rv 0 1 0\nf 1 2 3"}) {
    Mesh m;
    Status st = obj(text, m);
    ASSERT_TRUE(st.ok()) << st.to_string();
    EXPECT_EQ(m.vertex_count(), 3u);
    EXPECT_EQ(faces_of(m), want);
  }
  // Line numbers count CR-only and CRLF line ends.
  Mesh m;
  Status st = obj("v 0 0 0\rv 1 0 0\r\nv 0 1 0\rf 1 2 0\r", m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("line 4"), std::string::npos) << st.message();
}

TEST(ObjRead, BackslashJoinsLines) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 \\\n 0\nv 0 1 0\nf 1 2 \\\r\n 3\nl 1 \\\n 2\nf 3 2 1\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {2, 1, 0}}));
}

TEST(ObjRead, IndexZeroIsAnError) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 0 1 2\n", m);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("test.obj: line 5"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("index 0"), std::string::npos) << st.message();
  EXPECT_EQ(m.vertex_count(), 0u);  // nothing half-read is handed back
}

TEST(ObjRead, OutOfRangeIndexNamesFileLineIndexAndCount) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# c\nf 1 2 7\nv 1 1 1\n", m);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("test.obj: line 6"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("index 7"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("4 vertices"), std::string::npos) << st.message();
}

TEST(ObjRead, ForwardReferenceToALaterVertexIsAccepted) {
  Mesh m;
  Status st = obj("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}}));
}

TEST(ObjRead, HugeIndexIsAnError) {
  Mesh m;
  for (const char* text : {"v 0 0 0\nf 1 1 99999999999999999999999\n", "v 0 0 0\nf 1 1 4294967296\n",
                           "v 0 0 0\nf 1 1 -9223372036854775808\n"}) {
    Status st = obj(text, m);
    ASSERT_FALSE(st.ok()) << text;
    EXPECT_NE(st.message().find("line 2"), std::string::npos) << st.message();
  }
}

TEST(ObjRead, BadNumbersAndMalformedRecords) {
  struct Case {
    const char* text;
    const char* line;
    const char* says;
  };
  for (const Case& c : {Case{"v 0 0 0\nv 1 0 zero\n", "line 2", "'zero'"},
                        Case{"v 0 0 0\nv 1 0\n", "line 2", "no z coordinate"},
                        Case{"v 1.5.3 0 0\n", "line 1", "'1.5.3'"},
                        Case{"v 0 0 0\nf 1 a 1\n", "line 2", "'a'"},
                        Case{"v 0 0 0\nf 1 1x 1\n", "line 2", "'1x'"},
                        Case{"v 0 0 0\nf 1/x 1 1\n", "line 2", "'1/x'"},
                        Case{"v 0 0 0\nf 1/1/1/1 1 1\n", "line 2", "'1/1/1/1'"},
                        Case{"v 0 0 0\n\n\nf\n", "line 4", "no vertex indices"}}) {
    Mesh m;
    Status st = obj(c.text, m);
    ASSERT_FALSE(st.ok()) << c.text;
    EXPECT_EQ(st.code(), ErrorCode::parse_error);
    EXPECT_NE(st.message().find(std::string("test.obj: ") + c.line), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(c.says), std::string::npos) << st.message();
  }
}

TEST(ObjRead, NonFiniteRefusedByDefaultAcceptedWithOption) {
  const std::string text = "v 0 0 0\nv 1 inf 0\nv nan 1 -1e999\nf 1 2 3\n";
  Mesh m;
  Status st = obj(text, m);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("line 2"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("non-finite"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("--allow-nonfinite"), std::string::npos) << st.message();
  ReadOptions o;
  o.allow_nonfinite = true;
  st = obj(text, m, o);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(std::isinf(m.positions[4]));
  EXPECT_TRUE(std::isnan(m.positions[6]));
  EXPECT_TRUE(std::isinf(m.positions[8]) && m.positions[8] < 0);
  expect_roundtrip(m);
}

TEST(ObjRead, LimitsGiveLimitExceeded) {
  const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2 1\n";
  Mesh m;
  ReadOptions o;
  o.max_vertices = 2;
  EXPECT_EQ(obj(text, m, o).code(), ErrorCode::limit_exceeded);
  o.max_vertices = 3;
  o.max_faces = 1;
  EXPECT_EQ(obj(text, m, o).code(), ErrorCode::limit_exceeded);
  o.max_faces = 2;
  EXPECT_TRUE(obj(text, m, o).ok());
}

TEST(ObjRead, EmptyInputGivesEmptyMesh) {
  Mesh m;
  m.add_vertex(1, 2, 3);
  ASSERT_TRUE(obj("", m).ok());
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_EQ(m.face_count(), 0u);
}

TEST(ObjWrite, RoundTripIsBitExact) {
  Mesh m;
  const float xs[] = {0.1f,  -0.0f, 0.0f, 1e-38f, 1.4e-45f /* denormal */, 3.4028235e38f, -123456.789f,
                      1.0f / 3.0f, 16777217.0f, std::nextafter(1.0f, 2.0f), -1e-7f, 7.0f};
  for (size_t i = 0; i + 2 < sizeof xs / sizeof xs[0]; i += 3) m.add_vertex(xs[i], xs[i + 1], xs[i + 2]);
  m.add_vertex(1, 2, 3);  // unreferenced
  const uint32_t quad[] = {0, 1, 2, 3};
  m.add_face(quad, 4);
  m.add_triangle(0, 0, 1);  // degenerate
  const uint32_t pair[] = {2, 1};
  m.add_face(pair, 2);
  const uint32_t one[] = {3};
  m.add_face(one, 1);
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  EXPECT_NE(text.find("\nf 1 2 3 4\n"), std::string::npos) << text;
  EXPECT_NE(text.find("v 0.1 -0 0\n"), std::string::npos) << text;
  Mesh back;
  Status st = obj(text, back);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(bit_identical(m, back));
  EXPECT_TRUE(std::signbit(back.positions[1]));
}

TEST(ObjWrite, RefusesInvalidMesh) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_triangle(0, 0, 1);
  std::string text;
  EXPECT_EQ(tsm::write_obj(m, text).code(), ErrorCode::invalid_argument);
}

// ---------------------------------------------------------------- STL

using Tri = std::array<float, 9>;

std::string binary_stl(const std::string& header, const std::vector<Tri>& tris) {
  std::string out(80, '\0');
  std::memcpy(out.data(), header.data(), std::min<size_t>(header.size(), 80));
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>(v >> (8 * i)));
  };
  auto f32 = [&](float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    u32(b);
  };
  u32(static_cast<uint32_t>(tris.size()));
  for (const Tri& t : tris) {
    f32(0), f32(0), f32(1);  // normal
    for (float x : t) f32(x);
    out.push_back(0), out.push_back(0);  // attribute
  }
  return out;
}

// Two triangles sharing an edge, plus one with -0.0 where the first has +0.0.
const std::vector<Tri> kTris = {
    {0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}, {-0.0f, 0, 0, 1, 0, 0, 0, 1, 0}};

TEST(StlRead, BinaryWeldedAndUnwelded) {
  const std::string bytes = binary_stl("binary test", kTris);
  Mesh m;
  ReadInfo info;
  Status st = stl(bytes, m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(info.binary);
  EXPECT_EQ(info.format, tsm::MeshFormat::stl);
  EXPECT_EQ(m.vertex_count(), 5u);  // 4 corners + the -0.0 one kept apart
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {1, 3, 2}, {4, 1, 2}}));
  EXPECT_TRUE(std::signbit(m.positions[12]));
  ReadOptions o;
  o.stl_weld = false;
  st = stl(bytes, m, o);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.vertex_count(), 9u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {3, 4, 5}, {6, 7, 8}}));
  EXPECT_EQ(m.positions[9], 1.0f);
}

TEST(StlRead, BinaryWhoseHeaderStartsWithSolid) {
  const std::string bytes = binary_stl("solid exported by a careless tool", kTris);
  Mesh m;
  ReadInfo info;
  Status st = stl(bytes, m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(info.binary);
  EXPECT_EQ(m.face_count(), 3u);
  EXPECT_EQ(m.vertex_count(), 5u);
}

TEST(StlRead, EmptyBinary) {
  Mesh m;
  ASSERT_TRUE(stl(binary_stl("", {}), m).ok());
  EXPECT_EQ(m.face_count(), 0u);
}

TEST(StlRead, TruncatedBinaryNamesByteOffset) {
  std::string bytes = binary_stl("x", kTris);
  bytes.resize(bytes.size() - 7);
  Mesh m;
  Status st = stl(bytes, m);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("test.stl: byte 184:"), std::string::npos) << st.message();  // 84 + 2 * 50
  EXPECT_NE(st.message().find("truncated"), std::string::npos) << st.message();
  // Extra bytes after the triangles.
  bytes = binary_stl("x", kTris) + "junk";
  st = stl(bytes, m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("byte 234"), std::string::npos) << st.message();
  // Too short for a header.
  st = stl(std::string(40, '\x01'), m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("byte 40"), std::string::npos) << st.message();
  // A huge count in a small file fails at once.
  bytes = binary_stl("x", kTris);
  bytes[83] = '\x7f';
  st = stl(bytes, m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("truncated"), std::string::npos) << st.message();
}

TEST(StlRead, BinaryNonFiniteAndLimits) {
  std::vector<Tri> tris = kTris;
  tris[1][4] = std::numeric_limits<float>::quiet_NaN();
  const std::string bytes = binary_stl("", tris);
  Mesh m;
  Status st = stl(bytes, m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("byte 158"), std::string::npos) << st.message();  // 84 + 50 + 12 + 12
  EXPECT_NE(st.message().find("--allow-nonfinite"), std::string::npos) << st.message();
  ReadOptions o;
  o.allow_nonfinite = true;
  ASSERT_TRUE(stl(bytes, m, o).ok());
  EXPECT_TRUE(std::isnan(m.positions[m.face(1)[1] * 3 + 1]));
  o = ReadOptions();
  o.max_faces = 2;
  EXPECT_EQ(stl(binary_stl("", kTris), m, o).code(), ErrorCode::limit_exceeded);
  o = ReadOptions();
  o.max_vertices = 4;
  EXPECT_EQ(stl(binary_stl("", kTris), m, o).code(), ErrorCode::limit_exceeded);
  o.max_vertices = 5;
  EXPECT_TRUE(stl(binary_stl("", kTris), m, o).ok());
  o.stl_weld = false;
  EXPECT_EQ(stl(binary_stl("", kTris), m, o).code(), ErrorCode::limit_exceeded);
}

const char* const kAsciiStl =
    "solid  test \n"
    "  facet normal 0 0 1\n"
    "    outer loop\n"
    "      vertex 0 0 0\n"
    "      vertex 1 0 0\n"
    "      vertex 0 1 0\n"
    "    endloop\n"
    "  endfacet\n"
    "FACET NORMAL 0 0 1\r\n"
    "\tOuter   Loop\r\n"
    "\t\tVERTEX 1 0 0\r\n"
    "\t\tvertex   1e0  1.0   0.0  \r\n"
    "\n"
    "\t\tvertex 0 1 0\r\n"
    "\tENDLOOP\r\n"
    "EndFacet\r\n"
    "endsolid test\n";

TEST(StlRead, AsciiWeldedAndUnwelded) {
  Mesh m;
  ReadInfo info;
  Status st = stl(kAsciiStl, m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_FALSE(info.binary);
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {1, 3, 2}}));
  ReadOptions o;
  o.stl_weld = false;
  ASSERT_TRUE(stl(kAsciiStl, m, o).ok());
  EXPECT_EQ(m.vertex_count(), 6u);
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {3, 4, 5}}));
}

TEST(StlRead, AsciiMatchesBinary) {
  Mesh a, b;
  ASSERT_TRUE(stl(kAsciiStl, a).ok());
  ASSERT_TRUE(stl(binary_stl("", {kTris[0], kTris[1]}), b).ok());
  EXPECT_TRUE(bit_identical(a, b));
}

TEST(StlRead, AsciiErrorsNameTheLine) {
  struct Case {
    std::string text;
    const char* line;
    const char* says;
  };
  const std::string head = "solid x\nfacet normal 0 0 1\nouter loop\n";
  for (const Case& c : {Case{head + "vertex 0 0 0\nvertex 1 0 zz\n", "line 5", "'zz'"},
                        Case{head + "vertex 0 0 0\nvertex 1 0\nvertex 0 1 0\n", "line 5", "fewer than 3"},
                        Case{head + "vertex 0 0 0\nvertex 1 0 0\nendloop\n", "line 6", "2 vertices"},
                        Case{head + "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nvertex 0 1 0\n", "line 7",
                             "more than 3"},
                        Case{head + "vertex 0 0 0\nvertex 1 0 0\n", "line 6", "ends inside a facet"},
                        Case{"solid x\nfacet normal 0 0 1\nouter\nvertex", "line 4", "expected 'loop' after 'outer', found 'vertex'"},
                        Case{"solid x\nfoo\n", "line 2", "'foo'"},
                        Case{head + "vertex 0 0 0\nvertex 1 0 nan\n", "line 5", "non-finite"}}) {
    Mesh m;
    Status st = stl(c.text, m);
    ASSERT_FALSE(st.ok()) << c.text;
    EXPECT_EQ(st.code(), ErrorCode::parse_error);
    EXPECT_NE(st.message().find(std::string("test.stl: ") + c.line), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(c.says), std::string::npos) << st.message();
  }
}

TEST(StlRead, NeitherBinaryNorAscii) {
  Mesh m;
  Status st = stl(std::string(200, 'x'), m);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("byte"), std::string::npos) << st.message();
  EXPECT_FALSE(stl("", m).ok());
}

// ---------------------------------------------------------------- OFF

const char* const kCubeOff =
    "OFF\n"
    "# a cube\n"
    "8 6 12\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
    "0 0 1\n1 0 1\n1 1 1\n0 1 1  # comment after a vertex\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n"
    "\n# faces continue\n"
    "4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n";

TEST(OffRead, Cube) {
  Mesh m;
  ReadInfo info;
  Status st = off(kCubeOff, m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(info.format, tsm::MeshFormat::off);
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.face_count(), 6u);
  EXPECT_EQ(faces_of(m)[5], (std::vector<uint32_t>{3, 0, 4, 7}));
  EXPECT_EQ(m.positions[3 * 6 + 2], 1.0f);
  expect_roundtrip(m);
}

TEST(OffRead, PolygonsColoursAndVariants) {
  Mesh m;
  Status st = off("COFF 5 3 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n"
                  "2 2 2 0.5 0.5 0.5 1\n5 0 1 2 3 4 255 0 0\n3 0 1 2\n2 3 4 0.1 0.2 0.3\n",
                  m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2, 3, 4}, {0, 1, 2}, {3, 4}}));
  EXPECT_EQ(m.positions[12], 2.0f);
  for (const char* text : {"NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n",
                           "STCNOFF\n3 1 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 0 0\n"
                           "0 1 0 0 0 1 1 1 1 1 0 0\n3 0 1 2\n",
                           "OFF3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "OFF\r3 1\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2",
                           "# leading comment\n\nOFF\n3 1 0 # counts\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"}) {
    st = off(text, m);
    ASSERT_TRUE(st.ok()) << text << "\n" << st.to_string();
    EXPECT_EQ(m.vertex_count(), 3u) << text;
    EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}})) << text;
    EXPECT_EQ(m.positions[3], 1.0f) << text;
  }
  EXPECT_EQ(off("4OFF\n1 0 0\n0 0 0 1\n", m).code(), ErrorCode::unsupported);
  EXPECT_EQ(off("OFF BINARY\n", m).code(), ErrorCode::unsupported);
}

TEST(OffRead, TruncatedAndBadInput) {
  struct Case {
    std::string text;
    const char* line;
    const char* says;
  };
  for (const Case& c :
       {Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "line 6", "3 corners but only 5 bytes follow"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 # 2\n", "line 7", "the file ends where vertex index"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", "line 2", "only"},
        Case{"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "line 7", "ends at face 1"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n", "line 4", "'x'"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6", "index 3 is out of range"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "line 6", "negative"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n0\n", "line 6", "0 corners"},
        Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n999999 0 1 2\n", "line 6", "999999 corners"},
        Case{"OFF\n3 1 0\n0 0 inf\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3", "non-finite"},
        Case{"OBJ\n", "line 1", "'OFF' header"},
        Case{"", "line 1", "empty"}}) {
    Mesh m;
    Status st = off(c.text, m);
    ASSERT_FALSE(st.ok()) << c.text;
    EXPECT_EQ(st.code(), ErrorCode::parse_error) << st.message();
    EXPECT_NE(st.message().find(std::string("test.off: ") + c.line), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(c.says), std::string::npos) << st.message();
  }
}

TEST(OffRead, HugeCountsFailFast) {
  Mesh m;
  for (const char* text : {"OFF\n4000000000 1 0\n0 0 0\n", "OFF\n3 99999999999 0\n0 0 0\n1 0 0\n0 1 0\n",
                           "OFF\n18446744073709551615 18446744073709551615 0\n"}) {
    Status st = off(text, m);
    ASSERT_FALSE(st.ok()) << text;
    EXPECT_NE(st.message().find("line 2"), std::string::npos) << st.message();
  }
  EXPECT_FALSE(off("OFF\n99999999999999999999999 1 0\n", m).ok());
  ReadOptions o;
  o.max_vertices = 7;
  EXPECT_EQ(off(kCubeOff, m, o).code(), ErrorCode::limit_exceeded);
  o.max_vertices = 0;
  o.max_faces = 5;
  EXPECT_EQ(off(kCubeOff, m, o).code(), ErrorCode::limit_exceeded);
}

// ---------------------------------------------------------------- corpus

struct Expect {
  size_t vertices;
  size_t faces;
  size_t skipped;
};

TEST(CorpusEdge, ObjAndStlFilesLoadOrAreRefusedAsExpected) {
  TSM_REQUIRE_CORPUS();
  const std::map<std::string, Expect> loads = {
      {"cube_att.obj", {8, 12, 0}},
      {"cube_quads.obj", {8, 6, 0}},
      {"cube_subd.obj", {1538, 3072, 0}},
      {"deg_faces.obj", {6, 4, 0}},
      {"degenerate_mesh.obj", {3, 1, 0}},
      {"empty_name.obj", {3, 1, 0}},
      {"eof_test.obj", {3, 1, 0}},
      {"extra_vertex.obj", {10, 3, 0}},
      {"multiple_isolated_triangles.obj", {15, 5, 0}},
      {"multiple_tetrahedrons.obj", {20, 20, 0}},
      {"non_manifold_wrap.obj", {10, 12, 0}},
      {"octagon.obj", {8, 1, 0}},
      {"sphere.obj", {114, 224, 0}},
      {"test_lines.obj", {484, 0, 242}},
      {"test_nm.obj", {114, 170, 0}},
      {"three_faces_123.obj", {6, 3, 0}},
      {"triangle.obj", {3, 1, 0}},
      {"two_faces_123.obj", {6, 2, 0}},
      {"test_sphere.stl", {114, 224, 0}},
      {"test_sphere_ascii.stl", {114, 224, 0}},
  };
  // Refused by default, loaded with allow_nonfinite.
  const std::map<std::string, Expect> nonfinite = {{"inf_nan.obj", {3, 1, 0}}};

  size_t seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(tsm_test::corpus_file("edge"))) {
    const std::string file = entry.path().filename().string();
    const std::string ext = entry.path().extension().string();
    if (ext != ".obj" && ext != ".stl") continue;
    ++seen;
    SCOPED_TRACE(file);
    const std::string bytes = slurp(entry.path().string());
    ASSERT_FALSE(bytes.empty());
    auto read = [&](Mesh& m, const ReadOptions& o, ReadInfo* info) {
      return ext == ".obj" ? tsm::read_obj(bytes, file, m, o, info) : tsm::read_stl(bytes, file, m, o, info);
    };
    Mesh m;
    ReadInfo info;
    ReadOptions o;
    Expect want{};
    if (auto it = nonfinite.find(file); it != nonfinite.end()) {
      Status st = read(m, o, &info);
      ASSERT_FALSE(st.ok());
      EXPECT_EQ(st.code(), ErrorCode::parse_error);
      EXPECT_NE(st.message().find("non-finite"), std::string::npos) << st.message();
      EXPECT_NE(st.message().find(file + ": line 1"), std::string::npos) << st.message();
      o.allow_nonfinite = true;
      want = it->second;
    } else {
      auto it2 = loads.find(file);
      ASSERT_NE(it2, loads.end()) << "new corpus file without expected counts";
      want = it2->second;
    }
    Status st = read(m, o, &info);
    ASSERT_TRUE(st.ok()) << st.to_string();
    EXPECT_EQ(m.vertex_count(), want.vertices);
    EXPECT_EQ(m.face_count(), want.faces);
    EXPECT_EQ(info.skipped_elements, want.skipped);
    std::string why;
    EXPECT_TRUE(m.valid(&why)) << why;
    expect_roundtrip(m);
  }
  EXPECT_EQ(seen, loads.size() + nonfinite.size());
}

TEST(CorpusEdge, SpecificShapes) {
  TSM_REQUIRE_CORPUS();
  auto load = [](const std::string& rel, Mesh& m, ReadInfo* info = nullptr) {
    const std::string bytes = slurp(tsm_test::corpus_file(rel));
    return rel.size() > 4 && rel.substr(rel.size() - 4) == ".stl" ? tsm::read_stl(bytes, rel, m, {}, info)
                                                                   : tsm::read_obj(bytes, rel, m, {}, info);
  };
  Mesh m;
  ASSERT_TRUE(load("edge/octagon.obj", m).ok());
  EXPECT_EQ(m.face_size(0), 8u);
  ASSERT_TRUE(load("edge/cube_quads.obj", m).ok());
  for (size_t f = 0; f < m.face_count(); ++f) EXPECT_EQ(m.face_size(f), 4u);
  ASSERT_TRUE(load("edge/extra_vertex.obj", m).ok());
  EXPECT_EQ(m.unreferenced_vertex_count(), 1u);
  ASSERT_TRUE(load("edge/deg_faces.obj", m).ok());
  EXPECT_EQ(m.degenerate_face_count(), 1u);
  ASSERT_TRUE(load("edge/eof_test.obj", m).ok());
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}}));
  ReadInfo info;
  ASSERT_TRUE(load("edge/test_lines.obj", m, &info).ok());
  EXPECT_NE(info.notes.find("skipped 242 'l' records"), std::string::npos) << info.notes;
  Mesh bin, ascii;
  ReadInfo bi, ai;
  ASSERT_TRUE(load("edge/test_sphere.stl", bin, &bi).ok());
  ASSERT_TRUE(load("edge/test_sphere_ascii.stl", ascii, &ai).ok());
  EXPECT_TRUE(bi.binary);
  EXPECT_FALSE(ai.binary);
  EXPECT_EQ(faces_of(bin), faces_of(ascii));  // same welding, same first-appearance order
}

// ===========================================================================
// OFF attributes (N, C, ST prefixes, face colours) and the OFF writer

const tsm::Attribute* attr(const Mesh& m, tsm::AttributeDomain d, tsm::AttributeKind k) {
  for (const tsm::Attribute& a : m.attributes)
    if (a.domain == d && a.kind == k) return &a;
  return nullptr;
}

TEST(OffAttributes, CoffVertexColoursIntegerAndFloat) {
  Mesh m;
  ReadInfo info;
  ASSERT_TRUE(off("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n0 1 0 0 0 255 0\n3 0 1 2\n", m, {}, &info).ok());
  const tsm::Attribute* c = attr(m, tsm::AttributeDomain::vertex, tsm::AttributeKind::color);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->name, "color");
  EXPECT_EQ(c->type, tsm::AttributeType::u8);
  EXPECT_EQ(c->components, 4u);
  EXPECT_EQ(c->values, (std::vector<float>{255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0}));
  EXPECT_EQ(info.notes, "");
  // Floats (Geomview's 0..1 RGBA, or RGB) stay f32 as written.
  ASSERT_TRUE(off("COFF\n3 1 0\n0 0 0 1 0.5 0\n1 0 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2\n", m).ok());
  c = attr(m, tsm::AttributeDomain::vertex, tsm::AttributeKind::color);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->type, tsm::AttributeType::f32);
  EXPECT_EQ(c->components, 3u);
  EXPECT_EQ(c->values, (std::vector<float>{1, 0.5f, 0, 0, 1, 0, 0, 0, 1}));
}

TEST(OffAttributes, NormalsColoursTextureCoordinatesInGeomviewOrder) {
  Mesh m;
  ASSERT_TRUE(off("STCNOFF\n3 1 0\n0 0 0  0 0 1  10 20 30  0.25 0.75\n1 0 0  0 0 1  40 50 60  1 0\n"
                  "0 1 0  0 0 1  70 80 90  0 1\n3 0 1 2 1 0 0\n",
                  m)
                  .ok());
  EXPECT_EQ(positions_of(m), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  const tsm::Attribute* n = attr(m, tsm::AttributeDomain::vertex, tsm::AttributeKind::normal);
  const tsm::Attribute* c = attr(m, tsm::AttributeDomain::vertex, tsm::AttributeKind::color);
  const tsm::Attribute* t = attr(m, tsm::AttributeDomain::vertex, tsm::AttributeKind::texcoord);
  const tsm::Attribute* fc = attr(m, tsm::AttributeDomain::face, tsm::AttributeKind::color);
  ASSERT_TRUE(n && c && t && fc);
  EXPECT_EQ(n->values, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(c->values, (std::vector<float>{10, 20, 30, 40, 50, 60, 70, 80, 90}));
  EXPECT_EQ(c->type, tsm::AttributeType::u8);
  EXPECT_EQ(t->values, (std::vector<float>{0.25f, 0.75f, 1, 0, 0, 1}));
  EXPECT_EQ(fc->values, (std::vector<float>{1, 0, 0}));
}

TEST(OffAttributes, LinesThatDisagreeDropTheValuesWithANote) {
  Mesh m;
  ReadInfo info;
  // The second vertex has no colour: no colours, a note naming the lines.
  ASSERT_TRUE(off("COFF\n3 2 0\n0 0 0 1 0 0\n1 0 0\n0 1 0 0 0 1\n3 0 1 2 255 0 0\n3 0 2 1\n", m, {}, &info).ok());
  EXPECT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(m.face_count(), 2u);
  EXPECT_TRUE(m.attributes.empty());
  EXPECT_NE(info.notes.find("ignored the vertex colours the header 'COFF' announces: line 4"), std::string::npos)
      << info.notes;
  EXPECT_NE(info.notes.find("ignored the face colours: line 6 has one but line 7"), std::string::npos) << info.notes;
  // Numbers a plain OFF does not announce are named, not silently skipped.
  ASSERT_TRUE(off("OFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 1 0 0\n0 1 0\n3 0 1 2 7\n", m, {}, &info).ok());
  EXPECT_TRUE(m.attributes.empty());
  EXPECT_NE(info.notes.find("ignored the numbers after x y z on 2 vertex lines (first: line 3)"), std::string::npos)
      << info.notes;
  EXPECT_NE(info.notes.find("after the indices of 1 face"), std::string::npos) << info.notes;
  // Non-finite colours need the option, like coordinates.
  Status st = off("COFF\n1 0 0\n0 0 0 nan 0 0\n", m);
  EXPECT_EQ(st.code(), ErrorCode::parse_error);
  EXPECT_NE(st.message().find("test.off: line 3"), std::string::npos) << st.message();
}

TEST(OffWriter, RoundTripsPositionsFacesAndAttributes) {
  Mesh m = tsm_test::cube_quads();
  m.add_vertex(0.1f, 1e-30f, -3.25e7f);  // unreferenced, odd floats
  const uint32_t tri[3] = {0, 1, 2};
  m.add_face(tri, 3);
  tsm::Attribute color, normal, tex, fcolor;
  color.name = "color", color.kind = tsm::AttributeKind::color, color.type = tsm::AttributeType::u8;
  color.components = 4;
  normal.name = "normal", normal.kind = tsm::AttributeKind::normal, normal.components = 3;
  tex.name = "texcoord", tex.kind = tsm::AttributeKind::texcoord, tex.components = 2;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    for (int k = 0; k < 4; ++k) color.values.push_back(static_cast<float>((v * 37 + k * 11) % 256));
    normal.values.insert(normal.values.end(), {0.6f, 0.8f, 0.0f});
    tex.values.insert(tex.values.end(), {0.1f * static_cast<float>(v), 1.0f});
  }
  fcolor.name = "color", fcolor.kind = tsm::AttributeKind::color, fcolor.domain = tsm::AttributeDomain::face;
  fcolor.components = 3;
  for (size_t f = 0; f < m.face_count(); ++f) fcolor.values.insert(fcolor.values.end(), {0.0f, 1.0f, 0.5f});
  m.attributes = {color, normal, tex, fcolor};
  std::string text;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_off(m, tsm::WriteOptions{}, text, &info).ok());
  EXPECT_EQ(info.notes, "");
  EXPECT_EQ(text.substr(0, 8), "STCNOFF\n") << text;
  EXPECT_TRUE(tsm_test::contains(text, " 0.0 1.0 0.5\n")) << text;  // f32 colours marked as floats
  Mesh back;
  ReadInfo ri;
  ASSERT_TRUE(off(text, back, {}, &ri).ok());
  EXPECT_EQ(ri.notes, "");
  EXPECT_TRUE(bit_identical(m, back));
  ASSERT_EQ(back.attributes.size(), 4u);
  for (const tsm::Attribute& a : m.attributes) {
    const tsm::Attribute* b = attr(back, a.domain, a.kind);
    ASSERT_NE(b, nullptr) << a.name;
    EXPECT_EQ(b->type, a.type) << a.name;
    EXPECT_EQ(b->components, a.components) << a.name;
    EXPECT_EQ(b->values, a.values) << a.name;
  }
  // Colours only: COFF. No attributes: plain OFF, as the reader's own input.
  m.attributes = {color};
  ASSERT_TRUE(tsm::write_off(m, tsm::WriteOptions{}, text).ok());
  EXPECT_EQ(text.substr(0, 5), "COFF\n");
  m.attributes.clear();
  ASSERT_TRUE(tsm::write_off(m, tsm::WriteOptions{}, text).ok());
  EXPECT_EQ(text.substr(0, 4), "OFF\n");
  ASSERT_TRUE(off(text, back).ok());
  EXPECT_TRUE(bit_identical(m, back));
}

TEST(OffWriter, NotesWhatOffCannotHold) {
  Mesh m = tsm_test::icosphere(0);
  tsm::Attribute a;
  a.name = "confidence";
  a.values.assign(m.vertex_count(), 1.0f);
  m.attributes.push_back(a);
  m.metadata.push_back({"obj", "group g\n"});
  std::string text;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_off(m, tsm::WriteOptions{}, text, &info).ok());
  EXPECT_NE(info.notes.find("OFF cannot hold the vertex attribute 'confidence', metadata 'obj'"), std::string::npos)
      << info.notes;
  EXPECT_EQ(text.substr(0, 4), "OFF\n");
}

// ===========================================================================
// STL writer

TEST(StlWriter, BinaryAndAsciiRoundTripThroughTheReader) {
  const Mesh m = tsm_test::icosphere(2);
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    tsm::WriteOptions wo;
    wo.ascii = ascii;
    std::string bytes;
    tsm::WriteInfo info;
    ASSERT_TRUE(tsm::write_stl(m, wo, bytes, &info).ok());
    EXPECT_EQ(info.notes, "");
    if (ascii) {
      EXPECT_EQ(bytes.substr(0, 10), "solid tsm\n");
    } else {
      EXPECT_EQ(bytes.size(), 84 + 50 * m.face_count());
      EXPECT_NE(bytes.substr(0, 5), "solid");  // readers that look at the first word must not take it for ASCII
    }
    EXPECT_EQ(tsm::sniff_format(bytes), tsm::MeshFormat::stl);
    Mesh back;
    ReadInfo ri;
    ASSERT_TRUE(stl(bytes, back, {}, &ri).ok());
    EXPECT_EQ(ri.binary, !ascii);
    // Bit-exact positions (bits = 0), same faces up to the vertex order.
    const tsm::CompareResult cr = tsm::compare_meshes(m, back, 0);
    EXPECT_TRUE(cr.equal) << cr.difference;
  }
}

TEST(StlWriter, PolygonsBecomeFansAndWhatStlCannotHoldIsNoted) {
  Mesh m = tsm_test::cube_quads();  // 6 quads
  m.add_vertex(5, 5, 5);            // no face uses it
  const uint32_t edge[2] = {0, 1};
  m.add_face(edge, 2);
  tsm::Attribute a;
  a.name = "color";
  a.kind = tsm::AttributeKind::color;
  a.components = 3;
  a.values.assign(3 * m.vertex_count(), 0.5f);
  m.attributes.push_back(a);
  std::string bytes;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_stl(m, tsm::WriteOptions{}, bytes, &info).ok());
  EXPECT_EQ(bytes.size(), 84u + 50u * 12u);
  for (const char* part : {"split 6 polygons into triangle fans", "faces of 1 or 2 corners: left out 1",
                           "vertices no face uses: left out 1", "STL cannot hold the vertex attribute 'color'"})
    EXPECT_NE(info.notes.find(part), std::string::npos) << part << " in " << info.notes;
  Mesh back;
  ASSERT_TRUE(stl(bytes, back).ok());
  EXPECT_EQ(back.vertex_count(), 8u);
  EXPECT_EQ(back.face_count(), 12u);
  // The fan of a quad (a b c d) is (a b c), (a c d): the cube's area and
  // orientation are kept, which the triangulated cube of compare_meshes shows.
  Mesh tri;
  tri.positions = tsm_test::cube_quads().positions;
  const Mesh cube = tsm_test::cube_quads();
  for (size_t f = 0; f < cube.face_count(); ++f) {
    const uint32_t* c = cube.face(f);
    tri.add_triangle(c[0], c[1], c[2]);
    tri.add_triangle(c[0], c[2], c[3]);
  }
  const tsm::CompareResult cr = tsm::compare_meshes(tri, back, 0);
  EXPECT_TRUE(cr.equal) << cr.difference;
}

TEST(StlWriter, WriteMeshByExtension) {
  tsm_test::TempDir dir;
  const Mesh m = tsm_test::icosphere(1);
  for (const char* name : {"a.stl", "a.off"}) {
    SCOPED_TRACE(name);
    tsm::WriteInfo info;
    Status st = tsm::write_mesh(dir.file(name), m, tsm::WriteOptions{}, &info);
    ASSERT_TRUE(st.ok()) << st.to_string();
    Mesh back;
    ReadInfo ri;
    st = tsm::read_mesh(dir.file(name), back, {}, &ri);
    ASSERT_TRUE(st.ok()) << st.to_string();
    EXPECT_EQ(ri.format, std::string(name) == "a.stl" ? tsm::MeshFormat::stl : tsm::MeshFormat::off);
    const tsm::CompareResult cr = tsm::compare_meshes(m, back, 0);
    EXPECT_TRUE(cr.equal) << cr.difference;
  }
  Status st = tsm::write_mesh(dir.file("a.xyz"), m);
  EXPECT_EQ(st.code(), ErrorCode::invalid_argument);
  EXPECT_NE(st.message().find(".ply, .obj, .stl, .off, .gltf or .glb"), std::string::npos) << st.message();
}

}  // namespace

// A face without corners cannot be written as an OBJ or OFF line: both
// writers refuse the mesh, naming the face, instead of writing an empty line
// that would read back as another mesh.
TEST(TextWriters, RefuseAFaceWithoutCorners) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(1, 0, 0);
  m.add_vertex(0, 1, 0);
  m.add_triangle(0, 1, 2);
  m.face_offsets.push_back(m.face_offsets.back());  // face 1: no corners
  ASSERT_TRUE(m.valid());
  std::string out;
  tsm::Status s = tsm::write_obj(m, out);
  EXPECT_EQ(s.code(), ErrorCode::invalid_argument);
  EXPECT_TRUE(tsm_test::contains(s.message(), "cannot write OBJ: face 1 has no corners")) << s.to_string();
  s = tsm::write_off(m, tsm::WriteOptions(), out);
  EXPECT_EQ(s.code(), ErrorCode::invalid_argument);
  EXPECT_TRUE(tsm_test::contains(s.message(), "cannot write OFF: face 1 has no corners")) << s.to_string();
}
