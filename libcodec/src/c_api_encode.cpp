// The C API's encoder half (tsm.h): tsm_encode over tsm::encode. Not in
// the decoder library (tsm_decoder) nor the WebAssembly build. No exception
// or C++ type crosses it.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "c_api_internal.hpp"
#include "tsm/tsm.h"
#include "tsm/tsm.hpp"

using tsm::capi::guarded;

namespace {

tsm::EncodeOptions options_from(const tsm_encode_options* options) {
  tsm::EncodeOptions o;
  if (options) {
    if (options->quantization_bits) o.quantization_bits = options->quantization_bits;
    if (options->level >= 0) o.level = options->level;
    o.segment_faces = options->segment_faces;
    o.threads = options->threads;
    if (options->normal_bits) o.attribute_bits.normal = options->normal_bits;
    if (options->texcoord_bits) o.attribute_bits.texcoord = options->texcoord_bits;
    if (options->color_bits) o.attribute_bits.color = options->color_bits;
    if (options->generic_bits) o.attribute_bits.generic = options->generic_bits;
    o.keep_order = options->keep_order != 0;
    o.lossless = options->lossless != 0;
    o.allow_nonfinite = options->allow_nonfinite != 0;
    o.progressive = options->progressive != 0;
  }
  return o;
}

// A malloc'ed copy (at least one byte, so that empty is not NULL).
template <class T>
T* malloc_copy(const T* data, size_t n) {
  auto* buf = static_cast<T*>(std::malloc(n ? n * sizeof(T) : 1));
  if (buf && n) std::memcpy(buf, data, n * sizeof(T));
  return buf;
}

tsm::Status encode_into(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size,
                        tsm::EncodeMapping* mapping) {
  if (!mesh || !out || !out_size) return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
  *out = nullptr;
  *out_size = 0;
  std::string bytes;
  tsm::Status s = tsm::encode(mesh->get(), options_from(options), bytes, mapping);
  if (!s.ok()) return s;
  uint8_t* buf = malloc_copy(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  if (!buf) return tsm::Status(tsm::ErrorCode::limit_exceeded, "out of memory");
  *out = buf;
  *out_size = bytes.size();
  return s;
}

}  // namespace

extern "C" {

int tsm_encode(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size, char* err,
               size_t err_size) {
  return guarded(err, err_size, [&] { return encode_into(mesh, options, out, out_size, nullptr); });
}

int tsm_encode_mapped(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size,
                      uint32_t** vertex_from, uint32_t** face_from, uint32_t** first_corner, char* err,
                      size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!vertex_from || !face_from || !first_corner)
      return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    *vertex_from = *face_from = *first_corner = nullptr;
    tsm::EncodeMapping m;
    tsm::Status s = encode_into(mesh, options, out, out_size, &m);
    if (!s.ok()) return s;
    *vertex_from = malloc_copy(m.vertex_from.data(), m.vertex_from.size());
    *face_from = malloc_copy(m.face_from.data(), m.face_from.size());
    *first_corner = malloc_copy(m.first_corner.data(), m.first_corner.size());
    if (!*vertex_from || !*face_from || !*first_corner) {
      std::free(*vertex_from), std::free(*face_from), std::free(*first_corner), std::free(*out);
      *vertex_from = *face_from = *first_corner = nullptr;
      *out = nullptr;
      return tsm::Status(tsm::ErrorCode::limit_exceeded, "out of memory");
    }
    return s;
  });
}

}  // extern "C"
