#!/usr/bin/env bash
# Frames for the benches to replay as a camera would give them: one
# simulated 640x480 frame kept raw (with its camera.yaml and rig.yaml, in
# WORK/capture/), then that frame as PPM (WORK/frame.ppm) under FRAMES names
# (WORK/replay/f_NNNNNN.ppm): --source images then decodes no PNG.
#
# With BRACKET_STOPS (say "-3 -6 -9 -12", a bracket's default ladder), the
# same frame is also rendered at each of those exposures (sim.exposure_stops)
# into WORK/replay/ev<stops>/ under the same names: the replay then has
# exposure control (ImageFrameSource's exposure sets), and a recalibration's
# bracket runs on it as on a camera.
#
# usage: [BRACKET_STOPS="..."] scripts/replay-frames.sh PROBELIGHT WORK FRAMES   (run from the repository root)
set -euo pipefail
probelight=$1 work=$2 frames=$3
render_frame() {  # STOPS DIR: one raw frame at STOPS, as DIR/frame.ppm
  printf '%%YAML:1.0\n---\nsim:\n  exposure_stops: %s\n' "$1" >"$2.yaml"
  "$probelight" run --source sim --frames 1 --save-every 0 --quiet --config "$2.yaml" --out "$2/still" \
    --capture "$2/capture" >/dev/null
  python3 scripts/png_to_ppm.py "$2/capture/frame.png" "$2/frame.ppm"
}
"$probelight" run --source sim --frames 1 --save-every 0 --quiet --out "$work/still" --capture "$work/capture" >/dev/null
python3 scripts/png_to_ppm.py "$work/capture/frame.png" "$work/frame.ppm"
mkdir -p "$work/replay"
link_args=("$work/frame.ppm" "$work/replay")
for stops in ${BRACKET_STOPS:-}; do
  render_frame "$stops" "$work/ev$stops"
  mkdir -p "$work/replay/ev$stops"
  link_args+=("$work/ev$stops/frame.ppm" "$work/replay/ev$stops")
done
# One process for all the links: a shell loop forks ln per frame (100,000
# frames took 25 minutes).
python3 -c '
import os, sys
count, pairs = int(sys.argv[1]), sys.argv[2:]
for target, folder in zip(pairs[0::2], pairs[1::2]):
    for i in range(count):
        link = os.path.join(folder, "f_%06d.ppm" % i)
        if os.path.lexists(link):
            os.remove(link)
        os.symlink(target, link)
' "$frames" "${link_args[@]}"
