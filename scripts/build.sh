#!/usr/bin/env bash
# Configures and builds probelight (Release) into ./build with every core:
# everything (the program, its tests and benchmarks), or only the targets
# named (scripts/build.sh probelight). PROBELIGHT_BUILD_BENCH=OFF leaves the
# benchmarks out (CI: scripts/test-sanitizers.sh compile-checks them).
# Compiles through ccache where it is installed, and as a unity build with
# PROBELIGHT_UNITY_BUILD=ON (CI): scripts/compile-options.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/compile-options.sh
generator_for build
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPROBELIGHT_BUILD_BENCH="${PROBELIGHT_BUILD_BENCH:-ON}" "${generator_args[@]}" "${compile_cmake_args[@]}"
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
