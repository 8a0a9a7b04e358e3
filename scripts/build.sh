#!/usr/bin/env bash
# Configures and builds probelight (Release) into ./build with every core:
# everything (the program, its tests and benchmarks), or only the targets
# named (scripts/build.sh probelight).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
