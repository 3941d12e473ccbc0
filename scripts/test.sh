#!/usr/bin/env bash
# The whole test suite: install, build release (gcc, -O2) and ASan+UBSan
# (clang; the same build holds the libFuzzer targets), run the tests in both
# (the format spec's independent Python decoder against the C++ one and the
# Python module are release tests), then a short smoke run of every libFuzzer
# target (fuzz/run.sh; clang + libFuzzer are required: without them this
# fails, it never skips), then the browser
# test (web/test.sh: emscripten and Chromium from Debian; when they cannot be
# installed it prints "web test SKIPPED: <reason>" and the suite goes on,
# except in CI (CI=true), where that is a failure). In CI a missing
# ../shared/corpus fails the corpus tests too; locally they are skipped.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
jobs=$(nproc)
# Each phase's wall time, printed at the end (CI's budget is ~20 minutes).
start=$(date +%s)
last=$start
times=()
phase() {
  local now
  now=$(date +%s)
  [ -z "${current:-}" ] || times+=("$current: $((now - last)) s")
  current=${1%% (*}
  current=${current%%:*}
  last=$now
  [ "$1" = end ] || echo "== $1"
}
phase setup
bash scripts/setup.sh
for preset in release asan; do
  phase "$preset build"
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" -j "$jobs"
  phase "$preset tests"
  ctest --preset "$preset" -j "$jobs"
done
phase "fuzz smoke run (fixed executions and seed per target, $jobs at a time)"
FUZZ_JOBS=$jobs bash fuzz/run.sh --smoke
phase "browser test: the WebAssembly decoder in headless Chromium (web/test.sh; it says plainly when it skips, and fails instead in CI)"
bash web/test.sh
phase end
echo "== all passed in $(($(date +%s) - start)) s:"
printf '   %s\n' "${times[@]}"
