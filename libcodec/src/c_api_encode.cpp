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

extern "C" {

int tsm_encode(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size, char* err,
               size_t err_size) {
  return guarded(err, err_size, [&] {
    if (!mesh || !out || !out_size) return tsm::Status(tsm::ErrorCode::invalid_argument, "null argument");
    *out = nullptr;
    *out_size = 0;
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
    }
    std::string bytes;
    tsm::Status s = tsm::encode(mesh->get(), o, bytes);
    if (!s.ok()) return s;
    auto* buf = static_cast<uint8_t*>(std::malloc(bytes.size() ? bytes.size() : 1));
    if (!buf) return tsm::Status(tsm::ErrorCode::limit_exceeded, "out of memory");
    std::memcpy(buf, bytes.data(), bytes.size());
    *out = buf;
    *out_size = bytes.size();
    return s;
  });
}

}  // extern "C"
