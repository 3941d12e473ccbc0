#!/usr/bin/env bash
# Builds the libFuzzer targets (in the asan preset's build, build/asan: clang,
# ASan + UBSan, the libraries instrumented for coverage; the same build the
# test suite runs its tests in) and runs each for SECONDS with a generated
# seed corpus:
#
#   fuzz/run.sh SECONDS [TARGET...]     (targets: fuzz_decode fuzz_read_mesh fuzz_roundtrip fuzz_gltf_transcode)
#   fuzz/run.sh --smoke [TARGET...]     (the test suite's run: reproducible)
#
# --smoke runs a fixed number of executions per target (decode 10,000,
# read_mesh 6,000, roundtrip 800, gltf_transcode 1,000: about 15-90 s each here) with libFuzzer's
# seed fixed, from the generated seeds only (a fresh corpus, the kept one is
# not read), so a commit explores about the same inputs on every machine
# and every run (not exactly: coverage of threaded or timing-dependent code
# steers the mutations a little) instead of whatever a fast or slow machine
# reaches in 20 s; the open-ended search for new bugs is the SECONDS mode,
# run for hours.
#
# Prints, per target, the executions and the result; exits non-zero when a
# target finds a crash, leak, timeout or out-of-memory, with the path of the
# file that reproduces it (rerun it with: build/asan/fuzz/TARGET FILE).
# Seeds are generated into build/fuzz/seeds/TARGET/ by fuzz_seeds (never
# committed); inputs the fuzzer finds go to build/fuzz/corpus/TARGET/ and are
# kept for the next run; full logs in build/fuzz/logs/. Runs at nice 19, one
# target at a time and builds with -j1 (FUZZ_JOBS=N: N targets at once, -jN).
set -euo pipefail

usage() { echo "usage: fuzz/run.sh SECONDS|--smoke [fuzz_decode|fuzz_read_mesh|fuzz_roundtrip|fuzz_gltf_transcode]..." >&2; exit 2; }
[ $# -ge 1 ] || usage
smoke=0
if [ "$1" = --smoke ]; then
  smoke=1
  secs=600  # a ceiling only: the run counts below end each target first
else
  secs=$1
  [[ "$secs" =~ ^[1-9][0-9]*$ ]] || usage
fi
shift
smoke_runs() {
  case $1 in
    fuzz_decode) echo 10000 ;;
    fuzz_read_mesh) echo 6000 ;;
    fuzz_roundtrip) echo 800 ;;
    fuzz_gltf_transcode) echo 1000 ;;
  esac
}
all=(fuzz_roundtrip fuzz_decode fuzz_read_mesh fuzz_gltf_transcode)  # longest first
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz: unknown target '$t' (known: ${all[*]})" >&2; exit 2; }
done

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
build=build/fuzz
die() {
  echo "fuzz: FAILED: $*" >&2
  exit 1
}

# The toolchain: clang with libFuzzer. Without it there is no fuzzing, and
# that is an error, never a silent skip.
command -v clang++ >/dev/null 2>&1 ||
  die "clang++ is not installed; the fuzzers need clang and libFuzzer (bash scripts/setup.sh installs clang and libclang-rt-14-dev)"
probe_dir=$(mktemp -d)
trap 'rm -rf "$probe_dir"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' >"$probe_dir/p.cpp"
if ! clang++ -fsanitize=fuzzer,address,undefined "$probe_dir/p.cpp" -o "$probe_dir/p" >"$probe_dir/log" 2>&1; then
  cat "$probe_dir/log" >&2
  die "clang++ cannot link a libFuzzer target (-fsanitize=fuzzer): the libFuzzer runtime is missing (bash scripts/setup.sh installs libclang-rt-14-dev)"
fi

mkdir -p "$build/logs"
if ! cmake --preset asan >"$build/logs/configure.log" 2>&1; then
  cat "$build/logs/configure.log" >&2
  die "configuring build/asan (cmake --preset asan) failed (if it was first configured with another compiler, remove build/asan)"
fi
if ! nice -n 19 cmake --build build/asan -j "${FUZZ_JOBS:-1}" --target tsm_fuzz >"$build/logs/build.log" 2>&1; then
  tail -n 60 "$build/logs/build.log" >&2
  die "building the fuzz targets failed (full log: $build/logs/build.log)"
fi
bin=build/asan/fuzz
"$bin/fuzz_seeds" "$build/seeds" || die "the seed generator failed"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# One target: its run, then its result lines in $build/logs/$t.result
# (printed in the targets' order once all have run); returns non-zero on a
# finding.
run_target() {
  local t=$1 corpus=$build/corpus/$1 artifacts=$build/artifacts/$1 log=$build/logs/$1.log
  local extra=() start rc=0 took execs units artifact kind
  if [ "$smoke" = 1 ]; then
    corpus=$build/smoke-corpus/$t
    rm -rf "$corpus"
    extra+=(-seed=1 -runs="$(smoke_runs "$t")")
  fi
  mkdir -p "$corpus" "$artifacts"
  [ -f "fuzz/$t.dict" ] && extra+=("-dict=fuzz/$t.dict")
  start=$(date +%s)
  # -malloc_limit_mb: no input of a few kilobytes justifies a 512 MB block.
  nice -n 19 "$bin/$t" -max_total_time="$secs" -timeout=30 -rss_limit_mb=2048 -malloc_limit_mb=512 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" "${extra[@]}" "$corpus" "$build/seeds/$t" \
    >"$log" 2>&1 || rc=$?
  took=$(($(date +%s) - start))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  if [ -z "$execs" ]; then  # a crash ends the run before the final stats
    execs=$(grep -o '^#[0-9]*' "$log" | tail -n 1 | tr -d '#' || true)
  fi
  units=$(find "$corpus" -type f | wc -l)
  if [ "$rc" -eq 0 ]; then
    echo "fuzz: $t: ok, ${execs:-?} executions in ${took} s, corpus $units inputs" >"$build/logs/$t.result"
    return 0
  fi
  artifact=$(sed -n "s/.*Test unit written to \(.*\)$/\1/p" "$log" | tail -n 1)
  kind=$(grep -m1 -oE 'ERROR: (AddressSanitizer|UndefinedBehaviorSanitizer|LeakSanitizer|libFuzzer): [a-z-]+[^ ]*|runtime error: .*' "$log" || true)
  {
    echo "fuzz: $t: FAILED (exit $rc) after ${execs:-?} executions in ${took} s: ${kind:-see the log}"
    echo "fuzz: $t: reproducer: ${artifact:-none written}   (rerun: $bin/$t ${artifact:-FILE})"
    echo "fuzz: $t: log: $log; its end:"
    tail -n 40 "$log" | sed 's/^/    /'
  } >"$build/logs/$t.result"
  return 1
}

# FUZZ_JOBS targets at a time (each libFuzzer run is one process on one core).
for t in "${targets[@]}"; do
  rm -f "$build/logs/$t.result"
  while [ "$(jobs -rp | wc -l)" -ge "${FUZZ_JOBS:-1}" ]; do sleep 1; done
  run_target "$t" &
done
wait
failed=()
for t in "${targets[@]}"; do
  if [ -f "$build/logs/$t.result" ]; then
    cat "$build/logs/$t.result"
    grep -q "^fuzz: $t: ok," "$build/logs/$t.result" || failed+=("$t")
  else
    echo "fuzz: $t: FAILED: no result (log: $build/logs/$t.log)"
    failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]}" >&2
  exit 1
fi
if [ "$smoke" = 1 ]; then
  echo "fuzz: all ${#targets[@]} targets ran their smoke executions (seed 1) without a finding"
else
  echo "fuzz: all ${#targets[@]} targets ran ${secs} s each without a finding"
fi
