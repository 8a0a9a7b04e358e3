#!/usr/bin/env bash
# Builds the Debian package of this machine's architecture from the build
# folder (default build/): build/probelight_<version>_<arch>.deb. Made once:
# a .deb newer than the binary and everything packed into it is kept, so
# the package check (scripts/check-package.sh, in ctest) and the board VM
# (scripts/board-vm) take the same file.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${1:-build}
[ -d "$build_dir" ] || scripts/build.sh
cmake --build "$build_dir" --target probelight -j "$(nproc)"
deb=$(ls -t "$build_dir"/probelight_*.deb 2>/dev/null | head -n 1 || true)
if [ -n "$deb" ]; then
  # What cpack packs: the binary, its generated files, and the unit, the
  # board's files, the docs and Debian's files from the source tree.
  newer=$(find "$build_dir/probelight" "$build_dir/CPackConfig.cmake" "$build_dir/changelog.gz" \
                "$build_dir/probelight.1.gz" systemd board docs packaging README.md -newer "$deb" -print -quit)
  if [ -z "$newer" ]; then
    echo "package: $deb is up to date"
    exit 0
  fi
fi
rm -f "$build_dir"/probelight_*.deb
(cd "$build_dir" && cpack -G DEB > cpack.log 2>&1) || { cat "$build_dir/cpack.log"; exit 1; }
ls "$build_dir"/probelight_*.deb
