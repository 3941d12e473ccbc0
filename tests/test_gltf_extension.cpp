// glTF to glTF with TSM_mesh_compression (libio/src/gltf_*.cpp,
// format-spec/gltf/TSM_mesh_compression.md): a generated document (two
// triangle primitives sharing their vertices, a lines primitive, a morph
// target, a skin, an animation, materials, an embedded image, extras and an
// unknown extension) goes glb -> compressed glb -> plain glb; every
// primitive keeps its semantics, counts and values (within the quantization
// step, morph targets within half their grid step; integer attributes and
// ordinary accessors exactly, in the decoded order), the rest of the JSON is
// kept, --fallback copies equal the decoded values, extensionsRequired says
// what it must. Primitives naming the same accessors share one stream; morph
// targets on their grid come back exactly. Hostile input (a stream shared by
// primitives naming other accessors, broken target maps) gives errors, not
// crashes. Corpus: the real assets (Draco-compressed ones
// included, and meshopt ones made by gltfpack -cc when it is installed).
//
// The documents are built and read here with nlohmann-json and a reader of
// the test's own, not with the library's code.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/gltf_transcode.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using tsm_test::contains;

// ---------------------------------------------------------------------------
// GLB on the test side

uint32_t u32_at(const std::string& s, size_t at) {
  uint32_t v;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

void put32(std::string& s, uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); }

std::string make_glb(const json& doc, std::string bin) {
  std::string text = doc.dump();
  text.resize((text.size() + 3) / 4 * 4, ' ');
  bin.resize((bin.size() + 3) / 4 * 4, '\0');
  std::string out;
  put32(out, 0x46546C67);
  put32(out, 2);
  put32(out, static_cast<uint32_t>(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put32(out, static_cast<uint32_t>(text.size()));
  put32(out, 0x4E4F534A);
  out += text;
  if (!bin.empty()) {
    put32(out, static_cast<uint32_t>(bin.size()));
    put32(out, 0x004E4942);
    out += bin;
  }
  return out;
}

struct Glb {
  json doc;
  std::string bin;
};

Glb split_glb(const std::string& glb) {
  Glb g;
  EXPECT_EQ(u32_at(glb, 0), 0x46546C67u);
  EXPECT_EQ(u32_at(glb, 8), glb.size());
  const uint32_t jl = u32_at(glb, 12);
  g.doc = json::parse(glb.substr(20, jl));
  if (20 + jl + 8 <= glb.size()) g.bin = glb.substr(20 + jl + 8, u32_at(glb, 20 + jl));
  return g;
}

// An accessor's values as doubles (stored values; dense only, as tsm writes).
std::vector<double> accessor_values(const Glb& g, size_t index, size_t* components = nullptr) {
  const json& a = g.doc["accessors"][index];
  const std::string type = a["type"];
  const size_t n = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "MAT4" ? 16 : 4;
  if (components) *components = n;
  const int ct = a["componentType"];
  const size_t cb = ct == 5126 || ct == 5125 ? 4 : ct == 5123 || ct == 5122 ? 2 : 1;
  const size_t count = a["count"];
  std::vector<double> out(count * n, 0.0);
  if (!a.contains("bufferView")) return out;
  const json& v = g.doc["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t stride = v.value("byteStride", size_t(0)) ? v["byteStride"].get<size_t>() : cb * n;
  const size_t base = v.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
  for (size_t i = 0; i < count; ++i)
    for (size_t c = 0; c < n; ++c) {
      const char* p = g.bin.data() + base + i * stride + c * cb;
      double x = 0;
      if (ct == 5126) {
        float f;
        std::memcpy(&f, p, 4);
        x = f;
      } else if (ct == 5125) {
        x = u32_at(std::string(p, 4), 0);
      } else if (ct == 5123) {
        uint16_t h;
        std::memcpy(&h, p, 2);
        x = h;
      } else if (ct == 5121) {
        x = static_cast<uint8_t>(*p);
      }
      out[i * n + c] = x;
    }
  return out;
}

// ---------------------------------------------------------------------------
// The generated document

struct Source {
  std::string glb;
  json doc;
  size_t vertices = 0;
  std::vector<float> positions, normals, uvs, weights, target, custom;
  std::vector<uint32_t> tris0, tris1;  // the two triangle primitives
  float step = 0;                      // position quantization step at -q 12
};

size_t add_view(json& doc, std::string& bin, const std::string& bytes, int target) {
  bin.resize((bin.size() + 3) / 4 * 4, '\0');
  json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
  if (target) v["target"] = target;
  bin += bytes;
  doc["bufferViews"].push_back(v);
  return doc["bufferViews"].size() - 1;
}

size_t add_accessor(json& doc, std::string& bin, const std::string& bytes, int ct, const char* type, size_t count,
                    int target, bool normalized = false) {
  json a = {{"bufferView", add_view(doc, bin, bytes, target)}, {"componentType", ct}, {"count", count}, {"type", type}};
  if (normalized) a["normalized"] = true;
  doc["accessors"].push_back(a);
  return doc["accessors"].size() - 1;
}

std::string floats(const std::vector<float>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * 4);
}

// A POSITION accessor with the min and max glTF requires.
size_t add_positions(json& doc, std::string& bin, const std::vector<float>& p, size_t vertices) {
  std::vector<float> pmin(3, 1e9f), pmax(3, -1e9f);
  for (size_t i = 0; i < p.size(); ++i) {
    pmin[i % 3] = std::min(pmin[i % 3], p[i]);
    pmax[i % 3] = std::max(pmax[i % 3], p[i]);
  }
  const size_t pos = add_accessor(doc, bin, floats(p), 5126, "VEC3", vertices, 34962);
  doc["accessors"][pos]["min"] = pmin;
  doc["accessors"][pos]["max"] = pmax;
  return pos;
}

Source make_source() {
  Source s;
  const tsm::Mesh sphere = tsm_test::icosphere(3);
  s.vertices = sphere.vertex_count();
  s.positions = sphere.positions;
  for (size_t i = 0; i < s.vertices; ++i) {
    const float* p = &s.positions[3 * i];
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int c = 0; c < 3; ++c) s.normals.push_back(p[c] / len);
    s.uvs.push_back(0.5f + 0.5f * p[0] / len);
    s.uvs.push_back(0.5f + 0.25f * p[1] / len);
    const float w = 0.25f + 0.5f * static_cast<float>(i % 7) / 7.0f;
    s.weights.insert(s.weights.end(), {w, 1.0f - w, 0.0f, 0.0f});
    s.target.insert(s.target.end(), {0.0f, 0.01f * static_cast<float>(i % 5), 0.0f});
    s.custom.push_back(0.1f * static_cast<float>(i) + 0.03f);
  }
  for (size_t f = 0; f < sphere.face_count(); ++f)
    for (int k = 0; k < 3; ++k) (f % 3 == 0 ? s.tris1 : s.tris0).push_back(sphere.face(f)[k]);
  const tsm::BoundingBox box = tsm::bounding_box(sphere);
  s.step = static_cast<float>(box.largest_extent() / 4095.0);

  json doc = {{"asset", {{"version", "2.0"}, {"generator", "test"}}},
              {"extensionsUsed", {"EXT_test_unknown"}},
              {"scene", 0},
              {"scenes", {{{"nodes", {0, 2}}, {"extras", {{"note", "kept"}}}}}},
              {"accessors", json::array()},
              {"bufferViews", json::array()}};
  std::string bin;
  const size_t pos = add_positions(doc, bin, s.positions, s.vertices);
  const size_t nor = add_accessor(doc, bin, floats(s.normals), 5126, "VEC3", s.vertices, 34962);
  const size_t uv = add_accessor(doc, bin, floats(s.uvs), 5126, "VEC2", s.vertices, 34962);
  // JOINTS_0 numbers the vertices (exact integers): the test's vertex map.
  std::string joints;
  for (size_t i = 0; i < s.vertices; ++i) joints += {char(i & 0xFF), char(i >> 8), 0, 1};
  const size_t jnt = add_accessor(doc, bin, joints, 5121, "VEC4", s.vertices, 34962);
  const size_t wts = add_accessor(doc, bin, floats(s.weights), 5126, "VEC4", s.vertices, 34962);
  const size_t cus = add_accessor(doc, bin, floats(s.custom), 5126, "SCALAR", s.vertices, 34962);
  // One byte per vertex: written back with a 4-byte stride (vertex data alignment).
  std::string flags;
  for (size_t i = 0; i < s.vertices; ++i) flags += static_cast<char>(i % 3);
  const size_t flg = add_accessor(doc, bin, flags, 5121, "SCALAR", s.vertices, 34962);
  const size_t tgt = add_accessor(doc, bin, floats(s.target), 5126, "VEC3", s.vertices, 34962);
  doc["accessors"][tgt]["min"] = {0.0, 0.0, 0.0};
  doc["accessors"][tgt]["max"] = {0.0, 0.04f, 0.0};
  auto indices = [&](const std::vector<uint32_t>& t) {
    std::string b;
    for (uint32_t i : t) b += {char(i & 0xFF), char(i >> 8)};
    return add_accessor(doc, bin, b, 5123, "SCALAR", t.size(), 34963);
  };
  const size_t i0 = indices(s.tris0), i1 = indices(s.tris1);
  const std::vector<float> ibm = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const size_t inv = add_accessor(doc, bin, floats(ibm), 5126, "MAT4", 1, 0);
  const size_t times = add_accessor(doc, bin, floats({0.0f, 1.0f}), 5126, "SCALAR", 2, 0);
  doc["accessors"][times]["min"] = {0.0};
  doc["accessors"][times]["max"] = {1.0};
  const size_t rot = add_accessor(doc, bin, floats({0, 0, 0, 1, 0, 0.7071f, 0, 0.7071f}), 5126, "VEC4", 2, 0);
  const json attrs = {{"POSITION", pos},  {"NORMAL", nor},  {"TEXCOORD_0", uv}, {"JOINTS_0", jnt},
                      {"WEIGHTS_0", wts}, {"_CUSTOM", cus}, {"_FLAG", flg}};
  doc["meshes"] = {{{"name", "sphere"},
                    {"primitives",
                     {{{"attributes", attrs},
                       {"indices", i0},
                       {"material", 0},
                       {"targets", {{{"POSITION", tgt}}}},
                       {"extras", {{"part", "a"}}}},
                      {{"attributes", attrs}, {"indices", i1}, {"material", 1}},
                      {{"attributes", {{"POSITION", pos}}}, {"indices", i1}, {"mode", 1}}}},
                    {"weights", {0.5}}}};
  const size_t image = add_view(doc, bin, std::string("\x89PNG\r\n\x1a\n-not-really-a-png", 25), 0);
  doc["images"] = {{{"bufferView", image}, {"mimeType", "image/png"}}};
  doc["textures"] = {{{"source", 0}}};
  doc["materials"] = {{{"name", "red"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}},
                      {{"name", "blue"}, {"extensions", {{"EXT_test_unknown", {{"x", 1}}}}}}};
  doc["nodes"] = {{{"name", "body"}, {"mesh", 0}, {"skin", 0}, {"translation", {1.0, 2.0, 3.0}}},
                  {{"name", "joint"}},
                  {{"name", "root"}, {"children", {1}}}};
  doc["skins"] = {{{"joints", {1}}, {"inverseBindMatrices", inv}}};
  doc["animations"] = {{{"channels", {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "rotation"}}}}}},
                        {"samplers", {{{"input", times}, {"output", rot}, {"interpolation", "LINEAR"}}}}}};
  doc["buffers"] = {{{"byteLength", (bin.size() + 3) / 4 * 4}}};
  s.doc = doc;
  s.glb = make_glb(doc, bin);
  return s;
}

tsm::Status transcode(const std::string& in, bool compress, bool fallback, std::string& out,
                      tsm::GltfTranscodeReport* report = nullptr) {
  tsm::GltfTranscodeOptions o;
  o.compress = compress;
  o.fallback = fallback;
  o.encode.quantization_bits = 12;
  tsm::GltfOutput go;
  tsm::Status s = tsm::transcode_gltf(in, "test.glb", "", o, true, "test.bin", go, report);
  out = go.main;
  return s;
}

bool listed(const json& doc, const char* key, const std::string& name) {
  if (!doc.contains(key)) return false;
  for (const json& e : doc[key])
    if (e == name) return true;
  return false;
}

// Checks one decoded triangle primitive against the source: the JOINTS_0
// numbers map each output vertex to its source vertex.
void check_primitive(const Glb& g, const json& prim, const Source& s, const std::vector<uint32_t>& tris,
                     bool with_target) {
  const json& at = prim["attributes"];
  const std::vector<double> j = accessor_values(g, at["JOINTS_0"]);
  const size_t n = j.size() / 4;
  ASSERT_LE(n, s.vertices) << "the vertices the triangles use";
  std::vector<uint32_t> id(n);
  std::set<uint32_t> seen;
  for (size_t i = 0; i < n; ++i) {
    id[i] = static_cast<uint32_t>(j[4 * i] + 256 * j[4 * i + 1]);
    ASSERT_LT(id[i], s.vertices);
    seen.insert(id[i]);
    EXPECT_EQ(j[4 * i + 3], 1.0);
  }
  ASSERT_EQ(seen.size(), n) << "each source vertex at most once";
  const std::vector<double> p = accessor_values(g, at["POSITION"]), nn = accessor_values(g, at["NORMAL"]),
                            uv = accessor_values(g, at["TEXCOORD_0"]), w = accessor_values(g, at["WEIGHTS_0"]),
                            cu = accessor_values(g, at["_CUSTOM"]), fl = accessor_values(g, at["_FLAG"]);
  EXPECT_EQ(g.doc["accessors"][at["WEIGHTS_0"].get<size_t>()]["componentType"], 5123);
  EXPECT_EQ(g.doc["accessors"][at["WEIGHTS_0"].get<size_t>()]["normalized"], true);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[3 * i + c], s.positions[3 * id[i] + c], 0.51 * s.step);
    double dot = 0;
    for (int c = 0; c < 3; ++c) dot += nn[3 * i + c] * s.normals[3 * id[i] + c];
    EXPECT_GT(dot, 0.999);
    for (int c = 0; c < 2; ++c) EXPECT_NEAR(uv[2 * i + c], s.uvs[2 * id[i] + c], 1e-3);
    double sum = 0;
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(w[4 * i + c] / 65535.0, s.weights[4 * id[i] + c], 1.01 / 65535.0);
      sum += w[4 * i + c];
    }
    EXPECT_EQ(sum, 65535.0) << "weights sum to 1 exactly";
    EXPECT_EQ(cu[i], s.custom[id[i]]) << "float custom attributes are exact";
    EXPECT_EQ(fl[i], id[i] % 3) << "integer custom attributes are exact";
  }
  if (with_target) {
    // The target's grid: the largest power of two not above the position step.
    const double tstep = std::ldexp(1.0, std::ilogb(s.step));
    const std::vector<double> t = accessor_values(g, prim["targets"][0]["POSITION"]);
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(t[3 * i + c], s.target[3 * id[i] + c], 0.5 * tstep) << "morph target";
  }
  // The triangles, as source vertex triples rotated to start at the smallest.
  auto key = [](uint32_t a, uint32_t b, uint32_t c) {
    if (b < a && b < c) return std::make_tuple(b, c, a);
    if (c < a && c < b) return std::make_tuple(c, a, b);
    return std::make_tuple(a, b, c);
  };
  std::multiset<std::tuple<uint32_t, uint32_t, uint32_t>> want, got;
  for (size_t t = 0; t < tris.size(); t += 3) want.insert(key(tris[t], tris[t + 1], tris[t + 2]));
  const std::vector<double> ix = accessor_values(g, prim["indices"]);
  for (size_t t = 0; t + 2 < ix.size(); t += 3)
    got.insert(
        key(id[static_cast<size_t>(ix[t])], id[static_cast<size_t>(ix[t + 1])], id[static_cast<size_t>(ix[t + 2])]));
  EXPECT_EQ(got, want);
}

}  // namespace

TEST(GltfExtension, CompressedGlbDecodesToTheSourceAndKeepsTheDocument) {
  const Source s = make_source();
  std::string packed, plain;
  tsm::GltfTranscodeReport report;
  ASSERT_TRUE(transcode(s.glb, true, false, packed, &report).ok());
  EXPECT_EQ(report.primitives_compressed, 2u);
  EXPECT_EQ(report.primitives_kept, 1u);
  EXPECT_LT(packed.size(), s.glb.size());
  const Glb c = split_glb(packed);
  EXPECT_TRUE(listed(c.doc, "extensionsUsed", "TSM_mesh_compression"));
  EXPECT_TRUE(listed(c.doc, "extensionsRequired", "TSM_mesh_compression"));
  EXPECT_TRUE(listed(c.doc, "extensionsUsed", "EXT_test_unknown"));
  for (int p = 0; p < 2; ++p) {
    const json& prim = c.doc["meshes"][0]["primitives"][p];
    ASSERT_TRUE(prim["extensions"].contains("TSM_mesh_compression"));
    const json& ext = prim["extensions"]["TSM_mesh_compression"];
    EXPECT_FALSE(ext["attributes"].contains("POSITION"));
    EXPECT_TRUE(ext["attributes"].contains("NORMAL"));
    EXPECT_TRUE(ext["attributes"].contains("JOINTS_0"));
    EXPECT_TRUE(ext["attributes"].contains("WEIGHTS_0"));
    EXPECT_FALSE(ext["attributes"].contains("_CUSTOM")) << "float custom attributes stay ordinary accessors";
    EXPECT_EQ(ext.contains("targets"), p == 0) << "the morph target is in the stream";
    EXPECT_FALSE(c.doc["accessors"][prim["indices"].get<size_t>()].contains("bufferView"));
    EXPECT_FALSE(c.doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()].contains("bufferView"));
    EXPECT_TRUE(c.doc["accessors"][prim["attributes"]["_CUSTOM"].get<size_t>()].contains("bufferView"));
    EXPECT_TRUE(c.doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()].contains("min"));
    // The stream is a .tsm file.
    const json& view = c.doc["bufferViews"][ext["bufferView"].get<size_t>()];
    tsm::Mesh m;
    ASSERT_TRUE(
        tsm::decode(c.bin.substr(view.value("byteOffset", size_t(0)), view["byteLength"].get<size_t>()), m).ok());
    // Every accessor of the primitive has the stream's counts (primitive 1
    // keeps only the vertices its triangles use).
    for (const auto& kv : prim["attributes"].items())
      EXPECT_EQ(c.doc["accessors"][kv.value().get<size_t>()]["count"], m.vertex_count()) << kv.key();
    EXPECT_EQ(c.doc["accessors"][prim["indices"].get<size_t>()]["count"], 3 * m.face_count());
    EXPECT_EQ(m.vertex_count() < s.vertices, p == 1);
  }
  EXPECT_FALSE(c.doc["meshes"][0]["primitives"][2].contains("extensions")) << "lines stay uncompressed";
  for (const char* key : {"materials", "nodes", "skins", "animations", "scenes", "textures", "scene"})
    EXPECT_EQ(c.doc[key], s.doc[key]) << key;
  EXPECT_EQ(c.doc["meshes"][0]["primitives"][0]["extras"], s.doc["meshes"][0]["primitives"][0]["extras"]);
  EXPECT_TRUE(contains(c.doc["asset"]["generator"].get<std::string>(), std::string("tsm ") + tsm::version_string()));

  ASSERT_TRUE(transcode(packed, false, false, plain).ok());
  const Glb g = split_glb(plain);
  EXPECT_FALSE(listed(g.doc, "extensionsUsed", "TSM_mesh_compression"));
  EXPECT_FALSE(g.doc.contains("extensionsRequired"));
  for (const char* key : {"materials", "nodes", "skins", "animations", "scenes", "textures"})
    EXPECT_EQ(g.doc[key], s.doc[key]) << key;
  check_primitive(g, g.doc["meshes"][0]["primitives"][0], s, s.tris0, true);
  check_primitive(g, g.doc["meshes"][0]["primitives"][1], s, s.tris1, false);
  // The image's bytes, the skin's and the animation's accessors are kept.
  const json& iv = g.doc["bufferViews"][g.doc["images"][0]["bufferView"].get<size_t>()];
  EXPECT_EQ(g.bin.substr(iv.value("byteOffset", size_t(0)), iv["byteLength"].get<size_t>()),
            std::string("\x89PNG\r\n\x1a\n-not-really-a-png", 25));
  EXPECT_EQ(accessor_values(g, g.doc["animations"][0]["samplers"][0]["output"]).at(5), 0.7071f);
  EXPECT_EQ(accessor_values(g, g.doc["skins"][0]["inverseBindMatrices"]).at(15), 1.0);
}

TEST(GltfExtension, FallbackCopyEqualsTheDecodedValues) {
  const Source s = make_source();
  std::string packed, plain;
  ASSERT_TRUE(transcode(s.glb, true, true, packed).ok());
  const Glb c = split_glb(packed);
  EXPECT_TRUE(listed(c.doc, "extensionsUsed", "TSM_mesh_compression"));
  EXPECT_FALSE(listed(c.doc, "extensionsRequired", "TSM_mesh_compression"));
  ASSERT_TRUE(transcode(packed, false, false, plain).ok());
  const Glb g = split_glb(plain);
  for (int p = 0; p < 2; ++p) {
    const json& cp = c.doc["meshes"][0]["primitives"][p];
    const json& gp = g.doc["meshes"][0]["primitives"][p];
    EXPECT_TRUE(c.doc["accessors"][cp["indices"].get<size_t>()].contains("bufferView"));
    EXPECT_EQ(accessor_values(c, cp["indices"]), accessor_values(g, gp["indices"]));
    for (const auto& kv : cp["attributes"].items())
      EXPECT_EQ(accessor_values(c, kv.value()), accessor_values(g, gp["attributes"][kv.key()])) << kv.key();
  }
  check_primitive(c, c.doc["meshes"][0]["primitives"][0], s, s.tris0, true);
}

// KHR_mesh_quantization stays listed only while a mesh attribute it covers
// has an integer type: here every one is float, so it goes.
TEST(GltfExtension, MeshQuantizationDroppedWhenNothingIsQuantized) {
  const Source s = make_source();
  const Glb src = split_glb(s.glb);
  json doc = src.doc;
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) doc[key].push_back("KHR_mesh_quantization");
  const std::string listed_glb = make_glb(doc, src.bin);
  for (bool compress : {true, false}) {
    std::string out;
    ASSERT_TRUE(transcode(listed_glb, compress, false, out).ok());
    const Glb g = split_glb(out);
    EXPECT_FALSE(listed(g.doc, "extensionsUsed", "KHR_mesh_quantization")) << compress;
    EXPECT_FALSE(listed(g.doc, "extensionsRequired", "KHR_mesh_quantization")) << compress;
    EXPECT_TRUE(listed(g.doc, "extensionsUsed", "EXT_test_unknown")) << "other extensions stay";
  }
}

TEST(GltfExtension, HostileInputGivesErrors) {
  const Source s = make_source();
  // A buffer view past the buffer.
  json doc = s.doc;
  doc["bufferViews"][0]["byteLength"] = 1 << 30;
  Glb g = split_glb(s.glb);
  std::string out;
  tsm::Status st = transcode(make_glb(doc, g.bin), true, false, out);
  EXPECT_FALSE(st.ok());
  EXPECT_TRUE(contains(st.message(), "bufferViews[0]")) << st.message();
  // An accessor naming a view that does not exist.
  doc = s.doc;
  doc["accessors"][0]["bufferView"] = 999;
  st = transcode(make_glb(doc, g.bin), true, false, out);
  EXPECT_TRUE(contains(st.message(), "accessors[0].bufferView")) << st.message();
  // A broken tsm stream inside the extension.
  std::string packed;
  ASSERT_TRUE(transcode(s.glb, true, false, packed).ok());
  Glb c = split_glb(packed);
  const json& view =
      c.doc["bufferViews"]
           [c.doc["meshes"][0]["primitives"][0]["extensions"]["TSM_mesh_compression"]["bufferView"].get<size_t>()];
  const size_t at = view.value("byteOffset", size_t(0)), len = view["byteLength"];
  for (size_t k = at + len / 3; k < at + len / 3 + 16; ++k) c.bin[k] ^= 0x5A;
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_FALSE(st.ok());
  EXPECT_TRUE(contains(st.message(), "TSM_mesh_compression")) << st.message();
  // The stream's attribute list does not fit the map.
  c = split_glb(packed);
  c.doc["meshes"][0]["primitives"][0]["extensions"]["TSM_mesh_compression"]["attributes"]["NORMAL"] = 40;
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_TRUE(contains(st.message(), "attributes.NORMAL")) << st.message();
  // Truncated container, JSON nested too deep.
  EXPECT_FALSE(transcode(s.glb.substr(0, s.glb.size() / 2), true, false, out).ok());
  std::string deep =
      "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(5000, '[') + std::string(5000, ']') + "}";
  st = transcode(deep, true, false, out);
  EXPECT_TRUE(contains(st.message(), "nested")) << st.message();
}

namespace {

// A sphere in four triangle primitives: three (in two meshes, each with its
// own material) name the same accessors (POSITION, NORMAL, _ID numbering the
// vertices, indices and a morph target of POSITION and NORMAL displacements
// on their grids, mostly zero), the fourth the same POSITION with half the
// triangles.
struct SharedSource {
  std::string glb;
  json doc;
  size_t vertices = 0;
  std::vector<float> positions, target_p, target_n;
  std::vector<uint32_t> tris, half;
  double step = 0;         // position step at -q 12
  double target_step = 0;  // the largest power of two not above it
};

SharedSource make_shared_source(bool with_target, bool zero_target = false) {
  SharedSource s;
  const tsm::Mesh sphere = tsm_test::icosphere(3);
  s.vertices = sphere.vertex_count();
  s.positions = sphere.positions;
  s.step = tsm::bounding_box(sphere).largest_extent() / 4095.0;
  s.target_step = std::ldexp(1.0, std::ilogb(s.step));
  const double normal_step = std::ldexp(1.0, -10);  // the default normal bits
  std::vector<float> normals;
  std::string ids;
  for (size_t i = 0; i < s.vertices; ++i) {
    const float* p = &s.positions[3 * i];
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int c = 0; c < 3; ++c) normals.push_back(p[c] / len);
    ids += {char(i & 0xFF), char(i >> 8)};
    const bool moves = !zero_target && p[1] > 0.8f * len;  // the top cap moves up and tilts
    s.target_p.insert(s.target_p.end(), {0.0f, moves ? static_cast<float>(s.target_step * double(37 + i % 5)) : 0.0f,
                                         moves ? static_cast<float>(-s.target_step * 3.0) : 0.0f});
    s.target_n.insert(s.target_n.end(), {moves ? static_cast<float>(normal_step * 12.0) : 0.0f, 0.0f, 0.0f});
  }
  for (size_t f = 0; f < sphere.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      s.tris.push_back(sphere.face(f)[k]);
      if (f % 2 == 0) s.half.push_back(sphere.face(f)[k]);
    }
  json doc = {{"asset", {{"version", "2.0"}}},   {"scene", 0},
              {"scenes", {{{"nodes", {0, 1}}}}}, {"nodes", {{{"mesh", 0}}, {{"mesh", 1}}}},
              {"accessors", json::array()},      {"bufferViews", json::array()}};
  std::string bin;
  const size_t pos = add_positions(doc, bin, s.positions, s.vertices);
  const size_t nor = add_accessor(doc, bin, floats(normals), 5126, "VEC3", s.vertices, 34962);
  const size_t id = add_accessor(doc, bin, ids, 5123, "SCALAR", s.vertices, 34962);
  auto indices = [&](const std::vector<uint32_t>& t) {
    std::string b;
    for (uint32_t i : t) b += {char(i & 0xFF), char(i >> 8)};
    return add_accessor(doc, bin, b, 5123, "SCALAR", t.size(), 34963);
  };
  const size_t all = indices(s.tris), half = indices(s.half);
  json shared = {{"attributes", {{"POSITION", pos}, {"NORMAL", nor}, {"_ID", id}}}, {"indices", all}};
  if (with_target) {
    const size_t tp = add_accessor(doc, bin, floats(s.target_p), 5126, "VEC3", s.vertices, 34962);
    std::vector<float> tmin(3, 1e9f), tmax(3, -1e9f);
    for (size_t i = 0; i < s.target_p.size(); ++i) {
      tmin[i % 3] = std::min(tmin[i % 3], s.target_p[i]);
      tmax[i % 3] = std::max(tmax[i % 3], s.target_p[i]);
    }
    doc["accessors"][tp]["min"] = tmin;
    doc["accessors"][tp]["max"] = tmax;
    const size_t tn = add_accessor(doc, bin, floats(s.target_n), 5126, "VEC3", s.vertices, 34962);
    shared["targets"] = {{{"POSITION", tp}, {"NORMAL", tn}}};
  }
  auto with_material = [&](int m) {
    json p = shared;
    p["material"] = m;
    return p;
  };
  json other = {{"attributes", {{"POSITION", pos}, {"_ID", id}}}, {"indices", half}};
  doc["meshes"] = json::array();
  doc["meshes"].push_back({{"primitives", {with_material(0), with_material(1)}}});
  doc["meshes"].push_back({{"primitives", {with_material(2), other}}});
  doc["materials"] = {{{"name", "a"}}, {{"name", "b"}}, {{"name", "c"}}};
  doc["buffers"] = {{{"byteLength", (bin.size() + 3) / 4 * 4}}};
  s.doc = doc;
  s.glb = make_glb(doc, bin);
  return s;
}

const json& prim_at(const Glb& g, int mesh, int p) { return g.doc["meshes"][mesh]["primitives"][p]; }

std::string stream_of(const Glb& g, const json& prim) {
  const json& view = g.doc["bufferViews"][prim["extensions"]["TSM_mesh_compression"]["bufferView"].get<size_t>()];
  return g.bin.substr(view.value("byteOffset", size_t(0)), view["byteLength"].get<size_t>());
}

// The decoded primitive's _ID numbers (source vertex of each output vertex).
std::vector<uint32_t> ids_of(const Glb& g, const json& prim) {
  std::vector<uint32_t> out;
  for (double v : accessor_values(g, prim["attributes"]["_ID"])) out.push_back(static_cast<uint32_t>(v));
  return out;
}

}  // namespace

TEST(GltfExtension, SharedPrimitivesAreCodedOnceAndDecodedExactly) {
  const SharedSource s = make_shared_source(true);
  std::string packed, plain;
  tsm::GltfTranscodeReport report;
  ASSERT_TRUE(transcode(s.glb, true, false, packed, &report).ok());
  EXPECT_EQ(report.primitives_compressed, 4u);
  EXPECT_EQ(report.primitives_shared, 2u);
  EXPECT_EQ(report.vertices, s.vertices + std::set<uint32_t>(s.half.begin(), s.half.end()).size())
      << "the shared stream counted once";
  const Glb c = split_glb(packed);
  const json& first = prim_at(c, 0, 0);
  for (const auto& [m, p] : {std::pair<int, int>{0, 1}, {1, 0}}) {
    const json& other = prim_at(c, m, p);
    for (const char* key : {"attributes", "indices", "targets"}) EXPECT_EQ(other[key], first[key]) << key;
    EXPECT_EQ(other["extensions"], first["extensions"]) << "one stream";
    EXPECT_EQ(other["material"], m == 0 ? 1 : 2) << "the rest of the primitive is its own";
  }
  EXPECT_NE(prim_at(c, 1, 1)["extensions"]["TSM_mesh_compression"]["bufferView"],
            first["extensions"]["TSM_mesh_compression"]["bufferView"]);
  size_t streams = 0;
  std::set<size_t> views;
  for (int m = 0; m < 2; ++m)
    for (const json& p : c.doc["meshes"][m]["primitives"])
      views.insert(p["extensions"]["TSM_mesh_compression"]["bufferView"].get<size_t>());
  for (size_t v : views) streams += c.doc["bufferViews"][v]["byteLength"].get<size_t>();
  EXPECT_EQ(views.size(), 2u);
  EXPECT_EQ(report.stream_bytes, streams);

  ASSERT_TRUE(transcode(packed, false, false, plain).ok());
  const Glb g = split_glb(plain);
  const json& d0 = prim_at(g, 0, 0);
  for (const auto& [m, p] : {std::pair<int, int>{0, 1}, {1, 0}}) {
    EXPECT_EQ(prim_at(g, m, p)["attributes"], d0["attributes"]) << "the decoded glTF shares the accessors again";
    EXPECT_EQ(prim_at(g, m, p)["indices"], d0["indices"]);
    EXPECT_EQ(prim_at(g, m, p)["targets"], d0["targets"]);
    EXPECT_FALSE(prim_at(g, m, p).contains("extensions"));
  }
  // The shared data against the source: every vertex once, positions within
  // half a step, the triangles as given.
  const std::vector<uint32_t> id = ids_of(g, d0);
  ASSERT_EQ(id.size(), s.vertices);
  EXPECT_EQ(std::set<uint32_t>(id.begin(), id.end()).size(), s.vertices);
  const std::vector<double> pos = accessor_values(g, d0["attributes"]["POSITION"]);
  for (size_t i = 0; i < id.size(); ++i)
    for (int c3 = 0; c3 < 3; ++c3) EXPECT_NEAR(pos[3 * i + c3], s.positions[3 * id[i] + c3], 0.51 * s.step);
  std::multiset<std::vector<uint32_t>> want, got;
  auto rotated = [](uint32_t a, uint32_t b, uint32_t c3) {
    std::vector<uint32_t> t = {a, b, c3};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  for (size_t t = 0; t < s.tris.size(); t += 3) want.insert(rotated(s.tris[t], s.tris[t + 1], s.tris[t + 2]));
  const std::vector<double> ix = accessor_values(g, d0["indices"]);
  for (size_t t = 0; t + 2 < ix.size(); t += 3)
    got.insert(rotated(id[static_cast<size_t>(ix[t])], id[static_cast<size_t>(ix[t + 1])],
                       id[static_cast<size_t>(ix[t + 2])]));
  EXPECT_EQ(got, want);
}

TEST(GltfExtension, MorphTargetsRoundTripExactlyOnTheirGrid) {
  const SharedSource s = make_shared_source(true);
  std::string packed, plain, again;
  ASSERT_TRUE(transcode(s.glb, true, false, packed).ok());
  const Glb c = split_glb(packed);
  const json& prim = prim_at(c, 0, 0);
  const json& ext = prim["extensions"]["TSM_mesh_compression"];
  ASSERT_TRUE(ext.contains("targets"));
  ASSERT_EQ(ext["targets"].size(), 1u);
  EXPECT_TRUE(ext["targets"][0].contains("POSITION"));
  EXPECT_TRUE(ext["targets"][0].contains("NORMAL"));
  EXPECT_EQ(ext["targetSteps"]["POSITION"].get<double>(), s.target_step);
  EXPECT_EQ(ext["targetSteps"]["NORMAL"].get<double>(), std::ldexp(1.0, -10));
  for (const char* sem : {"POSITION", "NORMAL"})
    EXPECT_FALSE(c.doc["accessors"][prim["targets"][0][sem].get<size_t>()].contains("bufferView"))
        << sem << " is in the stream";
  EXPECT_TRUE(c.doc["accessors"][prim["targets"][0]["POSITION"].get<size_t>()].contains("min"));

  ASSERT_TRUE(transcode(packed, false, false, plain).ok());
  const Glb g = split_glb(plain);
  const json& d0 = prim_at(g, 0, 0);
  const std::vector<uint32_t> id = ids_of(g, d0);
  const std::vector<double> tp = accessor_values(g, d0["targets"][0]["POSITION"]),
                            tn = accessor_values(g, d0["targets"][0]["NORMAL"]);
  ASSERT_EQ(tp.size(), 3 * id.size());
  size_t moved = 0;
  for (size_t i = 0; i < id.size(); ++i) {
    for (int c3 = 0; c3 < 3; ++c3) {
      EXPECT_EQ(tp[3 * i + c3], s.target_p[3 * id[i] + c3]) << "on the grid: exact";
      EXPECT_EQ(tn[3 * i + c3], s.target_n[3 * id[i] + c3]) << "on the grid: exact";
    }
    moved += s.target_p[3 * id[i] + 1] != 0.0f;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_LT(moved, id.size() / 4);
  const json& tacc = g.doc["accessors"][d0["targets"][0]["POSITION"].get<size_t>()];
  EXPECT_EQ(tacc["min"][0], 0.0);
  EXPECT_EQ(tacc["max"][1].get<double>(), static_cast<float>(s.target_step * 41.0));

  // Canonical: the decoded glTF compresses to the same streams.
  ASSERT_TRUE(transcode(plain, true, false, again).ok());
  const Glb a = split_glb(again);
  EXPECT_EQ(stream_of(a, prim_at(a, 0, 0)), stream_of(c, prim));
  EXPECT_EQ(stream_of(a, prim_at(a, 1, 1)), stream_of(c, prim_at(c, 1, 1)));
}

// Displacements that are all zero (the common case: a target moves part of
// a mesh) cost a few bytes, not a value per vertex.
TEST(GltfExtension, ZeroMorphTargetCostsAlmostNothing) {
  std::string with, without, zero;
  ASSERT_TRUE(transcode(make_shared_source(false).glb, true, false, without).ok());
  ASSERT_TRUE(transcode(make_shared_source(true, true).glb, true, false, zero).ok());
  const Glb a = split_glb(without), b = split_glb(zero);
  const size_t base = stream_of(a, prim_at(a, 0, 0)).size(), more = stream_of(b, prim_at(b, 0, 0)).size();
  EXPECT_LT(more, base + 40) << base << " -> " << more << " bytes for " << make_shared_source(false).vertices
                             << " vertices";
}

TEST(GltfExtension, SharedStreamNamingOtherAccessorsIsRefused) {
  const SharedSource s = make_shared_source(true);
  std::string packed, out;
  ASSERT_TRUE(transcode(s.glb, true, false, packed).ok());
  // The second primitive names the shared stream with the fourth one's indices.
  Glb c = split_glb(packed);
  c.doc["meshes"][0]["primitives"][1]["indices"] = c.doc["meshes"][1]["primitives"][1]["indices"];
  tsm::Status st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_FALSE(st.ok());
  EXPECT_TRUE(contains(st.message(), "meshes[0].primitives[1].extensions.TSM_mesh_compression")) << st.message();
  EXPECT_TRUE(contains(st.message(), "is the stream of meshes[0].primitives[0]")) << st.message();
  // The fourth primitive names the shared stream.
  c = split_glb(packed);
  c.doc["meshes"][1]["primitives"][1]["extensions"] = c.doc["meshes"][0]["primitives"][0]["extensions"];
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_TRUE(contains(st.message(), "names other accessors")) << st.message();
  // Broken target maps.
  c = split_glb(packed);
  for (int m = 0; m < 2; ++m)
    for (json& p : c.doc["meshes"][m]["primitives"])
      if (p["extensions"]["TSM_mesh_compression"].contains("targetSteps"))
        p["extensions"]["TSM_mesh_compression"]["targetSteps"]["POSITION"] = -1.0;
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_TRUE(contains(st.message(), "targetSteps.POSITION")) << st.message();
  c = split_glb(packed);
  for (int m = 0; m < 2; ++m)
    for (json& p : c.doc["meshes"][m]["primitives"])
      if (p["extensions"]["TSM_mesh_compression"].contains("targets"))
        p["extensions"]["TSM_mesh_compression"]["targets"][0]["POSITION"] = 99;
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_TRUE(contains(st.message(), "targets[0].POSITION is not an index")) << st.message();
  c = split_glb(packed);
  for (int m = 0; m < 2; ++m)
    for (json& p : c.doc["meshes"][m]["primitives"])
      if (p["extensions"]["TSM_mesh_compression"].contains("targets"))
        p["extensions"]["TSM_mesh_compression"]["targets"][0]["NORMAL"] =
            p["extensions"]["TSM_mesh_compression"]["attributes"]["_ID"];
  st = transcode(make_glb(c.doc, c.bin), false, false, out);
  EXPECT_TRUE(contains(st.message(), "does not fit")) << st.message();
  // Random damage to the JSON and the streams: an answer every time, with a
  // message when it is a refusal, never an internal error.
  uint32_t rng = 12345;
  auto next = [&rng] {
    rng = rng * 1664525u + 1013904223u;
    return rng >> 8;
  };
  for (int trial = 0; trial < 300; ++trial) {
    std::string damaged = packed;
    for (int k = 0; k < 1 + trial % 4; ++k) damaged[20 + next() % (damaged.size() - 20)] = static_cast<char>(next());
    st = transcode(damaged, false, false, out);
    EXPECT_TRUE(st.ok() || !st.message().empty()) << trial;
    EXPECT_NE(st.code(), tsm::ErrorCode::internal) << trial << ": " << st.message();
  }
}

// `tsm bench DIR` benches the glTF files in a folder and below it (as for
// /usr/share/assimp/models/glTF2), and a document whose nodes form a cycle
// (invalid glTF; Draco's reader, run in the bench's process, recursed on it
// until the stack overflowed) is measured without taking the bench down.
TEST(GltfExtension, BenchTakesAFolderOfAssets) {
  const fs::path dir = fs::temp_directory_path() / ("tsm_gltf_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir / "sub");
  ASSERT_TRUE(tsm::write_mesh((dir / "sub" / "ball.glb").string(), tsm_test::icosphere(2)).ok());
  {
    std::ofstream(dir / "cycle.gltf") << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)"
                                      << R"("nodes":[{"children":[1]},{"children":[0]}]})";
  }
  { std::ofstream(dir / "notes.txt") << "not a mesh"; }
  const std::string cmd =
      std::string("'") + TSM_CLI_PATH + "' bench '" + dir.string() + "' --runs 1 -q 8 --json --quiet 2>/dev/null";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int status = ::pclose(p);
  ASSERT_TRUE(WIFEXITED(status)) << "the bench crashed: " << out;
  const json doc = json::parse(out, nullptr, false);
  ASSERT_TRUE(doc.is_object()) << out;
  std::vector<std::string> names;
  for (const json& row : doc["assets"]) names.push_back(row["asset"]);
  EXPECT_EQ(names, (std::vector<std::string>{"cycle.gltf", "ball.glb"})) << out;
  ASSERT_EQ(doc["assets"].size(), 2u);
  EXPECT_TRUE(doc["assets"][1]["tsm"]["ok"].get<bool>()) << out;
  fs::remove_all(dir);
}

TEST(GltfExtension, ExternalFilesStayInTheFolder) {
  const fs::path dir = fs::temp_directory_path() / ("tsm_gltf_ext_" + std::to_string(::getpid()));
  fs::create_directories(dir / "in");
  { std::ofstream(dir / "secret.bin", std::ios::binary) << std::string(64, 'x'); }
  json doc = {{"asset", {{"version", "2.0"}}}, {"buffers", {{{"uri", "../secret.bin"}, {"byteLength", 64}}}}};
  tsm::GltfOutput out;
  tsm::Status st = tsm::transcode_gltf(doc.dump(), "in.gltf", (dir / "in").string(), {}, true, "x.bin", out);
  EXPECT_FALSE(st.ok());
  EXPECT_TRUE(contains(st.message(), "'..'")) << st.message();
  doc["buffers"][0]["uri"] = (dir / "secret.bin").string();
  st = tsm::transcode_gltf(doc.dump(), "in.gltf", (dir / "in").string(), {}, true, "x.bin", out);
  EXPECT_TRUE(contains(st.message(), "absolute")) << st.message();
  // An image outside the folder is neither embedded nor copied.
  doc = {{"asset", {{"version", "2.0"}}}, {"images", {{{"uri", "../secret.png"}}}}};
  std::ofstream(dir / "secret.png", std::ios::binary) << "png";
  tsm::GltfTranscodeReport report;
  ASSERT_TRUE(tsm::transcode_gltf(doc.dump(), "in.gltf", (dir / "in").string(), {}, true, "x.bin", out, &report).ok());
  EXPECT_EQ(split_glb(out.main).doc["images"][0]["uri"], "../secret.png");
  EXPECT_TRUE(contains(report.notes, "'..'")) << report.notes;
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------
// Corpus: real assets, Draco and meshopt input

namespace {

// Triangles and vertices per primitive of a plain glTF file's meshes.
std::vector<std::pair<size_t, size_t>> primitive_counts(const Glb& g) {
  std::vector<std::pair<size_t, size_t>> out;
  for (const json& m : g.doc["meshes"])
    for (const json& p : m["primitives"]) {
      const size_t v = g.doc["accessors"][p["attributes"]["POSITION"].get<size_t>()]["count"];
      const size_t t =
          p.contains("indices") ? g.doc["accessors"][p["indices"].get<size_t>()]["count"].get<size_t>() : v;
      out.emplace_back(v, t);
    }
  return out;
}

// Same triangle counts; no more vertices (a primitive keeps the vertices
// its triangles use).
void expect_same_primitives(const std::vector<std::pair<size_t, size_t>>& in,
                            const std::vector<std::pair<size_t, size_t>>& out) {
  ASSERT_EQ(in.size(), out.size());
  for (size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(in[i].second, out[i].second) << "primitive " << i;
    EXPECT_LE(out[i].first, in[i].first) << "primitive " << i;
    EXPECT_GT(out[i].first, 0u) << "primitive " << i;
  }
}

tsm::Status transcode_file(const std::string& in, const fs::path& out, bool compress, bool fallback = false) {
  tsm::GltfTranscodeOptions o;
  o.compress = compress;
  o.fallback = fallback;
  o.encode.quantization_bits = 14;
  return tsm::transcode_gltf_file(in, out.string(), o);
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

}  // namespace

TEST(GltfExtensionCorpus, AssetsRoundTripWithTheirCounts) {
  TSM_REQUIRE_CORPUS();
  const fs::path tmp = fs::temp_directory_path() / ("tsm_gltf_assets_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  // The two engines (55,843 vertices each) only in the plain build: under
  // the sanitizers they took two minutes and reach no code the others miss.
  std::vector<const char*> assets = {"assets/Fox/Fox.gltf", "assets/CesiumMilkTruck/CesiumMilkTruck.gltf",
                                     "assets/MultiUVTest/MultiUVTest.gltf",
                                     "assets/VertexColorTest/VertexColorTest.gltf", "assets/Box_Draco.glb"};
  if (!tsm_test::kSanitized)
    assets.insert(assets.end(), {"assets/2CylinderEngine.glb", "assets/2CylinderEngine_Draco/2CylinderEngine.gltf"});
  for (const char* rel : assets) {
    SCOPED_TRACE(rel);
    const std::string in = tsm_test::corpus_file(rel);
    ASSERT_TRUE(transcode_file(in, tmp / "plain_in.glb", false).ok());
    tsm::Status st = transcode_file(in, tmp / "packed.glb", true);
    ASSERT_TRUE(st.ok()) << st.message();
    ASSERT_TRUE(transcode_file((tmp / "packed.glb").string(), tmp / "plain_out.glb", false).ok());
    const Glb a = split_glb(slurp(tmp / "plain_in.glb")), b = split_glb(slurp(tmp / "plain_out.glb"));
    const Glb p = split_glb(slurp(tmp / "packed.glb"));
    EXPECT_TRUE(listed(p.doc, "extensionsRequired", "TSM_mesh_compression"));
    expect_same_primitives(primitive_counts(a), primitive_counts(b));
    for (const char* key : {"nodes", "materials", "skins", "animations", "textures", "scenes"})
      EXPECT_EQ(a.doc.value(key, json()), b.doc.value(key, json())) << key;
    EXPECT_EQ(a.doc.value("images", json()).size(), b.doc.value("images", json()).size());
    // .gltf output: a .bin beside it.
    ASSERT_TRUE(transcode_file(in, tmp / "packed.gltf", true, true).ok());
    EXPECT_TRUE(fs::is_regular_file(tmp / "packed.bin"));
  }
  fs::remove_all(tmp);
}

TEST(GltfExtensionCorpus, MeshoptInputFromGltfpackTranscodes) {
  TSM_REQUIRE_CORPUS();
  if (std::system("command -v gltfpack >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "gltfpack not installed (Debian package gltfpack, scripts/setup.sh)";
  const fs::path tmp = fs::temp_directory_path() / ("tsm_gltf_meshopt_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const std::string in = tsm_test::corpus_file("assets/CesiumMilkTruck/CesiumMilkTruck.gltf");
  const std::string cmd = "gltfpack -cc -i '" + in + "' -o '" + (tmp / "mo.glb").string() + "' >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const Glb mo = split_glb(slurp(tmp / "mo.glb"));
  ASSERT_TRUE(listed(mo.doc, "extensionsRequired", "EXT_meshopt_compression"));
  ASSERT_TRUE(transcode_file((tmp / "mo.glb").string(), tmp / "plain_in.glb", false).ok());
  tsm::Status st = transcode_file((tmp / "mo.glb").string(), tmp / "packed.glb", true);
  ASSERT_TRUE(st.ok()) << st.message();
  ASSERT_TRUE(transcode_file((tmp / "packed.glb").string(), tmp / "plain_out.glb", false).ok());
  const Glb a = split_glb(slurp(tmp / "plain_in.glb")), b = split_glb(slurp(tmp / "plain_out.glb"));
  EXPECT_FALSE(listed(a.doc, "extensionsUsed", "EXT_meshopt_compression"));
  for (const json& v : a.doc["bufferViews"]) EXPECT_FALSE(v.contains("extensions")) << v.dump();
  expect_same_primitives(primitive_counts(a), primitive_counts(b));
  EXPECT_FALSE(primitive_counts(a).empty());
  fs::remove_all(tmp);
}

TEST(GltfExtensionCorpus, CompressedGltfEncodesToTsmThroughTheTool) {
  TSM_REQUIRE_CORPUS();
  const fs::path tmp = fs::temp_directory_path() / ("tsm_gltf_cli_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const std::string in = tsm_test::corpus_file("assets/2CylinderEngine_Draco/2CylinderEngine.gltf");
  const std::string cmd = std::string("'") + TSM_CLI_PATH + "' encode '" + in + "' -o '" + (tmp / "d.tsm").string() +
                          "' --quiet 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  tsm::Mesh m;
  ASSERT_TRUE(tsm::decode(slurp(tmp / "d.tsm"), m).ok());
  ASSERT_TRUE(transcode_file(in, tmp / "plain.glb", false).ok());
  size_t triangles = 0;
  for (const auto& vt : primitive_counts(split_glb(slurp(tmp / "plain.glb")))) triangles += vt.second / 3;
  EXPECT_EQ(m.face_count(), triangles);
  fs::remove_all(tmp);
}
