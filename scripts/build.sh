#!/usr/bin/env bash
# Configures and builds probelight (Release) into ./build with every core:
# everything (the program, its tests and benchmarks), or only the targets
# named (scripts/build.sh probelight). PROBELIGHT_BUILD_BENCH=OFF leaves the
# benchmarks out (CI: scripts/test-sanitizers.sh compile-checks them).
# Compiles through ccache where it is installed (scripts/ccache-options.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache-options.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPROBELIGHT_BUILD_BENCH="${PROBELIGHT_BUILD_BENCH:-ON}" "${ccache_cmake_args[@]}"
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
