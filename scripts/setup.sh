#!/usr/bin/env bash
# Installs everything tsm needs from Debian packages. Idempotent and quiet:
# prints nothing when all is installed, and the apt log only if apt fails.
# Runs as root (CI, fresh machines) or through sudo.
set -euo pipefail

PACKAGES=(
  # build
  g++ cmake ninja-build pkg-config git ca-certificates
  # core library
  libzstd-dev libeigen3-dev libxxhash-dev
  # glTF reading and writing (tinygltf's header, compiled in; its JSON library)
  libtinygltf-dev nlohmann-json3-dev
  # command-line tool
  libcli11-dev
  # tests (and the sanitizer build's runtime comes with gcc); python3 runs the
  # format spec's independent reference decoder (format-spec/check_decoder.sh)
  libgtest-dev python3 python3-zstandard zstd
  # the Python module tsmcodec (python/) and its tests, for Debian's python3
  pybind11-dev python3-numpy python3-pytest
  # comparison (optional at build time; the bench shows its columns when present);
  # Draco and meshoptimizer also decode KHR_draco_mesh_compression and
  # EXT_meshopt_compression glTF input (libio); gltfpack makes meshopt glTF
  # for the transcoding tests and the glTF size table
  libdraco-dev draco gltfpack
  # test data beyond the corpus (optional): real glTF, OBJ and other models
  # for `tsm bench /usr/share/assimp/models/glTF2` (shared meshes, morph targets)
  assimp-testmodels
  # comparison/oracles: CGAL's bounded-error Hausdorff distance checks `tsm
  # compare` and `tsm simplify` (tests/cgal, bench); meshoptimizer's simplifier
  # is the simplification benchmark's reference (header-only / optional)
  libcgal-dev libmeshoptimizer-dev
  # the rate-distortion plot for the README (scripts/rd_plot.py)
  python3-matplotlib
  # fuzzers (clang's libFuzzer)
  clang libclang-rt-14-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "setup: these packages are missing and I am not root (and there is no sudo): ${missing[*]}" >&2
    exit 1
  fi
fi

log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
  echo "setup: apt-get failed while installing: ${missing[*]}" >&2
  cat "$log" >&2
  exit 1
fi
