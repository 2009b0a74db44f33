#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (issue 15; docs/reliability.md).
#   scripts/sanitize.sh
# Builds build-sanitize/ with clang (-O1, both sanitizers, UB fatal, line tables only for the reports'
# stack traces; no Python module or benchmarks) and runs the test suite (docs/reliability.md gives the
# times). Leaks that third-party libraries never
# free (Simbody's CPodes, fontconfig, Mesa, OpenMPI) are suppressed by tests/sanitizers/lsan.supp; the
# mpirun tests run without leak detection (OpenMPI's dlopen-ed components leak from unloaded modules),
# every other check stays on.
set -euo pipefail
cd "$(dirname "$0")/.."
flags="-fsanitize=address,undefined"
# The code is also instrumented for libFuzzer (fuzzer-no-link: coverage counters and comparison
# tracing; the tests run about a fifth slower) and the fuzz target is built here, so CI fuzzes from
# this tree (ARMSIM_FUZZ_BUILD=build-sanitize scripts/fuzz.sh) instead of compiling every library again.
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DARMSIM_FUZZ=ON \
  -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only $flags,fuzzer-no-link -fno-omit-frame-pointer -fno-sanitize-recover=undefined" \
  -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" -DCMAKE_MODULE_LINKER_FLAGS="$flags" \
  -DARMSIM_BENCHMARKS=OFF -DARMSIM_PYTHON=OFF >/dev/null
cmake --build build-sanitize -j2
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# Latency bounds in the tests (a stop within 2 s of SIGTERM) scale by this: ASan poisons every byte freed,
# and a stopped 5e6-row trial frees gigabytes.
export ARMSIM_TEST_TIME_SCALE=4
mpi_tests="Mpi|TwoRanks"
# Coverage statistics over many virtual subjects run in the plain build only (2.3 min here under the
# sanitizers); every line they run is also run, under the sanitizers, by the single-fit tests.
# The same holds for the bias bound over 20 identified subjects and the prior check's uniformity over 30
# (58 s and 59 s here): one fit of each kind runs under the sanitizers in their single-fit tests.
statistical_tests="ChannelIntervalsCoverWhatThePopulationVariesAndTheFitShares|WidenedWidthBoundsTheSpreadOfEstimatesOfPeopleTheFitSimplifies"
statistical_tests+="|SynergistAwareIdentifierMeetsItsBiasBoundWhereTheThesisMethodFails|PriorCheckIsUniformInFamilyAndFlagsPeopleOfAnotherMuscleModel"
# The README's blocks (label docs) need the Python module, which this build leaves out; the commands
# they run are run here by the CLI tests.
doc_tests="docs[.]README[.]"
# Tests whose subject is not armsim's memory or arithmetic run in the plain build only: the main job's
# page in Chromium (the job itself runs here in Cli.MainJob...), a seeded command run twice for equal
# bytes (determinism; each command runs here in its own tests), and the study batch script under the
# local Slurm (the MPI ranks it starts run here in the Mpi tests). Under the sanitizers they took 152 s,
# 44 s and 122 s (2026-11-27).
plain_only="^report[.]|SeededCommandsWriteTheSameFilesTwice|^slurm[.]"
# ctest runs the longest tests first when it knows their times; a fresh tree does not, and the main job
# (110 s here) started last would run alone at the end. tests/sanitizers/ctest_costs.txt holds the times
# of the tests over 8 s under the sanitizers (names not found are ignored); ctest updates the file after.
mkdir -p build-sanitize/Testing/Temporary
[[ -f build-sanitize/Testing/Temporary/CTestCostData.txt ]] ||
  cp tests/sanitizers/ctest_costs.txt build-sanitize/Testing/Temporary/CTestCostData.txt
LSAN_OPTIONS=suppressions=$PWD/tests/sanitizers/lsan.supp \
  ctest --test-dir build-sanitize --output-on-failure -j2 --timeout 900 -E "$mpi_tests|$statistical_tests|$doc_tests|$plain_only"
ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-sanitize --output-on-failure -j2 --timeout 900 -R "$mpi_tests" -E "$plain_only"
