#!/usr/bin/env bash
# Frames for the benches to replay as a camera would give them: one
# simulated 640x480 frame kept raw (with its camera.yaml and rig.yaml, in
# WORK/capture/), then that frame as PPM (WORK/frame.ppm) under FRAMES names
# (WORK/replay/f_NNNNNN.ppm): --source images then decodes no PNG.
#
# usage: scripts/replay-frames.sh PROBELIGHT WORK FRAMES   (run from the repository root)
set -euo pipefail
probelight=$1 work=$2 frames=$3
"$probelight" run --source sim --frames 1 --save-every 0 --quiet --out "$work/still" --capture "$work/capture" >/dev/null
python3 scripts/png_to_ppm.py "$work/capture/frame.png" "$work/frame.ppm"
mkdir -p "$work/replay"
# One process for all the links: a shell loop forks ln per frame (100,000
# frames took 25 minutes).
python3 -c '
import os, sys
target, folder, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
for i in range(count):
    link = os.path.join(folder, "f_%06d.ppm" % i)
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(target, link)
' "$work/frame.ppm" "$work/replay" "$frames"
