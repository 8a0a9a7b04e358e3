#!/usr/bin/env bash
# The main job on a fresh machine: install, build the program (only it: the
# tests and benchmarks are scripts/test.sh's), and run the simulated kiosk
# for 300 frames. Composited frames and report.json land in ./out (or $1),
# and the last camera frame as the camera gave it, with its camera.yaml and
# rig.yaml, in out/capture/ (what `probelight analyze` and `render` take).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh probelight
out_dir=${1:-out}
build/probelight run --source sim --display headless --frames "${FRAMES:-300}" --out "$out_dir" \
  --capture "$out_dir/capture"
echo "probelight: frames and report in $out_dir/ (report: $out_dir/report.json), a raw frame in $out_dir/capture/"
