#!/usr/bin/env bash
# The README's camera-match picture: one simulated frame (a lens blur of
# 1.2 px and noise of 2.5 codes, the glazed bowl on the tag) composited
# without and with camera_match (noise and blur), a crop of each, enlarged
# 3 times, side by side: docs/camera-match.png.
#
# usage: scripts/camera-match-picture.sh [OUT.png]   (PROBELIGHT=path/to/probelight)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/camera-match.png}
probelight=${PROBELIGHT:-build/probelight}
[[ -x $probelight ]] || { echo "camera-match-picture: $probelight not built (scripts/build.sh probelight)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for match in false true; do
  cat >"$work/$match.yaml" <<YAML
%YAML:1.0
---
object:
  model: $PWD/board/models/ceramic-bowl.glb
camera_match:
  noise: $match
  blur: $match
sim:
  noise_sigma: 2.5
  lens_blur_sigma: 1.2
YAML
  "$probelight" run --source sim --display headless --frames 24 --quiet --config "$work/$match.yaml" \
    --out "$work/$match" >/dev/null
done
# The bowl and the tag's left and near edges (frame 23 of the default orbit).
python3 scripts/side_by_side.py "$work/false/frame_000023.png" "$work/true/frame_000023.png" 180 180 160 150 3 "$out"
echo "camera-match-picture: $out"
