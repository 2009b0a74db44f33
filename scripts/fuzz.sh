#!/usr/bin/env bash
# Fuzzes every loader of armsim with libFuzzer (issue 15; docs/reliability.md).
#   scripts/fuzz.sh [SECONDS_PER_LOADER] [RUNS_PER_LOADER] [PARALLEL]   (0 seconds: no time limit)
#   ARMSIM_FUZZ_BUILD=build-sanitize scripts/fuzz.sh 30   (CI: the sanitizer stage's tree, built with the
#                                                         same instrumentation, so nothing is compiled twice)
# Builds build-fuzz/ (or $ARMSIM_FUZZ_BUILD) with clang, AddressSanitizer and UndefinedBehaviorSanitizer
# (every library instrumented), then runs each loader from its seed corpus (fuzz/corpus/<loader>/; new inputs go to
# <build>/corpus/<loader>/) for the given time or number of runs (default 30 s), with seed 1,
# PARALLEL loaders at a time (default: the number of cores). A crash, hang (> 10 s per input), leak or
# sanitizer report fails the run (non-zero exit) with the input saved in the build folder.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
runs=${2:--1}
parallel=${3:-$(nproc)}
root=$PWD
build=$(realpath -m "${ARMSIM_FUZZ_BUILD:-build-fuzz}")
if [[ -z "${ARMSIM_FUZZ_BUILD:-}" ]]; then
  cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DARMSIM_FUZZ=ON \
    -DARMSIM_RENDER=OFF -DARMSIM_PYTHON=OFF -DARMSIM_TESTS=OFF -DARMSIM_BENCHMARKS=OFF \
    -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
elif ! grep -Eiq "^ARMSIM_FUZZ:BOOL=(ON|1|TRUE|YES)$" "$build/CMakeCache.txt" 2>/dev/null ||
     ! grep -q "^CMAKE_CXX_FLAGS:.*fuzzer-no-link" "$build/CMakeCache.txt"; then
  echo "fuzz: ARMSIM_FUZZ_BUILD=$build is not a tree configured with -DARMSIM_FUZZ=ON and -fsanitize=fuzzer-no-link" \
       "(scripts/sanitize.sh makes one)"
  exit 2
fi
cmake --build "$build" -j2 --target fuzz_loaders

fuzzLoader() {
  local loader=$1
  mkdir -p "$build/corpus/$loader"
  if (cd "$build" && ARMSIM_FUZZ_LOADER=$loader UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      ./fuzz/fuzz_loaders corpus/$loader "$root/fuzz/corpus/$loader" -max_total_time=$seconds -runs=$runs \
        -seed=1 -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 > fuzz_$loader.log 2>&1); then
    echo "== $loader: $(grep -E '^Done' "$build/fuzz_$loader.log")"
  else
    echo "== $loader: FAILED ($build/fuzz_$loader.log)"
    grep -E "ERROR|SUMMARY|Test unit written" "$build/fuzz_$loader.log" || true
    return 1
  fi
}

failed=0
running=0
for loader in $(ls fuzz/corpus); do
  if (( running >= parallel )); then
    wait -n || failed=1
    running=$((running - 1))
  fi
  fuzzLoader "$loader" &
  running=$((running + 1))
done
while (( running > 0 )); do
  wait -n || failed=1
  running=$((running - 1))
done
if (( failed )); then echo "fuzz: a loader failed (above)"; exit 1; fi
echo "fuzz: every loader clean"
