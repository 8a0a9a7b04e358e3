#!/usr/bin/env bash
# Configures and builds probelight (Release) into ./build with every core:
# everything (the program, its tests and benchmarks), or only the targets
# named (scripts/build.sh probelight). PROBELIGHT_BUILD_BENCH=OFF leaves the
# benchmarks out (CI: scripts/test-sanitizers.sh compile-checks them).
# Compiles through ccache where it is installed (scripts/install-deps.sh
# installs it), so a second build of the same sources is mostly cache hits.
set -euo pipefail
cd "$(dirname "$0")/.."
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPROBELIGHT_BUILD_BENCH="${PROBELIGHT_BUILD_BENCH:-ON}" "${launcher[@]}"
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build build -j"$(nproc)" "${targets[@]}"
