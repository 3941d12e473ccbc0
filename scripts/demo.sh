#!/usr/bin/env bash
# The main job: install, build (release), then compress and decompress the
# default mesh (the Stanford dragon) and compare with Draco in one process.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
bash scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release
tsm=build/release/cli/tsm
mesh=$(bash scripts/fetch-default-mesh.sh)
echo
if [ -n "$mesh" ]; then
  $tsm encode "$mesh" -o build/dragon.tsm -f
  $tsm decode build/dragon.tsm -o build/dragon-decoded.ply -f
  $tsm info build/dragon.tsm
  echo
  $tsm bench "$mesh" --runs 3
else
  echo "demo: the default mesh could not be fetched; benchmarking a generated sphere" >&2
  $tsm bench --runs 3
fi
