#!/bin/sh
# Checks reference_decoder.py against `tsm decode` (faces and float bits of
# every position) on the test meshes of test_meshes.py and a corpus mesh.
# Usage: check_decoder.sh [TSM_BINARY] [WORK_DIR]
set -e
here=$(cd "$(dirname "$0")" && pwd)
tsm=${1:-$here/../build/release/cli/tsm}
work=${2:-$(mktemp -d)}
dragon=$here/../../shared/corpus/dragon_vrip_res4.ply
python3 "$here/test_meshes.py" "$work"
check() {  # name mesh q level [segment_faces]
  "$tsm" encode "$2" -o "$work/$1.tsm" -q "$3" -l "$4" --segment-faces "${5:-0}" -f --quiet
  "$tsm" decode "$work/$1.tsm" -o "$work/$1.ply" -f --quiet
  python3 "$here/reference_decoder.py" "$work/$1.tsm" --compare "$work/$1.ply"
}
check triangle "$work/triangle.obj" 8 0
for l in 0 6 9; do check mixed_l$l "$work/mixed.obj" 16 $l; done
check mixed_small_l9 "$work/mixed_small.obj" 10 9
for l in 0 6 9; do check lattice_l$l "$work/lattice.obj" 12 $l; done
for l in 0 6; do check mixed_segments_l$l "$work/mixed.obj" 12 $l 7; done
check lattice_segments "$work/lattice.obj" 12 6 50
if [ -f "$dragon" ]; then
  for l in 0 6 9; do check dragon_l$l "$dragon" 11 $l; done
  check dragon_segments "$dragon" 11 6 2000
fi
