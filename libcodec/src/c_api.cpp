// The C API (tsm.h) over the C++ API, for bindings and the WebAssembly
// build: decoding (whole and streamed), meshes built and read, attributes
// and metadata; tsm_encode is in c_api_encode.cpp (the encoder's half). No
// exception or C++ type crosses it.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>

#include "c_api_internal.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

using tsm::capi::guarded;

struct tsm_stream {
  explicit tsm_stream(const tsm::DecodeOptions& o) : decoder(o) { mesh.view = &decoder.mesh(); }
  tsm::StreamDecoder decoder;
  tsm_mesh mesh;
};

namespace {

// Attribute number i of a mesh, or null.
const tsm::Attribute* attribute(const tsm_mesh* m, size_t i) {
  if (!m || i >= m->get().attributes.size()) return nullptr;
  return &m->get().attributes[i];
}

const tsm::MetadataEntry* metadata_entry(const tsm_mesh* m, size_t i, size_t* size) {
  if (size) *size = 0;
  if (!m || i >= m->get().metadata.size()) return nullptr;
  return &m->get().metadata[i];
}

tsm::Status invalid(const std::string& message) { return tsm::Status(tsm::ErrorCode::invalid_argument, message); }

tsm::DecodeOptions decode_options(const tsm_decode_options* options) {
  tsm::DecodeOptions o;
  if (options) {
    o.max_vertices = options->max_vertices;
    o.max_faces = options->max_faces;
    o.max_corners = options->max_corners;
    o.threads = options->threads;
  }
  return o;
}

}  // namespace

extern "C" {

int tsm_decode(const uint8_t* data, size_t size, const tsm_decode_options* options, tsm_mesh** out, char* err,
               size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!out || (!data && size)) return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    *out = nullptr;
    auto* m = new tsm_mesh;
    tsm::Status s =
        tsm::decode(std::string_view(reinterpret_cast<const char*>(data), size), m->mesh, decode_options(options));
    if (!s.ok()) {
      delete m;
      return s;
    }
    *out = m;
    return s;
  });
}

int tsm_decode_partial(const uint8_t* data, size_t size, const tsm_partial_options* partial,
                       const tsm_decode_options* options, tsm_mesh** out, tsm_partial_report* report, char* err,
                       size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!out || (!data && size)) return invalid("null argument");
    *out = nullptr;
    if (report) *report = tsm_partial_report{};
    tsm::PartialOptions p;
    if (partial) {
      p.max_bytes = partial->max_bytes;
      p.max_error = partial->max_error > 0 ? partial->max_error : -1;
    }
    tsm::PartialReport r;
    auto* m = new tsm_mesh;
    tsm::Status s = tsm::decode_partial(std::string_view(reinterpret_cast<const char*>(data), size), m->mesh, p, &r,
                                        decode_options(options));
    if (!s.ok()) {
      delete m;
      return s;
    }
    if (report) *report = tsm_partial_report{r.bytes_used, r.error, r.batches, r.complete ? 1 : 0};
    *out = m;
    return s;
  });
}

int tsm_mesh_create(const float* positions, size_t vertex_count, const uint32_t* face_sizes, size_t face_count,
                    const uint32_t* indices, size_t index_count, tsm_mesh** out, char* err, size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!out || (!positions && vertex_count) || (!indices && index_count))
      return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    *out = nullptr;
    if (index_count > 0xffffffffu || vertex_count > 0xffffffffu)
      return tsm::Status(tsm::ErrorCode::limit_exceeded, "more than 2^32 - 1 vertices or corners");
    auto* m = new tsm_mesh;
    m->mesh.positions.assign(positions, positions + 3 * vertex_count);
    m->mesh.indices.assign(indices, indices + index_count);
    m->mesh.face_offsets.assign(1, 0);
    uint64_t at = 0;
    for (size_t f = 0; f < face_count; ++f) {
      at += face_sizes ? face_sizes[f] : 3;
      m->mesh.face_offsets.push_back(static_cast<uint32_t>(at > 0xffffffffu ? 0xffffffffu : at));
    }
    std::string why;
    if (at != index_count || !m->mesh.valid(&why)) {
      delete m;
      return tsm::Status(tsm::ErrorCode::invalid_argument,
                         at != index_count ? "face sizes do not add up to index_count" : why);
    }
    *out = m;
    return tsm::Status::Ok();
  });
}

tsm_stream* tsm_stream_new(const tsm_decode_options* options) {
  try {
    tsm::DecodeOptions o = decode_options(options);
    o.threads = 0;
    return new tsm_stream(o);
  } catch (...) {
    return nullptr;
  }
}

int tsm_stream_feed(tsm_stream* s, const uint8_t* data, size_t size, char* err, size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!s || (!data && size)) return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    return s->decoder.feed(std::string_view(reinterpret_cast<const char*>(data), size));
  });
}

int tsm_stream_finish(tsm_stream* s, char* err, size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!s) return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    return s->decoder.finish();
  });
}

size_t tsm_stream_segment_count(const tsm_stream* s) { return s ? s->decoder.segment_count() : 0; }
size_t tsm_stream_segments_done(const tsm_stream* s) { return s ? s->decoder.segments_done() : 0; }
const tsm_mesh* tsm_stream_mesh(const tsm_stream* s) { return s ? &s->mesh : nullptr; }
void tsm_stream_free(tsm_stream* s) { delete s; }
void tsm_stream_stop_at_levels(tsm_stream* s, int on) {
  if (s) s->decoder.stop_at_levels(on != 0);
}
int tsm_stream_level_pending(const tsm_stream* s) { return s && s->decoder.level_pending() ? 1 : 0; }
int tsm_stream_progressive(const tsm_stream* s) { return s && s->decoder.progressive() ? 1 : 0; }
size_t tsm_stream_batches_done(const tsm_stream* s) { return s ? s->decoder.batches_done() : 0; }
double tsm_stream_level_error(const tsm_stream* s) { return s ? s->decoder.level_error() : -1; }

size_t tsm_mesh_vertex_count(const tsm_mesh* m) { return m ? m->get().vertex_count() : 0; }
size_t tsm_mesh_face_count(const tsm_mesh* m) { return m ? m->get().face_count() : 0; }
size_t tsm_mesh_index_count(const tsm_mesh* m) { return m ? m->get().corner_count() : 0; }
const float* tsm_mesh_positions(const tsm_mesh* m) { return m ? m->get().positions.data() : nullptr; }
const uint32_t* tsm_mesh_face_offsets(const tsm_mesh* m) { return m ? m->get().face_offsets.data() : nullptr; }
const uint32_t* tsm_mesh_indices(const tsm_mesh* m) { return m ? m->get().indices.data() : nullptr; }

size_t tsm_mesh_attribute_count(const tsm_mesh* m) { return m ? m->get().attributes.size() : 0; }
const char* tsm_mesh_attribute_name(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? a->name.c_str() : nullptr;
}
int tsm_mesh_attribute_kind(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? static_cast<int>(a->kind) : -1;
}
int tsm_mesh_attribute_domain(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? static_cast<int>(a->domain) : -1;
}
int tsm_mesh_attribute_type(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? static_cast<int>(a->type) : -1;
}
int tsm_mesh_attribute_components(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? static_cast<int>(a->components) : -1;
}
size_t tsm_mesh_attribute_value_count(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? a->value_count() : 0;
}
const float* tsm_mesh_attribute_values(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a ? a->values.data() : nullptr;
}
size_t tsm_mesh_attribute_index_count(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a && a->domain == tsm::AttributeDomain::corner ? a->indices.size() : 0;
}
const uint32_t* tsm_mesh_attribute_indices(const tsm_mesh* m, size_t i) {
  const tsm::Attribute* a = attribute(m, i);
  return a && a->domain == tsm::AttributeDomain::corner ? a->indices.data() : nullptr;
}

int tsm_mesh_add_attribute(tsm_mesh* m, const char* name, int kind, int domain, int type, int components,
                           const float* values, size_t value_count, const uint32_t* indices, size_t index_count,
                           char* err, size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!m || !name || (!values && value_count) || (!indices && index_count)) return invalid("null argument");
    if (m->view) return invalid("a stream's mesh is read-only");
    if (kind < TSM_KIND_GENERIC || kind > TSM_KIND_TEXCOORD) return invalid("unknown attribute kind " + std::to_string(kind));
    if (domain < TSM_DOMAIN_VERTEX || domain > TSM_DOMAIN_CORNER)
      return invalid("unknown attribute domain " + std::to_string(domain));
    if (type < TSM_TYPE_F32 || type > TSM_TYPE_I32) return invalid("unknown attribute type " + std::to_string(type));
    if (components < 1 || components > 4)
      return invalid("attribute '" + std::string(name) + "' has " + std::to_string(components) + " components (1..4)");
    if (domain != TSM_DOMAIN_CORNER && (indices || index_count))
      return invalid("attribute '" + std::string(name) + "': indices are for the corner domain only");
    if (value_count > SIZE_MAX / 4 || static_cast<uint64_t>(value_count) > 0xffffffffu ||
        static_cast<uint64_t>(index_count) > 0xffffffffu)
      return tsm::Status(tsm::ErrorCode::limit_exceeded, "more than 2^32 - 1 values or indices");
    tsm::Attribute a;
    a.name = name;
    a.kind = static_cast<tsm::AttributeKind>(kind);
    a.domain = static_cast<tsm::AttributeDomain>(domain);
    a.type = static_cast<tsm::AttributeType>(type);
    a.components = static_cast<uint32_t>(components);
    a.values.assign(values, values + value_count * a.components);
    a.indices.assign(indices, indices + index_count);
    tsm::Mesh& mesh = m->mesh;
    mesh.attributes.push_back(std::move(a));
    std::string why;
    if (!mesh.valid(&why)) {
      mesh.attributes.pop_back();
      return invalid(why);
    }
    return tsm::Status::Ok();
  });
}

size_t tsm_mesh_metadata_count(const tsm_mesh* m) { return m ? m->get().metadata.size() : 0; }
const char* tsm_mesh_metadata_key(const tsm_mesh* m, size_t i, size_t* size) {
  const tsm::MetadataEntry* e = metadata_entry(m, i, size);
  if (!e) return nullptr;
  if (size) *size = e->key.size();
  return e->key.c_str();
}
const uint8_t* tsm_mesh_metadata_value(const tsm_mesh* m, size_t i, size_t* size) {
  const tsm::MetadataEntry* e = metadata_entry(m, i, size);
  if (!e) return nullptr;
  if (size) *size = e->value.size();
  return reinterpret_cast<const uint8_t*>(e->value.c_str());
}

int tsm_mesh_add_metadata(tsm_mesh* m, const char* key, size_t key_size, const uint8_t* value, size_t value_size,
                          char* err, size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!m || !key || (!value && value_size)) return invalid("null argument");
    if (m->view) return invalid("a stream's mesh is read-only");
    tsm::MetadataEntry e;
    e.key.assign(key, key_size);
    if (value_size) e.value.assign(reinterpret_cast<const char*>(value), value_size);
    tsm::Mesh& mesh = m->mesh;
    mesh.metadata.push_back(std::move(e));
    std::string why;
    if (!mesh.valid(&why)) {
      mesh.metadata.pop_back();
      return invalid(why);
    }
    return tsm::Status::Ok();
  });
}

void tsm_mesh_free(tsm_mesh* m) { delete m; }
void tsm_free(void* buffer) { std::free(buffer); }
const char* tsm_version(void) { return tsm::version_string(); }

}  // extern "C"
