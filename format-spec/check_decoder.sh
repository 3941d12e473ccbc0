#!/bin/sh
# Checks reference_decoder.py against `tsm decode`, bit for bit, on the test
# meshes of test_meshes.py and on corpus meshes.
#
# Usage: check_decoder.sh [TSM_BINARY] [WORK_DIR]
#   TSM_BINARY: the tsm CLI (default: $TSM, else ../build/release/cli/tsm)
#   CORPUS=DIR: the corpus folder (default: ../../shared/corpus); missing corpus
#               files are skipped with a note, or fail the check when CI is set
#               (to anything but empty, 0 or false)
#
# How the outputs are compared (one line per case, IDENTICAL or DIFFERENT):
# * every case: `tsm decode X.tsm -o X.ply` (binary PLY) against the PLY that
#   reference_decoder.py writes the way io_ply.cpp does, byte for byte: the
#   header (so the attribute names, kinds, types and order), the float bits of
#   every position, the faces, every vertex and face attribute value, and every
#   corner attribute value as the per-face lists io_ply.cpp writes (one value
#   per corner);
# * cases with attributes also: `tsm decode X.tsm -o X.obj` against the
#   decoder's values (parsed exactly to binary32): positions, the first vertex
#   colour, and the whole value lists of the first texcoord (or 'texcoord3')
#   and normal attribute with every corner's index: so the shared value lists
#   of corner attributes (which values corners share, the values no corner
#   uses) are compared too, which PLY cannot express. Other corner attributes
#   are compared per corner through the PLY only.
# * metadata (section 9, §4.6): the CLI cannot write it, so test_meshes.py
#   --add-metadata inserts a raw section 9 into an encoded file; well-formed
#   ones must decode (and compare) on both sides, malformed ones must be
#   refused by both.
# * forged files (test_meshes.py --replace-in-mesh rewrites bytes of a mesh
#   section and its checksum, --forge-topology the run coding mode or the
#   length of the topology stream, --set-version the version field) must be
#   refused by both. A forging step that fails is a failed case.
# The last line gives the number of cases checked; none is a failure.
# Exit status: 0 when every case is IDENTICAL (and every malformed file
# refused by both), 1 otherwise.
here=$(cd "$(dirname "$0")" && pwd)
tsm=${1:-${TSM:-$here/../build/release/cli/tsm}}
work=${2:-$(mktemp -d)}
corpus=${CORPUS:-$here/../../shared/corpus}
dec=$here/reference_decoder.py
failed=""
cases=0
# Debian's python3 (where setup.sh installs python3-zstandard) when present,
# else whatever python3 is first on PATH; PYTHON overrides.
PY=${PYTHON:-$( [ -x /usr/bin/python3 ] && echo /usr/bin/python3 || echo python3 )}
"$PY" "$here/test_meshes.py" "$work" || exit 1

result() {  # name status
  cases=$((cases + 1))
  [ "$2" -eq 0 ] || failed="$failed $1"
}
encode() {  # name mesh q level [segment_faces [flag]] (q "" = none: --lossless takes no -q)
  "$tsm" encode "$2" -o "$work/$1.tsm" ${3:+-q "$3"} -l "$4" --segment-faces "${5:-0}" ${6:+"$6"} -f --quiet
}
check() {  # name mesh q level [segment_faces]: positions, faces and attributes through PLY
  if encode "$@" && "$tsm" decode "$work/$1.tsm" -o "$work/$1.ply" -f --quiet; then
    "$PY" "$dec" "$work/$1.tsm" --compare "$work/$1.ply" > "$work/$1.txt"
    st=$?; result "$1" $st; if [ $st -eq 0 ]; then sed 1d "$work/$1.txt"; else cat "$work/$1.txt"; fi
  else
    echo "$1: tsm failed"; result "$1" 1
  fi
}
acheck() {  # the same, and the corner value lists through OBJ
  if encode "$@" && "$tsm" decode "$work/$1.tsm" -o "$work/$1.ply" -f --quiet &&
     "$tsm" decode "$work/$1.tsm" -o "$work/$1.obj" -f --quiet; then
    "$PY" "$dec" "$work/$1.tsm" --compare "$work/$1.ply" --compare-obj "$work/$1.obj" > "$work/$1.txt"
    st=$?; result "$1" $st; if [ $st -eq 0 ]; then sed 1d "$work/$1.txt"; else cat "$work/$1.txt"; fi
  else
    echo "$1: tsm failed"; result "$1" 1
  fi
}
compare_file() {  # name: an existing $work/name.tsm
  if "$tsm" decode "$work/$1.tsm" -o "$work/$1.ply" -f --quiet; then
    "$PY" "$dec" "$work/$1.tsm" --compare "$work/$1.ply" > "$work/$1.txt"
    st=$?; result "$1" $st; if [ $st -eq 0 ]; then sed 1d "$work/$1.txt"; else cat "$work/$1.txt"; fi
  else
    echo "$1: tsm decode failed"; result "$1" 1
  fi
}
refused() {  # name: both decoders must refuse $work/name.tsm (corrupt_data)
  out=$("$PY" "$dec" "$work/$1.tsm")
  py=$?
  if "$tsm" decode "$work/$1.tsm" -o "$work/$1.ply" -f --quiet 2>/dev/null; then cpp=0; else cpp=$?; fi
  if [ $py -eq 2 ] && [ $cpp -ne 0 ]; then
    echo "$1: refused by both: ${out#*: }"; result "$1" 0
  else
    echo "$1: DIFFERENT: reference_decoder.py exit $py ($out), tsm decode exit $cpp"; result "$1" 1
  fi
}
forged() {  # name command...: runs a forging command; its failure is a failed case
  name=$1; shift
  if "$@"; then return 0; fi
  echo "$name: forging failed"; result "$name" 1; return 1
}
in_ci() { case "${CI:-}" in ""|0|false) return 1 ;; *) return 0 ;; esac; }
corpus_case() {  # check-function name file q level [segment_faces]
  fn=$1; shift
  if [ -f "$2" ]; then "$fn" "$@"
  elif in_ci; then echo "$1: FAILED, $2 not found (in CI the corpus must be there)"; result "$1" 1
  else echo "$1: skipped, $2 not found"; fi
}

# ---- connectivity and geometry
check triangle "$work/triangle.obj" 8 0
for l in 0 6 9; do check mixed_l$l "$work/mixed.obj" 16 $l; done
check mixed_q30_l0 "$work/mixed.obj" 30 0  # table-coded residuals of every bit length
check mixed_small_l9 "$work/mixed_small.obj" 10 9
check fan_l9 "$work/fan.obj" 12 9
for l in 0 6; do check irregular_l$l "$work/irregular.obj" 12 $l; done  # level 0: table-coded run values
check irregular_segments_l0 "$work/irregular.obj" 12 0 600
for l in 0 6 9; do check lattice_l$l "$work/lattice.obj" 12 $l; done
for q in 11 16; do check box_q$q "$work/box.obj" $q 6; done
for l in 0 6; do check mixed_segments_l$l "$work/mixed.obj" 12 $l 7; done
check lattice_segments "$work/lattice.obj" 12 6 50
for l in 0 6; do check double_sided_l$l "$work/double_sided.obj" 12 $l; done  # stitch targets by candidates
check double_sided_segments "$work/double_sided.obj" 12 6 300
for l in 1 2; do check mixed_l$l "$work/mixed.obj" 16 $l; done  # levels 1-2: gate or fan, lattice planes
dragon=$corpus/dragon_vrip_res4.ply
for l in 0 1 2 6 9; do corpus_case check dragon_l$l "$dragon" 11 $l; done
corpus_case check dragon_segments "$dragon" 11 6 2000
# keep-order files (§4.8): the order section reorders the decoded mesh
check keep_order_mixed "$work/mixed.obj" 12 6 0 --keep-order
check keep_order_double_sided "$work/double_sided.obj" 12 6 300 --keep-order
corpus_case check keep_order_dragon "$dragon" 11 6 0 --keep-order
# progressive files (§4.8): the base mesh, then batches of vertex splits and the loose vertices
check progressive_irregular "$work/irregular.obj" 12 6 0 --progressive
check progressive_mixed "$work/mixed.obj" 12 6 0 --progressive
check progressive_loose "$work/loose.obj" 12 6 0 --progressive  # 150 loose vertices
corpus_case check progressive_dragon "$dragon" 11 6 0 --progressive
# lossless files (§5.1): the exact grid and its exceptions
check lossless_mixed "$work/mixed.obj" "" 6 0 --lossless
check lossless_segments "$work/irregular.obj" "" 0 600 --lossless
corpus_case check lossless_dragon "$dragon" "" 6 0 --lossless
corpus_case check lossless_bunny "$corpus/bun_zipper.ply" "" 2 0 --lossless

# ---- attributes (§8.12)
for l in 0 9; do acheck attributes_obj_l$l "$work/attributes.obj" 12 $l; done
for l in 0 9; do acheck attributes_ply_l$l "$work/attributes.ply" 12 $l; done
acheck attributes_obj_segments "$work/attributes.obj" 12 6 60
acheck attributes_ply_segments "$work/attributes.ply" 12 6 100
acheck keep_order_attributes_obj "$work/attributes.obj" 12 6 60 --keep-order
acheck keep_order_attributes_ply "$work/attributes.ply" 12 6 0 --keep-order
acheck lossless_attributes_ply "$work/attributes.ply" "" 6 0 --lossless
edge=$corpus/edge
for f in cube_att.obj cube_att.ply sphere.obj test_nm.obj Box.ply test_pos_color.ply test_more_datatypes.ply; do
  corpus_case acheck "$(echo "$f" | tr . _)" "$edge/$f" 11 6
done
corpus_case acheck sphere_obj_segments "$edge/sphere.obj" 11 6 50
corpus_case acheck sphere_obj_q14 "$edge/sphere.obj" 14 6  # parallelograms with planes from the top
corpus_case acheck test_pos_color_ply_segments "$edge/test_pos_color.ply" 11 6 40
# welded meshes (§8.13): flat-shaded with slivers, and the glTF assets
for l in 0 6 9; do acheck flat_l$l "$work/flat.ply" 12 $l; done
for l in 0 6; do acheck cad_l$l "$work/cad.ply" 11 $l; done
acheck cad_obj "$work/cad.obj" 11 6
for f in Fox/Fox.gltf CesiumMilkTruck/CesiumMilkTruck.gltf MultiUVTest/MultiUVTest.gltf VertexColorTest/VertexColorTest.gltf; do
  corpus_case acheck "$(basename "$f" .gltf)" "$corpus/assets/$f" 11 6
done
# OBJ exports (tsm decode) of welded meshes: per-vertex values as corner
# attributes, one list entry per vertex (vn, vt), coded per vertex (§8.12
# predictor bit 4); flat.ply's has a vertex on no face (an unused value)
if encode flat_src "$work/flat.ply" 12 6 && "$tsm" decode "$work/flat_src.tsm" -o "$work/flat_export.obj" -f --quiet; then
  for l in 0 6; do acheck flat_obj_l$l "$work/flat_export.obj" 12 $l; done
else echo "flat_obj: tsm failed"; result flat_obj 1; fi
for f in Fox/Fox.gltf CesiumMilkTruck/CesiumMilkTruck.gltf; do
  n=$(basename "$f" .gltf)_obj
  [ -f "$corpus/assets/$f" ] && encode "${n}_src" "$corpus/assets/$f" 11 6 &&
    "$tsm" decode "$work/${n}_src.tsm" -o "$work/$n.obj" -f --quiet
  corpus_case acheck "$n" "$work/$n.obj" 11 6
done
# the truck's OBJ with its v, vt and vn lists deduplicated, as exporters
# write them: corner values shared across vertices (normals predicted by
# face or angle, §8.12 predictors 3 and 4, in the corner domain)
dedup_obj() {  # in out
  python3 - "$1" "$2" <<'PY'
import sys
lists, faces = {'v': [], 'vt': [], 'vn': []}, []
for line in open(sys.argv[1]):
    p = line.split()
    if p and p[0] in lists:
        lists[p[0]].append(' '.join(p[1:]))
    elif p and p[0] == 'f':
        faces.append(p[1:])
index, kept = {}, {}
for k, values in lists.items():
    first = {}
    index[k] = [first.setdefault(v, len(first)) for v in values]
    kept[k] = list(first)
with open(sys.argv[2], 'w') as out:
    for k in ('v', 'vt', 'vn'):
        out.writelines('%s %s\n' % (k, v) for v in kept[k])
    for f in faces:
        corners = []
        for c in f:
            t = c.split('/')
            corners.append('/'.join(str(index[k][int(x) - 1] + 1) if x else '' for k, x in zip(('v', 'vt', 'vn'), t)))
        out.write('f %s\n' % ' '.join(corners))
PY
}
if [ -f "$work/CesiumMilkTruck_obj.obj" ]; then
  dedup_obj "$work/CesiumMilkTruck_obj.obj" "$work/truck_dedup.obj"
  acheck truck_dedup_obj "$work/truck_dedup.obj" 11 6
  # with ranks (§8.13 points out): positions sharing an 8-bit grid point,
  # normals equal at 8 bits
  acheck truck_dedup_ranks "$work/truck_dedup.obj" 8 6 0 --normal-bits=8
fi
# the Fox's the same way: coded as split vertices, points out (§8.13)
if [ -f "$work/Fox_obj.obj" ]; then
  dedup_obj "$work/Fox_obj.obj" "$work/fox_dedup.obj"
  acheck fox_dedup_obj "$work/fox_dedup.obj" 11 6
fi
# predictor 2 (texture placement): vertex and corner domain, whole and segmented
acheck uv_vertex "$work/uv_vertex.ply" 12 6
acheck uv_vertex_segments "$work/uv_vertex.ply" 12 6 150
acheck uv_corner "$work/uv_corner.obj" 12 6
# the same through the points-out route at 10 bits: seams crossed by the
# walk, predicted across them (§8.12 "Across a seam"), mirrored charts too
acheck uv_seam_transfer "$work/uv_corner.obj" 10 6
acheck uv_corner_segments "$work/uv_corner.obj" 12 6 60
# the fast level: table-coded attribute residuals (§8.12.1) for predictor 2
# in both domains, and in segments with values shared across borders
acheck uv_vertex_l0 "$work/uv_vertex.ply" 12 0
acheck uv_corner_l0 "$work/uv_corner.obj" 12 0
acheck uv_corner_segments_l0 "$work/uv_corner.obj" 12 0 600
acheck unused_vt_l0 "$work/unused_vt.obj" 12 0
corpus_case check bunny "$corpus/bun_zipper.ply" 12 6
corpus_case check bunny_l0 "$corpus/bun_zipper.ply" 14 0  # table-coded residuals and run values
corpus_case check bunny_l2 "$corpus/bun_zipper.ply" 14 2  # fan with the tangent step
corpus_case check bunny_segments_l1 "$corpus/bun_zipper.ply" 12 1 20000  # fan in segments
corpus_case check bunny_segments "$corpus/bun_zipper.ply" 12 6 20000

# ---- metadata (§4.6)
meta="$PY $here/test_meshes.py --add-metadata"
forged metadata $meta "$work/attributes_ply_l0.tsm" "$work/metadata.tsm" \
  gltf='{"asset":{"version":"2.0"}}' note=hello empty= && compare_file metadata
forged metadata_segments $meta "$work/attributes_ply_segments.tsm" "$work/metadata_segments.tsm" k=v &&
  compare_file metadata_segments
forged metadata_none $meta "$work/triangle.tsm" "$work/metadata_none.tsm" --raw 00 && compare_file metadata_none
if command -v zstd > /dev/null; then  # codec 1: checked if python3 has the zstandard module, else skipped
  forged metadata_zstd $meta "$work/mixed_l6.tsm" "$work/metadata_zstd.tsm" --zstd \
    "gltf=$(head -c 3000 "$work/mixed.obj")" && compare_file metadata_zstd
elif in_ci; then
  echo "metadata_zstd: FAILED, no zstd command (scripts/setup.sh installs it)"; result metadata_zstd 1
else
  echo "metadata_zstd: skipped, no zstd command"
fi
for bad in duplicate_key:02016100016100 empty_key:01000000 trailing_byte:01016100ff \
           count_too_large:02016100 value_too_long:0101610500 truncated_count:80; do
  forged "metadata_${bad%%:*}" $meta "$work/triangle.tsm" "$work/metadata_${bad%%:*}.tsm" --raw "${bad#*:}" &&
    refused "metadata_${bad%%:*}"
done

# ---- forged files, refused by both
# The version field (§2): only 12 is read.
for v in 0 3 11 13 65535; do
  forged "version_$v" "$PY" "$here/test_meshes.py" --set-version "$work/mixed_l6.tsm" "$work/version_$v.tsm" $v &&
    refused "version_$v"
done
# Run tables (§8.3.1): forged modes and cut tables (irregular.obj at level 0 has mode 1).
topo="$PY $here/test_meshes.py --forge-topology"
for op in mode=2 mode=0 cut=1 cut=7 cut=40 cut=300; do
  name="run_tables_$(echo "$op" | tr = _)"
  forged "$name" $topo "$work/irregular_l0.tsm" "$work/$name.tsm" "$op" && refused "$name"
done
# Attribute headers (§8.12): an integer type on a grid, f32 as exact integers.
forge="$PY $here/test_meshes.py --replace-in-mesh"
forged forged_u16_grid $forge "$work/attributes_ply_l0.tsm" "$work/forged_u16_grid.tsm" 0f6c6162656c2000 \
  0f6c6162656c2021000000000000000000 && refused forged_u16_grid
forged forged_f32_exact $forge "$work/attributes_ply_l0.tsm" "$work/forged_f32_exact.tsm" \
  1574656d70657261747572650041 1574656d70657261747572650000 && refused forged_f32_exact

if [ "$cases" -eq 0 ]; then
  echo "0 cases checked: FAILED"
  exit 1
fi
if [ -n "$failed" ]; then
  echo "$cases cases checked, FAILED:$failed"
  exit 1
fi
echo "$cases cases checked, all IDENTICAL"
