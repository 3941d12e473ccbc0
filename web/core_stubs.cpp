// The core browser decoder (web/build.sh, tsm_decoder.wasm) links these in
// place of the decoding paths files rarely need: progressive batches
// (progressive_split.cpp), keep-order (order_coding.cpp), lossless exact
// grids (exact_grid.cpp) and zstd-coded sections (zstd's decompressor). Each one refuses and raises a flag;
// tsm.js reads the flag after every call into the core module
// (tsm_web_core_refused) and then decodes the same bytes with the full
// module (tsm_decoder.wasm), which has every path. A call that raised the
// flag may have returned success with a partial result (LevelMesh::init
// and exact_value cannot fail): tsm.js never reads results from such a call.
#include <zstd.h>

#include "exact_grid.hpp"
#include "order_coding.hpp"
#include "progressive.hpp"

namespace {
bool refused = false;

tsm::Status needs_full(const char* what) {
  refused = true;
  return tsm::Status(tsm::ErrorCode::unsupported, std::string(what) + ": needs the full decoder module");
}
}  // namespace

extern "C" {
// 1 when a call since the last query reached a path the core module lacks; clears the flag.
int tsm_web_core_refused() {
  const bool r = refused;
  refused = false;
  return r ? 1 : 0;
}

size_t ZSTD_decompress(void*, size_t, const void*, size_t) {
  refused = true;
  return static_cast<size_t>(-1);
}

unsigned ZSTD_isError(size_t code) { return code > static_cast<size_t>(-120) ? 1 : 0; }
}

namespace tsm {

void LevelMesh::init(Mesh&, const Header&) { refused = true; }

Status read_batch(std::string_view, BatchHeader&, std::string_view&) { return needs_full("progressive batch"); }

Status decode_batch(std::string_view, LevelMesh&, const BatchLimits&) { return needs_full("progressive batch"); }

Status decode_loose(std::string_view, LevelMesh&, const BatchLimits&) { return needs_full("loose vertices"); }

Status decode_order(std::string_view, Mesh&) { return needs_full("keep-order section"); }

float exact_value(double, int64_t, uint32_t) {
  refused = true;
  return 0;
}

Status apply_exceptions(std::string_view, std::vector<float>&) { return needs_full("exact grid exceptions"); }

}  // namespace tsm
