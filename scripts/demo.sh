#!/usr/bin/env bash
# The main job on a fresh machine: install, build, and run the simulated kiosk
# for 300 frames. Composited frames and report.json land in ./out (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
out_dir=${1:-out}
build/probelight run --source sim --display headless --frames "${FRAMES:-300}" --out "$out_dir"
echo "probelight: frames and report in $out_dir/ (report: $out_dir/report.json)"
