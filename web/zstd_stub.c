/* Stand-in for zstd's decompressor in the WebAssembly build, used only when
 * web/build.sh cannot get zstd's sources from Debian's source package. The
 * tsm encoder zstd-codes the metadata section (a glTF or OBJ source's side
 * data) and a lossless file's exceptions when that is smaller: such a file is
 * refused by a build with this stub (container_read.cpp reports the section
 * as not decodable). */
#include <stddef.h>

#define TSM_ZSTD_STUB_ERROR ((size_t)-1)

size_t ZSTD_decompress(void* dst, size_t dst_capacity, const void* src, size_t src_size) {
  (void)dst; (void)dst_capacity; (void)src; (void)src_size;
  return TSM_ZSTD_STUB_ERROR;
}

unsigned ZSTD_isError(size_t code) { return code > (size_t)-120; }
