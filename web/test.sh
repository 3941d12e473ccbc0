#!/usr/bin/env bash
# The browser side of tsm, end to end: installs what it needs, builds the
# WebAssembly decoder (web/build.sh), encodes the corpus meshes natively
# (web/prepare-data.sh), and runs the Chromium test (web/test/browser.mjs):
# each mesh streamed through the decoder in headless Chromium, counts and
# index/position checksums against the native decoder's, screenshots in
# build/web/screenshots/; then glTF with TSM_mesh_compression through three.js
# and the Khronos validator (web/test/gltf.mjs), and the npm package, packed,
# installed into a scratch project and imported (web/test/package.mjs).
#
#   web/test.sh            # the test
#   web/test.sh --bench    # then the decode-time bench beside draco3d and the sizes (build/web/bench.md),
#                          # and the glTF one beside draco3d and meshopt (build/web/gltf-bench.md)
#
# When emscripten or Chromium (or Node/npm) cannot be had, it prints
# "web test SKIPPED: <reason>" and exits 0, except in CI (the CI variable set
# to anything but "", "0" or "false"): there it prints "web test FAILED: cannot
# run in CI: <reason>" and exits 1, so a CI run cannot pass without the
# browser test. Any other failure exits non-zero.
set -uo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
BENCH=0
for a in "$@"; do case "$a" in --bench) BENCH=1 ;; *) echo "usage: web/test.sh [--bench]" >&2; exit 2 ;; esac; done

in_ci() { case "$(printf '%s' "${CI:-}" | tr '[:upper:]' '[:lower:]')" in ""|0|false) return 1 ;; *) return 0 ;; esac; }
skip() {
  if in_ci; then echo "web test FAILED: cannot run in CI: $*" >&2; exit 1; fi
  echo "web test SKIPPED: $*"; exit 0
}
fail() { echo "web test FAILED: $*" >&2; exit 1; }
mkdir -p "$ROOT/build/web"
LOG="$ROOT/build/web/install.log"
: > "$LOG"

# ---- Debian packages --------------------------------------------------------------
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
SUDO=""
if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then SUDO="sudo -n"; fi
APT_UPDATED=0
apt_install() {  # packages...; returns non-zero when they cannot be installed
  local missing=()
  for p in "$@"; do installed "$p" || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  command -v apt-get >/dev/null || return 1
  if [ "$(id -u)" -ne 0 ] && [ -z "$SUDO" ]; then return 1; fi
  if [ "$APT_UPDATED" = 0 ]; then $SUDO apt-get update -qq >>"$LOG" 2>&1 || return 1; APT_UPDATED=1; fi
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >>"$LOG" 2>&1
}

command -v node >/dev/null && command -v npm >/dev/null || skip "node and npm are not installed"
# the library's build dependencies (header-only in the wasm build), Draco's encoder CLI for the bench files,
# and Draco's and meshoptimizer's libraries: with them the native CLI reads Draco- and meshopt-compressed glTF (web/test/gltf.mjs)
apt_install libxxhash-dev libzstd-dev libeigen3-dev draco zstd libdraco-dev libmeshoptimizer-dev ||
  fail "cannot install libxxhash-dev libzstd-dev libeigen3-dev draco zstd libdraco-dev libmeshoptimizer-dev (see build/web/install.log)"
apt_install emscripten node-acorn || skip "emscripten cannot be installed (apt-get install emscripten node-acorn failed; build/web/install.log)"
command -v emcc >/dev/null || skip "emcc not found after installing emscripten"
apt_install chromium || skip "Chromium cannot be installed (apt-get install chromium failed; build/web/install.log)"
[ -x /usr/bin/chromium ] || skip "/usr/bin/chromium not found after installing chromium"

# ---- npm packages (web/package-lock.json) -----------------------------------------
if [ ! -d "$HERE/node_modules/playwright-core" ] || [ ! -d "$HERE/node_modules/draco3d" ] ||
   [ ! -d "$HERE/node_modules/three" ] || [ ! -d "$HERE/node_modules/gltf-validator" ] ||
   [ "$HERE/package-lock.json" -nt "$HERE/node_modules/.package-lock.json" ]; then
  (cd "$HERE" && npm ci --no-audit --no-fund >>"$LOG" 2>&1) || skip "npm ci in web/ failed (npm registry unreachable?; build/web/install.log)"
fi

# ---- build ------------------------------------------------------------------------
nice -n 10 bash "$HERE/build.sh" || fail "web/build.sh failed"
# The native CLI makes the reference figures: it must be of the same sources
# as the wasm, so it is (re)built when missing or older than libcodec/.
TSM="$ROOT/build/release/cli/tsm"
if [ ! -x "$TSM" ] || [ -n "$(find "$ROOT/libcodec" "$ROOT/cli" -newer "$TSM" -type f 2>/dev/null | head -1)" ]; then
  echo "web/test.sh: building the native tsm CLI (build/release) for the reference data"
  { { [ -f "$ROOT/build/release/CMakeCache.txt" ] || (cd "$ROOT" && cmake --preset release >/dev/null); } &&
    nice -n 10 cmake --build "$ROOT/build/release" --target tsm_cli -j 2 >"$ROOT/build/web/native-build.log" 2>&1; } ||
    fail "cannot build the native CLI (build/web/native-build.log)"
fi
TSM="$TSM" bash "$HERE/prepare-data.sh" || fail "web/prepare-data.sh failed"

# ---- test -------------------------------------------------------------------------
node "$HERE/test/browser.mjs" || fail "the Chromium test failed (screenshots in build/web/screenshots/)"
node "$HERE/test/gltf.mjs" || fail "the glTF / three.js test failed (screenshots in build/web/screenshots/gltf-*.png)"
node "$HERE/test/package.mjs" || fail "the npm package test failed (scratch project in build/web/pack-test/)"
if [ "$BENCH" = 1 ]; then
  node "$HERE/test/bench.mjs" || fail "the bench failed"
  node "$HERE/test/gltf-bench.mjs" || fail "the glTF bench failed"
fi
exit 0
