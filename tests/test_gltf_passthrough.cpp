// glTF pass-through (libio/src/io_gltf.cpp, Mesh::metadata "gltf"): a
// document with several meshes and primitives, materials, a node tree with
// transforms and an instanced mesh, textures, samplers, images (bytes in a
// buffer view, a data URI, an external URI), a camera, an animation, a skin,
// a morph target, a mesh outside the scene, extensions and extras comes back
// from read_gltf -> write_gltf, and through tsm::encode / tsm::decode and the
// command-line tool, with all of that unchanged and the geometry of every
// primitive equal up to quantization and vertex / face order.
//
// The documents are built and inspected here with nlohmann-json, not with
// the library's tinygltf, so the checks do not share the code under test.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "base64.hpp"
#include "test_util.hpp"
#include "tsm/compare.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {

using json = nlohmann::ordered_json;
using tsm::Mesh;
using tsm::ReadInfo;
using tsm::Status;
using tsm_test::contains;

// ---------------------------------------------------------------------------
// GLB / .gltf containers (test side)

std::string b64_decode(const std::string& in) {
  std::string out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : in) {
    int v;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    else if (c >= '0' && c <= '9') v = c - '0' + 52;
    else if (c == '+') v = 62;
    else if (c == '/') v = 63;
    else break;
    acc = acc << 6 | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((acc >> bits) & 0xFF);
    }
  }
  return out;
}

uint32_t u32_at(const std::string& s, size_t at) {
  uint32_t v;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

void put_u32(std::string& s, uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  s.append(b, 4);
}

// A glTF document and its (single) binary buffer.
struct Doc {
  json doc;
  std::string bin;
};

std::string to_glb(const Doc& d) {
  std::string j = d.doc.dump();
  while (j.size() % 4) j += ' ';
  std::string bin = d.bin;
  while (bin.size() % 4) bin += '\0';
  std::string out = "glTF";
  put_u32(out, 2);
  put_u32(out, static_cast<uint32_t>(12 + 8 + j.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put_u32(out, static_cast<uint32_t>(j.size()));
  put_u32(out, 0x4E4F534A);
  out += j;
  if (!bin.empty()) {
    put_u32(out, static_cast<uint32_t>(bin.size()));
    put_u32(out, 0x004E4942);
    out += bin;
  }
  return out;
}

// Parses GLB or .gltf text (data-URI buffer) written by the library.
::testing::AssertionResult parse_output(const std::string& bytes, Doc& d) {
  try {
    if (bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0) {
      if (bytes.size() < 20 || u32_at(bytes, 8) != bytes.size())
        return ::testing::AssertionFailure() << "bad GLB header";
      const uint32_t jl = u32_at(bytes, 12);
      if (u32_at(bytes, 16) != 0x4E4F534A || 20 + static_cast<size_t>(jl) > bytes.size())
        return ::testing::AssertionFailure() << "bad JSON chunk";
      d.doc = json::parse(bytes.substr(20, jl));
      d.bin.clear();
      const size_t at = 20 + jl;
      if (at < bytes.size()) {
        const uint32_t bl = u32_at(bytes, at);
        if (u32_at(bytes, at + 4) != 0x004E4942 || at + 8 + bl != bytes.size())
          return ::testing::AssertionFailure() << "bad BIN chunk";
        d.bin = bytes.substr(at + 8, bl);
      }
    } else {
      d.doc = json::parse(bytes);
      d.bin.clear();
      if (d.doc.contains("buffers")) {
        if (d.doc["buffers"].size() != 1) return ::testing::AssertionFailure() << "not one buffer";
        const std::string uri = d.doc["buffers"][0]["uri"].get<std::string>();
        const std::string prefix = "data:application/octet-stream;base64,";
        if (uri.compare(0, prefix.size(), prefix) != 0) return ::testing::AssertionFailure() << "not a data URI";
        d.bin = b64_decode(uri.substr(prefix.size()));
      }
    }
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "JSON: " << e.what();
  }
  if (d.doc.contains("buffers") && d.doc["buffers"][0]["byteLength"].get<size_t>() != d.bin.size())
    return ::testing::AssertionFailure() << "buffer byteLength " << d.doc["buffers"][0]["byteLength"] << " vs "
                                         << d.bin.size();
  return ::testing::AssertionSuccess();
}

// ---------------------------------------------------------------------------
// Building the test document

size_t add_view(Doc& d, const std::string& bytes, int target = 0) {
  while (d.bin.size() % 4) d.bin += '\0';
  json v = {{"buffer", 0}, {"byteOffset", d.bin.size()}, {"byteLength", bytes.size()}};
  if (target) v["target"] = target;
  d.bin += bytes;
  d.doc["bufferViews"].push_back(v);
  return d.doc["bufferViews"].size() - 1;
}

template <typename T>
std::string raw(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

size_t add_accessor(Doc& d, const std::string& bytes, int ct, size_t count, const char* type, int target = 0,
                    json extra = json::object()) {
  json a = {{"bufferView", add_view(d, bytes, target)}, {"componentType", ct}, {"count", count}, {"type", type}};
  for (auto& kv : extra.items()) a[kv.key()] = kv.value();
  d.doc["accessors"].push_back(a);
  return d.doc["accessors"].size() - 1;
}

size_t add_positions(Doc& d, const std::vector<float>& p, const std::string& name = "") {
  json extra = json::object();
  std::array<float, 3> lo = {p[0], p[1], p[2]}, hi = lo;
  for (size_t i = 0; i < p.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], p[i]);
    hi[i % 3] = std::max(hi[i % 3], p[i]);
  }
  extra["min"] = lo;
  extra["max"] = hi;
  if (!name.empty()) extra["name"] = name;
  return add_accessor(d, raw(p), 5126, p.size() / 3, "VEC3", 34962, extra);
}

const std::string& png_bytes() {
  static const std::string s = [] {
    std::string b = "\x89PNG\r\n\x1a\n";
    std::mt19937 rng(5);
    for (int i = 0; i < 199; ++i) b += static_cast<char>(rng() & 0xFF);  // 207 bytes: an odd length
    return b;
  }();
  return s;
}
const std::string kDataUriImage = "data:image/png;base64," + tsm_test::base64(std::string("\x89PNG\r\n\x1a\nsmall", 13));

// Two meshes in the scene (the body: two primitives with two materials
// sharing one vertex set; the wheel: a triangle fan with colours and a morph
// target, used by two nodes), a third mesh outside the scene, and all the
// rest of a scene file.
Doc test_document() {
  Doc d;
  json& j = d.doc;
  j["asset"] = {{"version", "2.0"}, {"generator", "tsm pass-through test"}, {"copyright", "none"},
                {"extras", {{"k", {1, 2, 3}}}}};
  j["extensionsUsed"] = {"KHR_materials_emissive_strength", "EXT_tsm_test"};
  j["extensions"] = {{"EXT_tsm_test", {{"answer", 42}}}};
  j["extras"] = {{"project", "pass-through"}, {"pi", 3.141592653589793}};
  j["scene"] = 0;
  j["scenes"] = json::array({{{"name", "main"}, {"nodes", {0}}}});
  j["bufferViews"] = json::array();
  j["accessors"] = json::array();

  // Body: a 4 x 4 grid with normals and texture coordinates; triangles 0..9
  // are primitive 0 (u16 indices), 10..17 primitive 1 (u8 indices).
  std::vector<float> pos, nrm, uv;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const float z = 0.25f * std::sin(static_cast<float>(x + 2 * y));
      pos.insert(pos.end(), {static_cast<float>(x) * 0.7f, static_cast<float>(y) * 0.45f, z});
      const float nx = 0.1f * static_cast<float>(x), ny = -0.2f * static_cast<float>(y), len = std::sqrt(nx * nx + ny * ny + 1);
      nrm.insert(nrm.end(), {nx / len, ny / len, 1 / len});
      uv.insert(uv.end(), {static_cast<float>(x) / 3.0f, 1.0f - static_cast<float>(y) / 3.0f});
    }
  std::vector<uint16_t> tris;
  for (uint16_t y = 0; y < 3; ++y)
    for (uint16_t x = 0; x < 3; ++x) {
      const uint16_t v = static_cast<uint16_t>(4 * y + x);
      tris.insert(tris.end(), {v, static_cast<uint16_t>(v + 1), static_cast<uint16_t>(v + 4)});
      tris.insert(tris.end(), {static_cast<uint16_t>(v + 1), static_cast<uint16_t>(v + 5), static_cast<uint16_t>(v + 4)});
    }
  const size_t body_pos = add_positions(d, pos, "body positions");
  const size_t body_nrm = add_accessor(d, raw(nrm), 5126, 16, "VEC3", 34962);
  const size_t body_uv = add_accessor(d, raw(uv), 5126, 16, "VEC2", 34962);
  const size_t body_i0 = add_accessor(d, raw(std::vector<uint16_t>(tris.begin(), tris.begin() + 30)), 5123, 30,
                                      "SCALAR", 34963, {{"name", "body indices A"}});
  std::vector<uint8_t> tail(tris.begin() + 30, tris.end());
  const size_t body_i1 = add_accessor(d, raw(tail), 5121, tail.size(), "SCALAR", 34963);

  // Wheel: a hexagon fan (centre + 6), RGBA u8 colours, one morph target.
  std::vector<float> wpos = {0, 0, 0};
  std::vector<uint8_t> wcol = {255, 255, 255, 255};
  std::vector<float> wdisp = {0, 0, 0.5f};
  for (int k = 0; k < 6; ++k) {
    const double a = k * 3.14159265358979 / 3;
    wpos.insert(wpos.end(), {static_cast<float>(0.3 * std::cos(a)), static_cast<float>(0.3 * std::sin(a)), 0.0f});
    wcol.insert(wcol.end(), {static_cast<uint8_t>(40 * k), 10, static_cast<uint8_t>(250 - 30 * k), 200});
    wdisp.insert(wdisp.end(), {0.01f * static_cast<float>(k), 0.0f, -0.125f});
  }
  const size_t wheel_pos = add_positions(d, wpos);
  const size_t wheel_col =
      add_accessor(d, raw(wcol), 5121, 7, "VEC4", 34962, {{"normalized", true}, {"name", "wheel colours"}});
  std::array<float, 3> dlo = {wdisp[0], wdisp[1], wdisp[2]}, dhi = dlo;
  for (size_t i = 0; i < wdisp.size(); ++i) {
    dlo[i % 3] = std::min(dlo[i % 3], wdisp[i]);
    dhi[i % 3] = std::max(dhi[i % 3], wdisp[i]);
  }
  const size_t wheel_target = add_accessor(d, raw(wdisp), 5126, 7, "VEC3", 34962, {{"min", dlo}, {"max", dhi}});
  const size_t wheel_idx =
      add_accessor(d, raw(std::vector<uint8_t>{0, 1, 2, 3, 4, 5, 6, 1}), 5121, 8, "SCALAR", 34963);

  // Spare: a mesh no node uses (kept as stored).
  const size_t spare_pos = add_positions(d, {9, 9, 9, 10, 9, 9, 9, 10, 9});

  // Animation and skin data.
  const size_t times = add_accessor(d, raw(std::vector<float>{0, 0.5f, 1}), 5126, 3, "SCALAR", 0,
                                    {{"min", {0}}, {"max", {1}}});
  const size_t rots = add_accessor(d, raw(std::vector<float>{0, 0, 0, 1, 0, 0, 0.7071068f, 0.7071068f, 0, 0, 1, 0}),
                                   5126, 3, "VEC4");
  const size_t weights = add_accessor(d, raw(std::vector<float>{0, 1, 0.25f}), 5126, 3, "SCALAR");
  std::vector<float> ibm(16, 0.0f);
  for (int i = 0; i < 4; ++i) ibm[5 * i] = 1;
  ibm[12] = -1.5f;
  const size_t ibm_acc = add_accessor(d, raw(ibm), 5126, 1, "MAT4");
  const size_t image_view = add_view(d, png_bytes());

  j["meshes"] = json::array(
      {{{"name", "body"},
        {"primitives",
         {{{"attributes", {{"POSITION", body_pos}, {"NORMAL", body_nrm}, {"TEXCOORD_0", body_uv}}},
           {"indices", body_i0},
           {"material", 0},
           {"extras", {{"part", "A"}}}},
          {{"attributes", {{"POSITION", body_pos}, {"NORMAL", body_nrm}, {"TEXCOORD_0", body_uv}}},
           {"indices", body_i1},
           {"material", 1},
           {"mode", 4}}}}},
       {{"name", "wheel"},
        {"primitives",
         {{{"attributes", {{"POSITION", wheel_pos}, {"COLOR_0", wheel_col}}},
           {"indices", wheel_idx},
           {"mode", 6},
           {"material", 2},
           {"targets", {{{"POSITION", wheel_target}}}}}}},
        {"weights", {0.5}},
        {"extras", {{"targetNames", {"flat"}}}}},
       {{"name", "spare"}, {"primitives", {{{"attributes", {{"POSITION", spare_pos}}}, {"material", 0}}}}}});
  j["nodes"] = json::array(
      {{{"name", "root"},
        {"children", {1, 2, 3, 4}},
        {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0.1, -0.2, 0.3, 1}},
        {"extras", {{"tag", "root"}}}},
       {{"name", "body"},
        {"mesh", 0},
        {"translation", {1, 2, 3}},
        {"rotation", {0, 0, 0.7071067811865476, 0.7071067811865476}},
        {"scale", {1, 1, 2}},
        {"children", {5}}},
       {{"name", "wheel L"}, {"mesh", 1}, {"translation", {-1, 0, 0.25}}},
       {{"name", "wheel R"}, {"mesh", 1}, {"translation", {1, 0, 0.25}}, {"weights", {0.75}}},
       {{"name", "camera"}, {"camera", 0}, {"translation", {0, 0, 10}}},
       {{"name", "joint"}, {"translation", {0, 0.5, 0}}}});
  j["materials"] = json::array(
      {{{"name", "paint"},
        {"pbrMetallicRoughness",
         {{"baseColorFactor", {0.8, 0.1, 0.1, 1}}, {"baseColorTexture", {{"index", 0}, {"texCoord", 0}}}, {"metallicFactor", 0.5}}},
        {"doubleSided", true}},
       {{"name", "glass"},
        {"alphaMode", "BLEND"},
        {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.3, 0.9, 0.4}}}},
        {"emissiveFactor", {1, 1, 1}},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 2.5}}}}}},
       {{"name", "rubber"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 1}}}}},
        {"normalTexture", {{"index", 2}, {"scale", 0.5}}}}});
  j["textures"] = json::array({{{"sampler", 0}, {"source", 0}}, {{"sampler", 1}, {"source", 1}}, {{"source", 2}}});
  j["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33648}, {"wrapT", 10497}},
                               {{"magFilter", 9728}, {"name", "nearest"}}});
  j["images"] = json::array({{{"name", "paint.png"}, {"mimeType", "image/png"}, {"bufferView", image_view}},
                             {{"uri", kDataUriImage}},
                             {{"uri", "textures/rubber%20normal.png"}}});
  j["cameras"] = json::array(
      {{{"name", "cam"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.01}, {"zfar", 100}, {"aspectRatio", 1.5}}}}});
  j["animations"] = json::array(
      {{{"name", "spin"},
        {"channels",
         {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}},
          {{"sampler", 1}, {"target", {{"node", 3}, {"path", "weights"}}}}}},
        {"samplers",
         {{{"input", times}, {"output", rots}, {"interpolation", "LINEAR"}}, {{"input", times}, {"output", weights}}}}}});
  j["skins"] = json::array({{{"name", "rig"}, {"joints", {5}}, {"inverseBindMatrices", ibm_acc}}});
  while (d.bin.size() % 4) d.bin += '\0';
  j["buffers"] = json::array({{{"byteLength", d.bin.size()}}});
  return d;
}

// ---------------------------------------------------------------------------
// Reading documents back (test side)

// The elements of accessor `a` as doubles (float, u8, u16, u32 components;
// normalized values as stored), `comps` per element.
std::vector<double> accessor_values(const Doc& d, size_t a, size_t* comps = nullptr) {
  const json& acc = d.doc["accessors"][a];
  const std::string type = acc["type"].get<std::string>();
  const size_t c = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 16;
  if (comps) *comps = c;
  const int ct = acc["componentType"].get<int>();
  const size_t cs = ct == 5121 ? 1 : ct == 5123 ? 2 : 4;
  const size_t count = acc["count"].get<size_t>();
  const json& view = d.doc["bufferViews"][acc["bufferView"].get<size_t>()];
  const size_t stride = view.value("byteStride", c * cs);
  const size_t base = view.value("byteOffset", size_t{0}) + acc.value("byteOffset", size_t{0});
  std::vector<double> out;
  for (size_t i = 0; i < count; ++i)
    for (size_t k = 0; k < c; ++k) {
      const char* p = d.bin.data() + base + i * stride + k * cs;
      if (ct == 5126) {
        float f;
        std::memcpy(&f, p, 4);
        out.push_back(f);
      } else if (ct == 5121) {
        out.push_back(static_cast<unsigned char>(*p));
      } else if (ct == 5123) {
        uint16_t v;
        std::memcpy(&v, p, 2);
        out.push_back(v);
      } else {
        uint32_t v;
        std::memcpy(&v, p, 4);
        out.push_back(v);
      }
    }
  return out;
}

std::string view_bytes(const Doc& d, size_t v) {
  const json& view = d.doc["bufferViews"][v];
  return d.bin.substr(view.value("byteOffset", size_t{0}), view["byteLength"].get<size_t>());
}

// A primitive's triangles, each as its three corners' values of `semantic`
// (rounded by `round`), rotated to start at the smallest corner; sorted.
using Corner = std::vector<int64_t>;
using Triangle = std::array<Corner, 3>;
template <typename Round>
std::vector<Triangle> triangles(const Doc& d, const json& prim, const std::string& semantic, Round round) {
  size_t comps;
  const std::vector<double> values = accessor_values(d, prim["attributes"][semantic].get<size_t>(), &comps);
  std::vector<size_t> idx;
  if (prim.contains("indices")) {
    for (double x : accessor_values(d, prim["indices"].get<size_t>())) idx.push_back(static_cast<size_t>(x));
  } else {
    for (size_t i = 0; i < values.size() / comps; ++i) idx.push_back(i);
  }
  const int mode = prim.value("mode", 4);
  std::vector<std::array<size_t, 3>> t;
  if (mode == 4) {
    for (size_t i = 0; i + 2 < idx.size(); i += 3) t.push_back({idx[i], idx[i + 1], idx[i + 2]});
  } else if (mode == 6) {
    for (size_t i = 1; i + 1 < idx.size(); ++i) t.push_back({idx[i], idx[i + 1], idx[0]});
  }
  std::vector<Triangle> out;
  for (const auto& tri : t) {
    Triangle x;
    for (int k = 0; k < 3; ++k) {
      x[k].clear();
      for (size_t c = 0; c < comps; ++c) x[k].push_back(round(values[tri[k] * comps + c], c));
    }
    const int first = static_cast<int>(std::min_element(x.begin(), x.end()) - x.begin());
    std::rotate(x.begin(), x.begin() + first, x.end());
    out.push_back(x);
  }
  std::sort(out.begin(), out.end());
  return out;
}

auto exact = [](double x, size_t) { return static_cast<int64_t>(std::llround(x * 1e9)); };

// Everything but the geometry: equal JSON (images and meshes looked at
// separately), the same bytes for the image and the animation / skin data.
void expect_same_document(const Doc& in, const Doc& out) {
  for (const char* key : {"asset", "extensionsUsed", "extensions", "extras", "scene", "scenes", "nodes", "materials",
                          "textures", "samplers", "cameras", "animations", "skins"})
    EXPECT_EQ(in.doc[key], out.doc[key]) << key;
  // Images: the bytes of the embedded one, the URIs as they were.
  ASSERT_EQ(out.doc["images"].size(), 3u);
  json image0 = out.doc["images"][0];
  EXPECT_EQ(view_bytes(out, image0["bufferView"].get<size_t>()), png_bytes());
  image0["bufferView"] = in.doc["images"][0]["bufferView"];
  EXPECT_EQ(image0, in.doc["images"][0]);
  EXPECT_EQ(out.doc["images"][1], in.doc["images"][1]);
  EXPECT_EQ(out.doc["images"][2], in.doc["images"][2]);
  // Animation and skin accessors: same index, same values.
  for (const json& s : in.doc["animations"][0]["samplers"])
    for (const char* k : {"input", "output"}) {
      const size_t a = s[k].get<size_t>();
      EXPECT_EQ(accessor_values(in, a), accessor_values(out, a)) << "animation accessor " << a;
    }
  const size_t ibm = in.doc["skins"][0]["inverseBindMatrices"].get<size_t>();
  EXPECT_EQ(accessor_values(in, ibm), accessor_values(out, ibm));
  // Meshes: the same primitives (material, extras, attribute names, targets).
  ASSERT_EQ(out.doc["meshes"].size(), in.doc["meshes"].size());
  for (size_t m = 0; m < in.doc["meshes"].size(); ++m) {
    const json& a = in.doc["meshes"][m];
    const json& b = out.doc["meshes"][m];
    EXPECT_EQ(a["name"], b["name"]);
    EXPECT_EQ(a.value("weights", json()), b.value("weights", json()));
    EXPECT_EQ(a.value("extras", json()), b.value("extras", json()));
    ASSERT_EQ(a["primitives"].size(), b["primitives"].size());
    for (size_t p = 0; p < a["primitives"].size(); ++p) {
      const json& x = a["primitives"][p];
      const json& y = b["primitives"][p];
      SCOPED_TRACE("mesh " + std::to_string(m) + " primitive " + std::to_string(p));
      EXPECT_EQ(x.value("material", -1), y.value("material", -1));
      EXPECT_EQ(x.value("extras", json()), y.value("extras", json()));
      EXPECT_EQ(y.value("mode", 4), 4);  // the fan comes back as triangles
      std::vector<std::string> ka, kb;
      for (auto& kv : x["attributes"].items()) ka.push_back(kv.key());
      for (auto& kv : y["attributes"].items()) kb.push_back(kv.key());
      EXPECT_EQ(ka, kb);
      EXPECT_EQ(x.contains("targets"), y.contains("targets"));
      if (x.contains("targets") && y.contains("targets")) {
        ASSERT_EQ(x["targets"].size(), y["targets"].size());
        for (size_t t = 0; t < x["targets"].size(); ++t) {
          EXPECT_TRUE(y["targets"][t].contains("POSITION"));
          const json& acc = out.doc["accessors"][y["targets"][t]["POSITION"].get<size_t>()];
          EXPECT_TRUE(acc.contains("min") && acc.contains("max"));  // required for a POSITION target
        }
      }
    }
  }
  // The mesh outside the scene is kept as stored.
  const json& spare = in.doc["meshes"][2]["primitives"][0];
  EXPECT_EQ(out.doc["meshes"][2]["primitives"][0], spare);
  EXPECT_EQ(accessor_values(in, spare["attributes"]["POSITION"].get<size_t>()),
            accessor_values(out, spare["attributes"]["POSITION"].get<size_t>()));
}

// Geometry per primitive: positions (through `round`) of every triangle.
template <typename Round>
void expect_same_triangles(const Doc& in, const Doc& out, Round round) {
  for (size_t m = 0; m < 2; ++m)
    for (size_t p = 0; p < in.doc["meshes"][m]["primitives"].size(); ++p) {
      SCOPED_TRACE("mesh " + std::to_string(m) + " primitive " + std::to_string(p));
      const auto a = triangles(in, in.doc["meshes"][m]["primitives"][p], "POSITION", round);
      const auto b = triangles(out, out.doc["meshes"][m]["primitives"][p], "POSITION", round);
      EXPECT_FALSE(a.empty());
      EXPECT_EQ(a, b);
    }
}

Status read_doc(const std::string& bytes, Mesh& m, ReadInfo* info = nullptr) {
  return tsm::read_gltf(bytes, "test.glb", m, tsm::ReadOptions(), info);
}

std::string write_doc(const Mesh& m, bool binary = true) {
  std::string out;
  const Status s = tsm::write_gltf(m, tsm::WriteOptions(), out, binary);
  EXPECT_TRUE(s.ok()) << s.to_string();
  return out;
}

const tsm::Attribute* find(const Mesh& m, const std::string& name) {
  for (const tsm::Attribute& a : m.attributes)
    if (a.name == name) return &a;
  return nullptr;
}

// ---------------------------------------------------------------------------

TEST(GltfPassThrough, ReaderKeepsTheDocumentAndTagsPrimitives) {
  const Doc in = test_document();
  Mesh m;
  ReadInfo info;
  const Status s = read_doc(to_glb(in), m, &info);
  ASSERT_TRUE(s.ok()) << s.to_string();
  EXPECT_EQ(m.vertex_count(), 16u + 7u);
  EXPECT_EQ(m.face_count(), 18u + 6u);
  ASSERT_NE(m.find_metadata("gltf"), nullptr);
  EXPECT_TRUE(m.valid());
  // Two vertex groups (body, wheel); the body's group has two primitives.
  const tsm::Attribute* group = find(m, "_gltf_group");
  const tsm::Attribute* prim = find(m, "_gltf_primitive");
  ASSERT_NE(group, nullptr);
  ASSERT_NE(prim, nullptr);
  EXPECT_EQ(group->domain, tsm::AttributeDomain::vertex);
  EXPECT_EQ(group->type, tsm::AttributeType::u16);
  EXPECT_EQ(prim->domain, tsm::AttributeDomain::face);
  EXPECT_EQ(group->values[0], 0.0f);
  EXPECT_EQ(group->values[16], 1.0f);
  EXPECT_EQ(prim->values[0], 0.0f);
  EXPECT_EQ(prim->values[10], 1.0f);
  EXPECT_EQ(prim->values[18], 2.0f);
  EXPECT_NE(find(m, "_gltf_target0_POSITION"), nullptr);
  // Nothing is said to be dropped any more.
  EXPECT_FALSE(contains(info.notes, "not kept")) << info.notes;
  EXPECT_TRUE(contains(info.notes, "1 mesh(es) not in the scene kept as stored")) << info.notes;
  std::cout << "[ figures  ] test document: GLB " << to_glb(in).size() << " bytes, of which BIN " << in.bin.size()
            << "; 'gltf' metadata entry " << m.find_metadata("gltf")->value.size() << " bytes\n";
  // A single-primitive file needs no tags.
  Mesh one;
  Doc single = in;
  single.doc["scenes"][0]["nodes"] = {2};
  ASSERT_TRUE(read_doc(to_glb(single), one).ok());
  EXPECT_EQ(find(one, "_gltf_group"), nullptr);
  EXPECT_EQ(find(one, "_gltf_primitive"), nullptr);
}

TEST(GltfPassThrough, ReadWriteGivesTheDocumentBack) {
  const Doc in = test_document();
  Mesh m;
  ASSERT_TRUE(read_doc(to_glb(in), m).ok());
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    const std::string bytes = write_doc(m, binary);
    Doc out;
    ASSERT_TRUE(parse_output(bytes, out));
    expect_same_document(in, out);
    expect_same_triangles(in, out, exact);
    // Normals, texture coordinates, colours per triangle corner, exactly.
    for (const char* sem : {"NORMAL", "TEXCOORD_0"})
      EXPECT_EQ(triangles(in, in.doc["meshes"][0]["primitives"][1], sem, exact),
                triangles(out, out.doc["meshes"][0]["primitives"][1], sem, exact));
    EXPECT_EQ(triangles(in, in.doc["meshes"][1]["primitives"][0], "COLOR_0", exact),
              triangles(out, out.doc["meshes"][1]["primitives"][0], "COLOR_0", exact));
    const json& col = out.doc["accessors"][out.doc["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"].get<size_t>()];
    EXPECT_EQ(col["componentType"], 5121);
    EXPECT_EQ(col["normalized"], true);
    EXPECT_EQ(col["name"], "wheel colours");  // the accessor's own fields are kept
    // The two body primitives still share their vertex accessors.
    EXPECT_EQ(out.doc["meshes"][0]["primitives"][0]["attributes"], out.doc["meshes"][0]["primitives"][1]["attributes"]);
    // The morph target's displacements, per vertex position.
    const json& wheel = out.doc["meshes"][1]["primitives"][0];
    const auto wp = accessor_values(out, wheel["attributes"]["POSITION"].get<size_t>());
    const auto wd = accessor_values(out, wheel["targets"][0]["POSITION"].get<size_t>());
    const json& wheel_in = in.doc["meshes"][1]["primitives"][0];
    const auto ip = accessor_values(in, wheel_in["attributes"]["POSITION"].get<size_t>());
    const auto id = accessor_values(in, wheel_in["targets"][0]["POSITION"].get<size_t>());
    std::map<std::vector<double>, std::vector<double>> a, b;
    for (size_t v = 0; v < 7; ++v) {
      a[{ip.begin() + 3 * v, ip.begin() + 3 * v + 3}] = {id.begin() + 3 * v, id.begin() + 3 * v + 3};
      b[{wp.begin() + 3 * v, wp.begin() + 3 * v + 3}] = {wd.begin() + 3 * v, wd.begin() + 3 * v + 3};
    }
    EXPECT_EQ(a, b);
    // Reading the output gives the same mesh, metadata and all.
    Mesh back;
    ASSERT_TRUE(tsm::read_gltf(bytes, "out", back, {}, nullptr).ok());
    const tsm::CompareResult r = tsm::compare_meshes(m, back, 0);
    EXPECT_TRUE(r.equal) << r.difference;
    // And writing that again gives the same bytes: the pass-through is a fixpoint.
    EXPECT_EQ(write_doc(back, binary), bytes);
  }
}

TEST(GltfPassThrough, ThroughTheCodec) {
  const Doc in = test_document();
  Mesh m;
  ASSERT_TRUE(read_doc(to_glb(in), m).ok());
  const int bits = 14;
  const tsm::Grid grid = tsm::Grid::for_mesh(m, bits);
  auto quantized = [&](double x, size_t axis) { return grid.quantize(x, static_cast<int>(axis)); };
  for (uint32_t segment_faces : {0u, 8u}) {
    SCOPED_TRACE("segment_faces " + std::to_string(segment_faces));
    tsm::EncodeOptions eo;
    eo.quantization_bits = bits;
    eo.segment_faces = segment_faces;
    std::string tsm_bytes;
    Status s = tsm::encode(m, eo, tsm_bytes);
    ASSERT_TRUE(s.ok()) << s.to_string();
    Mesh decoded;
    s = tsm::decode(tsm_bytes, decoded);
    ASSERT_TRUE(s.ok()) << s.to_string();
    ASSERT_NE(decoded.find_metadata("gltf"), nullptr) << "the codec does not give the metadata back";
    EXPECT_EQ(decoded.find_metadata("gltf")->value, m.find_metadata("gltf")->value);
    const tsm::CompareResult r = tsm::compare_meshes(m, decoded, bits);
    EXPECT_TRUE(r.equal) << r.difference;
    if (segment_faces == 0) {
      Mesh bare = m;
      bare.metadata.clear();
      std::string bare_bytes;
      ASSERT_TRUE(tsm::encode(bare, eo, bare_bytes).ok());
      std::cout << "[ figures  ] .tsm " << tsm_bytes.size() << " bytes, " << bare_bytes.size()
                << " without the 'gltf' entry\n";
    }
    for (bool binary : {true, false}) {
      const std::string bytes = write_doc(decoded, binary);
      Doc out;
      ASSERT_TRUE(parse_output(bytes, out));
      expect_same_document(in, out);
      expect_same_triangles(in, out, quantized);
    }
  }
}

TEST(GltfPassThrough, CommandLineEncodeDecode) {
  tsm_test::TempDir dir;
  const Doc in = test_document();
  {
    std::ofstream f(dir.file("in.glb"), std::ios::binary);
    const std::string glb = to_glb(in);
    f.write(glb.data(), static_cast<std::streamsize>(glb.size()));
  }
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string("'") + TSM_CLI_PATH + "' " + args + " >'" + dir.file("log") + "' 2>&1";
    return std::system(cmd.c_str());
  };
  const std::string d = "'" + dir.path.string() + "/";
  ASSERT_EQ(run("encode " + d + "in.glb' -o " + d + "out.tsm'"), 0);
  ASSERT_EQ(run("decode " + d + "out.tsm' -o " + d + "back.glb'"), 0);
  std::string bytes;
  ASSERT_TRUE(tsm::read_file(dir.file("back.glb"), bytes).ok());
  Doc out;
  ASSERT_TRUE(parse_output(bytes, out));
  expect_same_document(in, out);
}

// ---------------------------------------------------------------------------
// Damaged or mismatching pass-through data: an error, never a crash.

struct Parts {
  json wrapper;
  std::string bin;
};
Parts split(const std::string& value) {
  Parts p;
  const uint32_t jl = u32_at(value, 8);
  p.wrapper = json::parse(value.substr(12, jl));
  p.bin = value.substr(12 + jl);
  return p;
}
std::string join(const Parts& p) {
  const std::string j = p.wrapper.dump();
  std::string v = "tsmG";
  put_u32(v, 1);
  put_u32(v, static_cast<uint32_t>(j.size()));
  return v + j + p.bin;
}

Status write_with(const Mesh& m, const std::string& value) {
  Mesh x = m;
  for (auto& e : x.metadata)
    if (e.key == "gltf") e.value = value;
  std::string out = "stale";
  const Status s = tsm::write_gltf(x, tsm::WriteOptions(), out, true);
  if (!s.ok()) {
    EXPECT_TRUE(out.empty());
  }
  return s;
}

TEST(GltfPassThrough, DamagedOrMismatchingDataIsAnError) {
  const Doc in = test_document();
  Mesh m;
  ASSERT_TRUE(read_doc(to_glb(in), m).ok());
  const std::string value = m.find_metadata("gltf")->value;
  ASSERT_TRUE(write_with(m, value).ok());

  auto expect_error = [&](const Status& s, tsm::ErrorCode code, const std::string& part) {
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.code(), code) << s.to_string();
    EXPECT_TRUE(contains(s.message(), "metadata 'gltf'"));
    EXPECT_TRUE(contains(s.message(), part));
  };
  using tsm::ErrorCode;
  expect_error(write_with(m, ""), ErrorCode::corrupt_data, "'tsmG'");
  expect_error(write_with(m, "tsmX" + value.substr(4)), ErrorCode::corrupt_data, "'tsmG'");
  expect_error(write_with(m, value.substr(0, 4) + "\x02" + value.substr(5)), ErrorCode::corrupt_data, "version 2");
  expect_error(write_with(m, value.substr(0, 100)), ErrorCode::corrupt_data, "runs past its end");
  {
    std::string v = value;
    v[12] = ']';  // broken JSON
    expect_error(write_with(m, v), ErrorCode::corrupt_data, "does not parse");
  }
  {
    Parts p = split(value);
    p.wrapper["vertex_groups"][0] = 15;
    expect_error(write_with(m, join(p)), ErrorCode::invalid_argument, "describes 22 vertices");
  }
  {
    Parts p = split(value);
    p.wrapper["vertex_groups"] = {7, 16};  // groups swapped
    expect_error(write_with(m, join(p)), ErrorCode::invalid_argument, "vertex group 0 has 16 vertices");
  }
  {
    Parts p = split(value);
    p.wrapper["face_sets"][0][0] = 1;  // body triangles said to use the wheel's vertices
    expect_error(write_with(m, join(p)), ErrorCode::invalid_argument, "uses vertex");
  }
  {
    Parts p = split(value);
    p.wrapper["accessors"][0]["accessor"] = 100000;
    expect_error(write_with(m, join(p)), ErrorCode::corrupt_data, "names no accessor");
  }
  {
    Parts p = split(value);
    p.wrapper["accessors"][1]["accessor"] = p.wrapper["accessors"][0]["accessor"];
    expect_error(write_with(m, join(p)), ErrorCode::corrupt_data, "already filled");
  }
  {
    Parts p = split(value);
    p.wrapper["accessors"][0]["group"] = "zero";
    expect_error(write_with(m, join(p)), ErrorCode::corrupt_data, "names no vertex group");
  }
  {
    Parts p = split(value);
    p.wrapper["document"]["bufferViews"] = 7;
    expect_error(write_with(m, join(p)), ErrorCode::corrupt_data, "bufferViews");
  }
  {
    Parts p = split(value);
    p.wrapper["document"] = json::array();
    expect_error(write_with(m, join(p)), ErrorCode::corrupt_data, "no glTF document");
  }
  {
    Parts p = split(value);
    std::string deep(5000, '[');
    p.wrapper["document"]["extras"] = 1;
    std::string j = p.wrapper.dump();
    j.replace(j.find("\"extras\":1"), 10, "\"extras\":" + deep + std::string(5000, ']'));
    std::string v = "tsmG";
    put_u32(v, 1);
    put_u32(v, static_cast<uint32_t>(j.size()));
    expect_error(write_with(m, v + j + p.bin), ErrorCode::corrupt_data, "nests too deep");
  }
  // The mesh changed: a tag gone, a tag out of range, a vertex more.
  {
    Mesh x = m;
    x.attributes.erase(x.attributes.begin() + (find(x, "_gltf_group") - x.attributes.data()));
    std::string out;
    expect_error(tsm::write_gltf(x, {}, out, true), ErrorCode::invalid_argument, "'_gltf_group'");
  }
  {
    Mesh x = m;
    const_cast<tsm::Attribute*>(find(x, "_gltf_primitive"))->values[3] = 9;
    std::string out;
    expect_error(tsm::write_gltf(x, {}, out, true), ErrorCode::invalid_argument, "face 3");
  }
  {
    Mesh x = m;
    x.add_vertex(1, 2, 3);
    for (tsm::Attribute& a : x.attributes)
      if (a.domain == tsm::AttributeDomain::vertex) a.values.resize(a.values.size() + a.components, 0.0f);
    std::string out;
    expect_error(tsm::write_gltf(x, {}, out, true), ErrorCode::invalid_argument, "the mesh has 24");
  }
  {
    Mesh x = m;
    x.attributes.erase(x.attributes.begin() + (find(x, "normal") - x.attributes.data()));
    std::string out;
    expect_error(tsm::write_gltf(x, {}, out, true), ErrorCode::invalid_argument, "no vertex attribute 'normal'");
  }
  // Random damage: truncations and flipped bytes never crash (run under
  // ASan / UBSan by scripts/test.sh).
  for (size_t n = 0; n < value.size(); n += 37) (void)write_with(m, value.substr(0, n));
  std::mt19937 rng(99);
  size_t accepted = 0;
  for (int round = 0; round < 400; ++round) {
    std::string v = value;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k) {
      const size_t at = rng() % v.size();
      v[at] = static_cast<char>(rng() % 3 == 0 ? "0123456789[]{}\",:-"[rng() % 18] : static_cast<char>(rng() & 0xFF));
    }
    if (write_with(m, v).ok()) ++accepted;
  }
  std::cout << "[ figures  ] " << accepted << " of 400 randomly damaged entries still written\n";
}

TEST(GltfPassThrough, WithoutTheEntryTheWriterIsUnchanged) {
  const Doc in = test_document();
  Mesh m;
  ASSERT_TRUE(read_doc(to_glb(in), m).ok());
  m.metadata.clear();
  // The face tag is a face attribute, which the plain writer refuses...
  std::string out;
  EXPECT_EQ(tsm::write_gltf(m, {}, out, true).code(), tsm::ErrorCode::unsupported);
  // ...and without it: one mesh, one primitive.
  m.attributes.erase(m.attributes.begin() + (find(m, "_gltf_primitive") - m.attributes.data()));
  Doc d;
  ASSERT_TRUE(parse_output(write_doc(m), d));
  EXPECT_EQ(d.doc["meshes"].size(), 1u);
  EXPECT_EQ(d.doc["meshes"][0]["primitives"].size(), 1u);
  EXPECT_FALSE(d.doc.contains("materials"));
}

}  // namespace

namespace {

// fuzz_read_mesh (crash-3cc75120, after 142k executions): a mesh
// without "primitives" (glTF requires them; tinygltf reads none) was kept,
// but building the pass-through entry looked its primitives up with JSON
// operator[], which added "primitives": null to the stored document, and
// the document written from it was refused on reading ("'primitives' does
// not match what tinygltf read"). Both files must read, and the written one
// must give the same mesh back.
TEST(GltfPassThrough, MeshWithoutPrimitivesSurvivesTheRoundTrip) {
  Doc d;
  d.doc["asset"] = {{"version", "2.0"}};
  const size_t pos = add_positions(d, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  d.doc["meshes"] = json::array({json{{"primitives", json::array({json{{"attributes", {{"POSITION", pos}}}}})}},
                                 json{{"name", "no primitives"}, {"primitNOFF", json::array()}}});
  d.doc["nodes"] = json::array({json{{"mesh", 0}}, json{{"mesh", 1}}});
  d.doc["scenes"] = json::array({json{{"nodes", {0, 1}}}});
  d.doc["scene"] = 0;
  d.doc["buffers"] = json::array({json{{"byteLength", d.bin.size()}}});
  Mesh m;
  ASSERT_TRUE(read_doc(to_glb(d), m).ok());
  ASSERT_NE(m.find_metadata("gltf"), nullptr);
  EXPECT_EQ(m.face_count(), 1u);
  for (bool binary : {true, false}) {
    const std::string out = write_doc(m, binary);
    Doc o;
    ASSERT_TRUE(parse_output(out, o));
    EXPECT_FALSE(o.doc["meshes"][1].contains("primitives")) << o.doc["meshes"][1].dump();
    EXPECT_EQ(o.doc["meshes"][1]["name"], "no primitives");
    Mesh back;
    const Status s = tsm::read_gltf(out, binary ? "out.glb" : "out.gltf", back, tsm::ReadOptions(), nullptr);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_EQ(back.positions, m.positions);
    EXPECT_EQ(back.indices, m.indices);
  }
}

}  // namespace

// fuzz_read_mesh (CI smoke run, crash-6411d56f): a primitive whose POSITION
// accessor is empty (count 0, no buffer view) in a document without buffers.
// The writer gave it a zero-byte buffer view naming buffer 0 and wrote no
// buffer, and its own reader refused the result. Empty accessors now get no
// view (a buffer view holds at least one byte).
TEST(GltfPassThrough, EmptyAccessorGetsNoBufferView) {
  for (bool with_triangle : {false, true}) {
    Doc d;
    d.doc["asset"] = {{"version", "2.0"}};
    json prims = json::array();
    if (with_triangle) prims.push_back({{"attributes", {{"POSITION", add_positions(d, {0, 0, 0, 1, 0, 0, 0, 1, 0})}}}});
    d.doc["accessors"].push_back({{"componentType", 5126}, {"count", 0}, {"type", "VEC3"}});
    prims.push_back({{"attributes", {{"POSITION", d.doc["accessors"].size() - 1}}}});
    d.doc["meshes"] = json::array({json{{"primitives", prims}}});
    if (!d.bin.empty()) d.doc["buffers"] = json::array({json{{"byteLength", d.bin.size()}}});
    Mesh m;
    const Status r = read_doc(to_glb(d), m);
    ASSERT_TRUE(r.ok()) << r.to_string();
    EXPECT_EQ(m.vertex_count(), with_triangle ? 3u : 0u);
    for (bool binary : {true, false}) {
      const std::string out = write_doc(m, binary);
      Doc o;
      ASSERT_TRUE(parse_output(out, o));
      const json& empty = o.doc["accessors"][o.doc["meshes"][0]["primitives"][with_triangle ? 1 : 0]["attributes"]["POSITION"].get<size_t>()];
      EXPECT_EQ(empty["count"], 0) << o.doc.dump();
      EXPECT_FALSE(empty.contains("bufferView")) << o.doc.dump();
      if (o.doc.contains("bufferViews")) {
        for (const json& v : o.doc["bufferViews"]) EXPECT_GT(v["byteLength"].get<size_t>(), 0u) << o.doc.dump();
      }
      Mesh back;
      const Status s = tsm::read_gltf(out, binary ? "out.glb" : "out.gltf", back, tsm::ReadOptions(), nullptr);
      ASSERT_TRUE(s.ok()) << s.to_string();
      EXPECT_EQ(back.positions, m.positions);
      EXPECT_EQ(back.indices, m.indices);
    }
  }
}
