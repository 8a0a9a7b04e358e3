#!/usr/bin/env bash
# The tests again (tests/tiers.cmake: every unit, gpu and e2e test, and the
# accuracy tier's checks of the product's code), built by clang with
# AddressSanitizer and UndefinedBehaviorSanitizer into
# ./build-asan, then each libFuzzer target (fuzz/) for a short run on its
# corpus: scripts/fuzz.sh, on the same build. Any sanitizer report aborts
# the process that met it, so its test or fuzz run fails. The benchmarks
# are compiled here too (CI's release build leaves them out). Needs what
# scripts/install-deps.sh installs.
#
# usage: scripts/test-sanitizers.sh [FUZZ_SECONDS]   (default 30 a target; 0: no fuzzing)
#        SANITIZER_BUILD_ONLY=1 scripts/test-sanitizers.sh   (the build alone: .ci/run
#        makes it beside the board VM, whose emulator keeps one core)
#        SANITIZER_BUILD_JOBS=N   compile jobs (default the core count)
#
# Left out: the vm tier (the package and the board VM's host side: no code
# of ours beyond the binary's), and the tests labelled
# slow_under_sanitizers, each with its reason and what runs its code here,
# in tests/tiers.cmake.
#
# Leaks: the fuzz runs check them (LeakSanitizer, on every input; no GL in
# those processes). The tests do not: Mesa's drivers are unloaded at exit,
# and what they allocated for the process's life is then reported from an
# "<unknown module>" that no suppression can name. The soak
# (scripts/soak.sh) watches the whole kiosk's memory instead.
set -euo pipefail
cd "$(dirname "$0")/.."
fuzz_seconds=${1:-30}
source scripts/compile-options.sh
generator_for build-asan
# Line tables only: a report's stack still names files and lines, and the
# build does not write full debug information it never reads.
CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPROBELIGHT_FUZZ=ON \
  -DPROBELIGHT_BUILD_BENCH=ON "${generator_args[@]}" "${compile_cmake_args[@]}" \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG"
cmake --build build-asan -j"${SANITIZER_BUILD_JOBS:-$(nproc)}"
[[ ${SANITIZER_BUILD_ONLY:-0} == 1 ]] && exit 0
source scripts/sanitizer-options.sh
(cd build-asan && ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" ctest --output-on-failure -j"$(nproc)" --timeout 1800 \
  -LE '^(vm|slow_under_sanitizers)$')
if [[ $fuzz_seconds != 0 ]]; then
  scripts/fuzz.sh "$fuzz_seconds"
fi
