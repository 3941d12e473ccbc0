// Tests for the glTF 2.0 reader and writer (libio/src/io_gltf.cpp).
// Generated data only: meshes made here, .gltf JSON written here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "base64.hpp"
#include "test_util.hpp"
#include "mesh_gen.hpp"
#include "tsm/compare.hpp"
#include "tsm/gltf_transcode.hpp"
#include "tsm/io.hpp"

namespace {

using tsm::Attribute;
using tsm::AttributeDomain;
using tsm::AttributeKind;
using tsm::AttributeType;
using tsm::ErrorCode;
using tsm::Mesh;
using tsm::MeshFormat;
using tsm::ReadInfo;
using tsm::ReadOptions;
using tsm::Status;
using tsm::WriteOptions;
using tsm_test::bits;
using tsm_test::contains;

// Positions, faces and attributes identical, floats bit for bit.
::testing::AssertionResult identical(const Mesh& a, const Mesh& b) {
  if (a.positions.size() != b.positions.size())
    return ::testing::AssertionFailure() << "vertex counts " << a.vertex_count() << " vs " << b.vertex_count();
  for (size_t i = 0; i < a.positions.size(); ++i)
    if (bits(a.positions[i]) != bits(b.positions[i]))
      return ::testing::AssertionFailure() << "coordinate " << i << " differs";
  if (a.face_offsets != b.face_offsets) return ::testing::AssertionFailure() << "face offsets differ";
  if (a.indices != b.indices) return ::testing::AssertionFailure() << "face indices differ";
  if (a.attributes.size() != b.attributes.size())
    return ::testing::AssertionFailure() << "attribute counts " << a.attributes.size() << " vs " << b.attributes.size();
  for (size_t k = 0; k < a.attributes.size(); ++k) {
    const Attribute& x = a.attributes[k];
    const Attribute& y = b.attributes[k];
    if (x.name != y.name || x.kind != y.kind || x.domain != y.domain || x.type != y.type ||
        x.components != y.components || x.indices != y.indices || x.values.size() != y.values.size())
      return ::testing::AssertionFailure() << "attribute " << k << " ('" << x.name << "' vs '" << y.name
                                           << "') differs in name, kind, domain, type, components or size";
    for (size_t i = 0; i < x.values.size(); ++i)
      if (bits(x.values[i]) != bits(y.values[i]))
        return ::testing::AssertionFailure() << "attribute '" << x.name << "' value " << i << " differs: " << x.values[i]
                                             << " vs " << y.values[i];
  }
  return ::testing::AssertionSuccess();
}

Attribute vertex_attribute(const std::string& name, AttributeKind kind, AttributeType type, uint32_t comps) {
  Attribute a;
  a.name = name;
  a.kind = kind;
  a.type = type;
  a.components = comps;
  return a;
}

// An n x n grid of vertices, 2 (n-1)^2 triangles, awkward float positions,
// plus an unreferenced vertex.
Mesh grid(uint32_t n, uint32_t seed) {
  Mesh m;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x)
      m.add_vertex(static_cast<float>(x) + jitter(rng), static_cast<float>(y) / 3.0f, 1e-7f * jitter(rng));
  for (uint32_t y = 0; y + 1 < n; ++y)
    for (uint32_t x = 0; x + 1 < n; ++x) {
      const uint32_t v = y * n + x;
      m.add_triangle(v, v + 1, v + n);
      m.add_triangle(v + 1, v + n + 1, v + n);
    }
  m.add_vertex(-0.0f, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max());
  return m;
}

// The grid with normals, two UV sets, an RGBA u8 colour and an RGB float colour.
Mesh attributed(uint32_t n) {
  Mesh m = grid(n, 7);
  const size_t nv = m.vertex_count();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Attribute normal = vertex_attribute("normal", AttributeKind::normal, AttributeType::f32, 3);
  Attribute uv0 = vertex_attribute("texcoord0", AttributeKind::texcoord, AttributeType::f32, 2);
  Attribute uv1 = vertex_attribute("texcoord1", AttributeKind::texcoord, AttributeType::f32, 2);
  Attribute rgba = vertex_attribute("color", AttributeKind::color, AttributeType::u8, 4);
  Attribute rgb = vertex_attribute("color1", AttributeKind::color, AttributeType::f32, 3);
  for (size_t v = 0; v < nv; ++v) {
    float x = u(rng), y = u(rng), z = u(rng);
    const float len = std::sqrt(x * x + y * y + z * z) + 1e-3f;
    normal.values.insert(normal.values.end(), {x / len, y / len, z / len});
    uv0.values.insert(uv0.values.end(), {u(rng), u(rng) * 1e-20f});
    uv1.values.insert(uv1.values.end(), {static_cast<float>(v) / 7.0f, -0.0f});
    for (int c = 0; c < 4; ++c) rgba.values.push_back(static_cast<float>(rng() % 256));
    rgb.values.insert(rgb.values.end(), {u(rng) * 0.5f + 0.5f, 1.0f / 3.0f, 0.0f});
  }
  m.attributes = {normal, uv0, uv1, rgba, rgb};
  return m;
}

std::string write(const Mesh& m, bool binary) {
  std::string out;
  Status s = tsm::write_gltf(m, WriteOptions(), out, binary);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return out;
}

Status read(const std::string& bytes, Mesh& m, ReadInfo* info = nullptr, const ReadOptions& o = {},
            const std::string& name = "test.gltf") {
  return tsm::read_gltf(bytes, name, m, o, info);
}

// ---------------------------------------------------------------------------
// Hand-made files

using tsm_test::base64;

// Little-endian binary buffer builder.
struct Bin {
  std::string s;
  template <typename T>
  Bin& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
    return *this;
  }
  Bin& floats(std::initializer_list<float> v) {
    for (float x : v) put(x);
    return *this;
  }
  std::string uri() const { return "data:application/octet-stream;base64," + base64(s); }
};

// Replaces every "$KEY" in text.
std::string subst(std::string text, const std::string& key, const std::string& value) {
  for (size_t at; (at = text.find("$" + key)) != std::string::npos;) text.replace(at, key.size() + 1, value);
  return text;
}

// One triangle (and a fourth, unused vertex): positions at 0, uint16 indices at 48.
Bin triangle_bin() {
  Bin b;
  b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5});
  b.put<uint16_t>(0).put<uint16_t>(1).put<uint16_t>(2).put<uint16_t>(0);
  return b;
}

const char* kTriangleJson = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 56, "uri": "$URI"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 6}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [5,5,5]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
  ]
})";

std::string triangle_json() { return subst(kTriangleJson, "URI", triangle_bin().uri()); }

// Expects a failure naming the file and containing every part given.
void expect_error(const std::string& bytes, std::initializer_list<std::string> parts,
                  ErrorCode code = ErrorCode::parse_error, const ReadOptions& o = {}) {
  Mesh m;
  m.add_triangle(0, 0, 0);  // must be cleared on failure
  Status s = read(bytes, m, nullptr, o);
  ASSERT_FALSE(s.ok()) << "accepted: " << bytes.substr(0, 300);
  EXPECT_EQ(s.code(), code) << s.to_string();
  EXPECT_TRUE(contains(s.message(), "test.gltf: "));
  for (const std::string& p : parts) EXPECT_TRUE(contains(s.message(), p));
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_EQ(m.face_count(), 0u);
  EXPECT_TRUE(m.attributes.empty());
}

// ---------------------------------------------------------------------------
// Round trips

TEST(GltfRoundTrip, GlbAndGltfWithNormalsTwoUvSetsAndColoursAreBitExact) {
  const Mesh m = attributed(12);
  ASSERT_TRUE(m.valid());
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    const std::string bytes = write(m, binary);
    EXPECT_EQ(bytes.substr(0, 4) == "glTF", binary);
    EXPECT_EQ(tsm::sniff_format(bytes), binary ? MeshFormat::glb : MeshFormat::gltf);
    Mesh back;
    ReadInfo info;
    Status s = read(bytes, back, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_EQ(info.format, binary ? MeshFormat::glb : MeshFormat::gltf);
    EXPECT_EQ(info.binary, binary);
    EXPECT_TRUE(info.notes.empty()) << info.notes;
    EXPECT_TRUE(identical(m, back));
    ASSERT_EQ(back.attributes.size(), 5u);
    EXPECT_EQ(back.attributes[0].name, "normal");
    EXPECT_EQ(back.attributes[1].name, "texcoord0");
    EXPECT_EQ(back.attributes[2].name, "texcoord1");
    EXPECT_EQ(back.attributes[3].name, "color");
    EXPECT_EQ(back.attributes[3].type, AttributeType::u8);
    EXPECT_EQ(back.attributes[4].name, "color1");
    EXPECT_EQ(back.attributes[4].type, AttributeType::f32);
  }
  // The JSON form names the glTF semantics and normalized u8 colours.
  const std::string json = write(m, false);
  for (const char* part : {"\"NORMAL\"", "\"TEXCOORD_0\"", "\"TEXCOORD_1\"", "\"COLOR_0\"", "\"COLOR_1\"",
                           "\"normalized\": true", "data:application/octet-stream;base64,"})
    EXPECT_TRUE(contains(json, part));
}

TEST(GltfRoundTrip, U16ColoursGenericAttributesAndUint32Indices) {
  Mesh m = grid(300, 3);  // 90001 vertices: indices need uint32
  const size_t nv = m.vertex_count();
  Attribute rgb = vertex_attribute("color", AttributeKind::color, AttributeType::u16, 3);
  Attribute quality = vertex_attribute("quality", AttributeKind::generic, AttributeType::f32, 1);
  Attribute id = vertex_attribute("_ID", AttributeKind::generic, AttributeType::u16, 1);
  Attribute flags = vertex_attribute("_FLAGS", AttributeKind::generic, AttributeType::u8, 3);
  for (size_t v = 0; v < nv; ++v) {
    rgb.values.insert(rgb.values.end(), {static_cast<float>(v % 65536), 65535.0f, 0.0f});
    quality.values.push_back(static_cast<float>(v) * 0.001f);
    id.values.push_back(static_cast<float>(v % 65536));
    flags.values.insert(flags.values.end(), {static_cast<float>(v % 256), 255.0f, 0.0f});
  }
  m.attributes = {rgb, quality, id, flags};
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    Mesh back;
    Status s = read(write(m, binary), back);
    ASSERT_TRUE(s.ok()) << s.to_string();
    // Generic attributes become custom semantics ("quality" comes back as
    // "_quality"), read back after the colour, by name.
    Mesh expected = m;
    Attribute renamed = quality;
    renamed.name = "_quality";
    expected.attributes = {rgb, flags, id, renamed};
    EXPECT_TRUE(identical(expected, back));
  }
}

TEST(GltfRoundTrip, EmptyMeshAndVerticesWithoutFaces) {
  Mesh empty;
  Mesh points;
  points.add_vertex(1, 2, 3);
  points.add_vertex(-4, 5e-30f, 6);
  for (const Mesh* m : {&empty, &points})
    for (bool binary : {true, false}) {
      Mesh back;
      back.add_triangle(0, 0, 0);
      Status s = read(write(*m, binary), back);
      ASSERT_TRUE(s.ok()) << s.to_string();
      EXPECT_TRUE(identical(*m, back));
    }
}

TEST(GltfRoundTrip, WriteMeshAndReadMeshByExtension) {
  tsm_test::TempDir dir;
  const Mesh m = attributed(5);
  for (const char* file : {"a.glb", "b.gltf", "C.GLB"}) {
    const std::string path = dir.file(file);
    Status s = tsm::write_mesh(path, m);
    ASSERT_TRUE(s.ok()) << s.to_string();
    Mesh back;
    ReadInfo info;
    s = tsm::read_mesh(path, back, {}, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_TRUE(identical(m, back)) << file;
    EXPECT_EQ(info.format, tsm::format_from_extension(path));
  }
  EXPECT_EQ(tsm::format_from_extension("x.gltf"), MeshFormat::gltf);
  EXPECT_EQ(tsm::format_from_extension("x.GlB"), MeshFormat::glb);
  EXPECT_STREQ(tsm::mesh_format_name(MeshFormat::gltf), "glTF");
  EXPECT_STREQ(tsm::mesh_format_name(MeshFormat::glb), "GLB");
  // Content wins over the name: a .glb named .ply still reads.
  std::string glb = write(m, true);
  Mesh back;
  ReadInfo info;
  ASSERT_TRUE(tsm::read_mesh_from_memory(glb, "wrong.ply", back, {}, &info).ok());
  EXPECT_EQ(info.format, MeshFormat::glb);
  EXPECT_TRUE(identical(m, back));
}

// ---------------------------------------------------------------------------
// Reading hand-made files

TEST(GltfRead, MinimalJsonWithDataUriBuffer) {
  const std::string json = triangle_json();
  EXPECT_EQ(tsm::sniff_format(json), MeshFormat::gltf);
  Mesh m;
  ReadInfo info;
  Status s = tsm::read_mesh_from_memory(json, "tri.gltf", m, {}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(info.format, MeshFormat::gltf);
  EXPECT_FALSE(info.binary);
  ASSERT_EQ(m.vertex_count(), 4u);  // the unused fourth vertex is kept
  ASSERT_EQ(m.face_count(), 1u);
  EXPECT_EQ(tsm_test::faces_of(m), (tsm_test::Faces{{0, 1, 2}}));
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5}));
  EXPECT_TRUE(m.attributes.empty());
}

TEST(GltfRead, StripsAndFansFollowTheSpecWinding) {
  Bin b;
  b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 2, 0});
  b.put<uint8_t>(0).put<uint8_t>(1).put<uint8_t>(3).put<uint8_t>(3).put<uint8_t>(2).put<uint8_t>(0).put<uint8_t>(0).put<uint8_t>(0);
  std::string json = subst(R"({
    "asset": {"version": "2.0"},
    "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0}, "mode": 5},
      {"attributes": {"POSITION": 0}, "indices": 1, "mode": 6},
      {"attributes": {"POSITION": 0}, "mode": 1},
      {"attributes": {"POSITION": 0}, "mode": 0}
    ]}],
    "buffers": [{"byteLength": 68, "uri": "$URI"}],
    "bufferViews": [{"buffer": 0, "byteLength": 60}, {"buffer": 0, "byteOffset": 60, "byteLength": 5}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3"},
                  {"bufferView": 1, "componentType": 5121, "count": 5, "type": "SCALAR"}]
  })", "URI", b.uri());
  Mesh m;
  ReadInfo info;
  Status s = read(json, m, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.vertex_count(), 5u);  // every primitive uses the same POSITION accessor: vertices shared
  EXPECT_EQ(tsm_test::faces_of(m), (tsm_test::Faces{{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {1, 3, 0}, {3, 2, 0}}));
  EXPECT_TRUE(contains(info.notes, "1 degenerate strip/fan triangle(s) dropped"));
  EXPECT_TRUE(contains(info.notes, "2 lines segment(s) skipped"));
  EXPECT_TRUE(contains(info.notes, "5 points skipped"));
  EXPECT_TRUE(contains(info.notes, "4 primitives of 1 mesh(es) concatenated"));
  EXPECT_EQ(info.skipped_elements, 7u);
}

TEST(GltfRead, SceneMeshesConcatenatedTransformsIgnoredAndOtherContentKept) {
  // Mesh 0 (twice, one with a translation), mesh 1 (with a NORMAL and a u8
  // colour), mesh 2 outside the scene; a material, texture, image, sampler.
  Bin b;
  b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0});           // 0: positions A
  b.floats({5, 5, 5, 6, 5, 5, 5, 6, 5});           // 36: positions B
  b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1});           // 72: normals B
  b.put<uint32_t>(0x04030201).put<uint32_t>(0x08070605).put<uint32_t>(0x0C0B0A09);  // 108: RGBA u8 B
  std::string json = subst(R"({
    "asset": {"version": "2.0", "generator": "hand"},
    "scene": 1,
    "scenes": [{"nodes": [2]}, {"nodes": [0, 1]}],
    "nodes": [{"mesh": 0, "translation": [1, 2, 3], "children": [3]}, {"mesh": 1}, {"mesh": 2}, {"mesh": 0}],
    "meshes": [{"name": "A", "primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
               {"primitives": [{"attributes": {"POSITION": 1, "NORMAL": 2, "COLOR_0": 3}}]},
               {"primitives": [{"attributes": {"POSITION": 1}}]}],
    "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
    "textures": [{"source": 0, "sampler": 0}],
    "samplers": [{}],
    "images": [{"uri": "skin.png"}],
    "buffers": [{"byteLength": 120, "uri": "$URI"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 72, "byteLength": 36}, {"buffer": 0, "byteOffset": 108, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                  {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
                  {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"},
                  {"bufferView": 3, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"}]
  })", "URI", b.uri());
  Mesh m;
  ReadInfo info;
  Status s = read(json, m, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 5, 5, 5, 6, 5}));
  EXPECT_EQ(tsm_test::faces_of(m), (tsm_test::Faces{{0, 1, 2}, {3, 4, 5}}));
  ASSERT_EQ(m.attributes.size(), 3u);
  EXPECT_EQ(m.attributes[0].name, "normal");
  EXPECT_EQ(m.attributes[0].values, (std::vector<float>{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(m.attributes[1].name, "color");
  EXPECT_EQ(m.attributes[1].type, AttributeType::u8);
  EXPECT_EQ(m.attributes[1].values,
            (std::vector<float>{255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 1, 2, 3, 4, 5, 6, 7, 8, 9,
                                10, 11, 12}));
  // Two vertex groups: the pass-through tag says which vertex is whose
  // (test_gltf_passthrough.cpp tests the rest of the pass-through).
  EXPECT_EQ(m.attributes[2].name, "_gltf_group");
  EXPECT_EQ(m.attributes[2].values, (std::vector<float>{0, 0, 0, 1, 1, 1}));
  EXPECT_TRUE(m.valid());
  for (const char* part : {"read scene 1 of 2", "node transforms not applied", "1 mesh(es) used by several nodes read once",
                           "1 mesh(es) not in the scene kept as stored", "2 primitives of 2 mesh(es) concatenated",
                           "NORMAL missing in 1 of 2 vertex group(s): filled with zeros",
                           "COLOR_0 missing in 1 of 2 vertex group(s): filled with opaque white"})
    EXPECT_TRUE(contains(info.notes, part));
  // The material, texture, image and sampler are kept (Mesh::metadata "gltf").
  EXPECT_FALSE(contains(info.notes, "not kept")) << info.notes;
  ASSERT_NE(m.find_metadata("gltf"), nullptr);
  std::string out;
  ASSERT_TRUE(tsm::write_gltf(m, WriteOptions(), out, false).ok());
  for (const char* part : {"\"materials\"", "\"baseColorTexture\"", "\"skin.png\"", "\"samplers\""})
    EXPECT_TRUE(contains(out, part));
}

TEST(GltfRead, InterleavedStrideSparseAndQuantizedAttributes) {
  // Interleaved: position (12 bytes) + u8 RGB colour (3 bytes + 1 pad) + u16
  // normalized texcoord (4 bytes): stride 20. A sparse accessor moves vertex 2.
  Bin b;
  const float pos[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int v = 0; v < 3; ++v) {
    for (float x : pos[v]) b.put(x);
    b.put<uint8_t>(static_cast<uint8_t>(10 * v)).put<uint8_t>(20).put<uint8_t>(30).put<uint8_t>(0xEE);
    b.put<uint16_t>(65535).put<uint16_t>(0);
  }
  // 60: sparse index (u16) + pad, 64: sparse value
  b.put<uint16_t>(2).put<uint16_t>(0);
  b.floats({7, 8, 9});
  std::string json = subst(R"({
    "asset": {"version": "2.0"},
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1, "TEXCOORD_0": 2}}]}],
    "buffers": [{"byteLength": 76, "uri": "$URI"}],
    "bufferViews": [{"buffer": 0, "byteLength": 60, "byteStride": 20},
                    {"buffer": 0, "byteOffset": 60, "byteLength": 4}, {"buffer": 0, "byteOffset": 64, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                              "values": {"bufferView": 2}}},
                  {"bufferView": 0, "byteOffset": 12, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC3"},
                  {"bufferView": 0, "byteOffset": 16, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"}]
  })", "URI", b.uri());
  Mesh m;
  ReadInfo info;
  Status s = read(json, m, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 7, 8, 9}));
  ASSERT_EQ(m.attributes.size(), 2u);
  EXPECT_EQ(m.attributes[0].name, "texcoord0");
  EXPECT_EQ(m.attributes[0].values, (std::vector<float>{1, 0, 1, 0, 1, 0}));
  EXPECT_EQ(m.attributes[1].name, "color");
  EXPECT_EQ(m.attributes[1].type, AttributeType::u8);
  EXPECT_EQ(m.attributes[1].values, (std::vector<float>{0, 20, 30, 10, 20, 30, 20, 20, 30}));
}

TEST(GltfRead, ExternalBufferFilesOnlyWhenAllowed) {
  tsm_test::TempDir dir;
  const Bin b = triangle_bin();
  {
    std::ofstream f(dir.file("tri data.bin"), std::ios::binary);
    f << b.s;
  }
  const std::string json = subst(kTriangleJson, "URI", "tri%20data.bin");
  {
    std::ofstream f(dir.file("tri.gltf"), std::ios::binary);
    f << json;
  }
  Mesh m;
  Status s = tsm::read_mesh(dir.file("tri.gltf"), m);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.face_count(), 1u);
  // From memory: no file access unless a folder is given.
  expect_error(json, {"external files are not read here"});
  ReadOptions o;
  o.external_files_dir = dir.path.string();
  ASSERT_TRUE(read(json, m, nullptr, o).ok());
  EXPECT_EQ(m.face_count(), 1u);
  // Missing file, a folder, and a size that does not match byteLength.
  expect_error(subst(kTriangleJson, "URI", "missing.bin"), {"missing.bin"}, ErrorCode::parse_error, o);
  std::filesystem::create_directory(dir.file("sub"));
  expect_error(subst(kTriangleJson, "URI", "sub"), {"not a regular file"}, ErrorCode::parse_error, o);
  {
    std::ofstream f(dir.file("short.bin"), std::ios::binary);
    f << b.s.substr(0, 50);
  }
  expect_error(subst(kTriangleJson, "URI", "short.bin"), {"short.bin"}, ErrorCode::parse_error, o);
}

// A .gltf file's external buffers are read from its folder (and below)
// only: every spelling that leads elsewhere is refused, with the file and
// the URI named, and the "secret" outside is never read.
TEST(GltfRead, ExternalBuffersOutsideTheFolderAreRefused) {
  namespace fs = std::filesystem;
  tsm_test::TempDir root;
  const Bin b = triangle_bin();
  // The secret is a valid buffer: if it were read, the file would load.
  const std::string secret = root.file("secret.bin");
  {
    std::ofstream f(secret, std::ios::binary);
    f << b.s;
  }
  const fs::path model = root.path / "model";
  fs::create_directories(model / "sub");
  for (const fs::path& p : {model / "tri.bin", model / "sub" / "tri.bin"}) {
    std::ofstream f(p, std::ios::binary);
    f << b.s;
  }
  fs::create_symlink(secret, model / "abs_link.bin");           // absolute link out
  fs::create_symlink("../secret.bin", model / "rel_link.bin");  // relative link out
  fs::create_directory_symlink(root.path, model / "up");        // a folder link out
  fs::create_symlink("tri.bin", model / "inside_link.bin");     // a link that stays inside
  auto gltf_with = [&](const std::string& uri) {
    const std::string path = (model / "x.gltf").string();
    std::ofstream f(path, std::ios::binary);
    f << subst(kTriangleJson, "URI", uri);
    return path;
  };

  struct Case {
    std::string uri;   // as written in the JSON (JSON escapes included)
    std::string says;  // part of the message
  };
  const std::vector<Case> refused = {
      {"../secret.bin", "goes up a folder"},
      {"sub/../../secret.bin", "goes up a folder"},
      {"%2e%2e/secret.bin", "written as \"%2e%2e/secret.bin\""},
      {"%2E%2E%2Fsecret.bin", "goes up a folder"},
      {"..%2fsecret.bin", "goes up a folder"},
      {"..\\\\secret.bin", "backslash"},
      {secret, "absolute path"},
      {"%2F" + secret.substr(1), "absolute path"},
      {"file://" + secret, "file: URI"},
      {"file:../secret.bin", "file: URI"},
      {"FILE:secret.bin", "file: URI"},
      {"http://example.org/secret.bin", "absolute URI"},
      {"C:/secret.bin", "drive"},
      {"abs_link.bin", "symbolic link"},
      {"rel_link.bin", "symbolic link"},
      {"up/secret.bin", "symbolic link"},
  };
  for (const Case& c : refused) {
    Mesh m;
    Status s = tsm::read_mesh(gltf_with(c.uri), m);
    ASSERT_FALSE(s.ok()) << c.uri << ": the buffer outside the folder was read";
    EXPECT_EQ(s.code(), ErrorCode::parse_error) << c.uri;
    EXPECT_TRUE(contains(s.message(), "x.gltf: ")) << c.uri;
    EXPECT_TRUE(contains(s.message(), c.says)) << c.uri;
    EXPECT_TRUE(contains(s.message(), "refused")) << c.uri;
    EXPECT_TRUE(contains(s.message(), "buffers[0]")) << c.uri;
    EXPECT_EQ(m.vertex_count(), 0u) << c.uri;
  }
  // What stays inside is read: beside the file, in a subfolder (also
  // percent-encoded), through "./", and through a link that stays inside.
  for (const std::string uri : {"tri.bin", "sub/tri.bin", "sub%2Ftri.bin", "./tri.bin", "inside_link.bin"}) {
    Mesh m;
    Status s = tsm::read_mesh(gltf_with(uri), m);
    ASSERT_TRUE(s.ok()) << uri << ": " << s.to_string();
    EXPECT_EQ(m.face_count(), 1u) << uri;
  }
  // The same from memory, with the folder given.
  {
    Mesh m;
    ReadOptions o;
    o.external_files_dir = model.string();
    Status s = read(subst(kTriangleJson, "URI", "../secret.bin"), m, nullptr, o);
    ASSERT_FALSE(s.ok());
    EXPECT_TRUE(contains(s.message(), "goes up a folder"));
  }
}

TEST(GltfRead, DracoPrimitiveReadFromItsUncompressedCopyOnly) {
  std::string j = triangle_json();
  auto edit = [&](const std::string& from, const std::string& to) {
    const size_t at = j.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    j.replace(at, from.size(), to);
  };
  edit(R"("indices": 1})",
       R"("indices": 1, "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}})");
  Mesh m;
  ReadInfo info;
  Status s = read(j, m, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.face_count(), 1u);
  EXPECT_TRUE(contains(info.notes, "uncompressed copy of a Draco-compressed primitive"));
  // Without the copy the Draco data is decoded (here it is not Draco data).
  edit(R"({"bufferView": 0, "componentType": 5126)", R"({"componentType": 5126)");
  s = read(j, m, &info);
  EXPECT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.message(), "Draco")) << s.to_string();
}

// A glTF whose primitives only tsm's extension holds (what `tsm encode
// x.glb -o y.glb` writes) is read through the transcoder: the same mesh as
// the plain file, on the grid.
TEST(GltfRead, TsmCompressedPrimitivesDecodedFirst) {
  const Mesh ball = tsm_test::icosphere(2);
  std::string plain;
  ASSERT_TRUE(tsm::write_gltf(ball, tsm::WriteOptions{}, plain, true).ok());
  tsm::GltfTranscodeOptions options;
  options.encode.quantization_bits = 20;
  tsm::GltfOutput packed;
  ASSERT_TRUE(tsm::transcode_gltf(plain, "ball.glb", "", options, true, "", packed).ok());
  ASSERT_NE(packed.main.find("TSM_mesh_compression"), std::string::npos);
  Mesh m;
  ReadInfo info;
  Status s = tsm::read_gltf(packed.main, "packed.glb", m, ReadOptions{}, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_TRUE(contains(info.notes, "compressed primitives decoded first")) << info.notes;
  EXPECT_EQ(m.vertex_count(), ball.vertex_count());
  EXPECT_EQ(m.face_count(), ball.face_count());
  ASSERT_NE(m.find_metadata("gltf"), nullptr);  // the document, for writing glTF again
  m.metadata.clear();
  const tsm::CompareResult cr = tsm::compare_meshes(ball, m, 20);
  EXPECT_TRUE(cr.equal) << cr.difference;
  // A damaged stream is refused with the transcoder's message, not the reader's "unsupported".
  std::string broken = packed.main;
  const size_t at = broken.size() - 40;
  broken[at] = static_cast<char>(broken[at] ^ 0x5A);
  s = tsm::read_gltf(broken, "broken.glb", m, ReadOptions{}, &info);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.code(), ErrorCode::unsupported) << s.to_string();
}

TEST(GltfRead, NonFiniteValuesRefusedUnlessAllowed) {
  Bin b = triangle_bin();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&b.s[16], &nan, 4);
  const std::string json = subst(kTriangleJson, "URI", b.uri());
  expect_error(json, {"accessor 0", "element 1", "not finite", "allow_nonfinite"});
  ReadOptions o;
  o.allow_nonfinite = true;
  Mesh m;
  ASSERT_TRUE(read(json, m, nullptr, o).ok());
  EXPECT_TRUE(std::isnan(m.positions[4]));
}

TEST(GltfRead, LimitsAndReusedAccessorsCannotBlowUpMemory) {
  ReadOptions o;
  o.max_vertices = 3;
  expect_error(triangle_json(), {"max_vertices"}, ErrorCode::limit_exceeded, o);
  o = ReadOptions();
  o.max_faces = 0;
  // 4000 primitives, each with its own indices accessor over the same 60000-index view.
  Bin b;
  b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0});
  for (int i = 0; i < 60000; ++i) b.put<uint8_t>(static_cast<uint8_t>(i % 3));
  std::string prims, accessors = R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"})";
  for (int i = 0; i < 4000; ++i) {
    prims += std::string(i ? "," : "") + R"({"attributes": {"POSITION": 0}, "indices": )" + std::to_string(i + 1) + "}";
    accessors += R"(,{"bufferView": 1, "componentType": 5121, "count": 60000, "type": "SCALAR"})";
  }
  std::string json = R"({"asset": {"version": "2.0"}, "meshes": [{"primitives": [)" + prims +
                     R"(]}], "buffers": [{"byteLength": 60036, "uri": ")" + b.uri() +
                     R"("}], "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 60000}],
                     "accessors": [)" + accessors + "]}";
  expect_error(json, {"refused"}, ErrorCode::limit_exceeded);
  o.max_faces = 1000;
  expect_error(json, {"max_faces"}, ErrorCode::limit_exceeded, o);
}

// ---------------------------------------------------------------------------
// Malformed files

TEST(GltfMalformed, BadReferencesAndRanges) {
  auto with = [&](const std::string& from, const std::string& to) {
    std::string j = triangle_json();
    const size_t at = j.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) j.replace(at, from.size(), to);
    return j;
  };
  expect_error(with(R"("POSITION": 0)", R"("POSITION": 7)"), {"mesh 0 primitive 0 POSITION", "accessor 7 does not exist"});
  expect_error(with(R"("indices": 1)", R"("indices": 9)"), {"primitive indices accessor out of bounds"});
  expect_error(with(R"("count": 3, "type": "SCALAR")", R"("count": 4, "type": "SCALAR")"),
               {"indices (accessor 1)", "run past the end of buffer view 1"});
  expect_error(with(R"("byteOffset": 48, "byteLength": 6)", R"("byteOffset": 52, "byteLength": 6)"),
               {"buffer view 1", "runs past the end of buffer 0 (56 bytes)"});
  expect_error(with(R"("type": "VEC3", "min")", R"("type": "VEC2", "min")"), {"POSITION (accessor 0) is VEC2; expected VEC3"});
  expect_error(with(R"("componentType": 5123)", R"("componentType": 5122)"), {"indices have component type short"});
  expect_error(with(R"("nodes": [0]}])", R"("nodes": [3]}])"), {"scene 0 uses node 3, but there are 1 nodes"});
  expect_error(with(R"("nodes": [{"mesh": 0}])", R"("nodes": [{"mesh": 4}])"), {"node 0 uses mesh 4, but there are 1 meshes"});
  expect_error(with(R"("scene": 0)", R"("scene": 5)"), {"scene 5 is the default scene, but there are 1 scenes"});
  expect_error(with(R"("indices": 1}]})", R"("indices": 1, "mode": 9}]})"), {"unknown primitive mode 9"});
  expect_error(with(R"("version": "2.0")", R"("version": "1.0")"), {"only glTF 2.0 is read"});
  // A primitives object where glTF has an array (assimp-testmodels' wrongTypes/badArray.gltf).
  expect_error(with(R"("primitives": [{"attributes": {"POSITION": 0}, "indices": 1}])",
                    R"("primitives": {"x": {"attributes": {"POSITION": 0}, "indices": 1}})"),
               {"'meshes[0].primitives' is not an array"});
  expect_error(with(R"("byteLength": 48})", R"("byteLength": 48, "byteStride": 8})"), {"byteStride 8, less than the 12-byte element"});
  // Out-of-range vertex index: index 2 names vertex 9 of 4.
  {
    Bin bad = triangle_bin();
    bad.s[52] = 9;
    expect_error(subst(kTriangleJson, "URI", bad.uri()), {"index 2 is 9, but POSITION has 4 vertices"});
  }
  // Indices not a multiple of 3.
  expect_error(with(R"("count": 3, "type": "SCALAR")", R"("count": 2, "type": "SCALAR")"), {"2 triangle corners, not a multiple of 3"});
  // Sparse index past the accessor's end.
  {
    Bin sb = triangle_bin();
    sb.put<uint16_t>(4).put<uint16_t>(0);  // 56: the sparse index, padding
    sb.floats({1, 1, 1});                  // 60: its value
    std::string j = subst(kTriangleJson, "URI", sb.uri());
    auto edit = [&](const std::string& from, const std::string& to) {
      const size_t at = j.find(from);
      ASSERT_NE(at, std::string::npos) << from;
      j.replace(at, from.size(), to);
    };
    edit(R"("count": 4, "type": "VEC3",)",
         R"("count": 4, "type": "VEC3", "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5123},)"
         R"( "values": {"bufferView": 3}},)");
    edit(R"("byteLength": 56)", R"("byteLength": 72)");
    edit(R"({"buffer": 0, "byteOffset": 48, "byteLength": 6})",
         R"({"buffer": 0, "byteOffset": 48, "byteLength": 6}, {"buffer": 0, "byteOffset": 56, "byteLength": 4},)"
         R"( {"buffer": 0, "byteOffset": 60, "byteLength": 12})");
    expect_error(j, {"sparse index 0 is 4, but the accessor has 4 elements"});
  }
  // Draco compression is refused clearly.
  expect_error(with(R"("asset")", R"("extensionsRequired": ["KHR_draco_mesh_compression"], "asset")"),
               {"Draco"}, ErrorCode::unsupported);
}

TEST(GltfMalformed, BrokenJsonAndContainers) {
  expect_error("{\"asset\": {\"version\": \"2.0\"}, ", {"invalid glTF"});
  expect_error("[1, 2, 3]", {"not a glTF file"});
  expect_error("", {"not a glTF file"});
  expect_error(std::string(100000, '[') + std::string(100000, ']'), {"not a glTF file"});
  expect_error("{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + std::string(5000, '[') + std::string(5000, ']') + "}",
               {"nests arrays and objects more than 128 deep"});
  expect_error("{\"asset\": {}}", {"invalid glTF"});

  const std::string glb = write(attributed(4), true);
  // Wrong magic: the content is not glTF at all.
  std::string bad = glb;
  bad[3] = 'X';
  expect_error(bad, {"not a glTF file"});
  // Version 1.
  bad = glb;
  bad[4] = 1;
  expect_error(bad, {"GLB version 1", "only version 2"});
  // Chunk types.
  bad = glb;
  bad[16] = 'X';
  expect_error(bad, {"byte 16: the first GLB chunk must be JSON"});
  // Every truncation: an error, never a crash.
  for (size_t n = 0; n < glb.size(); n += (n < 64 ? 1 : 7)) {
    Mesh m;
    Status s = read(glb.substr(0, n), m);
    ASSERT_FALSE(s.ok()) << "truncated to " << n << " bytes";
    EXPECT_TRUE(contains(s.message(), "test.gltf: ")) << s.message();
    if (n >= 12) {
      EXPECT_TRUE(contains(s.message(), "truncated GLB")) << n;
    }
  }
  // A length field shorter than the file: the rest is ignored, with a note.
  std::string longer = glb + std::string(8, '\0');
  Mesh m;
  ReadInfo info;
  ASSERT_TRUE(read(longer, m, &info).ok());
  EXPECT_TRUE(contains(info.notes, "8 bytes after the end of the GLB ignored"));
}

TEST(GltfMalformed, RandomDamageNeverCrashes) {
  const std::string glb = write(attributed(4), true);
  const std::string json = triangle_json();
  std::mt19937 rng(1234);
  size_t accepted = 0;
  for (int round = 0; round < 3000; ++round) {
    std::string bytes = round % 2 ? glb : json;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % bytes.size();
      switch (rng() % 4) {
        case 0: bytes[at] = static_cast<char>(rng()); break;
        case 1: bytes[at] = "0123456789-[]{}\",:e"[rng() % 19]; break;
        case 2: bytes.erase(at, 1 + rng() % 8); break;
        default: bytes.insert(at, 1, static_cast<char>(rng())); break;
      }
      if (bytes.empty()) bytes = "x";
    }
    Mesh m;
    ReadInfo info;
    Status s = read(bytes, m, &info);
    if (s.ok()) {
      ++accepted;
      std::string why;
      EXPECT_TRUE(m.valid(&why)) << why;
      EXPECT_TRUE(m.all_finite());
    } else {
      EXPECT_TRUE(contains(s.message(), "test.gltf: "));
      EXPECT_NE(s.code(), ErrorCode::internal) << s.to_string();
    }
  }
  EXPECT_GT(accepted, 0u);
}

// ---------------------------------------------------------------------------
// What the writer refuses

// A document that names its images by relative URI needs those files beside
// the written output: the writer says so, and says nothing for data URIs.
TEST(GltfWrite, NotesImagesNamedByRelativeUri) {
  std::string json = triangle_json();
  json.insert(json.rfind('}'), R"(, "images": [{"uri": "tex.png"}, {"uri": "data:image/png;base64,AAAA"}])");
  Mesh m;
  Status s = tsm::read_mesh_from_memory(json, "tri.gltf", m, {}, nullptr);
  ASSERT_TRUE(s.ok()) << s.to_string();
  for (bool binary : {false, true}) {
    std::string out;
    tsm::WriteInfo info;
    s = tsm::write_gltf(m, WriteOptions(), out, binary, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_TRUE(contains(info.notes, "1 image file")) << info.notes;
    EXPECT_TRUE(contains(info.notes, "tex.png")) << info.notes;
  }
  Mesh no_images;
  ASSERT_TRUE(tsm::read_mesh_from_memory(triangle_json(), "tri.gltf", no_images, {}, nullptr).ok());
  std::string out;
  tsm::WriteInfo none;
  ASSERT_TRUE(tsm::write_gltf(no_images, WriteOptions(), out, false, &none).ok());
  EXPECT_TRUE(none.notes.empty()) << none.notes;
}

TEST(GltfWrite, RefusesPolygonsAndFaceOrCornerAttributes) {
  std::string out;
  Mesh quad = grid(3, 1);
  const uint32_t q[] = {0, 1, 4, 3};
  quad.add_face(q, 4);
  Status s = tsm::write_gltf(quad, WriteOptions(), out, true);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), ErrorCode::unsupported);
  EXPECT_TRUE(contains(s.message(), "triangles only"));
  EXPECT_TRUE(contains(s.message(), "face 8 has 4 corners"));
  EXPECT_TRUE(contains(s.message(), "write PLY or OBJ"));
  EXPECT_TRUE(out.empty());

  Mesh corner = grid(3, 1);
  Attribute uv = vertex_attribute("uv", AttributeKind::texcoord, AttributeType::f32, 2);
  uv.domain = AttributeDomain::corner;
  uv.values = {0, 0, 1, 1};
  for (size_t i = 0; i < corner.corner_count(); ++i) uv.indices.push_back(static_cast<uint32_t>(i % 2));
  corner.attributes.push_back(uv);
  ASSERT_TRUE(corner.valid());
  s = tsm::write_gltf(corner, WriteOptions(), out, false);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), ErrorCode::unsupported);
  EXPECT_TRUE(contains(s.message(), "'uv' is per face corner"));
  EXPECT_TRUE(contains(s.message(), "write PLY or OBJ"));

  Mesh face = grid(3, 1);
  Attribute fc = vertex_attribute("material", AttributeKind::generic, AttributeType::u8, 1);
  fc.domain = AttributeDomain::face;
  fc.values.assign(face.face_count(), 1.0f);
  face.attributes.push_back(fc);
  s = tsm::write_gltf(face, WriteOptions(), out, true);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.message(), "'material' is per face"));

  Mesh inf = grid(3, 1);
  inf.positions[4] = std::numeric_limits<float>::infinity();
  s = tsm::write_gltf(inf, WriteOptions(), out, true);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.message(), "vertex 1 has a non-finite coordinate"));

  Mesh badcolor = attributed(3);
  badcolor.attributes[3].values[5] = 256.0f;
  s = tsm::write_gltf(badcolor, WriteOptions(), out, true);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.message(), "'color' has type u8 but value 256"));

  // write_mesh names the file and leaves nothing behind.
  tsm_test::TempDir dir;
  s = tsm::write_mesh(dir.file("q.glb"), quad);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.message(), "q.glb: "));
  EXPECT_FALSE(std::filesystem::exists(dir.file("q.glb")));
}

// ---------------------------------------------------------------------------
// The command-line tool: encode --input-format gltf|glb, decode --format gltf|glb

TEST(GltfCli, EncodeAndDecodeGltfAndGlb) {
  tsm_test::TempDir dir;
  const Mesh m = attributed(6);
  ASSERT_TRUE(tsm::write_mesh(dir.file("in.glb"), m).ok());
  ASSERT_TRUE(tsm::write_mesh(dir.file("in.gltf"), m).ok());
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string("'") + TSM_CLI_PATH + "' " + args + " >'" + dir.file("log") + "' 2>&1";
    return std::system(cmd.c_str());
  };
  const std::string d = "'" + dir.path.string() + "/";
  EXPECT_EQ(run("encode " + d + "in.glb' -o " + d + "a.tsm'"), 0);
  EXPECT_EQ(run("encode --input-format gltf - -o " + d + "b.tsm' < " + d + "in.gltf'"), 0);
  EXPECT_EQ(run("decode " + d + "a.tsm' -o " + d + "a.gltf'"), 0);
  EXPECT_EQ(run("decode " + d + "b.tsm' --format glb -o " + d + "b.glb'"), 0);
  EXPECT_EQ(run("decode " + d + "b.tsm' --format glb -o " + d + "outdir/'"), 0);
  EXPECT_NE(run("decode " + d + "b.tsm' --format gltf -o " + d + "b.ply'"), 0);  // the name says PLY
  for (const char* out : {"a.gltf", "b.glb", "outdir/b.glb"}) {
    Mesh back;
    Status s = tsm::read_mesh(dir.file(out), back);
    ASSERT_TRUE(s.ok()) << out << ": " << s.to_string();
    EXPECT_EQ(back.vertex_count(), m.vertex_count()) << out;
    EXPECT_EQ(back.face_count(), m.face_count()) << out;
  }
}

}  // namespace
