#!/usr/bin/env bash
# A figure that does not move with the machine's load: the CPU instructions
# TagTracker::track (detect_pose: the tag detector, the corner refinement,
# the pose and its polish) executes per frame, counted by callgrind
# (valgrind) on replayed 640x480 frames, with one detector thread (callgrind
# counts the thread that calls track(), not libapriltag's workers). Two
# runs: the defaults (a still camera keeps its refinement:
# tracking.refinement_reuse_px) and refinement every frame (reuse 0, what a
# moving camera costs). Compare a change against these numbers, not against
# milliseconds.
#
# usage: scripts/bench-instructions.sh [FRAMES]   (default 20; about 1 min a run)
#   PROBELIGHT=path/to/probelight (default build/probelight)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-20}
probelight=${PROBELIGHT:-build/probelight}
command -v valgrind >/dev/null || { echo "bench-instructions: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
[[ -x $probelight ]] || { echo "bench-instructions: $probelight not built (scripts/build.sh probelight)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scripts/replay-frames.sh "$probelight" "$work" "$frames"

printf '%%YAML:1.0\n---\ntracking:\n  threads: 1\n' >"$work/reuse.yaml"
printf '%%YAML:1.0\n---\ntracking:\n  threads: 1\n  refinement_reuse_px: 0.0\n' >"$work/every_frame.yaml"
printf '| run | frames tracked | instructions per frame in TagTracker::track |\n|---|---|---|\n'
for config in reuse every_frame; do
  valgrind --tool=callgrind --callgrind-out-file="$work/$config.out" \
    --toggle-collect='probelight::tracking::TagTracker::track(*' \
    "$probelight" run --source images --images "$work/replay/*.ppm" --calibration "$work/capture/camera.yaml" \
    --rig "$work/capture/rig.yaml" --config "$work/$config.yaml" --frames 0 --save-every 0 --quiet \
    --out "$work/run_$config" >/dev/null 2>"$work/$config.log"
  instructions=$(sed -n 's/^summary: *//p' "$work/$config.out")
  tracked=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(r['stages']['detect_pose']['runs'])" "$work/run_$config/report.json")
  label=$([[ $config == reuse ]] && echo "defaults (still camera: refinement kept)" || echo "refinement every frame (refinement_reuse_px 0)")
  printf '| %s | %s | %s |\n' "$label" "$tracked" "$(( instructions / tracked ))"
done
