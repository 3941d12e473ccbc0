#!/usr/bin/env bash
# Builds the tsm decoder for the browser, from the sources of the native
# decoder library (libcodec/decoder_sources.txt, CMake's tsm_decoder), with
# emcc directly (no CMake), as two modules (emscripten glue + WebAssembly):
#   build/web/tsm_decoder.{js,wasm}       the core, what tsm.js loads first: every
#                                         path the encoder's default files take
#   build/web/tsm_decoder_full.{js,wasm}  every path: progressive batches, keep-order,
#                                         lossless exact grids and zstd-coded sections
#                                         besides; tsm.js loads it when a file needs one
# The core links web/core_stubs.cpp instead of CORE_OMITS and zstd's
# decompressor: each stub refuses and raises a flag tsm.js reads.
#
#   web/build.sh            # needs emcc (Debian: apt-get install emscripten node-acorn)
#   TSM_WEB_DEBUG=1 web/build.sh   # -O1 -g, assertions on
#
# zstd: the container allows zstd-coded sections, so the decompressor is
# compiled from Debian's zstd source package (apt-get source libzstd, fetched
# into build/web/ with a private deb-src list; the system's apt configuration
# is not touched). When that cannot be had, web/zstd_stub.c stands in and a
# zstd section is refused with an error.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${TSM_WEB_OUT:-$ROOT/build/web}"
# TSM_WEB_LIBCODEC: another libcodec/ (a snapshot, say) to build from instead of this tree's
LIBCODEC="${TSM_WEB_LIBCODEC:-$ROOT/libcodec}"
OBJ="$OUT/obj"
mkdir -p "$OUT" "$OBJ"
JOBS="${TSM_WEB_JOBS:-2}"

# emscripten 3.1.6 (Debian) runs acorn from Node and finds it through NODE_PATH.
if [ -d /usr/share/nodejs/acorn ]; then
  export NODE_PATH="/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}"
fi
command -v emcc >/dev/null || { echo "web/build.sh: emcc not found (apt-get install emscripten node-acorn)" >&2; exit 1; }

VERSION="$(sed -n 's/^project(tsm VERSION \([0-9.]*\).*/\1/p' "$ROOT/CMakeLists.txt")"
OPT=(-O3 -DNDEBUG)
LOPT=(-O3)
# Speed or size, per file. The stages a decode spends its time in keep -O3:
# connectivity (vertex and triangle trees, bounding loops), geometry
# prediction and its coders, attributes, the split layout of glTF meshes,
# part assembly (decode.cpp: dequantization, copies). Everything else is
# compiled -Oz (after OPT, so it wins): the container, the C API, keep-order,
# progressive batches, exact grids, segments, messages and zstd; a source
# file added to the decoder is -Oz until it is named here. -Oz on
# attributes.cpp or geometry_predict.cpp slows the bunny or dragon res2 by
# 10-15%, on decode.cpp by 3%.
COLD=(-Oz)
if [ "${TSM_WEB_DEBUG:-0}" = 1 ]; then OPT=(-O1 -g); LOPT=(-O1 -g -sASSERTIONS=1); COLD=(); fi
HOT_FILES="attributes.cpp bounding_loop.cpp connectivity_decode.cpp decode.cpp geometry_predict.cpp range_coder.cpp
           rans_coder.cpp split_layout.cpp table_coder.cpp triangle_tree.cpp"
is_cold() {
  case " $(echo $HOT_FILES) " in *" $(basename "$1") "*) return 1 ;; esac
  return 0
}
# TSM_WEB_FLAGS: extra compile and link flags, for trying variants (e.g. "-flto", "-msimd128");
# TSM_WEB_HOT_FLAGS: extra compile flags of the HOT_FILES only (e.g. "-mllvm -inline-threshold=400")
read -r -a EXTRA <<<"${TSM_WEB_FLAGS:-}"
OPT+=("${EXTRA[@]}")
LOPT+=("${EXTRA[@]}")
read -r -a HOT_EXTRA <<<"${TSM_WEB_HOT_FLAGS:-}"

# ---- zstd decompressor (Debian source package) --------------------------------
ZSTD_SRC=""
zstd_from_debian() {
  local dir="$OUT/zstd"
  if [ -f "$dir/.ok" ]; then ZSTD_SRC="$(cat "$dir/.ok")"; return 0; fi
  command -v apt-get >/dev/null || return 1
  rm -rf "$dir" && mkdir -p "$dir/apt/lists/partial" "$dir/src"
  # A private source list and state dir: asks Debian's archive for the source
  # package only, without adding deb-src to the system's configuration.
  local suite
  suite="$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-bookworm}")"
  echo "deb-src http://deb.debian.org/debian ${suite:-bookworm} main" > "$dir/apt/sources.list"
  local aptopts=(-o "Dir::Etc::SourceList=$dir/apt/sources.list" -o "Dir::Etc::SourceParts=$dir/apt/none"
                 -o "Dir::State::Lists=$dir/apt/lists" -o "Dir::Cache=$dir/apt/cache" -qq)
  mkdir -p "$dir/apt/cache/archives/partial"
  apt-get "${aptopts[@]}" update >"$dir/apt.log" 2>&1 || return 1
  (cd "$dir/src" && apt-get "${aptopts[@]}" source --download-only libzstd >>"$dir/apt.log" 2>&1) || return 1
  local tarball
  tarball="$(ls "$dir"/src/libzstd_*.orig.tar.* 2>/dev/null | head -1)"
  [ -n "$tarball" ] || return 1
  tar -xf "$tarball" -C "$dir/src" || return 1
  local lib
  lib="$(ls -d "$dir"/src/zstd-*/lib 2>/dev/null | head -1)"
  [ -f "$lib/decompress/zstd_decompress.c" ] || return 1
  echo "$lib" > "$dir/.ok"
  ZSTD_SRC="$lib"
}

ZSTD_CFLAGS=()
ZSTD_FILES=()
ZSTD_H=""
ZSTD_MODE=debian
if [ "${TSM_WEB_ZSTD:-debian}" = debian ] && zstd_from_debian; then
  echo "web/build.sh: zstd decompressor from Debian's source package ($ZSTD_SRC)"
  ZSTD_CFLAGS=(-I"$ZSTD_SRC" -DZSTD_DISABLE_ASM -DZSTD_NO_TRACE -DXXH_NAMESPACE=ZSTD_ -DZSTD_LEGACY_SUPPORT=0
               -DZSTD_STRIP_ERROR_STRINGS -DHUF_FORCE_DECOMPRESS_X1 -DZSTD_FORCE_DECOMPRESS_SEQUENCES_SHORT
               -DZSTD_NO_INLINE -DZSTD_NO_UNUSED_FUNCTIONS -DDYNAMIC_BMI2=0)
  ZSTD_FILES=("$ZSTD_SRC"/common/{entropy_common,error_private,fse_decompress,xxhash,zstd_common}.c
              "$ZSTD_SRC"/decompress/{huf_decompress,zstd_ddict,zstd_decompress,zstd_decompress_block}.c)
  ZSTD_INC=(-I"$ZSTD_SRC")
else
  echo "web/build.sh: zstd source not available; zstd-coded sections will be refused (web/zstd_stub.c)"
  ZSTD_FILES=("$ROOT/web/zstd_stub.c")
  ZSTD_INC=()
  ZSTD_MODE=stub
  # zstd.h for container_read.cpp: Debian's libzstd-dev header, through the one-header dir below
  ZSTD_H=/usr/include/zstd.h
fi
# ---- library sources: the decoder library's list ---------------------------------
# libcodec/decoder_sources.txt, the list CMake builds tsm_decoder from: every
# source decoding needs, none of the encoder's entry points nor zstd's
# compressor (so no stub stands in for it). One path per line, relative to
# libcodec/; '#' starts a comment.
SOURCE_LIST="$LIBCODEC/decoder_sources.txt"
[ -f "$SOURCE_LIST" ] || { echo "web/build.sh: $SOURCE_LIST not found" >&2; exit 1; }
LIB_FILES=()
while IFS= read -r line || [ -n "$line" ]; do
  line="${line%%#*}"
  line="${line//[[:space:]]/}"
  [ -z "$line" ] && continue
  [ -f "$LIBCODEC/$line" ] || { echo "web/build.sh: $SOURCE_LIST lists $line, which is missing" >&2; exit 1; }
  LIB_FILES+=("$LIBCODEC/$line")
done < "$SOURCE_LIST"

CXXFLAGS=("${OPT[@]}" -std=c++17 -DTSM_VERSION="\"$VERSION\"" -DTSM_NO_THREADS -DXXH_INLINE_ALL
          -DEIGEN_DONT_PARALLELIZE -DEIGEN_MPL2_ONLY
          -I"$LIBCODEC/include" -I"$LIBCODEC/src" -isystem /usr/include/eigen3
          -isystem "$OUT/sysinc" "${ZSTD_INC[@]}")
# xxhash.h (header-only with XXH_INLINE_ALL) from Debian's libxxhash-dev,
# reached through a one-header include dir so nothing else of /usr/include leaks in.
mkdir -p "$OUT/sysinc"
XXH=/usr/include/xxhash.h
[ -f "$XXH" ] || { echo "web/build.sh: $XXH not found (apt-get install libxxhash-dev)" >&2; exit 1; }
ln -sf "$XXH" "$OUT/sysinc/xxhash.h"
rm -f "$OUT/sysinc/zstd.h" "$OUT/sysinc/zstd_errors.h"
if [ -n "$ZSTD_H" ]; then
  [ -f "$ZSTD_H" ] || { echo "web/build.sh: $ZSTD_H not found (apt-get install libzstd-dev)" >&2; exit 1; }
  ln -sf "$ZSTD_H" "$OUT/sysinc/zstd.h"
fi

compile() {  # src obj flags...
  local src="$1" obj="$2"; shift 2
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ "$OUT/.flags" -nt "$obj" ]; then
    emcc "$@" -c "$src" -o "$obj"
  fi
}
FLAGSIG="$(printf '%s\n' "$LIBCODEC" "${CXXFLAGS[@]}" "${ZSTD_CFLAGS[@]}" "${LOPT[@]}" "${COLD[@]}" "$HOT_FILES" "${HOT_EXTRA[@]}")"
if [ ! -f "$OUT/.flags" ] || [ "$(cat "$OUT/.flags")" != "$FLAGSIG" ]; then printf '%s\n' "$FLAGSIG" > "$OUT/.flags"; fi
# headers: rebuild everything when any library header is newer than the last link
if [ -f "$OUT/tsm_decoder.wasm" ]; then
  if [ -n "$(find "$LIBCODEC" -name '*.h*' -newer "$OUT/tsm_decoder.wasm" | head -1)" ]; then rm -f "$OBJ"/*.o; fi
fi

OBJS=()
pids=()
run() { compile "$@" & pids+=($!); if [ "${#pids[@]}" -ge "$JOBS" ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi; }
for f in "${LIB_FILES[@]}"; do
  o="$OBJ/lib_$(basename "${f%.cpp}").o"; OBJS+=("$o")
  if is_cold "$f"; then run "$f" "$o" "${CXXFLAGS[@]}" "${COLD[@]}"; else run "$f" "$o" "${CXXFLAGS[@]}" "${HOT_EXTRA[@]}"; fi
done
for f in "${ZSTD_FILES[@]}"; do
  o="$OBJ/z_$(basename "${f%.c}").o"; OBJS+=("$o"); run "$f" "$o" "${OPT[@]}" "${COLD[@]}" "${ZSTD_CFLAGS[@]}" "${ZSTD_INC[@]}"
done
# The core module's stand-ins (web/core_stubs.cpp).
STUBS_O="$OBJ/web_core_stubs.o"
run "$ROOT/web/core_stubs.cpp" "$STUBS_O" "${CXXFLAGS[@]}" "${COLD[@]}"
for p in "${pids[@]}"; do wait "$p"; done
# The core leaves out the sources of progressive batches, keep-order and
# lossless exact grids, and zstd's decompressor (z_*.o; in the stub build, zstd_stub.c).
CORE_OMITS="progressive_split.cpp order_coding.cpp exact_grid.cpp"
CORE_OBJS=()
for o in "${OBJS[@]}"; do
  b="$(basename "$o" .o)"
  case "$b" in z_*) continue ;; esac
  case " $CORE_OMITS " in *" ${b#lib_}.cpp "*) continue ;; esac
  CORE_OBJS+=("$o")
done
CORE_OBJS+=("$STUBS_O")

# ---- link ----------------------------------------------------------------------
EXPORTS="_malloc,_free,_tsm_decode,_tsm_mesh_vertex_count,_tsm_mesh_face_count,_tsm_mesh_index_count"
EXPORTS+=",_tsm_mesh_positions,_tsm_mesh_face_offsets,_tsm_mesh_indices,_tsm_mesh_free,_tsm_version"
if grep -q "tsm_stream_new" "$LIBCODEC/include/tsm/tsm.h"; then
  EXPORTS+=",_tsm_stream_new,_tsm_stream_feed,_tsm_stream_finish,_tsm_stream_segment_count"
  EXPORTS+=",_tsm_stream_segments_done,_tsm_stream_mesh,_tsm_stream_free"
  EXPORTS+=",_tsm_stream_stop_at_levels,_tsm_stream_level_pending,_tsm_stream_progressive"
  EXPORTS+=",_tsm_stream_batches_done,_tsm_stream_level_error"
  echo "web/build.sh: streaming C API found, exported"
else
  echo "web/build.sh: no streaming C API in tsm.h yet; whole-file decode only"
fi
if grep -q "tsm_mesh_attribute_count" "$LIBCODEC/include/tsm/tsm.h"; then
  EXPORTS+=",_tsm_mesh_attribute_count,_tsm_mesh_attribute_name,_tsm_mesh_attribute_kind,_tsm_mesh_attribute_domain"
  EXPORTS+=",_tsm_mesh_attribute_type,_tsm_mesh_attribute_components,_tsm_mesh_attribute_value_count"
  EXPORTS+=",_tsm_mesh_attribute_values,_tsm_mesh_attribute_index_count,_tsm_mesh_attribute_indices"
  EXPORTS+=",_tsm_mesh_metadata_count,_tsm_mesh_metadata_key,_tsm_mesh_metadata_value"
  echo "web/build.sh: attribute and metadata accessors found, exported"
fi
# Binaryen inlines every function of one caller whatever its size: decode_part
# became one 92 KB function (connectivity, geometry, attributes, split layout).
# One-caller functions above 500 bytes stay calls (largest function 33 KB):
# +0.9 KB gzip, decode 0-10% faster under Node (2CylinderEngine 76.0 -> 69.6
# ms, dragon res2 55.2 -> 49.8, bunny unchanged).
LINK_TUNE=(-sBINARYEN_EXTRA_PASSES=--one-caller-inline-max-function-size=500)
[ "${TSM_WEB_DEBUG:-0}" = 1 ] && LINK_TUNE=()
link() {  # output.js exports objects...
  local out="$1" exports="$2"; shift 2
  emcc "${LOPT[@]}" "${LINK_TUNE[@]}" "$@" -o "$out" \
    -sMODULARIZE=1 -sEXPORT_ES6=1 -sEXPORT_NAME=createTsmModule \
    -sENVIRONMENT=web,worker -sFILESYSTEM=0 \
    -sALLOW_MEMORY_GROWTH=1 -sMAXIMUM_MEMORY=4GB -sINITIAL_MEMORY=16MB -sMALLOC=emmalloc \
    -sEXPORTED_FUNCTIONS="$exports" -sEXPORTED_RUNTIME_METHODS=[] \
    -sINCOMING_MODULE_JS_API=[wasmBinary,locateFile,instantiateWasm,print,printErr,onAbort] \
    -sTEXTDECODER=2 -sDYNAMIC_EXECUTION=0
  local w="${out%.js}.wasm"
  echo "web/build.sh: built $out + $(basename "$w") ($(stat -c %s "$w") bytes wasm, $(stat -c %s "$out") bytes js)"
}
link "$OUT/tsm_decoder_full.js" "$EXPORTS" "${OBJS[@]}"
link "$OUT/tsm_decoder.js" "$EXPORTS,_tsm_web_core_refused" "${CORE_OBJS[@]}"
# The JS API and the three.js plugin beside the glue: build/web/ is the folder a site serves.
cp "$ROOT/web/tsm.js" "$ROOT/web/tsm-worker.js" "$ROOT/web/gltf-tsm-extension.js" "$OUT/"
STREAMING=false
grep -q "tsm_stream_new" "$LIBCODEC/include/tsm/tsm.h" && STREAMING=true
ATTRIBUTES=false
grep -q "tsm_mesh_attribute_count" "$LIBCODEC/include/tsm/tsm.h" && ATTRIBUTES=true
printf '{"version": "%s", "zstd": "%s", "streaming": %s, "attributes": %s}\n' "$VERSION" "$ZSTD_MODE" "$STREAMING" \
  "$ATTRIBUTES" > "$OUT/build-info.json"
