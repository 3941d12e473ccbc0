// Tests for attributes (normals, colours, texture coordinates, generic
// values) in the PLY and OBJ readers and writers (io_ply.cpp, io_obj.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::Attribute;
using tsm::AttributeDomain;
using tsm::AttributeKind;
using tsm::AttributeType;
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

::testing::AssertionResult same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
  for (size_t i = 0; i < a.size(); ++i)
    if (bits(a[i]) != bits(b[i]))
      return ::testing::AssertionFailure() << "value " << i << " differs: " << a[i] << " (bits " << std::hex
                                           << bits(a[i]) << ") vs " << b[i] << " (bits " << bits(b[i]) << ")";
  return ::testing::AssertionSuccess();
}

const char* domain_name(AttributeDomain d) {
  return d == AttributeDomain::vertex ? "vertex" : d == AttributeDomain::face ? "face" : "corner";
}

// Everything of two attributes, values compared by their bits.
::testing::AssertionResult same_attribute(const Attribute& a, const Attribute& b) {
  if (a.name != b.name) return ::testing::AssertionFailure() << "names '" << a.name << "' vs '" << b.name << "'";
  if (a.kind != b.kind) return ::testing::AssertionFailure() << a.name << ": kinds differ";
  if (a.domain != b.domain)
    return ::testing::AssertionFailure() << a.name << ": domains " << domain_name(a.domain) << " vs "
                                         << domain_name(b.domain);
  if (a.type != b.type)
    return ::testing::AssertionFailure() << a.name << ": types " << int(a.type) << " vs " << int(b.type);
  if (a.components != b.components) return ::testing::AssertionFailure() << a.name << ": components differ";
  auto r = same_bits(a.values, b.values);
  if (!r) return r << " (attribute '" << a.name << "')";
  if (a.indices != b.indices) return ::testing::AssertionFailure() << a.name << ": indices differ";
  return ::testing::AssertionSuccess();
}

// The values each corner sees, in corner order (any domain).
std::vector<float> per_corner(const Mesh& m, const Attribute& a) {
  std::vector<float> out;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t j = 0; j < m.face_size(f); ++j) {
      const size_t c = m.face_offsets[f] + j;
      const size_t v = a.domain == AttributeDomain::vertex ? m.indices[c]
                       : a.domain == AttributeDomain::face ? f
                                                           : a.indices[c];
      for (uint32_t q = 0; q < a.components; ++q) out.push_back(a.values[v * a.components + q]);
    }
  return out;
}

const Attribute* find(const Mesh& m, const std::string& name) {
  for (const Attribute& a : m.attributes)
    if (a.name == name) return &a;
  return nullptr;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = s.find(from, at)) != std::string::npos; at += to.size()) s.replace(at, from.size(), to);
  return s;
}

Status ply(const std::string& bytes, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_ply(bytes, "attr.ply", m, o, info);
}
Status obj(const std::string& text, Mesh& m, const ReadOptions& o = {}, ReadInfo* info = nullptr) {
  return tsm::read_obj(text, "attr.obj", m, o, info);
}

// Expects a parse_error naming the file and containing every part given;
// the mesh handed in is cleared.
void expect_error(Status (*read)(const std::string&, Mesh&, const ReadOptions&, ReadInfo*), const std::string& bytes,
                  std::initializer_list<std::string> parts, const ReadOptions& o = {}) {
  Mesh m;
  m.add_triangle(0, 0, 0);
  Status s = read(bytes, m, o, nullptr);
  ASSERT_FALSE(s.ok()) << "accepted: " << bytes.substr(0, 300);
  EXPECT_EQ(s.code(), ErrorCode::parse_error) << s.to_string();
  for (const std::string& p : parts) EXPECT_TRUE(contains(s.message(), p));
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_TRUE(m.attributes.empty());
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

Attribute make(const std::string& name, AttributeKind kind, AttributeDomain domain, AttributeType type,
               uint32_t components, std::vector<float> values, std::vector<uint32_t> indices = {}) {
  Attribute a;
  a.name = name;
  a.kind = kind;
  a.domain = domain;
  a.type = type;
  a.components = components;
  a.values = std::move(values);
  a.indices = std::move(indices);
  return a;
}

// Five vertices, a quad and two triangles (10 corners).
Mesh base_mesh() {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(1, 0, 0);
  m.add_vertex(1, 1, 0);
  m.add_vertex(0, 1, 0);
  m.add_vertex(0.5f, 0.5f, 1);
  const uint32_t quad[] = {0, 1, 2, 3};
  m.add_face(quad, 4);
  m.add_triangle(0, 1, 4);
  m.add_triangle(2, 3, 4);
  return m;
}

const float kDenormal = from_bits(0x00000001u);
const float kThird = 1.0f / 3.0f;

// Vertex- and face-domain attributes of every kind and type PLY can hold
// exactly, in the order a PLY read gives them back.
Mesh vertex_and_face_mesh() {
  Mesh m = base_mesh();
  using K = AttributeKind;
  using D = AttributeDomain;
  using T = AttributeType;
  m.attributes.push_back(make("normal", K::normal, D::vertex, T::f32, 3,
                              {0, 0, 1, -0.0f, 1, 0, kThird, -kThird, kThird, kDenormal, 0.6f, 0.8f, 1, 0, 0}));
  m.attributes.push_back(make("color", K::color, D::vertex, T::u8, 4,
                              {0, 255, 128, 255, 1, 2, 3, 4, 255, 255, 255, 0, 10, 20, 30, 40, 200, 100, 50, 25}));
  m.attributes.push_back(make("texcoord", K::texcoord, D::vertex, T::f32, 2,
                              {0, 0, 1, 0, 1, 1, 0, 1, 0.5f, 16777217.0f}));
  m.attributes.push_back(make("quality", K::generic, D::vertex, T::f32, 1, {0.1f, 1e-30f, -3e38f, 7, 0}));
  m.attributes.push_back(make("id", K::generic, D::vertex, T::i32, 1, {-16777216, 0, 16777216, -1, 2147483520.0f}));
  m.attributes.push_back(make("flags", K::generic, D::vertex, T::u16, 1, {0, 65535, 1, 2, 3}));
  m.attributes.push_back(make("weights", K::generic, D::vertex, T::f32, 3,
                              {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0.25f, 0.5f, 0.125f}));
  m.attributes.push_back(make("color", K::color, D::face, T::u16, 3, {0, 65535, 300, 1, 2, 3, 4, 5, 6}));
  m.attributes.push_back(make("material", K::generic, D::face, T::u8, 1, {0, 7, 255}));
  m.attributes.push_back(make("normal", K::normal, D::face, T::f32, 3, {0, 0, 1, 0, -1, 0, kThird, 0, -kThird}));
  m.attributes.push_back(make("pair", K::generic, D::face, T::i32, 2, {-5, 5, 0, 1, -2147483648.0f, 12}));
  return m;
}

// Corner-domain attributes: a texture atlas with shared values (and one
// unused), per-corner normals, a 4-component generic of integer type.
Mesh corner_mesh() {
  Mesh m = base_mesh();
  using K = AttributeKind;
  using D = AttributeDomain;
  using T = AttributeType;
  m.attributes.push_back(make("texcoord", K::texcoord, D::corner, T::f32, 2,
                              {0, 0, 1, 0, 1, 1, 0, 1, 0.5f, kThird, 9, 9 /* unused */},
                              {0, 1, 2, 3, 0, 1, 4, 2, 3, 4}));
  m.attributes.push_back(make("normal", K::normal, D::corner, T::f32, 3, {0, 0, 1, 0, 0, -1, -0.0f, kDenormal, 1},
                              {0, 0, 0, 0, 1, 1, 2, 2, 2, 1}));
  m.attributes.push_back(make("tangent", K::generic, D::corner, T::u16, 4, {1, 2, 3, 4, 65535, 0, 0, 65535},
                              {0, 1, 0, 1, 0, 1, 0, 1, 1, 1}));
  m.attributes.push_back(make("color", K::color, D::corner, T::u8, 3, {255, 0, 0, 0, 255, 0},
                              {0, 0, 0, 0, 1, 1, 1, 0, 0, 0}));
  return m;
}

Mesh write_read_ply(const Mesh& m, bool ascii, ReadInfo* info = nullptr, std::string* bytes_out = nullptr) {
  WriteOptions wo;
  wo.ascii = ascii;
  std::string bytes;
  Status w = tsm::write_ply(m, wo, bytes);
  EXPECT_TRUE(w.ok()) << w.to_string();
  Mesh back;
  Status r = ply(bytes, back, {}, info);
  EXPECT_TRUE(r.ok()) << r.to_string();
  std::string why;
  EXPECT_TRUE(back.valid(&why)) << why;
  if (bytes_out) *bytes_out = bytes;
  return back;
}

// ===========================================================================
// PLY round trips

TEST(PlyAttributes, VertexAndFaceAttributesRoundTripExactly) {
  const Mesh m = vertex_and_face_mesh();
  ASSERT_TRUE(m.valid());
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    ReadInfo info;
    const Mesh back = write_read_ply(m, ascii, &info);
    EXPECT_TRUE(info.notes.empty()) << info.notes;
    EXPECT_EQ(back.positions, m.positions);
    EXPECT_EQ(faces_of(back), faces_of(m));
    ASSERT_EQ(back.attributes.size(), m.attributes.size());
    for (size_t i = 0; i < m.attributes.size(); ++i) EXPECT_TRUE(same_attribute(back.attributes[i], m.attributes[i]));
  }
}

TEST(PlyAttributes, HeaderUsesTheConventionalNamesAndTypes) {
  std::string text;
  WriteOptions wo;
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(vertex_and_face_mesh(), wo, text).ok());
  EXPECT_TRUE(contains(text,
                       "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                       "property float nx\nproperty float ny\nproperty float nz\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                       "property float s\nproperty float t\nproperty float quality\nproperty int id\n"
                       "property ushort flags\n"
                       "property float weights_0\nproperty float weights_1\nproperty float weights_2\n"
                       "element face 3\nproperty list uchar uint vertex_indices\n"
                       "property ushort red\nproperty ushort green\nproperty ushort blue\nproperty uchar material\n"
                       "property float nx\nproperty float ny\nproperty float nz\nproperty int pair_0\n"
                       "property int pair_1\nend_header\n"));
  // Integers as integers, floats as shortest round-trip text.
  EXPECT_TRUE(contains(text, "\n0 0 0 0 0 1 0 255 128 255 0 0 0.1 -16777216 0 1 2 3\n"));
  EXPECT_TRUE(contains(text, "\n4 0 1 2 3 0 65535 300 0 0 0 1 -5 5\n"));
  std::string corner;
  ASSERT_TRUE(tsm::write_ply(corner_mesh(), wo, corner).ok());
  EXPECT_TRUE(contains(corner,
                       "property list uchar uint vertex_indices\nproperty list uchar float texcoord\n"
                       "property list uchar float normal\nproperty list uchar ushort tangent\n"
                       "property list uchar uchar color\nend_header\n"));
  // Face 1 (corners 4..6): texcoord values 0 1 4, normals 1 1 2, tangent 0 1 0, colour 1 1 1.
  EXPECT_TRUE(contains(corner, "\n3 0 1 4 6 0 0 1 0 0.5 0.33333334 9 0 0 -1 0 0 -1 -0 1e-45 1 12 1 2 3 4 65535 0 0 "
                               "65535 1 2 3 4 9 0 255 0 0 255 0 0 255 0\n"));
}

TEST(PlyAttributes, CornerAttributesKeepTheirValuePerCornerShared) {
  const Mesh m = corner_mesh();
  ASSERT_TRUE(m.valid());
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    const Mesh back = write_read_ply(m, ascii);
    EXPECT_EQ(faces_of(back), faces_of(m));
    ASSERT_EQ(back.attributes.size(), m.attributes.size());
    for (size_t i = 0; i < m.attributes.size(); ++i) {
      const Attribute& a = m.attributes[i];
      const Attribute& b = back.attributes[i];
      SCOPED_TRACE(a.name);
      EXPECT_EQ(b.name, a.name);
      EXPECT_EQ(b.kind, a.kind);
      EXPECT_EQ(b.domain, AttributeDomain::corner);
      EXPECT_EQ(b.type, a.type);
      EXPECT_EQ(b.components, a.components);
      // The same value at every corner; equal values shared, in the order
      // the corners first use them (each new index the next one).
      EXPECT_TRUE(same_bits(per_corner(back, b), per_corner(m, a)));
      EXPECT_LT(b.value_count(), m.corner_count());
      uint32_t next = 0;
      for (uint32_t x : b.indices) {
        EXPECT_LE(x, next);
        if (x == next) ++next;
      }
      EXPECT_EQ(next, b.value_count());
    }
    // A second round trip changes nothing more.
    const Mesh again = write_read_ply(back, ascii);
    ASSERT_EQ(again.attributes.size(), back.attributes.size());
    for (size_t i = 0; i < back.attributes.size(); ++i)
      EXPECT_TRUE(same_attribute(again.attributes[i], back.attributes[i]));
  }
}

TEST(PlyAttributes, EverythingAtOnceAndWideCornerLists) {
  Mesh m = vertex_and_face_mesh();
  for (Attribute& a : corner_mesh().attributes) m.attributes.push_back(a);
  // A face of 100 corners: its 4-component corner list needs a uint count.
  std::vector<uint32_t> ring;
  for (uint32_t i = 0; i < 100; ++i) ring.push_back(i % 5);
  m.add_face(ring.data(), ring.size());
  for (Attribute& a : m.attributes) {
    if (a.domain == AttributeDomain::face) a.values.insert(a.values.end(), a.values.begin(), a.values.begin() + a.components);
    if (a.domain == AttributeDomain::corner)
      for (uint32_t i = 0; i < 100; ++i) a.indices.push_back(i % 2);
  }
  std::string why;
  ASSERT_TRUE(m.valid(&why)) << why;
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    std::string bytes;
    const Mesh back = write_read_ply(m, ascii, nullptr, &bytes);
    EXPECT_TRUE(contains(bytes, "property list uint ushort tangent\n"));
    EXPECT_TRUE(contains(bytes, "property list uchar float texcoord\n"));
    ASSERT_EQ(back.attributes.size(), m.attributes.size());
    for (size_t i = 0; i < m.attributes.size(); ++i) {
      SCOPED_TRACE(m.attributes[i].name);
      if (m.attributes[i].domain != AttributeDomain::corner) {
        EXPECT_TRUE(same_attribute(back.attributes[i], m.attributes[i]));
      } else {
        EXPECT_TRUE(same_bits(per_corner(back, back.attributes[i]), per_corner(m, m.attributes[i])));
      }
    }
  }
}

TEST(PlyAttributes, NonFiniteValuesNeedTheOption) {
  Mesh m = base_mesh();
  m.attributes.push_back(make("quality", AttributeKind::generic, AttributeDomain::vertex, AttributeType::f32, 1,
                              {0, std::numeric_limits<float>::infinity(), from_bits(0x7fc00001u), 1, 2}));
  ReadOptions allow;
  allow.allow_nonfinite = true;
  for (bool ascii : {false, true}) {
    WriteOptions wo;
    wo.ascii = ascii;
    std::string bytes;
    ASSERT_TRUE(tsm::write_ply(m, wo, bytes).ok());
    Mesh back;
    Status s = ply(bytes, back, allow);
    ASSERT_TRUE(s.ok()) << s.to_string();
    ASSERT_EQ(back.attributes.size(), 1u);
    EXPECT_TRUE(std::isinf(back.attributes[0].values[1]));
    EXPECT_TRUE(std::isnan(back.attributes[0].values[2]));
    if (!ascii) {
      EXPECT_EQ(bits(back.attributes[0].values[2]), 0x7fc00001u);  // binary keeps the payload
    }
    const size_t body = bytes.find("end_header\n") + 11;
    if (ascii) {
      expect_error(ply, bytes, {"attr.ply: line 13:", "vertex 1", "non-finite", "'quality'", "--allow-nonfinite"});
    } else {
      expect_error(ply, bytes, {"attr.ply: byte " + std::to_string(body + 16 + 12) + ":", "vertex 1", "'quality'"});
    }
  }
}

TEST(PlyAttributes, MeshesWithoutAttributesAreWrittenAsBefore) {
  Mesh m = base_mesh();
  std::string plain, text;
  ASSERT_TRUE(tsm::write_ply(m, {}, plain).ok());
  WriteOptions wo;
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(m, wo, text).ok());
  EXPECT_EQ(text,
            "ply\nformat ascii 1.0\ncomment written by tsm\nelement vertex 5\n"
            "property float x\nproperty float y\nproperty float z\n"
            "element face 3\nproperty list uchar uint vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 1 2 3\n3 0 1 4\n3 2 3 4\n");
  const std::string header = replace_all(text.substr(0, text.find("end_header\n") + 11), "ascii", "binary_little_endian");
  EXPECT_EQ(plain.substr(0, header.size()), header);
  EXPECT_EQ(plain.size(), header.size() + 5 * 12 + 3 + 4 * 10);
  Mesh back;
  ReadInfo info;
  ASSERT_TRUE(ply(plain, back, {}, &info).ok());
  EXPECT_TRUE(back.attributes.empty());
  EXPECT_TRUE(info.notes.empty()) << info.notes;
}

// ===========================================================================
// PLY reading of hand-written files

TEST(PlyAttributes, ReadsEveryTextureCoordinateNaming) {
  struct Case {
    const char* s;
    const char* t;
  };
  for (const Case& c : {Case{"s", "t"}, Case{"u", "v"}, Case{"texture_u", "texture_v"}, Case{"texture_s", "texture_t"}}) {
    SCOPED_TRACE(c.s);
    const std::string text = std::string("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                         "property float z\nproperty double ") +
                             c.s + "\nproperty float " + c.t +
                             "\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                             "0 0 0 0.1 0.2\n1 0 0 0.3 0.4\n0 1 0 0.5 0.6\n3 0 1 2\n";
    Mesh m;
    Status s = ply(text, m);
    ASSERT_TRUE(s.ok()) << s.to_string();
    ASSERT_EQ(m.attributes.size(), 1u);
    const Attribute& a = m.attributes[0];
    EXPECT_EQ(a.name, "texcoord");
    EXPECT_EQ(a.kind, AttributeKind::texcoord);
    EXPECT_EQ(a.domain, AttributeDomain::vertex);
    EXPECT_EQ(a.type, AttributeType::f32);
    EXPECT_TRUE(same_bits(a.values, {static_cast<float>(0.1), 0.2f, static_cast<float>(0.3), 0.4f,
                                     static_cast<float>(0.5), 0.6f}));
  }
  // Half a pair is a generic attribute of its own.
  Mesh m;
  ASSERT_TRUE(ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                  "property float u\nproperty uchar alpha\nproperty float nx\nproperty float ny\nend_header\n"
                  "0 0 0 0.5 7 1 2\n",
                  m)
                  .ok());
  ASSERT_EQ(m.attributes.size(), 4u);
  EXPECT_EQ(m.attributes[0].name, "u");
  EXPECT_EQ(m.attributes[1].name, "alpha");
  EXPECT_EQ(m.attributes[1].type, AttributeType::u8);
  EXPECT_EQ(m.attributes[2].name, "nx");
  for (const Attribute& a : m.attributes) {
    EXPECT_EQ(a.kind, AttributeKind::generic);
    EXPECT_EQ(a.components, 1u);
  }
}

TEST(PlyAttributes, BigEndianTypesMapToTheClosestType) {
  const std::string header =
      "ply\nformat binary_big_endian 1.0\n"
      "element vertex 2\n"
      "property char c\nproperty float x\nproperty short s\nproperty float y\nproperty uint big\n"
      "property float z\nproperty double d\nproperty uchar red\nproperty ushort green\nproperty uchar blue\n"
      "property float nz\nproperty float nx\nproperty float ny\n"
      "element face 1\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
      "property list ushort double texcoord\nproperty char level\n"
      "end_header\n";
  Body b;
  b.big = true;
  b.put<int8_t>(-128).put(1.f).put<int16_t>(-32768).put(2.f).put<uint32_t>(16777216u).put(3.f).put(0.1);
  b.put<uint8_t>(255).put<uint16_t>(65535).put<uint8_t>(0).put(0.f).put(1.f).put(-0.f);
  b.put<int8_t>(127).put(4.f).put<int16_t>(32767).put(5.f).put<uint32_t>(7u).put(6.f).put(-1e300);
  b.put<uint8_t>(1).put<uint16_t>(2).put<uint8_t>(3).put(0.5f).put(0.25f).put(0.125f);
  b.put<uint8_t>(9).put<uint8_t>(2).put<int32_t>(1).put<int32_t>(0);
  b.put<uint16_t>(4).put(0.5).put(1.5).put(2.5).put(3.5).put<int8_t>(-3);
  Mesh m;
  ReadInfo info;
  ReadOptions allow;
  allow.allow_nonfinite = true;  // -1e300 does not fit a float
  Status s = ply(header + b.s, m, allow, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  EXPECT_EQ(m.positions, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  ASSERT_EQ(m.attributes.size(), 9u);
  // Order: by the first property of each.
  const Attribute& c = m.attributes[0];
  EXPECT_EQ(c.name, "c");
  EXPECT_EQ(c.type, AttributeType::i32);
  EXPECT_EQ(c.values, (std::vector<float>{-128, 127}));
  EXPECT_EQ(m.attributes[1].name, "s");
  EXPECT_EQ(m.attributes[1].type, AttributeType::i32);
  EXPECT_EQ(m.attributes[1].values, (std::vector<float>{-32768, 32767}));
  EXPECT_EQ(m.attributes[2].name, "big");
  EXPECT_EQ(m.attributes[2].type, AttributeType::i32);
  EXPECT_EQ(m.attributes[2].values, (std::vector<float>{16777216, 7}));
  EXPECT_EQ(m.attributes[3].name, "d");
  EXPECT_EQ(m.attributes[3].type, AttributeType::f32);
  EXPECT_EQ(bits(m.attributes[3].values[0]), bits(static_cast<float>(0.1)));
  EXPECT_EQ(m.attributes[3].values[1], -std::numeric_limits<float>::infinity());
  const Attribute& color = m.attributes[4];
  EXPECT_EQ(color.kind, AttributeKind::color);
  EXPECT_EQ(color.type, AttributeType::u16);  // uchar and ushort components
  EXPECT_EQ(color.values, (std::vector<float>{255, 65535, 0, 1, 2, 3}));
  const Attribute& normal = m.attributes[5];
  EXPECT_EQ(normal.kind, AttributeKind::normal);
  EXPECT_TRUE(same_bits(normal.values, {1.f, -0.f, 0.f, 0.25f, 0.125f, 0.5f}));  // nx ny nz order
  EXPECT_EQ(m.attributes[6].name, "flags");
  EXPECT_EQ(m.attributes[6].domain, AttributeDomain::face);
  EXPECT_EQ(m.attributes[6].values, (std::vector<float>{9}));
  const Attribute& tex = m.attributes[7];
  EXPECT_EQ(tex.kind, AttributeKind::texcoord);
  EXPECT_EQ(tex.domain, AttributeDomain::corner);
  EXPECT_EQ(tex.values, (std::vector<float>{0.5f, 1.5f, 2.5f, 3.5f}));
  EXPECT_EQ(tex.indices, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(m.attributes[8].name, "level");
  EXPECT_EQ(m.attributes[8].values, (std::vector<float>{-3}));
  // Without the option the double beyond float range is refused.
  expect_error(ply, header + b.s, {"vertex 1", "non-finite", "'d'", "--allow-nonfinite"});
}

TEST(PlyAttributes, IntegersBeyondFloatPrecisionAreRoundedWithANote) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property int id\nproperty uint stamp\nend_header\n"
      "0 0 0 16777216 1\n1 0 0 16777217 4294967295\n0 1 0 -2147483648 16777218\n";
  Mesh m;
  ReadInfo info;
  Status s = ply(text, m, {}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  ASSERT_EQ(m.attributes.size(), 2u);
  EXPECT_EQ(m.attributes[0].type, AttributeType::f32);
  EXPECT_EQ(m.attributes[0].values, (std::vector<float>{16777216, 16777216, -2147483648.0f}));
  EXPECT_EQ(m.attributes[1].type, AttributeType::f32);
  EXPECT_EQ(m.attributes[1].values[1], 4294967296.0f);
  EXPECT_EQ(m.attributes[1].values[2], 16777218.0f);  // even: exact
  EXPECT_TRUE(contains(info.notes, "property 'id' of element 'vertex': 1 integer value(s) beyond float precision "
                                   "(first at vertex 1); attribute 'id' is kept as f32, rounded"));
  EXPECT_TRUE(contains(info.notes, "property 'stamp'"));
  // Exact ones keep their integer type.
  Mesh exact;
  ASSERT_TRUE(ply(replace_all(replace_all(text, "16777217", "5"), "4294967295", "6"), exact).ok());
  EXPECT_EQ(exact.attributes[0].type, AttributeType::i32);
  EXPECT_EQ(exact.attributes[1].type, AttributeType::i32);
  // Binary, the same.
  Body b;
  b.put(0.f).put(0.f).put(0.f).put<int32_t>(-16777217);
  Mesh bin;
  ReadInfo binfo;
  ASSERT_TRUE(ply("ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "property float z\nproperty int id\nend_header\n" + b.s,
                  bin, {}, &binfo)
                  .ok());
  EXPECT_EQ(bin.attributes[0].type, AttributeType::f32);
  EXPECT_EQ(bin.attributes[0].values[0], -16777216.0f);
  EXPECT_TRUE(contains(binfo.notes, "first at vertex 0"));
}

TEST(PlyAttributes, FaceListsThatDoNotFitAreSkippedWithANote) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 3\nproperty list uchar int vertex_indices\nproperty list uchar float weights\n"
      "property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  {
    // weights: 1 per corner, then 2 per corner: skipped. texcoord empty everywhere: ignored.
    Mesh m;
    ReadInfo info;
    Status s = ply(head + "3 0 1 2 3 1 2 3 0\n3 2 1 0 6 1 2 3 4 5 6 0\n3 0 2 1 3 7 8 9 0\n", m, {}, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_TRUE(m.attributes.empty());
    EXPECT_TRUE(contains(info.notes, "skipped list property 'weights' of element 'face': face 1 has 6 values for 3 "
                                     "corners"));
    EXPECT_TRUE(contains(info.notes, "ignored the empty 'texcoord' lists"));
    EXPECT_EQ(m.face_count(), 3u);
  }
  {
    // Texture coordinates on some faces only: skipped; weights kept (1 per corner).
    Mesh m;
    ReadInfo info;
    Status s = ply(head + "3 0 1 2 3 1 2 3 6 0 0 1 0 0 1\n3 2 1 0 3 4 5 6 0\n3 0 2 1 3 7 8 9 6 0 0 1 0 0 1\n", m, {},
                   &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    ASSERT_EQ(m.attributes.size(), 1u);
    EXPECT_EQ(m.attributes[0].name, "weights");
    EXPECT_EQ(m.attributes[0].domain, AttributeDomain::corner);
    EXPECT_EQ(m.attributes[0].values, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
    EXPECT_TRUE(contains(info.notes, "skipped list property 'texcoord' of element 'face': face 1 has none while "
                                     "face 0 has some"));
  }
  {
    // Faces with no corners are skipped, with their values.
    Mesh m;
    ReadInfo info;
    Status s = ply(head + "0 2 9 9 4 9 9 9 9\n3 2 1 0 3 4 5 6 6 1 2 3 4 5 6\n3 0 2 1 3 7 8 9 6 0 0 1 0 0 1\n", m, {},
                   &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_EQ(m.face_count(), 2u);
    ASSERT_EQ(m.attributes.size(), 2u);
    EXPECT_EQ(m.attributes[0].values, (std::vector<float>{4, 5, 6, 7, 8, 9}));
    EXPECT_EQ(m.attributes[1].values, (std::vector<float>{1, 2, 3, 4, 5, 6, 0, 0, 1, 0, 0, 1}));
    std::string why;
    EXPECT_TRUE(m.valid(&why)) << why;
  }
}

// The layout of PlyRead.SkippedElementWithListBeforeFaces (test_io_ply.cpp)
// with a well-formed texcoord list in both bodies: the same mesh, the same
// attributes and the same notes from ascii and binary.
TEST(PlyAttributes, AsciiAndBinaryAgreeAroundSkippedElements) {
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
  Body b;
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(0.f).put(1.f).put(0.5f);
  b.put<uint8_t>(2).put<int32_t>(0).put<int32_t>(1).put<uint8_t>(255);
  b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put<uint8_t>(7);
  b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2);
  b.put<uint8_t>(6).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(1.f);
  b.put(0.25);
  Mesh a, m;
  ReadInfo ai, bi;
  Status s = ply(text, a, {}, &ai);
  ASSERT_TRUE(s.ok()) << s.to_string();
  s = ply("ply\nformat binary_little_endian 1.0\n" + head + b.s, m, {}, &bi);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(ai.notes, bi.notes);
  EXPECT_TRUE(contains(ai.notes, "skipped element 'edge' (2)"));
  EXPECT_EQ(ai.skipped_elements, 3u);
  ASSERT_EQ(a.attributes.size(), 1u);
  ASSERT_EQ(m.attributes.size(), 1u);
  EXPECT_TRUE(same_attribute(a.attributes[0], m.attributes[0]));
  EXPECT_EQ(a.attributes[0].values, (std::vector<float>{0, 0, 1, 0, 0, 1}));
}

TEST(PlyAttributes, MalformedAttributeDataGivesClearErrors) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float nx\n"
      "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n"
      "property short level\nend_header\n";
  const std::string good = head + "0 0 0 1 2 3 0.5\n1 0 0 4 5 6 0.5\n0 1 0 7 8 9 0.5\n3 0 1 2 6 0 0 1 0 0 1 -4\n";
  Mesh m;
  ASSERT_TRUE(ply(good, m).ok());
  ASSERT_EQ(m.attributes.size(), 4u);
  EXPECT_EQ(m.attributes[0].type, AttributeType::u8);
  expect_error(ply, replace_all(good, "4 5 6", "4 300 6"),
               {"attr.ply: line 17:", "vertex 1", "property 'green'", "300 is out of range for uchar (0 to 255)"});
  expect_error(ply, replace_all(good, "4 5 6", "4 -1 6"), {"line 17:", "-1 is out of range for uchar"});
  expect_error(ply, replace_all(good, "4 5 6", "4 5.5 6"), {"line 17:", "'5.5' is not an integer (the property is uchar)"});
  expect_error(ply, replace_all(good, "7 8 9 0.5", "7 8 9 half"), {"line 18:", "vertex 2", "property 'nx'", "'half'"});
  expect_error(ply, replace_all(good, "7 8 9 0.5", "7 8 9"), {"line 18:", "vertex 2", "line ends before property 'nx'"});
  expect_error(ply, replace_all(good, " -4\n", " 40000\n"), {"line 19:", "face 0", "'level'", "out of range for short"});
  expect_error(ply, replace_all(good, "6 0 0 1 0 0 1", "5 0 0 1 0 0 1"),
               {"line 19:", "face 0: property 'texcoord' holds 5 values"});
  expect_error(ply, replace_all(good, "6 0 0 1 0 0 1 -4", "4 0 0 1 0 -4"),
               {"attr.ply: line 19:", "face 0: property 'texcoord' holds 4 values; expected 2 per corner (6 for its 3 "
                                      "corners)"});
  expect_error(ply, replace_all(good, "6 0 0 1 0 0 1", "6 0 0 1 0 0 x"), {"line 19:", "'texcoord'", "'x'"});
  // 255.0 in a uchar column is 255.
  Mesh lenient;
  ASSERT_TRUE(ply(replace_all(good, "1 2 3", "1.0 2e0 255.0"), lenient).ok());
  EXPECT_EQ(lenient.attributes[0].values[2], 255.0f);
  // Binary: the byte offset of the list.
  const std::string bhead = replace_all(head, "ascii", "binary_little_endian");
  Body b;
  for (int v = 0; v < 3; ++v) b.put(0.f).put(0.f).put(0.f).put<uint8_t>(1).put<uint8_t>(2).put<uint8_t>(3).put(0.5f);
  b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2);
  const size_t list_at = bhead.size() + b.s.size();
  b.put<uint8_t>(4).put(0.f).put(0.f).put(1.f).put(0.f).put<int16_t>(-4);
  expect_error(ply, bhead + b.s,
               {"attr.ply: byte " + std::to_string(list_at) + ":", "face 0: property 'texcoord' holds 4 values"});
  // The file ends inside a list of values.
  expect_error(ply, bhead + b.s.substr(0, list_at - bhead.size() + 5), {"the file ends inside face 0"});
}

// Random damage to files with attributes never crashes and never yields an
// invalid mesh.
TEST(PlyAttributes, MutatedInputsNeverCrash) {
  Mesh m = vertex_and_face_mesh();
  for (Attribute& a : corner_mesh().attributes) m.attributes.push_back(a);
  std::string bin, text;
  ASSERT_TRUE(tsm::write_ply(m, {}, bin).ok());
  WriteOptions wo;
  wo.ascii = true;
  ASSERT_TRUE(tsm::write_ply(m, wo, text).ok());
  std::mt19937 rng(2024);
  int accepted = 0;
  for (const std::string* base : {&bin, &text}) {
    for (int iter = 0; iter < 2000; ++iter) {
      std::string s = *base;
      const int edits = 1 + static_cast<int>(rng() % 3);
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
      Mesh out;
      ReadOptions o;
      o.allow_nonfinite = (iter & 1) != 0;
      Status st = ply(s, out, o);
      if (st.ok()) {
        ++accepted;
        std::string why;
        EXPECT_TRUE(out.valid(&why)) << why;
      } else {
        EXPECT_TRUE(st.code() == ErrorCode::parse_error || st.code() == ErrorCode::limit_exceeded) << st.to_string();
        EXPECT_TRUE(contains(st.message(), "attr.ply: "));
        EXPECT_TRUE(out.attributes.empty());
      }
    }
  }
  EXPECT_GT(accepted, 0);
}

TEST(PlyAttributes, WriterRefusesWhatPlyCannotSay) {
  auto expect_refused = [](const Mesh& m, const std::string& says) {
    std::string out = "untouched";
    Status s = tsm::write_ply(m, {}, out);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.code(), ErrorCode::invalid_argument);
    EXPECT_TRUE(contains(s.message(), says));
  };
  using K = AttributeKind;
  using D = AttributeDomain;
  using T = AttributeType;
  Mesh m = base_mesh();
  m.attributes.push_back(make("x", K::generic, D::vertex, T::f32, 1, {0, 1, 2, 3, 4}));
  expect_refused(m, "property 'x' of element 'vertex', which another property has");
  m.attributes[0].name = "two words";
  expect_refused(m, "'two words' is not one word of printable characters");
  m.attributes[0].name = "";
  expect_refused(m, "is not one word");
  m.attributes[0] = make("red", K::generic, D::vertex, T::u8, 1, {0, 1, 2, 3, 256});
  expect_refused(m, "attribute 0 ('red') is of type uchar but its value 4 is 256, not an integer from 0 to 255");
  m.attributes[0].values[4] = 0.5f;
  expect_refused(m, "value 4 is 0.5");
  m.attributes[0].values[4] = std::numeric_limits<float>::quiet_NaN();
  expect_refused(m, "value 4 is nan");
  m.attributes[0].values[4] = 4;
  m.attributes.push_back(make("color", K::color, D::vertex, T::u8, 3, std::vector<float>(15, 1.0f)));
  expect_refused(m, "attribute 1 ('color') would be written as property 'red'");
  // Two corner texcoords both named texcoord.
  Mesh c = base_mesh();
  Attribute t = corner_mesh().attributes[0];
  c.attributes.push_back(t);
  c.attributes.push_back(t);
  expect_refused(c, "property 'texcoord' of element 'face'");
  // The second normal of a domain goes by its own name.
  Mesh two = base_mesh();
  two.attributes.push_back(make("normal", K::normal, D::vertex, T::f32, 3, std::vector<float>(15, 0.5f)));
  two.attributes.push_back(make("bent", K::normal, D::vertex, T::f32, 3, std::vector<float>(15, 0.25f)));
  const Mesh back = write_read_ply(two, false);
  ASSERT_EQ(back.attributes.size(), 2u);
  EXPECT_EQ(back.attributes[1].name, "bent");
  EXPECT_EQ(back.attributes[1].kind, AttributeKind::generic);
  EXPECT_EQ(back.attributes[1].components, 3u);
  EXPECT_EQ(back.attributes[1].values, two.attributes[1].values);
}

// ===========================================================================
// OBJ

TEST(ObjAttributes, ReadsTextureCoordinatesAndNormalsPerCorner) {
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
      "vt 0 0\nvt 1 0 0\nvt 0.5 1\nvt 9 9\n"  // the last one is used by no corner
      "vn 0 0 1\nvn 1 0 0\n"
      "f 1/1/1 2/2/1 3/3/2\n"
      "f -4/-4/-2 -3/-2/-1 -1/-3/-1\n"
      "vn 0 -1 0\n"
      "f 1/3/3 2/3/-1 4/1/1 3/2/3\n";
  Mesh m;
  ReadInfo info;
  Status st = obj(text, m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {0, 1, 3}, {0, 1, 3, 2}}));
  ASSERT_EQ(m.attributes.size(), 2u);
  const Attribute& t = m.attributes[0];
  EXPECT_EQ(t.name, "texcoord");
  EXPECT_EQ(t.kind, AttributeKind::texcoord);
  EXPECT_EQ(t.domain, AttributeDomain::corner);
  EXPECT_EQ(t.type, AttributeType::f32);
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.values, (std::vector<float>{0, 0, 1, 0, 0.5f, 1, 9, 9}));
  EXPECT_EQ(t.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 1, 2, 2, 0, 1}));
  const Attribute& n = m.attributes[1];
  EXPECT_EQ(n.name, "normal");
  EXPECT_EQ(n.kind, AttributeKind::normal);
  EXPECT_EQ(n.components, 3u);
  EXPECT_EQ(n.values, (std::vector<float>{0, 0, 1, 1, 0, 0, 0, -1, 0}));
  EXPECT_EQ(n.indices, (std::vector<uint32_t>{0, 0, 1, 0, 1, 1, 2, 2, 0, 2}));
  std::string why;
  EXPECT_TRUE(m.valid(&why)) << why;
}

TEST(ObjAttributes, OnlyTextureOrOnlyNormalForms) {
  Mesh m;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.75\nvn 0 0 1\nf 1/1 2/1 3/1\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(m.attributes.size(), 1u);
  EXPECT_EQ(m.attributes[0].name, "texcoord");
  EXPECT_EQ(m.attributes[0].indices, (std::vector<uint32_t>{0, 0, 0}));
  ReadInfo info;
  st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.75\nvn 0 0 1\nf 1//1 2//1 3//1\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(m.attributes.size(), 1u);
  EXPECT_EQ(m.attributes[0].name, "normal");
  EXPECT_TRUE(contains(info.notes, "ignored 1 'vt' record (no face corner uses them)"));
  // 'vt u' alone: v is 0.
  st = obj("v 0 0 0\nvt 0.5\nf 1/1\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.attributes[0].values, (std::vector<float>{0.5f, 0}));
  // Forward references, as for vertices.
  st = obj("v 0 0 0\nf 1/2/1\nvt 0 0\nvt 1 1\nvn 1 0 0\n", m);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.attributes[0].indices, (std::vector<uint32_t>{1}));
}

TEST(ObjAttributes, CornersWithoutIndicesAmongCornersWithThemDropTheList) {
  Mesh m;
  ReadInfo info;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
                  "f 1/1/1 2/1/1 3/1/1\n"
                  "f 1//1 2//1 3//1\n",
                  m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(m.face_count(), 2u);
  ASSERT_EQ(m.attributes.size(), 1u);
  EXPECT_EQ(m.attributes[0].name, "normal");
  EXPECT_TRUE(contains(info.notes, "ignored the texture indices and 'vt' records: line 6 has a face corner with a "
                                   "texture index but line 7 has one without"));
  // Bad indices in a dropped list do not matter.
  st = obj("v 0 0 0\nf 1/7 1 1\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(m.attributes.empty());
}

TEST(ObjAttributes, ThirdTextureCoordinateKeptAsTexcoord3) {
  Mesh m;
  ReadInfo info;
  Status st = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0 0\nvt 1 0 0.5\nvt 0 1\nf 1/1 2/2 3/3\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(m.attributes.size(), 1u);
  const Attribute& a = m.attributes[0];
  EXPECT_EQ(a.name, "texcoord3");
  EXPECT_EQ(a.kind, AttributeKind::generic);
  EXPECT_EQ(a.components, 3u);
  EXPECT_EQ(a.values, (std::vector<float>{0, 0, 0, 1, 0, 0.5f, 0, 1, 0}));
  EXPECT_TRUE(contains(info.notes, "'texcoord3'"));
  // And it is written back as vt u v w.
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  EXPECT_TRUE(contains(text, "vt 1 0 0.5\n"));
  Mesh back;
  ASSERT_TRUE(obj(text, back).ok());
  ASSERT_EQ(back.attributes.size(), 1u);
  EXPECT_TRUE(same_attribute(back.attributes[0], a));
}

TEST(ObjAttributes, VertexColours) {
  Mesh m;
  ReadInfo info;
  Status st = obj("v 0 0 0 1 0.5 0\nv 1 0 0 0 0 1 # blue\nv 0 1 0 \\\n 0.25 0.25 0.25\nf 1 2 3\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(m.attributes.size(), 1u);
  const Attribute& c = m.attributes[0];
  EXPECT_EQ(c.name, "color");
  EXPECT_EQ(c.kind, AttributeKind::color);
  EXPECT_EQ(c.domain, AttributeDomain::vertex);
  EXPECT_EQ(c.type, AttributeType::f32);
  EXPECT_EQ(c.values, (std::vector<float>{1, 0.5f, 0, 0, 0, 1, 0.25f, 0.25f, 0.25f}));
  // Some without colours: dropped with a note. A w (one number) is no colour.
  st = obj("v 0 0 0 1 0.5 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(m.attributes.empty());
  EXPECT_TRUE(contains(info.notes, "ignored the vertex colours: line 1 has 'v x y z r g b' but line 2 has no colour"));
  st = obj("v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1 0.5 0.5 0.5\nf 1 2 3\n", m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(m.attributes.empty());
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  // Non-finite colours follow the option.
  expect_error(obj, "v 0 0 0 1 nan 0\n", {"attr.obj: line 1:", "non-finite vertex colour", "--allow-nonfinite"});
  ReadOptions allow;
  allow.allow_nonfinite = true;
  ASSERT_TRUE(obj("v 0 0 0 1 nan 0\n", m, allow).ok());
  EXPECT_TRUE(std::isnan(m.attributes.at(0).values[1]));
}

TEST(ObjAttributes, MalformedAttributeRecordsAndIndicesGiveClearErrors) {
  const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_error(obj, v3 + "vt\n", {"attr.obj: line 4:", "'vt' record has no u value"});
  expect_error(obj, v3 + "vt 0 zero\n", {"attr.obj: line 4:", "bad number 'zero' for the v of a 'vt' record"});
  expect_error(obj, v3 + "vn 0 1\n", {"attr.obj: line 4:", "'vn' record has no z value (expected 'vn x y z')"});
  expect_error(obj, v3 + "vn 0 1 1e\n", {"attr.obj: line 4:", "bad number '1e' for the z"});
  expect_error(obj, v3 + "vn 0 nan 1\n", {"attr.obj: line 4:", "non-finite normal component 'nan'", "--allow-nonfinite"});
  expect_error(obj, v3 + "vt inf 0\n", {"attr.obj: line 4:", "non-finite texture coordinate"});
  expect_error(obj, v3 + "vt 0 0\nvt 1 1\n\nf 1/1 2/2 3/3\n",
               {"attr.obj: line 7:", "texture index 3 is out of range (the file has 2 'vt' records)"});
  expect_error(obj, v3 + "vn 0 0 1\nf 1//1 2//1 3//2\nvn 1 0 0\nf 1//3 2//1 3//1\n",
               {"attr.obj: line 7:", "normal index 3 is out of range (the file has 2 'vn' records)"});
  expect_error(obj, v3 + "vt 0 0\nf 1/1 2/-2 3/1\n",
               {"attr.obj: line 5:", "relative texture index -2 reaches before the first 'vt' (1 defined so far)"});
  expect_error(obj, v3 + "vt 0 0\nf 1/1 2/0 3/1\n", {"attr.obj: line 5:", "texture index 0 in a face"});
  expect_error(obj, v3 + "vt 0 0\nf 1/1 2/1 3/99999999999\n", {"attr.obj: line 5:", "texture index 99999999999 is out of range"});
  expect_error(obj, v3 + "f 1/1/x 2 3\n", {"attr.obj: line 4:", "bad normal index"});
  ReadOptions allow;
  allow.allow_nonfinite = true;
  Mesh m;
  ASSERT_TRUE(obj(v3 + "vn 0 nan 1\nf 1//1 2//1 3//1\n", m, allow).ok());
  EXPECT_TRUE(std::isnan(m.attributes.at(0).values[1]));
}

TEST(ObjAttributes, CornerAttributesRoundTripExactly) {
  Mesh m = base_mesh();
  using K = AttributeKind;
  using D = AttributeDomain;
  using T = AttributeType;
  m.attributes.push_back(make("color", K::color, D::vertex, T::f32, 3,
                              {0, 0.1f, 1, kThird, kDenormal, -0.0f, 1, 1, 1, 0.5f, 0.25f, 0.125f, 3e38f, 1e-7f, 2}));
  m.attributes.push_back(make("texcoord", K::texcoord, D::corner, T::f32, 2,
                              {0, 0, 1, 0, 1, 1, 0, 1, 0.5f, kThird, 9, 9}, {0, 1, 2, 3, 0, 1, 4, 2, 3, 4}));
  m.attributes.push_back(make("normal", K::normal, D::corner, T::f32, 3, {0, 0, 1, 0, 0, -1, -0.0f, kDenormal, 1},
                              {0, 0, 0, 0, 1, 1, 2, 2, 2, 1}));
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  EXPECT_TRUE(contains(text, "v 0 0 0 0 0.1 1\n"));
  EXPECT_TRUE(contains(text, "vt 0.5 0.33333334\nvt 9 9\nvn 0 0 1\n"));
  EXPECT_TRUE(contains(text, "\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf 1/1/2 2/2/2 5/5/3\n"));
  EXPECT_FALSE(contains(text, "not written"));
  Mesh back;
  ReadInfo info;
  Status st = obj(text, back, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  EXPECT_EQ(faces_of(back), faces_of(m));
  EXPECT_TRUE(same_bits(back.positions, m.positions));
  ASSERT_EQ(back.attributes.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(same_attribute(back.attributes[i], m.attributes[i]));
  // Only texture coordinates, only normals.
  for (size_t drop : {1, 2}) {
    Mesh one = m;
    one.attributes.erase(one.attributes.begin() + static_cast<long>(drop));
    ASSERT_TRUE(tsm::write_obj(one, text).ok());
    EXPECT_TRUE(contains(text, drop == 1 ? "\nf 1//1 2//1 3//1 4//1\n" : "\nf 1/1 2/2 3/3 4/4\n")) << text;
    ASSERT_TRUE(obj(text, back).ok());
    ASSERT_EQ(back.attributes.size(), 2u);
    for (size_t i = 0; i < 2; ++i) EXPECT_TRUE(same_attribute(back.attributes[i], one.attributes[i]));
  }
}

TEST(ObjAttributes, VertexAndFaceDomainAttributesComeBackPerCorner) {
  Mesh m = base_mesh();
  using K = AttributeKind;
  using D = AttributeDomain;
  using T = AttributeType;
  m.attributes.push_back(make("texcoord", K::texcoord, D::vertex, T::f32, 2, {0, 0, 1, 0, 1, 1, 0, 1, 0.5f, kThird}));
  m.attributes.push_back(make("normal", K::normal, D::face, T::f32, 3, {0, 0, 1, 0, -1, 0, 0.6f, 0.8f, 0}));
  m.attributes.push_back(make("color", K::color, D::vertex, T::u8, 4,
                              {255, 0, 0, 1, 0, 255, 0, 2, 0, 0, 255, 3, 128, 128, 128, 4, 1, 2, 3, 5}));
  m.attributes.push_back(make("quality", K::generic, D::face, T::f32, 1, {1, 2, 3}));
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  EXPECT_TRUE(contains(text, "# tsm: not written (OBJ cannot hold them): the alpha of vertex attribute 'color', "
                             "face attribute 'quality'\n"));
  EXPECT_TRUE(contains(text, "\nv 0 0 0 1 0 0\n"));
  EXPECT_TRUE(contains(text, "\nv 0 1 0 0.5019608 0.5019608 0.5019608\n"));  // 128 / 255
  EXPECT_TRUE(contains(text, "\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf 1/1/2 2/2/2 5/5/2\nf 3/3/3 4/4/3 5/5/3\n"));
  Mesh back;
  ASSERT_TRUE(obj(text, back).ok());
  ASSERT_EQ(back.attributes.size(), 3u);
  const Attribute* color = find(back, "color");
  ASSERT_NE(color, nullptr);
  EXPECT_EQ(color->type, AttributeType::f32);
  EXPECT_EQ(color->values[0], 1.0f);
  EXPECT_EQ(color->values[9], static_cast<float>(128.0 / 255.0));
  for (const char* name : {"texcoord", "normal"}) {
    const Attribute* a = find(back, name);
    const Attribute* b = find(m, name);
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->domain, AttributeDomain::corner);
    EXPECT_TRUE(same_bits(a->values, b->values));  // the list is the per-vertex / per-face one
    EXPECT_TRUE(same_bits(per_corner(back, *a), per_corner(m, *b)));
  }
}

TEST(ObjAttributes, MeshesWithoutAttributesAreWrittenAsBefore) {
  std::string text;
  ASSERT_TRUE(tsm::write_obj(base_mesh(), text).ok());
  EXPECT_EQ(text,
            "# tsm: 5 vertices, 3 faces\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n"
            "f 1 2 3 4\nf 1 2 5\nf 3 4 5\n");
  Mesh back;
  ReadInfo info;
  ASSERT_TRUE(obj(text, back, {}, &info).ok());
  EXPECT_TRUE(back.attributes.empty());
  EXPECT_TRUE(info.notes.empty()) << info.notes;
}

TEST(ObjAttributes, MutatedInputsNeverCrash) {
  Mesh m = base_mesh();
  m.attributes.push_back(make("color", AttributeKind::color, AttributeDomain::vertex, AttributeType::f32, 3,
                              std::vector<float>(15, 0.5f)));
  for (Attribute& a : corner_mesh().attributes)
    if (a.kind == AttributeKind::texcoord || a.kind == AttributeKind::normal) m.attributes.push_back(a);
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  std::mt19937 rng(77);
  int accepted = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    std::string s = text;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % s.size();
      switch (rng() % 4) {
        case 0: s[at] = static_cast<char>(rng()); break;
        case 1: s.erase(at, 1 + rng() % 8); break;
        case 2: s.insert(at, 1, "0123456789 \n-/."[rng() % 15]); break;
        default: s[at] = "9\n /-"[rng() % 5]; break;
      }
      if (s.empty()) s = "v";
    }
    Mesh out;
    ReadOptions o;
    o.allow_nonfinite = (iter & 1) != 0;
    Status st = obj(s, out, o);
    if (st.ok()) {
      ++accepted;
      std::string why;
      EXPECT_TRUE(out.valid(&why)) << why;
    } else {
      EXPECT_TRUE(st.code() == ErrorCode::parse_error || st.code() == ErrorCode::limit_exceeded) << st.to_string();
      EXPECT_TRUE(contains(st.message(), "attr.obj: line "));
      EXPECT_TRUE(out.attributes.empty());
    }
  }
  EXPECT_GT(accepted, 0);
}

// ===========================================================================
// Corpus files that carry attributes

Status read_corpus(const std::string& rel, Mesh& m, ReadInfo* info = nullptr) {
  const std::string bytes = slurp(tsm_test::corpus_file(rel));
  return tsm::read_mesh_from_memory(bytes, rel, m, {}, info);
}

// PLY and OBJ writers give back what was read (PLY: corner values per corner).
void expect_written_back(const Mesh& m) {
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "PLY ascii" : "PLY binary");
    const Mesh back = write_read_ply(m, ascii);
    ASSERT_EQ(back.attributes.size(), m.attributes.size());
    // By name: PLY puts face properties before the corner lists, so the
    // order can differ.
    for (const Attribute& a : m.attributes) {
      const Attribute* b = find(back, a.name);
      ASSERT_NE(b, nullptr) << a.name;
      if (a.domain == AttributeDomain::corner) {
        EXPECT_TRUE(same_bits(per_corner(back, *b), per_corner(m, a))) << a.name;
      } else {
        EXPECT_TRUE(same_attribute(*b, a)) << a.name;
      }
    }
  }
  std::string text;
  ASSERT_TRUE(tsm::write_obj(m, text).ok());
  Mesh back;
  Status st = obj(text, back);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(same_bits(back.positions, m.positions));
  for (const Attribute& a : m.attributes) {
    if (a.kind != AttributeKind::texcoord && a.kind != AttributeKind::normal) continue;
    const Attribute* b = find(back, a.name);
    ASSERT_NE(b, nullptr) << a.name;
    EXPECT_TRUE(same_bits(per_corner(back, *b), per_corner(m, a))) << a.name;
  }
}

TEST(AttributeCorpus, ObjFiles) {
  TSM_REQUIRE_CORPUS();
  Mesh m;
  ReadInfo info;
  Status st = read_corpus("edge/cube_att.obj", m, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  ASSERT_EQ(m.attributes.size(), 2u);
  const Attribute& t = m.attributes[0];
  EXPECT_EQ(t.kind, AttributeKind::texcoord);
  EXPECT_EQ(t.domain, AttributeDomain::corner);
  EXPECT_EQ(t.values, (std::vector<float>{0, 0, 0, 1, 1, 0, 1, 1}));
  EXPECT_EQ(t.indices.size(), 36u);
  EXPECT_EQ(std::vector<uint32_t>(t.indices.begin(), t.indices.begin() + 3), (std::vector<uint32_t>{3, 0, 1}));
  const Attribute& n = m.attributes[1];
  EXPECT_EQ(n.kind, AttributeKind::normal);
  EXPECT_EQ(n.value_count(), 6u);
  EXPECT_EQ(std::vector<float>(n.values.begin(), n.values.begin() + 6), (std::vector<float>{0, 0, 1, 0, 0, -1}));
  EXPECT_EQ(std::vector<uint32_t>(n.indices.begin(), n.indices.begin() + 3), (std::vector<uint32_t>{1, 1, 1}));
  expect_written_back(m);

  ASSERT_TRUE(read_corpus("edge/cube_quads.obj", m).ok());
  ASSERT_EQ(m.attributes.size(), 2u);
  EXPECT_EQ(m.attributes[0].indices.size(), 24u);
  expect_written_back(m);

  // Normals only, one per vertex (MeshLab's v//n).
  for (const char* file : {"edge/sphere.obj", "edge/test_nm.obj", "edge/extra_vertex.obj"}) {
    SCOPED_TRACE(file);
    ASSERT_TRUE(read_corpus(file, m, &info).ok());
    // sphere.obj has one o, g, usemtl and s record each: the "obj" metadata
    // says them, no face attribute is needed.
    ASSERT_EQ(m.attributes.size(), 1u);
    const Attribute& a = m.attributes[0];
    EXPECT_EQ(a.kind, AttributeKind::normal);
    EXPECT_EQ(a.value_count(), m.vertex_count());
    EXPECT_EQ(a.indices, m.indices);
    expect_written_back(m);
  }
  ASSERT_TRUE(read_corpus("edge/sphere.obj", m).ok());
  EXPECT_EQ(m.attributes[0].values[0], 0.44254783f);
  EXPECT_EQ(m.attributes[0].values[2], -8.0352547e-17f);
  const tsm::MetadataEntry* e = m.find_metadata("obj");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->value, "mtllib sphere.mtl\nobject sphere1\ngroup sphere1_default\nmaterial default\nsmoothing 1\n");
}

TEST(AttributeCorpus, PlyFiles) {
  TSM_REQUIRE_CORPUS();
  Mesh m;
  ReadInfo info;
  ASSERT_TRUE(read_corpus("edge/cube_att.ply", m, &info).ok());
  EXPECT_TRUE(info.notes.empty()) << info.notes;
  ASSERT_EQ(m.attributes.size(), 2u);
  const Attribute& n = m.attributes[0];
  EXPECT_EQ(n.kind, AttributeKind::normal);
  EXPECT_EQ(n.domain, AttributeDomain::vertex);
  EXPECT_EQ(n.value_count(), 24u);
  EXPECT_EQ(std::vector<float>(n.values.begin(), n.values.begin() + 6), (std::vector<float>{-1, 0, 0, 0, 0, 1}));
  const Attribute& t = m.attributes[1];
  EXPECT_EQ(t.kind, AttributeKind::texcoord);
  EXPECT_EQ(t.domain, AttributeDomain::corner);
  EXPECT_EQ(t.value_count(), 4u);  // 36 corners, 4 distinct values shared
  EXPECT_EQ(std::vector<float>(t.values.begin(), t.values.begin() + 6), (std::vector<float>{1, 1, 0, 0, 0, 1}));
  expect_written_back(m);

  // RGBA uchar colours, binary and ascii the same.
  Mesh bin, text;
  for (const char* file : {"edge/test_pos_color.ply", "edge/test_pos_color_ascii.ply", "edge/test_generic.ply"}) {
    SCOPED_TRACE(file);
    ASSERT_TRUE(read_corpus(file, m).ok());
    ASSERT_EQ(m.attributes.size(), 1u);
    const Attribute& c = m.attributes[0];
    EXPECT_EQ(c.kind, AttributeKind::color);
    EXPECT_EQ(c.type, AttributeType::u8);
    EXPECT_EQ(c.components, 4u);
    EXPECT_EQ(c.value_count(), 114u);
    EXPECT_EQ(std::vector<float>(c.values.begin(), c.values.begin() + 8),
              (std::vector<float>{209, 0, 122, 255, 77, 0, 205, 255}));
    expect_written_back(m);
    (std::string(file).find("ascii") != std::string::npos ? text : bin) = m;
  }
  EXPECT_EQ(bin.attributes[0].values, text.attributes[0].values);

  for (const char* file : {"edge/test_more_datatypes.ply", "edge/test_extra_whitespace.ply"}) {
    SCOPED_TRACE(file);
    ASSERT_TRUE(read_corpus(file, m).ok());
    ASSERT_EQ(m.attributes.size(), 1u);
    EXPECT_EQ(m.attributes[0].type, AttributeType::u8);  // uchar and uint8
    EXPECT_EQ(m.attributes[0].values,
              (std::vector<float>{209, 0, 122, 255, 77, 0, 205, 255, 0, 0, 255, 255}));
  }

  // Box.ply: float normals and RGB uchar colours.
  ASSERT_TRUE(read_corpus("edge/Box.ply", m, &info).ok());
  ASSERT_EQ(m.attributes.size(), 2u);
  EXPECT_EQ(m.attributes[0].kind, AttributeKind::normal);
  EXPECT_EQ(m.attributes[0].value_count(), 24u);
  EXPECT_EQ(std::vector<float>(m.attributes[0].values.begin(), m.attributes[0].values.begin() + 3),
            (std::vector<float>{-1, 0, 0}));
  EXPECT_EQ(m.attributes[1].kind, AttributeKind::color);
  EXPECT_EQ(m.attributes[1].components, 3u);
  EXPECT_EQ(m.attributes[1].type, AttributeType::u8);
  EXPECT_EQ(std::vector<float>(m.attributes[1].values.begin(), m.attributes[1].values.begin() + 3),
            (std::vector<float>{250, 250, 250}));
  EXPECT_TRUE(contains(info.notes, "skipped element 'material' (1)"));
  expect_written_back(m);

  // Files without attributes give none.
  for (const char* file : {"edge/cube_quads.ply", "edge/point_cloud_test_pos.ply"}) {
    ASSERT_TRUE(read_corpus(file, m).ok());
    EXPECT_TRUE(m.attributes.empty()) << file;
  }
}

// ===========================================================================
// OBJ objects, groups, materials and smoothing groups ('obj:*' + "obj")

// Each face's "o=..|g=..|m=..|s=.." from the 'obj:*' attributes and the
// "obj" metadata entry, decoded here independently of the writer.
std::vector<std::string> face_labels(const Mesh& m) {
  std::map<std::string, std::vector<std::string>> lists;
  if (const tsm::MetadataEntry* e = m.find_metadata("obj")) {
    std::istringstream in(e->value);
    std::string line;
    while (std::getline(in, line)) {
      const size_t sp = line.find(' ');
      lists[line.substr(0, sp)].push_back(sp == std::string::npos ? std::string() : line.substr(sp + 1));
    }
  }
  std::vector<std::string> out(m.face_count());
  for (const char* list : {"object", "group", "material", "smoothing"}) {
    const Attribute* a = find(m, std::string("obj:") + list);
    for (size_t f = 0; f < m.face_count(); ++f) {
      std::string text = "(none)";
      if (a) {
        const size_t k = static_cast<size_t>(a->values[f]);
        text = k < lists[list].size() ? lists[list][k] : "(missing entry " + std::to_string(k) + ")";
      }
      out[f] += std::string(list) + "=" + text + "|";
    }
  }
  return out;
}

TEST(ObjGroups, ReadIntoFaceAttributesAndMetadata) {
  Mesh m;
  ReadInfo info;
  Status st = obj("mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                  "f 1 2 3\n"                                 // before any record
                  "o thing # a comment\ng left  side\nusemtl mat#2\ns 1\nf 2 4 3\n"
                  "g\nf 1 2 4\n"                              // a bare g: the empty text again
                  "g left  side\nusemtl red\ns off\nf 1 3 4\n",
                  m, {}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(m.face_count(), 4u);
  const tsm::MetadataEntry* e = m.find_metadata("obj");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->value,
            "mtllib a.mtl b.mtl\nobject \nobject thing\ngroup \ngroup left  side\nmaterial \nmaterial mat#2\n"
            "material red\nsmoothing \nsmoothing 1\nsmoothing off\n");
  struct Want {
    const char* name;
    std::vector<float> values;
  };
  for (const Want& w : {Want{"obj:object", {0, 1, 1, 1}}, Want{"obj:group", {0, 1, 0, 1}},
                        Want{"obj:material", {0, 1, 1, 2}}, Want{"obj:smoothing", {0, 1, 1, 2}}}) {
    const Attribute* a = find(m, w.name);
    ASSERT_NE(a, nullptr) << w.name;
    EXPECT_EQ(a->domain, AttributeDomain::face);
    EXPECT_EQ(a->kind, AttributeKind::generic);
    EXPECT_EQ(a->type, AttributeType::i32);
    EXPECT_EQ(a->values, w.values) << w.name;
  }
  // Files without these records get neither attributes nor metadata.
  Mesh plain;
  ASSERT_TRUE(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", plain).ok());
  EXPECT_TRUE(plain.attributes.empty());
  EXPECT_TRUE(plain.metadata.empty());
}

TEST(ObjGroups, WrittenBackAsRecords) {
  const std::string text =
      "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\no a\ng x y\nusemtl red\ns 2\nf 2 4 3\n"
      "usemtl blue\nf 1 2 4\no b\nf 1 3 4\n";
  Mesh m;
  ASSERT_TRUE(obj(text, m).ok());
  std::string out;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_obj(m, out, &info).ok());
  EXPECT_EQ(info.notes, "");
  EXPECT_TRUE(contains(out, "mtllib scene.mtl\nv 0 0 0\n")) << out;
  EXPECT_TRUE(contains(out, "f 1 2 3\no a\ng x y\nusemtl red\ns 2\nf 2 4 3\nusemtl blue\nf 1 2 4\no b\nf 1 3 4\n"))
      << out;
  Mesh back;
  ASSERT_TRUE(obj(out, back).ok());
  EXPECT_EQ(face_labels(back), face_labels(m));
  // Faces in another order (as the decoder gives them): an entry that comes
  // back to the empty text is written as the bare keyword (s: "s off").
  Mesh reordered = m;
  std::vector<uint32_t> order{3, 0, 1, 2};
  reordered.indices.clear();
  reordered.face_offsets = {0};
  for (tsm::Attribute& a : reordered.attributes) a.values.clear();
  for (uint32_t f : order) {
    reordered.add_face(m.face(f), m.face_size(f));
    for (size_t k = 0; k < m.attributes.size(); ++k) reordered.attributes[k].values.push_back(m.attributes[k].values[f]);
  }
  ASSERT_TRUE(tsm::write_obj(reordered, out).ok());
  EXPECT_TRUE(contains(out, "f 1 3 4\no\ng\nusemtl\ns off\nf 1 2 3\n")) << out;
  ASSERT_TRUE(obj(out, back).ok());
  std::vector<std::string> want = face_labels(m), got = face_labels(back);
  // "s off" is how OBJ says "no smoothing group".
  want[0].replace(want[0].find("smoothing=|"), 11, "smoothing=off|");
  for (size_t i = 0; i < order.size(); ++i) EXPECT_EQ(got[i], want[order[i]]) << i;
}

// The round trip of the issue: an OBJ with two objects, three groups, two
// materials and mtllib, through encode and decode (which reorder faces and
// vertices) and write_obj / read_obj, keeps every face's object, group,
// material and smoothing group.
TEST(ObjGroups, SurviveEncodeDecodeAndWriteRead) {
  const Mesh sphere = tsm_test::icosphere(2);
  std::ostringstream text;
  text << "# two objects, three groups, two materials\nmtllib scene.mtl\n";
  for (size_t v = 0; v < sphere.vertex_count(); ++v)
    text << "v " << sphere.positions[3 * v] << " " << sphere.positions[3 * v + 1] << " " << sphere.positions[3 * v + 2]
         << "\n";
  for (size_t f = 0; f < sphere.face_count(); ++f) {
    if (f == 0) text << "o first\ng left\nusemtl red\ns 1\n";
    if (f == 100) text << "g right side\nusemtl blue\n";
    if (f == 170) text << "usemtl red\ns off\n";
    if (f == 200) text << "o second\ng third\nusemtl blue\n";
    const uint32_t* c = sphere.face(f);
    text << "f " << c[0] + 1 << " " << c[1] + 1 << " " << c[2] + 1 << "\n";
  }
  Mesh m;
  ASSERT_TRUE(obj(text.str(), m).ok());
  ASSERT_EQ(m.face_count(), sphere.face_count());

  std::string bytes;
  Status st = tsm::encode(m, tsm::EncodeOptions{}, bytes);
  ASSERT_TRUE(st.ok()) << st.to_string();
  Mesh decoded;
  st = tsm::decode(bytes, decoded);
  ASSERT_TRUE(st.ok()) << st.to_string();
  std::string written;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_obj(decoded, written, &info).ok());
  EXPECT_EQ(info.notes, "");
  Mesh back;
  ASSERT_TRUE(obj(written, back).ok());
  ASSERT_EQ(back.face_count(), m.face_count());
  EXPECT_TRUE(contains(written, "mtllib scene.mtl\n"));

  // Faces matched by their corners' positions (to the quantization's
  // precision; the sphere's vertices are far apart).
  auto key = [](const Mesh& mesh, size_t f) {
    std::vector<long> k;
    for (uint32_t i = 0; i < mesh.face_size(f); ++i)
      for (int a = 0; a < 3; ++a) k.push_back(std::lround(mesh.positions[3 * size_t{mesh.face(f)[i]} + a] * 1000));
    std::vector<std::vector<long>> corners;
    for (size_t i = 0; i < k.size(); i += 3) corners.push_back({k[i], k[i + 1], k[i + 2]});
    std::sort(corners.begin(), corners.end());
    return corners;
  };
  std::map<std::vector<std::vector<long>>, std::string> original;
  const std::vector<std::string> labels = face_labels(m);
  for (size_t f = 0; f < m.face_count(); ++f) original[key(m, f)] = labels[f];
  ASSERT_EQ(original.size(), m.face_count());
  const std::vector<std::string> got = face_labels(back);
  size_t moved = 0;
  for (size_t f = 0; f < back.face_count(); ++f) {
    auto it = original.find(key(back, f));
    ASSERT_NE(it, original.end()) << "face " << f;
    EXPECT_EQ(got[f], it->second) << "face " << f;
    moved += got[f] != labels[f];
  }
  EXPECT_GT(moved, 0u) << "the codec kept the face order; the test would not see a reordering";
  // The labels are what the file said.
  EXPECT_TRUE(contains(labels[0], "object=first|group=left|material=red|smoothing=1|"));
  EXPECT_TRUE(contains(labels[150], "object=first|group=right side|material=blue|smoothing=1|"));
  EXPECT_TRUE(contains(labels[180], "object=first|group=right side|material=red|smoothing=off|"));
  EXPECT_TRUE(contains(labels[300], "object=second|group=third|material=blue|smoothing=off|"));
}

TEST(ObjGroups, OtherWritersKeepTheNumbersOrSayWhatTheyDrop) {
  Mesh m;
  ASSERT_TRUE(obj("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng g1\nusemtl m1\nf 1 2 3\ng g2\nusemtl m2\nf 1 3 2\n", m).ok());
  // PLY keeps the numbers as face properties, not the names.
  std::string out;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_ply(m, WriteOptions{}, out, &info).ok());
  EXPECT_TRUE(contains(info.notes, "PLY cannot hold the metadata 'obj'")) << info.notes;
  Mesh back;
  ASSERT_TRUE(tsm::read_ply(out, "g.ply", back, {}, nullptr).ok());
  ASSERT_NE(find(back, "obj:group"), nullptr);
  // From PLY (no names) to OBJ: the groups stay apart under made-up names.
  ASSERT_TRUE(tsm::write_obj(back, out).ok());
  EXPECT_TRUE(contains(out, "g group0\nusemtl material0\nf 1 2 3\ng group1\nusemtl material1\nf 1 3 2\n")) << out;
}

TEST(ObjGroups, WriteMeshToGltfLeavesThemOutWithANote) {
  Mesh m;
  ASSERT_TRUE(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\ng b\nf 1 3 2\n", m).ok());
  ASSERT_NE(find(m, "obj:group"), nullptr);
  // write_gltf itself refuses face attributes ...
  std::string bytes;
  EXPECT_FALSE(tsm::write_gltf(m, WriteOptions{}, bytes, true).ok());
  // ... write_mesh leaves the groups out and says so.
  tsm_test::TempDir dir;
  tsm::WriteInfo info;
  Status st = tsm::write_mesh(dir.file("m.glb"), m, WriteOptions{}, &info);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_TRUE(contains(info.notes, "glTF cannot hold the OBJ object, group, material and smoothing group of each face "
                                   "(face attributes 'obj:group')"))
      << info.notes;
  Mesh back;
  ASSERT_TRUE(tsm::read_mesh(dir.file("m.glb"), back).ok());
  EXPECT_EQ(back.face_count(), 2u);
  Mesh copy = m;
  EXPECT_TRUE(tsm::drop_obj_face_labels(copy, nullptr));
  EXPECT_TRUE(copy.attributes.empty());
  EXPECT_FALSE(tsm::drop_obj_face_labels(copy, nullptr));
}

TEST(ObjGroups, OneTextForTheWholeFileNeedsNoAttribute) {
  Mesh m;
  ASSERT_TRUE(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\no only\nusemtl red\nf 1 2 3\nf 1 3 2\n", m).ok());
  EXPECT_TRUE(m.attributes.empty());
  const tsm::MetadataEntry* e = m.find_metadata("obj");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->value, "object only\nmaterial red\n");
  std::string out;
  ASSERT_TRUE(tsm::write_obj(m, out).ok());
  EXPECT_TRUE(contains(out, "v 0 1 0\no only\nusemtl red\nf 1 2 3\nf 1 3 2\n")) << out;
}

TEST(WriteNotes, ObjWriterNamesWhatItDrops) {
  Mesh m = tsm_test::icosphere(0);
  Attribute a;
  a.name = "confidence";
  a.values.assign(m.vertex_count(), 0.5f);
  m.attributes.push_back(a);
  m.metadata.push_back({"gltf", "{}"});
  std::string out;
  tsm::WriteInfo info;
  ASSERT_TRUE(tsm::write_obj(m, out, &info).ok());
  EXPECT_TRUE(contains(info.notes, "OBJ cannot hold the vertex attribute 'confidence', metadata 'gltf'")) << info.notes;
  EXPECT_TRUE(contains(out, "# tsm: not written (OBJ cannot hold them): vertex attribute 'confidence'\n")) << out;
  // Nothing to say when everything fits.
  tsm::WriteInfo none;
  ASSERT_TRUE(tsm::write_obj(tsm_test::icosphere(0), out, &none).ok());
  EXPECT_EQ(none.notes, "");
}

}  // namespace
