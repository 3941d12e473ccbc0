#!/usr/bin/env bash
# Encodes the corpus meshes for the demo, the browser test and the bench into
# build/web/data/: NAME.tsm (native `tsm encode`, -q 14), NAME.drc (Debian's
# draco_encoder -cl 10 -qp 14), NAME.ref.json (counts and FNV-1a checksums of
# the native decoder's output: `tsm decode` to binary PLY, read by
# web/tools/ply-ref.mjs), and index.json listing them.
#
#   web/prepare-data.sh [NAME ...]      # default: every mesh below
# Env: TSM (the native CLI, default build/release/cli/tsm), CORPUS (../shared/corpus),
#      TSM_ENCODE_ARGS (extra `tsm encode` options, e.g. "--segment-faces 20000").
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
TSM="${TSM:-$ROOT/build/release/cli/tsm}"
CORPUS="${CORPUS:-$ROOT/../shared/corpus}"
OUT="$ROOT/build/web/data"
mkdir -p "$OUT"

# name:source (relative to the corpus)[:faces per segment, when the encoder has --segment-faces][:level]
# [:progressive][:drop (--drop-attributes: bunny_pos is the bunny as Draco's PLY reader sees it, positions
# only, so the bench times the same content for both)]
MESHES="bunny:bun_zipper.ply dragon_res4:dragon_vrip_res4.ply dragon_res3:dragon_vrip_res3.ply
dragon_res2:dragon_vrip_res2.ply dragon:dragon_vrip.ply cube_quads:edge/cube_quads.obj
dragon_seg16k:dragon_vrip.ply:16384 bunny_seg4k:bun_zipper.ply:4096
dragon_res4_l0:dragon_vrip_res4.ply::0 bunny_l0:bun_zipper.ply::0 bunny_l2:bun_zipper.ply::2
dragon_res3_l1:dragon_vrip_res3.ply::1
bunny_prog:bun_zipper.ply:::progressive dragon_res4_prog:dragon_vrip_res4.ply:::progressive
bunny_pos:bun_zipper.ply::::drop"
SEGMENTS=0
"$TSM" encode --help 2>/dev/null | grep -q -- --segment-faces && SEGMENTS=1

[ -x "$TSM" ] || { echo "prepare-data: $TSM not built (cmake --preset release && cmake --build --preset release)" >&2; exit 1; }
[ -d "$CORPUS" ] || { echo "prepare-data: no corpus at $CORPUS" >&2; exit 1; }
HAVE_DRACO=1
command -v draco_encoder >/dev/null || { HAVE_DRACO=0; echo "prepare-data: draco_encoder not found (apt-get install draco): no .drc files" >&2; }

make_ref() {  # NAME: NAME.ref.json from the native decoder's output
  local name="$1" ref="$OUT/$1.ref.json"
  if [ ! -f "$ref" ] || [ "$TSM" -nt "$ref" ] || [ "$OUT/$name.tsm" -nt "$ref" ]; then
    "$TSM" decode "$OUT/$name.tsm" -o "$OUT/$name.decoded.ply" -f --quiet
    node "$HERE/tools/ply-ref.mjs" "$OUT/$name.decoded.ply" > "$ref.tmp" && mv "$ref.tmp" "$ref"
    rm -f "$OUT/$name.decoded.ply"
  fi
}

want=("$@")
list=()
for entry in $MESHES; do
  IFS=: read -r name rel segfaces level progressive drop <<<"$entry"
  src="$CORPUS/$rel"
  extra="${TSM_ENCODE_ARGS:-}"
  if [ -n "$segfaces" ]; then
    [ "$SEGMENTS" = 1 ] || continue  # no segments in this encoder: the variant would be the same file
    extra="$extra --segment-faces $segfaces"
  fi
  # A level (the fast ones: format version 9's table-coded run values and
  # attribute residuals, version 10's fan predictor at levels 1-2) for a
  # variant of a mesh listed whole.
  [ -n "$level" ] && extra="$extra -l $level"
  # A progressive file (a base mesh, then batches of vertex splits).
  [ -n "$progressive" ] && extra="$extra --progressive --drop-attributes"
  [ -n "$drop" ] && extra="$extra --drop-attributes"
  if [ "${#want[@]}" -gt 0 ] && [[ ! " ${want[*]} " == *" $name "* ]]; then continue; fi
  [ -f "$src" ] || { echo "prepare-data: $src missing, skipped" >&2; continue; }
  list+=("$name")
  ARGS_SIG="$(echo "$extra" | tr ' ' '_')"
  tsmf="$OUT/$name.tsm" drc="$OUT/$name.drc" ref="$OUT/$name.ref.json" sig="$OUT/$name.args"
  if [ ! -f "$tsmf" ] || [ "$src" -nt "$tsmf" ] || [ "$TSM" -nt "$tsmf" ] || [ "$(cat "$sig" 2>/dev/null)" != "$ARGS_SIG" ]; then
    # shellcheck disable=SC2086
    "$TSM" encode "$src" -o "$tsmf" -q 14 -f --quiet $extra
    echo "$ARGS_SIG" > "$sig"
    rm -f "$ref"
  fi
  make_ref "$name"
  if [ -n "$segfaces" ] || [ -n "$level" ] || [ -n "$progressive" ] || [ -n "$drop" ]; then drc=/nonexistent  # the same mesh as its whole-file entry for Draco
  elif [ "$HAVE_DRACO" = 1 ] && { [ ! -f "$drc" ] || [ "$src" -nt "$drc" ]; }; then
    draco_encoder -i "$src" -o "$drc" -cl 10 -qp 14 >/dev/null
  fi
  echo "prepare-data: $name: $(stat -c %s "$tsmf") bytes .tsm$( [ -f "$drc" ] && echo ", $(stat -c %s "$drc") bytes .drc")"
done

# NAME_zstd: the same files with every section zstd-coded (the format allows
# it, the encoder never does it): tests the zstd path of the decoders.
if command -v zstd >/dev/null; then
  for base in dragon_res4 bunny_seg4k; do
    [[ " ${list[*]} " == *" $base "* ]] || continue
    name="${base}_zstd"
    if [ ! -f "$OUT/$name.tsm" ] || [ "$OUT/$base.tsm" -nt "$OUT/$name.tsm" ]; then
      node "$HERE/tools/zstd-sections.mjs" "$OUT/$base.tsm" "$OUT/$name.tsm" 2>/dev/null
    fi
    make_ref "$name"
    list+=("$name")
    echo "prepare-data: $name: $(stat -c %s "$OUT/$name.tsm") bytes .tsm (every section zstd-coded)"
  done
else
  echo "prepare-data: no zstd command (apt-get install zstd): no zstd-coded test files" >&2
fi

# index.json: what the pages offer
{
  echo "["
  sep=""
  for name in "${list[@]}"; do
    drcsize=null
    [ -f "$OUT/$name.drc" ] && drcsize="$(stat -c %s "$OUT/$name.drc")"
    segs="$("$TSM" info "$OUT/$name.tsm" 2>/dev/null | sed -n 's/.*segments \([0-9,]*\).*/\1/p' | tr -d , | head -1)"
    batches="$("$TSM" info "$OUT/$name.tsm" 2>/dev/null | sed -n 's/.* \([0-9]*\) refinement batches.*/\1/p' | head -1)"
    printf '%s  {"name": "%s", "tsmBytes": %s, "drcBytes": %s, "segments": %s, "batches": %s, "ref": %s}' "$sep" "$name" \
      "$(stat -c %s "$OUT/$name.tsm")" "$drcsize" "${segs:-1}" "${batches:-0}" "$(cat "$OUT/$name.ref.json")"
    sep=$',\n'
  done
  printf '\n]\n'
} > "$OUT/index.json"
