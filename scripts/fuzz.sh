#!/usr/bin/env bash
# Fuzzes every loader of armsim with libFuzzer (issue 15; docs/reliability.md).
#   scripts/fuzz.sh [SECONDS_PER_LOADER] [RUNS_PER_LOADER]      (0 seconds: no time limit)
# Builds build-fuzz/ with clang, AddressSanitizer and UndefinedBehaviorSanitizer (every library
# instrumented), then runs each loader from its seed corpus (fuzz/corpus/<loader>/; new inputs go to
# build-fuzz/corpus/<loader>/) for the given time or number of runs (default 30 s). A crash, hang
# (> 10 s per input), leak or sanitizer report stops with a non-zero exit and the input in build-fuzz/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
runs=${2:--1}
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DARMSIM_FUZZ=ON \
  -DARMSIM_RENDER=OFF -DARMSIM_PYTHON=OFF -DARMSIM_TESTS=OFF -DARMSIM_BENCHMARKS=OFF \
  -DCMAKE_CXX_FLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build build-fuzz -j2 --target fuzz_loaders
for loader in $(ls fuzz/corpus); do
  mkdir -p build-fuzz/corpus/$loader
  echo "== $loader"
  (cd build-fuzz && ARMSIM_FUZZ_LOADER=$loader UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    ./fuzz/fuzz_loaders corpus/$loader ../fuzz/corpus/$loader -max_total_time=$seconds -runs=$runs \
      -seed=1 -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 > fuzz_$loader.log 2>&1) || {
        grep -E "ERROR|SUMMARY|Test unit written" build-fuzz/fuzz_$loader.log; echo "fuzz: $loader failed (build-fuzz/fuzz_$loader.log)"; exit 1; }
  grep -E "^stat::number_of_executed_units|^Done" build-fuzz/fuzz_$loader.log
done
