// The TSM_mesh_compression writer (format-spec/gltf/TSM_mesh_compression.md):
// each triangle primitive of a plain glTF document becomes one tsm stream in
// a buffer view. The encoder decodes its own stream and writes the
// primitive's accessors from the decoded mesh (count, type, min / max; with
// --fallback their data too), so that accessors and stream agree. Morph
// targets' float POSITION / NORMAL / TANGENT displacements go into the stream
// as integers on a power-of-two grid (zero stays exactly zero). Attributes
// the stream does not hold exactly enough (float custom attributes) are
// written as ordinary accessors in the decoded vertex order, which a second
// encoding with a vertex-number attribute tells (checked to give the same
// mesh). Primitives naming the same accessors (indices, attributes, targets)
// share one stream and its accessors, as they shared the input's.
// Also the top-level transcoder: load, decode compressed input, compress (or
// not: tsm decode), embed or copy images, save.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "gltf_document.hpp"
#include "gltf_files.hpp"
#include "gltf_transcode_internal.hpp"
#include "tsm/io.hpp"

namespace tsm::gltf {

namespace {

constexpr int kPrimitiveTriangles = 4;
// Vertex numbers travel as float values of an i32 attribute: exact below 2^24.
constexpr size_t kMaxNumberedVertices = size_t(1) << 24;
// The codec's limit on a stream's attributes (targets past it stay ordinary accessors).
constexpr size_t kMaxStreamAttributes = 64;
// A morph target's grid units: integers exact as floats (2^24), and steps
// that keep units x step a normal float.
constexpr double kMaxTargetUnits = 16777216.0;
constexpr int kMinTargetStepExponent = -100;

// One attribute (or morph target) of the primitive being compressed.
struct Slot {
  std::string semantic;
  int target = -1;  // morph target index, -1 for the primitive's attributes
  size_t accessor = 0;
  AccessorData data;
  int stream = -1;  // index in the stream's attributes; -1: an ordinary accessor
  double step = 0;  // a morph target in the stream: its values are the stream's integers x step
  // The accessor the stream's values fill.
  int out_type = kFloat;
  bool out_normalized = false;
};

bool starts_with(const std::string& s, const char* prefix) { return s.compare(0, std::strlen(prefix), prefix) == 0; }

// Float skin weights as normalized unsigned shorts (a type the glTF core
// allows for WEIGHTS_n), each vertex's summing to exactly 65535 when its
// floats sum to 1: coded exactly from there.
std::vector<float> weights_u16(const AccessorData& d) {
  std::vector<float> out(d.raw.size());
  for (size_t i = 0; i < d.count; ++i) {
    double sum = 0, qsum = 0;
    size_t largest = 0;
    for (uint32_t c = 0; c < d.components; ++c) {
      const size_t k = i * d.components + c;
      sum += d.raw[k];
      out[k] = static_cast<float>(std::nearbyint(std::min(1.0, std::max(0.0, d.raw[k])) * 65535.0));
      qsum += out[k];
      if (d.raw[k] > d.raw[i * d.components + largest]) largest = c;
    }
    const size_t k = i * d.components + largest;
    if (std::fabs(sum - 1.0) < 1e-3 && out[k] + (65535.0 - qsum) >= 0 && out[k] + (65535.0 - qsum) <= 65535.0)
      out[k] += static_cast<float>(65535.0 - qsum);
  }
  return out;
}

// How a primitive attribute goes into the stream: false when it stays an
// ordinary accessor. Integer accessors are coded exactly (their values and
// componentType kept); NORMAL as unit vectors; float TEXCOORD_n, COLOR_n and
// TANGENT quantized; float WEIGHTS_n as normalized unsigned shorts.
bool stream_attribute(const std::string& sem, const AccessorData& d, Attribute& att, int& out_type,
                      bool& out_normalized) {
  att = Attribute();
  att.components = d.components;
  out_type = kFloat;
  out_normalized = false;
  if (starts_with(sem, "WEIGHTS_") && d.component_type == kFloat) {
    att.name = sem;
    att.type = AttributeType::u16;
    att.values = weights_u16(d);
    out_type = kUShort;
    out_normalized = true;
    return true;
  }
  if (sem == "NORMAL" && d.components == 3) {
    att.name = "normal";
    att.kind = AttributeKind::normal;
    att.values = d.values();
    return true;
  }
  const bool color = starts_with(sem, "COLOR_") && (d.components == 3 || d.components == 4);
  att.name = sem == "COLOR_0"                ? "color"
             : color                         ? "color" + sem.substr(6)
             : starts_with(sem, "TEXCOORD_") ? "texcoord" + sem.substr(9)
                                             : sem;
  if (d.component_type != kFloat) {
    att.type = d.component_type == kUByte    ? AttributeType::u8
               : d.component_type == kUShort ? AttributeType::u16
                                             : AttributeType::i32;
    if (color && att.type != AttributeType::i32) att.kind = AttributeKind::color;
    att.values.assign(d.raw.begin(), d.raw.end());
    out_type = d.component_type;
    out_normalized = d.normalized;
    return true;
  }
  if (starts_with(sem, "TEXCOORD_") && d.components == 2)
    att.kind = AttributeKind::texcoord;
  else if (color)
    att.kind = AttributeKind::color;
  else if (!(sem == "TANGENT" && d.components == 4))
    return false;
  att.values = d.values();
  return true;
}

// The grid of a morph target's displacements (TSM_mesh_compression.md,
// "targets"): a power of two, so that units x step is exactly a float and a
// zero displacement stays zero. POSITION: the largest power of two not above
// the position grid's step (the precision of the positions); NORMAL and
// TANGENT: 2^-normal bits. 0: the semantic stays an ordinary accessor.
double target_step(const std::string& sem, const Mesh& mesh, const EncodeOptions& o) {
  if (sem == "NORMAL" || sem == "TANGENT") return std::ldexp(1.0, -o.attribute_bits.normal);
  if (sem != "POSITION" || o.lossless) return 0;
  const double step = Grid::for_mesh(mesh, o.quantization_bits).step;
  if (!(step > 0) || std::ilogb(step) < kMinTargetStepExponent) return 0;
  return std::ldexp(1.0, std::ilogb(step));
}

// A float VEC3 morph target as a stream attribute: its values in grid units,
// coded exactly (i32). False when it is not one or a value is off the range.
bool stream_target(const Slot& s, double step, Attribute& att) {
  if (!(step > 0) || s.data.component_type != kFloat || s.data.components != 3) return false;
  att = Attribute();
  att.name = s.semantic.substr(0, 1) + std::to_string(s.target);  // P0, N0, T0 (informative only)
  att.type = AttributeType::i32;
  att.components = 3;
  att.values.resize(s.data.raw.size());
  for (size_t i = 0; i < att.values.size(); ++i) {
    const double units = std::nearbyint(s.data.raw[i] / step) + 0.0;  // -0 as 0
    if (!(std::fabs(units) <= kMaxTargetUnits)) return false;
    att.values[i] = static_cast<float>(units);
  }
  return true;
}

// How many times each accessor is named where the transcoder knows to look.
std::vector<int> accessor_references(const Document& doc) {
  std::vector<int> refs(doc.count_of("accessors"), 0);
  auto add = [&](const ojson& v) {
    if (v.is_number_unsigned() && v.get<uint64_t>() < refs.size()) ++refs[v.get<size_t>()];
  };
  auto add_values = [&](const ojson& obj) {
    if (obj.is_object())
      for (const auto& kv : obj.items()) add(kv.value());
  };
  for (size_t m = 0; m < doc.count_of("meshes"); ++m) {
    const ojson& mesh = doc.json["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (const ojson& p : mesh["primitives"]) {
      if (!p.is_object()) continue;
      if (p.contains("attributes")) add_values(p["attributes"]);
      if (p.contains("indices")) add(p["indices"]);
      if (p.contains("targets") && p["targets"].is_array())
        for (const ojson& t : p["targets"]) add_values(t);
    }
  }
  for (size_t a = 0; a < doc.count_of("animations"); ++a) {
    const ojson& anim = doc.json["animations"][a];
    if (anim.is_object() && anim.contains("samplers") && anim["samplers"].is_array())
      for (const ojson& s : anim["samplers"])
        if (s.is_object()) {
          if (s.contains("input")) add(s["input"]);
          if (s.contains("output")) add(s["output"]);
        }
  }
  for (size_t s = 0; s < doc.count_of("skins"); ++s)
    if (doc.json["skins"][s].is_object() && doc.json["skins"][s].contains("inverseBindMatrices"))
      add(doc.json["skins"][s]["inverseBindMatrices"]);
  for (size_t n = 0; n < doc.count_of("nodes"); ++n) {
    const ojson& node = doc.json["nodes"][n];
    if (node.is_object() && node.contains("extensions") && node["extensions"].is_object() &&
        node["extensions"].contains("EXT_mesh_gpu_instancing") &&
        node["extensions"]["EXT_mesh_gpu_instancing"].is_object() &&
        node["extensions"]["EXT_mesh_gpu_instancing"].contains("attributes"))
      add_values(node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]);
  }
  return refs;
}

void strip_data(ojson& a) {
  for (const char* key : {"bufferView", "byteOffset", "sparse", "min", "max"}) a.erase(key);
}

// The accessor a compressed primitive writes instead of `old`: `old` itself
// when nothing else names it any more (the last of the primitives sharing
// it: no accessor is left behind, and no index elsewhere changes), else a
// new one (name, extras kept).
size_t output_accessor(Document& doc, size_t old, std::vector<int>& refs) {
  --refs[old];
  if (refs[old] == 0) {
    strip_data(doc.json["accessors"][old]);
    return old;
  }
  ojson copy = doc.json["accessors"][old];
  strip_data(copy);
  doc.json["accessors"].push_back(copy);
  refs.push_back(1);
  return doc.json["accessors"].size() - 1;
}

// Describes accessor `acc` as `count` values; with data (`raw` given and
// `with_data`), writes them into a new buffer view.
void write_accessor(Document& doc, size_t acc, int ct, bool normalized, uint32_t components,
                    const std::vector<double>& raw, bool with_data, bool min_max, int target) {
  ojson& a = doc.json["accessors"][acc];
  a["componentType"] = ct;
  a["count"] = raw.size() / components;
  a["type"] = type_for_components(components);
  if (normalized)
    a["normalized"] = true;
  else
    a.erase("normalized");
  if (min_max) set_min_max(a, raw, components);
  if (!with_data) return;
  size_t stride = 0;
  std::string bytes = pack_values(raw, ct, components, target, &stride);  // sets stride first
  a["bufferView"] = add_buffer_view(doc, std::move(bytes), target, stride);
}

// Values of an ordinary accessor in the decoded vertex order.
std::vector<double> reordered(const AccessorData& d, const std::vector<uint32_t>& order) {
  std::vector<double> out(order.size() * d.components);
  for (size_t i = 0; i < order.size(); ++i)
    for (uint32_t c = 0; c < d.components; ++c) out[i * d.components + c] = d.raw[order[i] * d.components + c];
  return out;
}

// The decoded vertex order of `mesh` (decoded[i] is input vertex order[i]):
// encodes it again with the vertex numbers as an attribute and checks that
// this gives the same mesh. False when it does not (or cannot be told).
bool decoded_order(const Mesh& mesh, const Mesh& decoded, const EncodeOptions& options, std::vector<uint32_t>& order) {
  if (mesh.vertex_count() >= kMaxNumberedVertices) return false;
  Mesh numbered = mesh;
  Attribute id;
  id.name = "_tsm_vertex";
  id.type = AttributeType::i32;
  id.values.resize(mesh.vertex_count());
  for (size_t i = 0; i < id.values.size(); ++i) id.values[i] = static_cast<float>(i);
  numbered.attributes.push_back(id);
  std::string bytes;
  Mesh back;
  if (!encode(numbered, options, bytes).ok() || !decode(bytes, back).ok()) return false;
  if (back.positions != decoded.positions || back.indices != decoded.indices) return false;
  const std::vector<float>& ids = back.attributes.back().values;
  order.resize(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    if (!(ids[i] >= 0) || ids[i] >= static_cast<float>(mesh.vertex_count())) return false;
    order[i] = static_cast<uint32_t>(ids[i]);
  }
  return true;
}

// Reads the primitive's attributes and morph targets (all `n` values long).
Status read_slots(const Document& doc, const ojson& prim, const std::string& where, std::vector<Slot>& slots) {
  auto read_map = [&](const ojson& obj, int target) -> Status {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      Slot s;
      s.semantic = it.key();
      s.target = target;
      int64_t acc = -1;
      TSM_RETURN_IF_ERROR(doc.index_of(obj, it.key().c_str(), doc.count_of("accessors"), where, acc));
      s.accessor = static_cast<size_t>(acc);
      TSM_RETURN_IF_ERROR(read_accessor(doc, s.accessor, s.data));
      slots.push_back(std::move(s));
    }
    return Status::Ok();
  };
  TSM_RETURN_IF_ERROR(read_map(prim["attributes"], -1));
  if (prim.contains("targets") && prim["targets"].is_array())
    for (size_t t = 0; t < prim["targets"].size(); ++t)
      if (prim["targets"][t].is_object()) TSM_RETURN_IF_ERROR(read_map(prim["targets"][t], static_cast<int>(t)));
  return Status::Ok();
}

// Primitives that share a vertex buffer each use part of it: each keeps only
// the vertices its triangles use (in their order), so that every stream
// holds its own vertices once.
void compact_vertices(std::vector<Slot>& slots, std::vector<uint32_t>& idx, size_t n) {
  std::vector<uint32_t> remap(n, UINT32_MAX);
  for (uint32_t v : idx) remap[v] = 0;
  std::vector<uint32_t> kept;
  for (size_t v = 0; v < n; ++v)
    if (remap[v] == 0) {
      remap[v] = static_cast<uint32_t>(kept.size());
      kept.push_back(static_cast<uint32_t>(v));
    }
  if (kept.size() == n) return;
  for (uint32_t& v : idx) v = remap[v];
  for (Slot& s : slots) {
    s.data.raw = reordered(s.data, kept);
    s.data.count = kept.size();
  }
}

struct Compressor {
  Document& doc;
  const GltfTranscodeOptions& options;
  GltfTranscodeReport& report;
  std::vector<int> refs;
  // Values the primitives may read in all: accessors shared by many
  // primitives are read (and encoded) once per primitive, so a small file
  // naming one accessor from thousands of primitives is refused, not run.
  size_t budget = 0;

  Status primitive(ojson& prim, const std::string& where);
  Status write(ojson& prim, std::vector<Slot>& slots, const Mesh& decoded, const std::vector<uint32_t>& order,
               std::string stream, int indices_ct, int64_t indices);
};

Status Compressor::primitive(ojson& prim, const std::string& where) {
  auto keep = [&](const std::string& why) {
    ++report.primitives_kept;
    if (!why.empty()) report.add_note(where + " kept uncompressed: " + why);
    return Status::Ok();
  };
  if (!prim.is_object() || !prim.contains("attributes") || !prim["attributes"].is_object())
    return doc.error(where + " has no attributes object");
  if (prim.value("mode", kPrimitiveTriangles) != kPrimitiveTriangles) return keep("");
  if (!prim["attributes"].contains("POSITION")) return keep("no POSITION");
  std::vector<Slot> slots;
  TSM_RETURN_IF_ERROR(read_slots(doc, prim, where, slots));
  for (const Slot& s : slots) {
    if (s.data.raw.size() > budget)
      return doc.error(where +
                       ": the primitives read their shared accessors over and over (more values than 64 "
                       "times the file's bytes); refused");
    budget -= s.data.raw.size();
  }
  const Slot* position = nullptr;
  for (const Slot& s : slots)
    if (s.semantic == "POSITION" && s.target < 0) position = &s;
  if (position->data.components != 3) return doc.error(where + ": POSITION is not a VEC3");
  const size_t n = position->data.count;
  for (const Slot& s : slots)
    if (s.data.count != n)
      return doc.error(where + ": accessor of " + s.semantic + " has count " + std::to_string(s.data.count) +
                       ", POSITION " + std::to_string(n));
  std::vector<uint32_t> idx;
  int64_t indices = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(prim, "indices", doc.count_of("accessors"), where, indices));
  if (indices >= 0) {
    TSM_RETURN_IF_ERROR(read_indices(doc, static_cast<size_t>(indices), idx));
  } else {
    idx.resize(n);
    for (size_t i = 0; i < n; ++i) idx[i] = static_cast<uint32_t>(i);
  }
  if (idx.size() % 3 != 0) return doc.error(where + ": the triangle indices are not a multiple of 3");
  for (uint32_t v : idx)
    if (v >= n) return doc.error(where + ": a triangle index is past the vertex count " + std::to_string(n));
  if (idx.empty()) return keep("no triangles");
  compact_vertices(slots, idx, n);

  Mesh mesh;
  mesh.positions = position->data.values();
  mesh.face_offsets.resize(idx.size() / 3 + 1);
  for (size_t f = 0; f < mesh.face_offsets.size(); ++f) mesh.face_offsets[f] = static_cast<uint32_t>(3 * f);
  mesh.indices = idx;
  bool outside = false;
  for (Slot& s : slots) {
    if (s.target < 0 && s.semantic == "POSITION") continue;
    Attribute att;
    if (s.target >= 0) {
      s.step = target_step(s.semantic, mesh, options.encode);
      if (mesh.attributes.size() < kMaxStreamAttributes && stream_target(s, s.step, att)) {
        s.stream = static_cast<int>(mesh.attributes.size());
        mesh.attributes.push_back(std::move(att));
      } else {
        outside = true;
      }
      continue;
    }
    if (mesh.attributes.size() < kMaxStreamAttributes &&
        stream_attribute(s.semantic, s.data, att, s.out_type, s.out_normalized)) {
      s.stream = static_cast<int>(mesh.attributes.size());
      mesh.attributes.push_back(std::move(att));
    } else {
      outside = true;
    }
  }
  if (!mesh.all_finite()) return keep("NaN or infinite values (tsm quantizes on a grid)");

  std::string stream;
  Status s = encode(mesh, options.encode, stream);
  if (!s.ok()) return keep("the encoder refused it: " + s.message());
  Mesh decoded;
  s = decode(stream, decoded);
  if (!s.ok())
    return Status(ErrorCode::internal, doc.name + ": " + where + ": tsm cannot decode its own stream: " + s.message());
  std::vector<uint32_t> order;
  if (outside && !decoded_order(mesh, decoded, options.encode, order))
    return keep("its uncompressed attributes could not be put in the decoded vertex order");
  const int indices_ct =
      indices >= 0 ? doc.json["accessors"][static_cast<size_t>(indices)].value("componentType", kUInt) : kUInt;
  return write(prim, slots, decoded, order, std::move(stream), indices_ct, indices);
}

Status Compressor::write(ojson& prim, std::vector<Slot>& slots, const Mesh& decoded, const std::vector<uint32_t>& order,
                         std::string stream, int indices_ct, int64_t indices) {
  const bool data = options.fallback;
  const size_t n = decoded.vertex_count();
  // Indices: the input's type when every index fits it (the largest value of
  // a type is the primitive restart value, not an index), else wider.
  int ct = indices_ct;
  if (ct == kUByte && n > 255) ct = kUShort;
  if (ct != kUInt && n > 65535) ct = kUInt;
  size_t acc = 0;
  if (indices >= 0) {
    acc = output_accessor(doc, static_cast<size_t>(indices), refs);
  } else {
    doc.json["accessors"].push_back(ojson::object());
    refs.push_back(1);
    acc = doc.json["accessors"].size() - 1;
  }
  prim["indices"] = acc;
  write_accessor(doc, acc, ct, false, 1, std::vector<double>(decoded.indices.begin(), decoded.indices.end()), data,
                 false, kElementArrayBuffer);
  ojson ext_attributes = ojson::object();
  ojson ext_targets = ojson::array(), steps = ojson::object();
  if (prim.contains("targets") && prim["targets"].is_array())
    for (size_t t = 0; t < prim["targets"].size(); ++t) ext_targets.push_back(ojson::object());
  for (Slot& s : slots) {
    ojson& holder = s.target < 0 ? prim["attributes"] : prim["targets"][static_cast<size_t>(s.target)];
    const bool had_min_max = doc.json["accessors"][s.accessor].contains("min") || s.semantic == "POSITION";
    acc = output_accessor(doc, s.accessor, refs);
    holder[s.semantic] = acc;
    if (s.semantic == "POSITION" && s.target < 0) {
      write_accessor(doc, acc, kFloat, false, 3,
                     std::vector<double>(decoded.positions.begin(), decoded.positions.end()), data, true, kArrayBuffer);
    } else if (s.stream >= 0 && s.target >= 0) {
      const Attribute& att = decoded.attributes[static_cast<size_t>(s.stream)];
      std::vector<double> values(att.values.size());
      for (size_t i = 0; i < values.size(); ++i) values[i] = target_delta(att.values[i], s.step);
      write_accessor(doc, acc, kFloat, false, 3, values, data, had_min_max, kArrayBuffer);
      ext_targets[static_cast<size_t>(s.target)][s.semantic] = s.stream;
      steps[s.semantic] = s.step;
    } else if (s.stream >= 0) {
      const Attribute& att = decoded.attributes[static_cast<size_t>(s.stream)];
      write_accessor(doc, acc, s.out_type, s.out_normalized, s.data.components,
                     std::vector<double>(att.values.begin(), att.values.end()), data, false, kArrayBuffer);
      ext_attributes[s.semantic] = s.stream;
    } else {
      write_accessor(doc, acc, s.data.component_type, s.data.normalized, s.data.components, reordered(s.data, order),
                     true, had_min_max, kArrayBuffer);
    }
  }
  report.stream_bytes += stream.size();
  report.vertices += n;
  report.triangles += decoded.face_count();
  ++report.primitives_compressed;
  ojson ext = ojson::object();
  ext["bufferView"] = add_buffer_view(doc, std::move(stream), 0, 0);
  ext["attributes"] = ext_attributes;
  if (!steps.empty()) {
    ext["targets"] = ext_targets;
    ext["targetSteps"] = steps;
  }
  if (!prim.contains("extensions") || !prim["extensions"].is_object()) prim["extensions"] = ojson::object();
  prim["extensions"]["TSM_mesh_compression"] = ext;
  return Status::Ok();
}

const char* image_mime_type(const std::string& uri) {
  std::string ext = std::filesystem::path(uri).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".webp") return "image/webp";
  if (ext == ".ktx2") return "image/ktx2";
  return nullptr;
}

// GLB output: images named by relative URI move into the binary chunk.
Status embed_images(Document& doc, GltfTranscodeReport& report) {
  for (size_t i = 0; i < doc.count_of("images"); ++i) {
    ojson& im = doc.json["images"][i];
    if (!im.is_object() || !im.contains("uri") || !im["uri"].is_string()) continue;
    const std::string uri = im["uri"].get<std::string>();
    const char* mime = image_mime_type(uri);
    if (uri.compare(0, 5, "data:") == 0 || !mime) continue;
    std::string bytes;
    Status s = read_file_beside(doc.dir, uri, bytes);
    if (!s.ok()) {
      report.add_note("images[" + std::to_string(i) + "] left as an external file: " + s.message());
      continue;
    }
    im.erase("uri");
    im["mimeType"] = mime;
    im["bufferView"] = add_buffer_view(doc, std::move(bytes), 0, 0);
  }
  return Status::Ok();
}

}  // namespace

std::string sharing_key(const ojson& prim) {
  if (!prim.is_object()) return {};
  nlohmann::json key = nlohmann::json::object();  // sorted members
  for (const char* k : {"attributes", "indices", "targets"})
    if (prim.contains(k)) key[k] = nlohmann::json::parse(prim[k].dump());
  key["mode"] =
      prim.contains("mode") ? nlohmann::json::parse(prim["mode"].dump()) : nlohmann::json(kPrimitiveTriangles);
  return key.dump();
}

namespace {

// The accessors a primitive names (attributes, indices, targets), each as
// often as accessor_references counts it.
std::vector<size_t> named_accessors(const ojson& prim) {
  std::vector<size_t> out;
  auto one = [&](const ojson& v) {
    if (v.is_number_unsigned()) out.push_back(v.get<size_t>());
  };
  auto values = [&](const ojson& obj) {
    if (obj.is_object())
      for (const auto& kv : obj.items()) one(kv.value());
  };
  if (prim.contains("attributes")) values(prim["attributes"]);
  if (prim.contains("indices")) one(prim["indices"]);
  if (prim.contains("targets") && prim["targets"].is_array())
    for (const ojson& t : prim["targets"]) values(t);
  return out;
}

// Primitives repeating an earlier one's accessors will name the first one's
// output: the references they add are taken off, so that the first one's
// accessors count once for the whole group.
void count_groups_once(Document& doc, std::vector<int>& refs) {
  std::map<std::string, int> seen;
  for (size_t m = 0; m < doc.count_of("meshes"); ++m) {
    const ojson& mesh = doc.json["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (const ojson& prim : mesh["primitives"]) {
      const std::string key = sharing_key(prim);
      if (!key.empty() && seen[key]++ > 0)
        for (size_t a : named_accessors(prim))
          if (a < refs.size()) --refs[a];
    }
  }
}

// A primitive with the same accessors as `first` (already done): names
// first's stream and accessors, or stays uncompressed as first did.
void share_primitive(ojson& prim, const ojson& first, GltfTranscodeReport& report) {
  if (!first.contains("extensions") || !first["extensions"].contains("TSM_mesh_compression")) {
    ++report.primitives_kept;
    return;
  }
  for (const char* k : {"attributes", "indices", "targets"})
    if (first.contains(k)) prim[k] = first[k];
  if (!prim.contains("extensions") || !prim["extensions"].is_object()) prim["extensions"] = ojson::object();
  prim["extensions"]["TSM_mesh_compression"] = first["extensions"]["TSM_mesh_compression"];
  ++report.primitives_compressed;
  ++report.primitives_shared;
}

}  // namespace

Status compress_document(Document& doc, const GltfTranscodeOptions& options, GltfTranscodeReport& report) {
  Compressor c{doc, options, report, accessor_references(doc), size_t(1) << 20};
  for (const std::string& b : doc.buffers) c.budget += 64 * b.size();
  count_groups_once(doc, c.refs);
  std::map<std::string, ojson> done;  // sharing key -> the first such primitive, as written
  for (size_t m = 0; m < doc.count_of("meshes"); ++m) {
    ojson& mesh = doc.json["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (size_t p = 0; p < mesh["primitives"].size(); ++p) {
      ojson& prim = mesh["primitives"][p];
      const std::string key = sharing_key(prim);
      const auto first = done.find(key);
      if (!key.empty() && first != done.end()) {
        share_primitive(prim, first->second, report);
        continue;
      }
      TSM_RETURN_IF_ERROR(c.primitive(prim, "meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]"));
      if (!key.empty()) done.emplace(key, prim);
    }
  }
  if (report.primitives_compressed > 0) use_extension(doc.json, "TSM_mesh_compression", !options.fallback);
  return Status::Ok();
}

}  // namespace tsm::gltf

namespace tsm {

namespace {

// A URI's file name ("%20" -> ' '); the URI was checked by read_file_beside.
std::string percent_decoded(const std::string& s) {
  std::string r;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      r += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      r += s[i];
    }
  }
  return r;
}

}  // namespace

Status transcode_gltf(std::string_view bytes, const std::string& name, const std::string& dir,
                      const GltfTranscodeOptions& options, bool binary, const std::string& bin_uri, GltfOutput& out,
                      GltfTranscodeReport* report) {
  GltfTranscodeReport local;
  GltfTranscodeReport& r = report ? *report : local;
  r = GltfTranscodeReport();
  out = GltfOutput();
  try {
    gltf::Document doc;
    TSM_RETURN_IF_ERROR(gltf::load_document(bytes, name, dir, doc));
    TSM_RETURN_IF_ERROR(gltf::decompress_document(doc));
    if (options.compress) TSM_RETURN_IF_ERROR(gltf::compress_document(doc, options, r));
    if (binary) {
      TSM_RETURN_IF_ERROR(gltf::embed_images(doc, r));
    } else {
      for (const std::string& uri : gltf::image_files(doc)) {
        std::string image;
        Status s = read_file_beside(dir, uri, image);
        if (s.ok())
          out.files.emplace_back(uri, std::move(image));
        else
          r.add_note("image \"" + uri + "\" not copied: " + s.message());
      }
    }
    gltf::drop_unused_mesh_quantization(doc.json);
    std::string bin;
    TSM_RETURN_IF_ERROR(gltf::save_document(doc, binary, bin_uri, out.main, bin));
    if (!binary && !bin.empty()) out.files.insert(out.files.begin(), {bin_uri, std::move(bin)});
    return Status::Ok();
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::limit_exceeded, name + ": out of memory");
  } catch (const std::exception& e) {  // a JSON member of an unexpected type
    return Status(ErrorCode::parse_error, name + ": invalid glTF: " + e.what());
  }
}

Status transcode_gltf_file(const std::string& input, const std::string& output, const GltfTranscodeOptions& options,
                           GltfTranscodeReport* report) {
  namespace fs = std::filesystem;
  std::string bytes;
  TSM_RETURN_IF_ERROR(read_file(input, bytes));
  const fs::path in_dir = fs::path(input).parent_path().empty() ? fs::path(".") : fs::path(input).parent_path();
  const fs::path out_path(output);
  const fs::path out_dir = out_path.parent_path().empty() ? fs::path(".") : out_path.parent_path();
  const bool binary = format_from_extension(output) != MeshFormat::gltf;
  const std::string bin_uri = out_path.stem().string() + ".bin";
  GltfOutput out;
  TSM_RETURN_IF_ERROR(transcode_gltf(bytes, input, in_dir.string(), options, binary, bin_uri, out, report));
  std::error_code ec;
  fs::create_directories(out_dir, ec);  // missing folders are made, as for .tsm outputs
  const bool same_dir = fs::equivalent(in_dir, out_dir, ec);
  for (const auto& file : out.files) {
    const bool image = file.first != bin_uri;
    if (image && same_dir) continue;  // already beside the output
    const fs::path target = out_dir / percent_decoded(file.first);
    if (image && fs::exists(target, ec)) {  // never replaced: it may be another asset's
      if (report) report->add_note("image " + target.string() + " exists already, left as it is");
      continue;
    }
    if (image) fs::create_directories(target.parent_path(), ec);
    TSM_RETURN_IF_ERROR(write_file_atomic(target.string(), file.second));
  }
  return write_file_atomic(output, out.main);
}

}  // namespace tsm
