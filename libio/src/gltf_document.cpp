// The glTF document of the transcoder (see gltf_document.hpp): loading
// (.glb container and .gltf JSON, buffers from the GLB chunk, data: URIs or
// files beside the .gltf), bounds-checked accessor reading, new buffer
// views, and saving with the buffer views still used packed into one buffer.
// Every count, offset and stride is checked against the bytes before use.
#include "gltf_document.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

#include "gltf_files.hpp"
#include "tsm/version.h"

namespace tsm::gltf {

namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr size_t kMaxJsonDepth = 128;
// Accessors without a buffer view are zeros: bound what one may allocate.
constexpr size_t kMaxZeroValues = size_t(1) << 26;

uint32_t load_u32(const char* p) {
  const auto* u = reinterpret_cast<const unsigned char*>(p);
  return static_cast<uint32_t>(u[0]) | static_cast<uint32_t>(u[1]) << 8 | static_cast<uint32_t>(u[2]) << 16 |
         static_cast<uint32_t>(u[3]) << 24;
}

void put_u32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}

// Deepest nesting of arrays and objects outside strings, stopping past limit.
size_t json_depth(std::string_view s, size_t limit) {
  size_t depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > limit) return deepest;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+' || c == '-') return 62;
  if (c == '/' || c == '_') return 63;
  return -1;
}

bool base64_decode(std::string_view in, std::string& out) {
  out.clear();
  out.reserve(in.size() / 4 * 3);
  uint32_t acc = 0;
  int bits = 0;
  for (char c : in) {
    if (c == '=') break;
    const int v = base64_value(c);
    if (v < 0) return false;
    acc = acc << 6 | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((acc >> bits) & 0xFF);
    }
  }
  return true;
}

// "data:...;base64,": true and the bytes, or false when not a data URI.
bool data_uri(const std::string& uri, std::string& out, bool& ok) {
  if (uri.compare(0, 5, "data:") != 0) return false;
  const size_t comma = uri.find(',');
  const size_t b64 = uri.find(";base64,");
  ok = comma != std::string::npos && b64 != std::string::npos && b64 + 7 == comma &&
       base64_decode(std::string_view(uri).substr(comma + 1), out);
  return true;
}

Status split_glb(const Document& doc, std::string_view bytes, std::string_view& json, std::string_view& bin,
                 bool& has_bin) {
  if (bytes.size() < 20) return doc.error("GLB shorter than its 12-byte header and first chunk header");
  if (load_u32(bytes.data() + 4) != 2)
    return doc.error("GLB version " + std::to_string(load_u32(bytes.data() + 4)) + " (only glTF 2.0 is read)");
  const uint64_t length = load_u32(bytes.data() + 8);
  if (length > bytes.size())
    return doc.error("GLB header says " + std::to_string(length) + " bytes, the file has " +
                     std::to_string(bytes.size()) + " (truncated?)");
  size_t at = 12;
  has_bin = false;
  bool has_json = false;
  while (at + 8 <= length) {
    const uint64_t size = load_u32(bytes.data() + at);
    const uint32_t type = load_u32(bytes.data() + at + 4);
    if (size > length - at - 8) return doc.error("GLB chunk at byte " + std::to_string(at) + " runs past the file");
    const std::string_view body = bytes.substr(at + 8, size);
    if (!has_json) {
      if (type != kChunkJson) return doc.error("GLB's first chunk is not JSON");
      json = body;
      has_json = true;
    } else if (type == kChunkBin && !has_bin) {
      bin = body;
      has_bin = true;
    }
    at += 8 + size;
  }
  if (!has_json) return doc.error("GLB without a JSON chunk");
  return Status::Ok();
}

Status load_buffers(Document& doc, std::string_view bin, bool has_bin) {
  const size_t n = doc.count_of("buffers");
  doc.buffers.assign(n, std::string());
  for (size_t i = 0; i < n; ++i) {
    const ojson& b = doc.json["buffers"][i];
    const std::string where = "buffers[" + std::to_string(i) + "]";
    if (!b.is_object() || !b.contains("byteLength") || !b["byteLength"].is_number_unsigned())
      return doc.error(where + " has no valid byteLength");
    const uint64_t length = b["byteLength"].get<uint64_t>();
    std::string& out = doc.buffers[i];
    if (!b.contains("uri")) {
      const bool meshopt_fallback =
          b.contains("extensions") && b["extensions"].is_object() &&
          (b["extensions"].contains("EXT_meshopt_compression") || b["extensions"].contains("KHR_meshopt_compression"));
      if (i == 0 && has_bin)
        out.assign(bin.data(), bin.size());
      else if (!meshopt_fallback)
        return doc.error(where + " has no uri and is not the GLB binary chunk");
      // A meshopt fallback buffer has no bytes: its views are compressed.
      if (meshopt_fallback && !(i == 0 && has_bin)) continue;
    } else {
      if (!b["uri"].is_string()) return doc.error(where + ".uri is not a string");
      const std::string uri = b["uri"].get<std::string>();
      bool ok = false;
      if (data_uri(uri, out, ok)) {
        if (!ok) return doc.error(where + ": a data: URI that is not base64 data");
      } else {
        Status s = read_file_beside(doc.dir, uri, out);
        if (!s.ok()) return Status(s.code(), doc.name + ": " + where + ": " + s.message());
      }
    }
    if (out.size() < length)
      return doc.error(where + " says byteLength " + std::to_string(length) + " but holds " +
                       std::to_string(out.size()) + " bytes");
    out.resize(length);
  }
  return Status::Ok();
}

// The bytes of a buffer view, checked.
Status view_bytes(const Document& doc, size_t view, std::string_view& out, size_t& stride) {
  const std::string where = "bufferViews[" + std::to_string(view) + "]";
  const ojson& v = doc.json["bufferViews"][view];
  if (!v.is_object()) return doc.error(where + " is not an object");
  int64_t buffer = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(v, "buffer", doc.buffers.size(), where, buffer));
  if (buffer < 0) return doc.error(where + " names no buffer");
  const uint64_t offset = v.value("byteOffset", uint64_t(0));
  if (!v.contains("byteLength") || !v["byteLength"].is_number_unsigned())
    return doc.error(where + " has no valid byteLength");
  const uint64_t length = v["byteLength"].get<uint64_t>();
  const std::string& data = doc.buffers[static_cast<size_t>(buffer)];
  if (offset > data.size() || length > data.size() - offset)
    return doc.error(where + " (bytes " + std::to_string(offset) + ".." + std::to_string(offset + length) +
                     ") lies outside buffers[" + std::to_string(buffer) + "] (" + std::to_string(data.size()) +
                     " bytes)");
  stride = v.contains("byteStride") && v["byteStride"].is_number_unsigned() ? v["byteStride"].get<size_t>() : 0;
  out = std::string_view(data).substr(offset, length);
  return Status::Ok();
}

double load_component(int ct, const char* p) {
  switch (ct) {
    case kByte: return static_cast<int8_t>(*p);
    case kUByte: return static_cast<uint8_t>(*p);
    case kShort: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case kUShort: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case kUInt: return load_u32(p);
    default: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
  }
}

// Reads `count` elements of `components` x `ct` from a view into dst.
Status read_elements(const Document& doc, size_t view, uint64_t offset, size_t count, uint32_t components, int ct,
                     bool vertex_stride, const std::string& where, double* dst) {
  std::string_view bytes;
  size_t stride = 0;
  TSM_RETURN_IF_ERROR(view_bytes(doc, view, bytes, stride));
  const size_t elem = component_bytes(ct) * components;
  if (!vertex_stride || stride == 0) stride = elem;
  if (stride < elem) return doc.error(where + ": byteStride " + std::to_string(stride) + " below the element size");
  if (count > 0 && (offset > bytes.size() || (bytes.size() - offset < elem) ||
                    (count - 1) > (bytes.size() - offset - elem) / stride))
    return doc.error(where + ": " + std::to_string(count) + " elements do not fit in bufferViews[" +
                     std::to_string(view) + "] (" + std::to_string(bytes.size()) + " bytes from offset " +
                     std::to_string(offset) + ")");
  const size_t cb = component_bytes(ct);
  for (size_t i = 0; i < count; ++i)
    for (uint32_t c = 0; c < components; ++c)
      dst[i * components + c] = load_component(ct, bytes.data() + offset + i * stride + c * cb);
  return Status::Ok();
}

double normalized_value(int ct, double v) {
  switch (ct) {
    case kByte: return std::max(v / 127.0, -1.0);
    case kUByte: return v / 255.0;
    case kShort: return std::max(v / 32767.0, -1.0);
    case kUShort: return v / 65535.0;
    default: return v;
  }
}

}  // namespace

Status Document::error(const std::string& what) const {
  return Status(ErrorCode::parse_error, name + ": invalid glTF: " + what);
}

size_t Document::count_of(const char* array) const {
  const auto it = json.find(array);
  return it != json.end() && it->is_array() ? it->size() : 0;
}

Status Document::index_of(const ojson& obj, const char* key, size_t limit, const std::string& where,
                          int64_t& out) const {
  out = -1;
  if (!obj.is_object() || !obj.contains(key)) return Status::Ok();
  const ojson& v = obj[key];
  if (!v.is_number_unsigned() || v.get<uint64_t>() >= limit)
    return error(where + "." + key + " is not an index below " + std::to_string(limit));
  out = static_cast<int64_t>(v.get<uint64_t>());
  return Status::Ok();
}

size_t component_bytes(int ct) {
  switch (ct) {
    case kByte:
    case kUByte: return 1;
    case kShort:
    case kUShort: return 2;
    case kUInt:
    case kFloat: return 4;
    default: return 0;
  }
}

uint32_t type_components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  return 0;
}

const char* type_for_components(uint32_t c) {
  static const char* const names[] = {"SCALAR", "VEC2", "VEC3", "VEC4"};
  return c >= 1 && c <= 4 ? names[c - 1] : "SCALAR";
}

std::vector<float> AccessorData::values() const {
  std::vector<float> out(raw.size());
  for (size_t i = 0; i < raw.size(); ++i)
    out[i] = static_cast<float>(normalized ? normalized_value(component_type, raw[i]) : raw[i]);
  return out;
}

Status load_document(std::string_view bytes, const std::string& name, const std::string& dir, Document& doc) {
  doc = Document();
  doc.name = name;
  doc.dir = dir;
  std::string_view json_text = bytes, bin;
  bool has_bin = false;
  if (bytes.size() >= 4 && load_u32(bytes.data()) == kGlbMagic)
    TSM_RETURN_IF_ERROR(split_glb(doc, bytes, json_text, bin, has_bin));
  if (json_depth(json_text, kMaxJsonDepth) > kMaxJsonDepth)
    return doc.error("JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  try {
    doc.json = ojson::parse(json_text.begin(), json_text.end());
  } catch (const std::exception& e) {
    return doc.error(std::string("JSON does not parse: ") + e.what());
  }
  if (!doc.json.is_object() || !doc.json.contains("asset")) return doc.error("no \"asset\" object");
  for (const char* array : {"buffers", "bufferViews", "accessors", "meshes"})
    if (doc.json.contains(array) && !doc.json[array].is_array())
      return doc.error(std::string(array) + " is not an array");
  return load_buffers(doc, bin, has_bin);
}

Status read_accessor(const Document& doc, size_t index, AccessorData& out) {
  const std::string where = "accessors[" + std::to_string(index) + "]";
  if (index >= doc.count_of("accessors")) return doc.error(where + " does not exist");
  const ojson& a = doc.json["accessors"][index];
  if (!a.is_object()) return doc.error(where + " is not an object");
  out = AccessorData();
  out.component_type = a.value("componentType", 0);
  out.components = a.contains("type") && a["type"].is_string() ? type_components(a["type"].get<std::string>()) : 0;
  out.normalized = a.value("normalized", false);
  if (component_bytes(out.component_type) == 0 || out.components == 0)
    return doc.error(where + " has an unknown componentType or a type other than SCALAR / VEC2..4");
  if (!a.contains("count") || !a["count"].is_number_unsigned() || a["count"].get<uint64_t>() == 0)
    return doc.error(where + ".count is not a positive integer");
  const uint64_t count = a["count"].get<uint64_t>();
  int64_t view = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(a, "bufferView", doc.count_of("bufferViews"), where, view));
  const size_t elem = component_bytes(out.component_type) * out.components;
  // Counts are bounded by the bytes that hold them before anything is allocated.
  size_t data_bytes = 0;
  for (const std::string& b : doc.buffers) data_bytes += b.size();
  if (view >= 0 ? count > data_bytes / elem : count * out.components > kMaxZeroValues)
    return doc.error(where + ".count " + std::to_string(count) + " is more than the buffers hold");
  out.count = static_cast<size_t>(count);
  out.raw.assign(out.count * out.components, 0.0);
  if (view >= 0)
    TSM_RETURN_IF_ERROR(read_elements(doc, static_cast<size_t>(view), a.value("byteOffset", uint64_t(0)), out.count,
                                      out.components, out.component_type, true, where, out.raw.data()));
  if (a.contains("sparse")) {
    const ojson& sp = a["sparse"];
    const std::string sw = where + ".sparse";
    if (!sp.is_object() || !sp.contains("count") || !sp["count"].is_number_unsigned() ||
        sp["count"].get<uint64_t>() > count || !sp.contains("indices") || !sp.contains("values"))
      return doc.error(sw + " is malformed (count above the accessor's, or indices / values missing)");
    const size_t n = sp["count"].get<size_t>();
    const ojson& si = sp["indices"];
    const ojson& sv = sp["values"];
    int64_t iv = -1, vv = -1;
    TSM_RETURN_IF_ERROR(doc.index_of(si, "bufferView", doc.count_of("bufferViews"), sw + ".indices", iv));
    TSM_RETURN_IF_ERROR(doc.index_of(sv, "bufferView", doc.count_of("bufferViews"), sw + ".values", vv));
    const int ict = si.value("componentType", 0);
    if (iv < 0 || vv < 0 || (ict != kUByte && ict != kUShort && ict != kUInt))
      return doc.error(sw + " needs indices and values buffer views and unsigned indices");
    std::vector<double> idx(n), val(n * out.components);
    TSM_RETURN_IF_ERROR(read_elements(doc, static_cast<size_t>(iv), si.value("byteOffset", uint64_t(0)), n, 1, ict,
                                      false, sw + ".indices", idx.data()));
    TSM_RETURN_IF_ERROR(read_elements(doc, static_cast<size_t>(vv), sv.value("byteOffset", uint64_t(0)), n,
                                      out.components, out.component_type, false, sw + ".values", val.data()));
    for (size_t k = 0; k < n; ++k) {
      if (idx[k] >= static_cast<double>(out.count)) return doc.error(sw + ": index past the accessor's count");
      const size_t at = static_cast<size_t>(idx[k]);
      for (uint32_t c = 0; c < out.components; ++c) out.raw[at * out.components + c] = val[k * out.components + c];
    }
  }
  return Status::Ok();
}

Status read_indices(const Document& doc, size_t index, std::vector<uint32_t>& out) {
  AccessorData a;
  TSM_RETURN_IF_ERROR(read_accessor(doc, index, a));
  if (a.components != 1 || (a.component_type != kUByte && a.component_type != kUShort && a.component_type != kUInt))
    return doc.error("accessors[" + std::to_string(index) + "] holds indices but is not a SCALAR of unsigned integers");
  out.resize(a.raw.size());
  for (size_t i = 0; i < a.raw.size(); ++i) out[i] = static_cast<uint32_t>(a.raw[i]);
  return Status::Ok();
}

size_t add_buffer_view(Document& doc, std::string bytes, int target, size_t stride) {
  ojson buffer = ojson::object();
  buffer["byteLength"] = bytes.size();
  if (!doc.json.contains("buffers")) doc.json["buffers"] = ojson::array();
  doc.json["buffers"].push_back(buffer);
  doc.buffers.push_back(std::move(bytes));
  ojson view = ojson::object();
  view["buffer"] = doc.buffers.size() - 1;
  view["byteLength"] = doc.buffers.back().size();
  if (stride) view["byteStride"] = stride;
  if (target) view["target"] = target;
  if (!doc.json.contains("bufferViews")) doc.json["bufferViews"] = ojson::array();
  doc.json["bufferViews"].push_back(view);
  return doc.json["bufferViews"].size() - 1;
}

std::string pack_values(const std::vector<double>& raw, int ct, uint32_t components, int target, size_t* stride) {
  const size_t cb = component_bytes(ct);
  size_t elem = cb * components;
  if (target == kArrayBuffer) elem = (elem + 3) / 4 * 4;
  if (stride) *stride = target == kArrayBuffer && elem != cb * components ? elem : 0;
  const size_t count = components ? raw.size() / components : 0;
  std::string out(count * elem, '\0');
  for (size_t i = 0; i < count; ++i)
    for (uint32_t c = 0; c < components; ++c) {
      char* p = &out[i * elem + c * cb];
      const double v = raw[i * components + c];
      if (ct == kFloat) {
        const float f = static_cast<float>(v);
        std::memcpy(p, &f, 4);
        continue;
      }
      double lo = 0, hi = 0;
      switch (ct) {
        case kByte: lo = -128, hi = 127; break;
        case kUByte: hi = 255; break;
        case kShort: lo = -32768, hi = 32767; break;
        case kUShort: hi = 65535; break;
        default: hi = 4294967295.0;
      }
      const double r = std::min(hi, std::max(lo, std::nearbyint(v)));
      const int64_t iv = static_cast<int64_t>(r);
      for (size_t b = 0; b < cb; ++b) p[b] = static_cast<char>((static_cast<uint64_t>(iv) >> (8 * b)) & 0xFF);
    }
  return out;
}

void use_extension(ojson& json, const std::string& name, bool required) {
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    if (!required && std::strcmp(key, "extensionsRequired") == 0) break;
    if (!json.contains(key) || !json[key].is_array()) json[key] = ojson::array();
    bool there = false;
    for (const ojson& e : json[key]) there = there || e == name;
    if (!there) json[key].push_back(name);
  }
}

void drop_extension(ojson& json, const std::string& name) {
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    if (!json.contains(key) || !json[key].is_array()) continue;
    ojson kept = ojson::array();
    for (const ojson& e : json[key])
      if (e != name) kept.push_back(e);
    if (kept.empty())
      json.erase(key);
    else
      json[key] = kept;
  }
}

namespace {

// An attribute KHR_mesh_quantization lets be an integer type.
bool quantizable_semantic(const std::string& semantic) {
  return semantic == "POSITION" || semantic == "NORMAL" || semantic == "TANGENT" ||
         semantic.rfind("TEXCOORD_", 0) == 0;
}

bool integer_accessor(const ojson& json, const ojson& index) {
  if (!index.is_number_unsigned() || !json.contains("accessors") || !json["accessors"].is_array()) return false;
  const size_t a = index.get<size_t>();
  if (a >= json["accessors"].size() || !json["accessors"][a].is_object()) return false;
  const ojson& type = json["accessors"][a].contains("componentType") ? json["accessors"][a]["componentType"] : ojson();
  return type.is_number() && type != kFloat;
}

bool uses_quantized_attribute(const ojson& json, const ojson& attributes) {
  if (!attributes.is_object()) return false;
  for (auto it = attributes.begin(); it != attributes.end(); ++it)
    if (quantizable_semantic(it.key()) && integer_accessor(json, it.value())) return true;
  return false;
}

}  // namespace

void drop_unused_mesh_quantization(ojson& json) {
  if (!json.contains("meshes") || !json["meshes"].is_array()) {
    drop_extension(json, "KHR_mesh_quantization");
    return;
  }
  for (const ojson& mesh : json["meshes"]) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (const ojson& prim : mesh["primitives"]) {
      if (!prim.is_object()) continue;
      if (prim.contains("attributes") && uses_quantized_attribute(json, prim["attributes"])) return;
      if (prim.contains("targets") && prim["targets"].is_array())
        for (const ojson& target : prim["targets"])
          if (uses_quantized_attribute(json, target)) return;
    }
  }
  drop_extension(json, "KHR_mesh_quantization");
}

std::vector<std::string> image_files(const Document& doc) {
  std::vector<std::string> out;
  for (size_t i = 0; i < doc.count_of("images"); ++i) {
    const ojson& im = doc.json["images"][i];
    if (im.is_object() && im.contains("uri") && im["uri"].is_string()) {
      const std::string uri = im["uri"].get<std::string>();
      if (uri.compare(0, 5, "data:") != 0) out.push_back(uri);
    }
  }
  return out;
}

namespace {

// Extensions known to name buffer views under other keys than "bufferView"
// (property tables: "values", "arrayOffsets", "stringOffsets"). With one of
// them in extensionsUsed no buffer view is dropped; every other extension
// (KHR_draco_mesh_compression, KHR_texture_basisu, EXT_mesh_gpu_instancing,
// ...) follows the core's convention of a "bufferView" member.
bool views_all_known(const ojson& json) {
  static const std::set<std::string> other_keys = {"EXT_structural_metadata", "EXT_mesh_features",
                                                   "EXT_instance_features", "EXT_feature_metadata"};
  if (!json.contains("extensionsUsed") || !json["extensionsUsed"].is_array()) return true;
  for (const ojson& e : json["extensionsUsed"])
    if (e.is_string() && other_keys.count(e.get<std::string>())) return false;
  return true;
}

void collect_views(const ojson& j, std::set<uint64_t>& used) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "bufferView" && it.value().is_number_unsigned())
        used.insert(it.value().get<uint64_t>());
      else
        collect_views(it.value(), used);
    }
  } else if (j.is_array()) {
    for (const ojson& e : j) collect_views(e, used);
  }
}

void renumber_views(ojson& j, const std::map<uint64_t, uint64_t>& to) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "bufferView" && it.value().is_number_unsigned()) {
        const auto f = to.find(it.value().get<uint64_t>());
        if (f != to.end()) it.value() = f->second;
      } else {
        renumber_views(it.value(), to);
      }
    }
  } else if (j.is_array()) {
    for (ojson& e : j) renumber_views(e, to);
  }
}

// Animation and skin accessors must not use a view with byteStride (the
// spec; some exporters add one anyway): drop it from views that no vertex
// attribute uses and whose accessors are tightly packed, which means the same.
void drop_needless_strides(Document& doc) {
  const size_t views = doc.count_of("bufferViews");
  std::vector<char> vertex(views, 0), loose(views, 0);
  for (size_t m = 0; m < doc.count_of("meshes"); ++m) {
    const ojson& mesh = doc.json["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (const ojson& p : mesh["primitives"]) {
      std::vector<const ojson*> maps;
      if (p.is_object() && p.contains("attributes")) maps.push_back(&p["attributes"]);
      if (p.is_object() && p.contains("targets") && p["targets"].is_array())
        for (const ojson& t : p["targets"]) maps.push_back(&t);
      for (const ojson* map : maps) {
        if (!map->is_object()) continue;
        for (const auto& kv : map->items()) {
          if (!kv.value().is_number_unsigned() || kv.value().get<uint64_t>() >= doc.count_of("accessors")) continue;
          const ojson& a = doc.json["accessors"][kv.value().get<size_t>()];
          if (a.is_object() && a.contains("bufferView") && a["bufferView"].is_number_unsigned() &&
              a["bufferView"].get<uint64_t>() < views)
            vertex[a["bufferView"].get<size_t>()] = 1;
        }
      }
    }
  }
  for (size_t i = 0; i < doc.count_of("accessors"); ++i) {
    const ojson& a = doc.json["accessors"][i];
    if (!a.is_object() || !a.contains("bufferView") || !a["bufferView"].is_number_unsigned() ||
        a["bufferView"].get<uint64_t>() >= views)
      continue;
    const size_t v = a["bufferView"].get<size_t>();
    const ojson& view = doc.json["bufferViews"][v];
    const std::string type = a.contains("type") && a["type"].is_string() ? a["type"].get<std::string>() : "";
    const size_t columns = type == "MAT4" ? 16 : type == "MAT3" ? 9 : type == "MAT2" ? 4 : type_components(type);
    const size_t elem = component_bytes(a.value("componentType", 0)) * columns;
    if (!view.is_object() || !view.contains("byteStride") || view["byteStride"] != elem) loose[v] = 1;
  }
  for (size_t v = 0; v < views; ++v) {
    ojson& view = doc.json["bufferViews"][v];
    if (view.is_object() && view.contains("byteStride") && !vertex[v] && !loose[v]) view.erase("byteStride");
  }
}

}  // namespace

Status save_document(Document& doc, bool binary, const std::string& bin_uri, std::string& main, std::string& bin) {
  ojson& json = doc.json;
  drop_needless_strides(doc);
  const size_t views = doc.count_of("bufferViews");
  std::set<uint64_t> used;
  if (views_all_known(json)) {
    ojson scan = json;
    scan.erase("bufferViews");
    collect_views(scan, used);
  } else {
    for (size_t i = 0; i < views; ++i) used.insert(i);
  }
  // Pack the used views into one buffer, each at a multiple of 4.
  ojson new_views = ojson::array();
  std::map<uint64_t, uint64_t> to;
  bin.clear();
  for (size_t i = 0; i < views; ++i) {
    if (!used.count(i)) continue;
    std::string_view bytes;
    size_t stride = 0;
    TSM_RETURN_IF_ERROR(view_bytes(doc, i, bytes, stride));
    bin.resize((bin.size() + 3) / 4 * 4, '\0');
    ojson v = json["bufferViews"][i];
    v["buffer"] = 0;
    if (bin.empty())
      v.erase("byteOffset");
    else
      v["byteOffset"] = bin.size();
    // byteOffset first, as usual.
    ojson ordered = ojson::object();
    ordered["buffer"] = 0;
    if (v.contains("byteOffset")) ordered["byteOffset"] = v["byteOffset"];
    for (auto it = v.begin(); it != v.end(); ++it)
      if (it.key() != "buffer" && it.key() != "byteOffset") ordered[it.key()] = it.value();
    bin.append(bytes.data(), bytes.size());
    to[i] = new_views.size();
    new_views.push_back(ordered);
  }
  renumber_views(json, to);
  if (new_views.empty()) {
    json.erase("bufferViews");
    json.erase("buffers");
  } else {
    json["bufferViews"] = new_views;
    ojson buffer = ojson::object();
    buffer["byteLength"] = bin.size();
    if (!binary) buffer["uri"] = bin_uri;
    json["buffers"] = ojson::array({buffer});
  }
  doc.buffers.assign(1, bin);
  json["asset"]["generator"] = std::string("tsm ") + TSM_VERSION_STRING;
  std::string text = json.dump();
  if (!binary) {
    main = std::move(text);
    return Status::Ok();
  }
  text.resize((text.size() + 3) / 4 * 4, ' ');
  const size_t bin_padded = (bin.size() + 3) / 4 * 4;
  const uint64_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin_padded);
  if (total > std::numeric_limits<uint32_t>::max())
    return Status(ErrorCode::limit_exceeded, doc.name + ": the output is larger than a GLB can hold (4 GiB)");
  main.clear();
  main.reserve(total);
  put_u32(main, kGlbMagic);
  put_u32(main, 2);
  put_u32(main, static_cast<uint32_t>(total));
  put_u32(main, static_cast<uint32_t>(text.size()));
  put_u32(main, kChunkJson);
  main += text;
  if (!bin.empty()) {
    put_u32(main, static_cast<uint32_t>(bin_padded));
    put_u32(main, kChunkBin);
    main += bin;
    main.resize(total, '\0');
  }
  return Status::Ok();
}

}  // namespace tsm::gltf
