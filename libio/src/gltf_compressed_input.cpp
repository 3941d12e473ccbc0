// Compressed glTF input for the transcoder: turns every compressed part of a
// document into ordinary accessors and buffer views, so the rest of the
// transcoder sees a plain glTF. Handles
//   - TSM_mesh_compression (format-spec/gltf/TSM_mesh_compression.md): the
//     primitive's tsm stream decoded by the codec, morph targets included; a
//     stream several primitives name (with the same accessors) once;
//   - KHR_draco_mesh_compression: the primitive's Draco stream decoded by
//     Draco's decoder (Debian libdraco-dev, when the build found it);
//   - EXT_meshopt_compression / KHR_meshopt_compression: compressed buffer
//     views decoded by meshoptimizer (Debian libmeshoptimizer-dev, when
//     found), filters included.
// Without the library a file that needs it is refused with the package to
// install. Decoded counts are checked against the accessors they fill.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "gltf_document.hpp"
#include "gltf_transcode_internal.hpp"
#include "tsm/tsm.hpp"

#ifdef TSM_IO_HAVE_DRACO
#include <draco/compression/decode.h>
#endif
#ifdef TSM_IO_HAVE_MESHOPT
#include <meshoptimizer.h>
#endif

namespace tsm::gltf {

namespace {

constexpr size_t kMaxDecodedView = size_t(1) << 30;
// meshoptimizer's codecs shrink data at most 64 times (the vertex codec's
// 2-bit header per 16 bytes): a view claiming more is refused before the
// allocation.
constexpr uint64_t kMaxMeshoptRatio = 128;

// The bytes of a buffer view (checked), for an extension's stream.
Status stream_bytes(const Document& doc, const ojson& ext, const std::string& where, std::string_view& out) {
  int64_t view = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(ext, "bufferView", doc.count_of("bufferViews"), where, view));
  if (view < 0) return doc.error(where + " names no bufferView");
  const ojson& v = doc.json["bufferViews"][static_cast<size_t>(view)];
  int64_t buffer = -1;
  const std::string vw = "bufferViews[" + std::to_string(view) + "]";
  TSM_RETURN_IF_ERROR(doc.index_of(v, "buffer", doc.buffers.size(), vw, buffer));
  if (buffer < 0 || !v.contains("byteLength") || !v["byteLength"].is_number_unsigned())
    return doc.error(vw + " needs buffer and byteLength");
  const uint64_t offset = v.value("byteOffset", uint64_t(0)), length = v["byteLength"].get<uint64_t>();
  const std::string& data = doc.buffers[static_cast<size_t>(buffer)];
  if (offset > data.size() || length > data.size() - offset)
    return doc.error(vw + " lies outside buffers[" + std::to_string(buffer) + "] (" + std::to_string(data.size()) +
                     " bytes)");
  out = std::string_view(data).substr(offset, length);
  return Status::Ok();
}

// Components of an attribute accessor, checked.
Status accessor_shape(const Document& doc, size_t acc, int& ct, uint32_t& components) {
  const ojson& a = doc.json["accessors"][acc];
  ct = a.value("componentType", 0);
  components = a.contains("type") && a["type"].is_string() ? type_components(a["type"].get<std::string>()) : 0;
  if (component_bytes(ct) == 0 || components == 0)
    return doc.error("accessors[" + std::to_string(acc) + "] has an unknown componentType or type");
  return Status::Ok();
}

// The semantic -> accessor map of a primitive, checked.
Status primitive_accessor(const Document& doc, const ojson& prim, const std::string& semantic, const std::string& where,
                          size_t& acc) {
  const ojson& attrs = prim["attributes"];
  int64_t a = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(attrs, semantic.c_str(), doc.count_of("accessors"), where + ".attributes", a));
  if (a < 0) return doc.error(where + ": the extension names " + semantic + ", which the primitive does not have");
  acc = static_cast<size_t>(a);
  return Status::Ok();
}

#ifdef TSM_IO_HAVE_DRACO
Status decode_draco(Document& doc, ojson& prim, const std::string& where) {
  const ojson& ext = prim["extensions"]["KHR_draco_mesh_compression"];
  const std::string ew = where + ".extensions.KHR_draco_mesh_compression";
  std::string_view bytes;
  TSM_RETURN_IF_ERROR(stream_bytes(doc, ext, ew, bytes));
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    return Status(ErrorCode::parse_error,
                  doc.name + ": " + ew + ": Draco cannot decode the stream: " + decoded.status().error_msg_string());
  const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  const size_t points = mesh->num_points();
  if (prim.contains("indices")) {
    int64_t ia = -1;
    TSM_RETURN_IF_ERROR(doc.index_of(prim, "indices", doc.count_of("accessors"), where, ia));
    std::vector<double> idx;
    idx.reserve(size_t(mesh->num_faces()) * 3);
    for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
      for (int k = 0; k < 3; ++k) idx.push_back(mesh->face(f)[k].value());
    TSM_RETURN_IF_ERROR(fill_accessor(doc, static_cast<size_t>(ia), idx, 1, kElementArrayBuffer));
  }
  if (!ext.contains("attributes") || !ext["attributes"].is_object()) return doc.error(ew + " has no attributes");
  for (auto it = ext["attributes"].begin(); it != ext["attributes"].end(); ++it) {
    size_t acc = 0;
    TSM_RETURN_IF_ERROR(primitive_accessor(doc, prim, it.key(), where, acc));
    if (!it.value().is_number_unsigned()) return doc.error(ew + ".attributes." + it.key() + " is not an id");
    const draco::PointAttribute* att = mesh->GetAttributeByUniqueId(it.value().get<uint32_t>());
    if (!att) return doc.error(ew + ".attributes." + it.key() + ": the Draco stream has no attribute of that id");
    int ct = 0;
    uint32_t n = 0;
    TSM_RETURN_IF_ERROR(accessor_shape(doc, acc, ct, n));
    std::vector<double> raw(points * n);
    float f[4] = {0, 0, 0, 0};
    int32_t i32[4] = {0, 0, 0, 0};
    for (size_t p = 0; p < points; ++p) {
      const draco::AttributeValueIndex v = att->mapped_index(draco::PointIndex(static_cast<uint32_t>(p)));
      const bool ok = ct == kFloat ? att->ConvertValue<float>(v, static_cast<int8_t>(n), f)
                                   : att->ConvertValue<int32_t>(v, static_cast<int8_t>(n), i32);
      if (!ok)
        return doc.error(ew + ".attributes." + it.key() + ": Draco cannot give its values as the accessor's type");
      for (uint32_t c = 0; c < n; ++c)
        raw[p * n + c] = ct == kFloat ? static_cast<double>(f[c]) : static_cast<double>(i32[c]);
    }
    TSM_RETURN_IF_ERROR(fill_accessor(doc, acc, raw, n, kArrayBuffer));
  }
  prim["extensions"].erase("KHR_draco_mesh_compression");
  if (prim["extensions"].empty()) prim.erase("extensions");
  return Status::Ok();
}
#endif

#ifdef TSM_IO_HAVE_MESHOPT
Status decode_meshopt_view(Document& doc, size_t index, const char* name) {
  ojson& view = doc.json["bufferViews"][index];
  const ojson& ext = view["extensions"][name];
  const std::string where = "bufferViews[" + std::to_string(index) + "].extensions." + name;
  int64_t buffer = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(ext, "buffer", doc.buffers.size(), where, buffer));
  if (buffer < 0) return doc.error(where + " names no buffer");
  const uint64_t offset = ext.value("byteOffset", uint64_t(0)), length = ext.value("byteLength", uint64_t(0));
  const uint64_t stride = ext.value("byteStride", uint64_t(0)), count = ext.value("count", uint64_t(0));
  const std::string mode = ext.value("mode", std::string()), filter = ext.value("filter", std::string("NONE"));
  const std::string& data = doc.buffers[static_cast<size_t>(buffer)];
  if (offset > data.size() || length > data.size() - offset)
    return doc.error(where + ": bytes " + std::to_string(offset) + "+" + std::to_string(length) +
                     " lie outside buffers[" + std::to_string(buffer) + "]");
  if (stride == 0 || stride > 256 || count == 0 || count > kMaxDecodedView / stride ||
      count * stride > view.value("byteLength", uint64_t(0)) || count * stride > kMaxMeshoptRatio * length + 4096)
    return doc.error(where + ": byteStride " + std::to_string(stride) + " x count " + std::to_string(count) +
                     " does not fit the buffer view");
  const auto* src = reinterpret_cast<const unsigned char*>(data.data() + offset);
  std::string out(static_cast<size_t>(count * stride), '\0');
  int rc = -1;
  if (mode == "ATTRIBUTES" && stride % 4 == 0)
    rc = meshopt_decodeVertexBuffer(&out[0], count, stride, src, length);
  else if (mode == "TRIANGLES" && (stride == 2 || stride == 4) && count % 3 == 0)
    rc = meshopt_decodeIndexBuffer(&out[0], count, stride, src, length);
  else if (mode == "INDICES" && (stride == 2 || stride == 4))
    rc = meshopt_decodeIndexSequence(&out[0], count, stride, src, length);
  else
    return doc.error(where + ": mode \"" + mode + "\" with byteStride " + std::to_string(stride) + " is not valid");
  if (rc != 0) return doc.error(where + ": meshoptimizer cannot decode the data (error " + std::to_string(rc) + ")");
  if (filter == "OCTAHEDRAL" && (stride == 4 || stride == 8))
    meshopt_decodeFilterOct(&out[0], count, stride);
  else if (filter == "QUATERNION" && stride == 8)
    meshopt_decodeFilterQuat(&out[0], count, stride);
  else if (filter == "EXPONENTIAL" && stride % 4 == 0)
    meshopt_decodeFilterExp(&out[0], count, stride);
  else if (filter != "NONE")
    return doc.error(where + ": filter \"" + filter + "\" is not valid here");
  doc.buffers.push_back(std::move(out));
  doc.json["buffers"].push_back(ojson{{"byteLength", doc.buffers.back().size()}});
  view["buffer"] = doc.buffers.size() - 1;
  view["byteOffset"] = 0;
  view["byteLength"] = doc.buffers.back().size();
  view["extensions"].erase(name);
  if (view["extensions"].empty()) view.erase("extensions");
  return Status::Ok();
}
#endif

Status decode_meshopt(Document& doc) {
  bool found = false;
  for (size_t i = 0; i < doc.count_of("bufferViews"); ++i) {
    ojson& view = doc.json["bufferViews"][i];
    if (!view.is_object() || !view.contains("extensions") || !view["extensions"].is_object()) continue;
    for (const char* name : {"EXT_meshopt_compression", "KHR_meshopt_compression"}) {
      // (decoding one removes an emptied "extensions": never recreate it here)
      if (!view.contains("extensions") || !view["extensions"].contains(name)) continue;
      found = true;
#ifdef TSM_IO_HAVE_MESHOPT
      TSM_RETURN_IF_ERROR(decode_meshopt_view(doc, i, name));
#else
      return Status(ErrorCode::unsupported,
                    doc.name + ": uses " + name +
                        ", and this tsm was built without meshoptimizer: install libmeshoptimizer-dev "
                        "(scripts/setup.sh) and rebuild, or give an uncompressed glTF");
#endif
    }
  }
  if (found) {
    drop_extension(doc.json, "EXT_meshopt_compression");
    drop_extension(doc.json, "KHR_meshopt_compression");
  }
  return Status::Ok();
}

// The morph targets a stream holds (the extension's "targets" and
// "targetSteps"): FLOAT VEC3 accessors, each the stream's i32 vertex
// attribute times its semantic's step.
Status decode_targets(Document& doc, const ojson& prim, const ojson& ext, const Mesh& mesh, const std::string& ew) {
  if (!ext.contains("targets")) return Status::Ok();
  const ojson& targets = ext["targets"];
  const size_t have = prim.contains("targets") && prim["targets"].is_array() ? prim["targets"].size() : 0;
  if (!targets.is_array() || targets.size() != have)
    return doc.error(ew + ".targets is not an array of one object per morph target of the primitive (" +
                     std::to_string(have) + ")");
  if (!ext.contains("targetSteps") || !ext["targetSteps"].is_object())
    return doc.error(ew + " has targets but no targetSteps object");
  for (size_t t = 0; t < have; ++t) {
    const std::string tw = ew + ".targets[" + std::to_string(t) + "]";
    if (!targets[t].is_object()) return doc.error(tw + " is not an object");
    for (auto it = targets[t].begin(); it != targets[t].end(); ++it) {
      const std::string aw = tw + "." + it.key();
      if (!it.value().is_number_unsigned() || it.value().get<uint64_t>() >= mesh.attributes.size())
        return doc.error(aw + " is not an index below the stream's " + std::to_string(mesh.attributes.size()) +
                         " attributes");
      const Attribute& att = mesh.attributes[it.value().get<size_t>()];
      const ojson& steps = ext["targetSteps"];
      const double step = steps.contains(it.key()) && steps[it.key()].is_number() ? steps[it.key()].get<double>() : 0;
      if (!(step > 0) || !std::isfinite(step))
        return doc.error(ew + ".targetSteps." + it.key() + " is not a positive number");
      int64_t acc = -1;
      TSM_RETURN_IF_ERROR(doc.index_of(prim["targets"][t], it.key().c_str(), doc.count_of("accessors"),
                                       "targets[" + std::to_string(t) + "]", acc));
      if (acc < 0) return doc.error(aw + ": the primitive's morph target has no " + it.key());
      int ct = 0;
      uint32_t comps = 0;
      TSM_RETURN_IF_ERROR(accessor_shape(doc, static_cast<size_t>(acc), ct, comps));
      if (att.domain != AttributeDomain::vertex || att.type != AttributeType::i32 || att.components != comps ||
          att.value_count() != mesh.vertex_count() || ct != kFloat)
        return doc.error(aw + ": stream attribute '" + att.name + "' does not fit accessors[" + std::to_string(acc) +
                         "] (an i32 vertex attribute of the accessor's components; a FLOAT accessor)");
      std::vector<double> raw(att.values.size());
      for (size_t i = 0; i < raw.size(); ++i) raw[i] = target_delta(att.values[i], step);
      TSM_RETURN_IF_ERROR(fill_accessor(doc, static_cast<size_t>(acc), raw, comps, kArrayBuffer));
    }
  }
  return Status::Ok();
}

// Writes a decoded tsm mesh into the primitive's accessors.
Status decode_tsm(Document& doc, ojson& prim, const std::string& where) {
  const ojson& ext = prim["extensions"]["TSM_mesh_compression"];
  const std::string ew = where + ".extensions.TSM_mesh_compression";
  std::string_view bytes;
  TSM_RETURN_IF_ERROR(stream_bytes(doc, ext, ew, bytes));
  Mesh mesh;
  Status s = decode(bytes, mesh);
  if (!s.ok()) return Status(s.code(), doc.name + ": " + ew + ": the tsm stream does not decode: " + s.message());
  if (!mesh.all_triangles()) return doc.error(ew + ": the tsm stream holds faces that are not triangles");
  const size_t n = mesh.vertex_count();
  int64_t ia = -1;
  TSM_RETURN_IF_ERROR(doc.index_of(prim, "indices", doc.count_of("accessors"), where, ia));
  if (ia < 0) return doc.error(where + ": a TSM_mesh_compression primitive needs an indices accessor");
  TSM_RETURN_IF_ERROR(fill_accessor(doc, static_cast<size_t>(ia),
                                    std::vector<double>(mesh.indices.begin(), mesh.indices.end()), 1,
                                    kElementArrayBuffer));
  size_t pos = 0;
  TSM_RETURN_IF_ERROR(primitive_accessor(doc, prim, "POSITION", where, pos));
  TSM_RETURN_IF_ERROR(
      fill_accessor(doc, pos, std::vector<double>(mesh.positions.begin(), mesh.positions.end()), 3, kArrayBuffer));
  if (!ext.contains("attributes") || !ext["attributes"].is_object()) return doc.error(ew + " has no attributes");
  for (auto it = ext["attributes"].begin(); it != ext["attributes"].end(); ++it) {
    const std::string aw = ew + ".attributes." + it.key();
    if (!it.value().is_number_unsigned() || it.value().get<uint64_t>() >= mesh.attributes.size())
      return doc.error(aw + " is not an index below the stream's " + std::to_string(mesh.attributes.size()) +
                       " attributes");
    const Attribute& att = mesh.attributes[it.value().get<size_t>()];
    size_t acc = 0;
    TSM_RETURN_IF_ERROR(primitive_accessor(doc, prim, it.key(), where, acc));
    int ct = 0;
    uint32_t comps = 0;
    TSM_RETURN_IF_ERROR(accessor_shape(doc, acc, ct, comps));
    if (att.domain != AttributeDomain::vertex || att.components != comps || att.value_count() != n ||
        (ct == kFloat) != (att.type == AttributeType::f32))
      return doc.error(aw + ": stream attribute '" + att.name + "' does not fit accessors[" + std::to_string(acc) +
                       "] (a vertex attribute of the accessor's components, float for FLOAT accessors, integer "
                       "for integer ones)");
    TSM_RETURN_IF_ERROR(
        fill_accessor(doc, acc, std::vector<double>(att.values.begin(), att.values.end()), comps, kArrayBuffer));
  }
  TSM_RETURN_IF_ERROR(decode_targets(doc, prim, ext, mesh, ew));
  // Accessors outside the stream must have the stream's vertex count.
  std::vector<std::pair<std::string, const ojson*>> maps = {{"", &prim["attributes"]}};
  if (prim.contains("targets") && prim["targets"].is_array())
    for (size_t t = 0; t < prim["targets"].size(); ++t)
      if (prim["targets"][t].is_object()) maps.emplace_back("targets[" + std::to_string(t) + "].", &prim["targets"][t]);
  for (const auto& [prefix, map] : maps)
    for (auto it = map->begin(); it != map->end(); ++it) {
      if (!it.value().is_number_unsigned() || it.value().get<uint64_t>() >= doc.count_of("accessors")) continue;
      const ojson& a = doc.json["accessors"][it.value().get<size_t>()];
      if (a.value("count", uint64_t(0)) != n)
        return doc.error(where + ": accessor of " + prefix + it.key() + " has count " +
                         std::to_string(a.value("count", 0)) + ", the tsm stream " + std::to_string(n) + " vertices");
    }
  prim["extensions"].erase("TSM_mesh_compression");
  if (prim["extensions"].empty()) prim.erase("extensions");
  return Status::Ok();
}

// A stream already decoded for an earlier primitive: where, and what its
// primitive named (sharing_key of the primitive and of the extension).
struct SharedStream {
  std::string where;
  std::string key;
};

std::string stream_key(const ojson& prim) {
  const ojson& ext = prim["extensions"]["TSM_mesh_compression"];
  ojson e = ojson::object();
  for (const char* k : {"attributes", "targets", "targetSteps"})
    if (ext.is_object() && ext.contains(k)) e[k] = ext[k];
  return sharing_key(prim) + nlohmann::json::parse(e.dump()).dump();
}

// Decodes the primitive's stream, or, when an earlier primitive named the
// same buffer view, checks that it names the same accessors (they hold the
// decoded data already) and refuses the file otherwise.
Status decode_or_share(Document& doc, ojson& prim, const std::string& where, std::map<int64_t, SharedStream>& streams) {
  const std::string ew = where + ".extensions.TSM_mesh_compression";
  int64_t view = -1;
  TSM_RETURN_IF_ERROR(
      doc.index_of(prim["extensions"]["TSM_mesh_compression"], "bufferView", doc.count_of("bufferViews"), ew, view));
  const std::string key = stream_key(prim);
  const auto first = streams.find(view);
  if (first == streams.end()) {
    streams[view] = SharedStream{where, key};
    return decode_tsm(doc, prim, where);
  }
  if (first->second.key != key)
    return doc.error(ew + ": bufferView " + std::to_string(view) + " is the stream of " + first->second.where +
                     ", which names other accessors (a stream is shared only by primitives with the same indices, "
                     "attributes and targets): the file is corrupt; re-encode it from its source");
  prim["extensions"].erase("TSM_mesh_compression");
  if (prim["extensions"].empty()) prim.erase("extensions");
  return Status::Ok();
}

}  // namespace

Status fill_accessor(Document& doc, size_t acc, const std::vector<double>& raw, uint32_t components, int target) {
  ojson& a = doc.json["accessors"][acc];
  const int ct = a.value("componentType", 0);
  const uint32_t want = a.contains("type") && a["type"].is_string() ? type_components(a["type"].get<std::string>()) : 0;
  if (component_bytes(ct) == 0 || want != components)
    return doc.error("accessors[" + std::to_string(acc) + "]: componentType or type does not fit the decoded data (" +
                     std::to_string(components) + " components)");
  const size_t count = raw.size() / components;
  if (count == 0) return doc.error("accessors[" + std::to_string(acc) + "]: the decoded data is empty");
  size_t stride = 0;
  std::string bytes = pack_values(raw, ct, components, target, &stride);  // sets stride first
  const size_t view = add_buffer_view(doc, std::move(bytes), target, stride);
  a["bufferView"] = view;
  a.erase("byteOffset");
  a.erase("sparse");
  a["count"] = count;
  if (a.contains("min") || a.contains("max") || target == kArrayBuffer) set_min_max(a, raw, components);
  return Status::Ok();
}

void set_min_max(ojson& a, const std::vector<double>& raw, uint32_t components) {
  std::vector<double> lo(components, 0), hi(components, 0);
  const size_t count = components ? raw.size() / components : 0;
  for (size_t i = 0; i < count; ++i)
    for (uint32_t c = 0; c < components; ++c) {
      const double v = raw[i * components + c];
      lo[c] = i == 0 ? v : std::min(lo[c], v);
      hi[c] = i == 0 ? v : std::max(hi[c], v);
    }
  const bool is_float = a.value("componentType", 0) == kFloat;
  ojson mn = ojson::array(), mx = ojson::array();
  for (uint32_t c = 0; c < components; ++c) {
    if (is_float) {
      mn.push_back(static_cast<float>(lo[c]));
      mx.push_back(static_cast<float>(hi[c]));
    } else {
      mn.push_back(static_cast<int64_t>(lo[c]));
      mx.push_back(static_cast<int64_t>(hi[c]));
    }
  }
  a["min"] = mn;
  a["max"] = mx;
}

Status decompress_document(Document& doc) {
  TSM_RETURN_IF_ERROR(decode_meshopt(doc));
  bool draco = false, tsm = false;
  std::map<int64_t, SharedStream> streams;
  for (size_t m = 0; m < doc.count_of("meshes"); ++m) {
    ojson& mesh = doc.json["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (size_t p = 0; p < mesh["primitives"].size(); ++p) {
      ojson& prim = mesh["primitives"][p];
      const std::string where = "meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]";
      if (!prim.is_object() || !prim.contains("extensions") || !prim["extensions"].is_object()) continue;
      if (!prim.contains("attributes") || !prim["attributes"].is_object())
        return doc.error(where + " has no attributes object");
      if (prim["extensions"].contains("TSM_mesh_compression")) {
        TSM_RETURN_IF_ERROR(decode_or_share(doc, prim, where, streams));
        tsm = true;
      }
      if (prim.contains("extensions") && prim["extensions"].contains("KHR_draco_mesh_compression")) {
        draco = true;
#ifdef TSM_IO_HAVE_DRACO
        TSM_RETURN_IF_ERROR(decode_draco(doc, prim, where));
#else
        return Status(ErrorCode::unsupported,
                      doc.name + ": " + where +
                          " uses KHR_draco_mesh_compression, and this tsm was built without Draco: install "
                          "libdraco-dev (scripts/setup.sh) and rebuild, or give an uncompressed glTF");
#endif
      }
    }
  }
  if (draco) drop_extension(doc.json, "KHR_draco_mesh_compression");
  if (tsm) drop_extension(doc.json, "TSM_mesh_compression");
  return Status::Ok();
}

}  // namespace tsm::gltf
