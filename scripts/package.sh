#!/usr/bin/env bash
# Builds the Debian package of this machine's architecture from the build
# folder (default build/): build/probelight_<version>_<arch>.deb.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${1:-build}
[ -d "$build_dir" ] || scripts/build.sh
cmake --build "$build_dir" --target probelight -j "$(nproc)"
(cd "$build_dir" && cpack -G DEB)
ls "$build_dir"/probelight_*.deb
