#!/usr/bin/env bash
# The product's own frame rate, as the issue's targets define it, and the
# demo's, on this machine:
#   1. defaults on a still camera;
#   2. the reflection and diffuse maps remade every frame;
#   3. maps and shadow maps remade every frame;
#   and 1. with the camera match (camera_match.noise, .blur and .bloom:
#   the frame's noise and blur measured and given to the object, and the
#   lens's glare round its light above white, issue 19),
#   and without the object following the camera's exposure and white
#   balance (camera_match.response, on by default), and with everything of
#   issue 19 on (those, motion_blur, and the virtual lamp with its
#   exposure; the replayed camera is still, so motion blur skips);
# each on 640x480 frames the simulator rendered once and that are replayed
# from raw PPM files (--source images: no simulator runs, no PNG is decoded
# or written, as with a camera), and 4. the demo as the user sees it
# (scripts/demo.sh's run: the simulator and a PNG per frame).
#
# The rate is report.json's fps_steady (1000 / the median interval between
# shown frames). The machine is shared and noisy, so the configurations run
# in interleaved rounds and the table gives each one's median over the rounds
# with the per-stage medians (ms) of its median round.
#
# Then each stage against its limit (probelight_bench's ratio/ benchmarks,
# bench/stage_limits.hpp: the same passes with trivial shaders of as many
# texture reads), stage and limit back to back.
#
# usage: scripts/bench-pipeline.sh [ROUNDS] [OUT.csv]
#   PROBELIGHT=path/to/probelight (default build/probelight)
#   PROBELIGHT_BENCH=path/to/probelight_bench (default build/probelight_bench; absent: no ratios)
#   FRAMES=frames per replayed run (default 600)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-3}
csv=${2:-}
probelight=${PROBELIGHT:-build/probelight}
frames=${FRAMES:-600}
[[ -x $probelight ]] || { echo "bench-pipeline: $probelight not built (scripts/build.sh probelight)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

scripts/replay-frames.sh "$probelight" "$work" "$frames"

printf '%%YAML:1.0\n---\nmap_updates:\n  max_age_frames: 1\n' >"$work/maps.yaml"
printf '%%YAML:1.0\n---\nmap_updates:\n  max_age_frames: 1\nlights:\n  shadow_updates: every_frame\n' >"$work/maps_shadows.yaml"
printf '%%YAML:1.0\n---\ncamera_match:\n  noise: true\n  blur: true\n  bloom: true\n' >"$work/camera_match.yaml"
printf '%%YAML:1.0\n---\ncamera_match:\n  response: false\n' >"$work/no_response.yaml"
printf '%%YAML:1.0\n---\ncamera_match:\n  noise: true\n  blur: true\n  bloom: true\n  motion_blur: true\nvirtual_lamp:\n  enabled: true\n' >"$work/everything.yaml"

configs=(defaults camera_match everything no_response maps maps_shadows demo)
for ((round = 1; round <= rounds; ++round)); do
  for config in "${configs[@]}"; do
    out="$work/run_${config}_$round"
    if [[ $config == demo ]]; then
      "$probelight" run --source sim --display headless --frames 300 --quiet --out "$out" >/dev/null
    else
      config_flag=()
      [[ $config == defaults ]] || config_flag=(--config "$work/$config.yaml")
      "$probelight" run --source images --images "$work/replay/*.ppm" --calibration "$work/capture/camera.yaml" \
        --rig "$work/capture/rig.yaml" "${config_flag[@]}" --frames 0 --save-every 0 --quiet --out "$out" >/dev/null
    fi
  done
done

python3 - "$work" "$rounds" "$csv" "${configs[@]}" <<'EOF'
import json, statistics, sys
work, rounds, csv_path, configs = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4:]
labels = {"defaults": "defaults, still camera (replayed)", "maps": "maps every frame (replayed)",
          "camera_match": "defaults + camera_match noise, blur and bloom (replayed)",
          "no_response": "defaults without camera_match.response (replayed)",
          "everything": "defaults + every camera_match effect and the virtual lamp (replayed)",
          "maps_shadows": "maps and shadows every frame (replayed)", "demo": "demo: simulator + a PNG per frame"}
stages = ["upload", "detect_pose", "probe_to_cube", "diffuse_blur", "clipped_rescale", "shadows", "match_response",
          "match_noise", "match_blur", "match_motion", "lamp_exposure", "virtual_lamp", "bloom", "render", "present"]
rows = []
print("| run | fps (median of %d rounds; all) | " % rounds + " | ".join(stages) + " |")
print("|---|---|" + "---|" * len(stages))
for config in configs:
    reports = [json.load(open(f"{work}/run_{config}_{r}/report.json")) for r in range(1, rounds + 1)]
    fps = [r["fps_steady"] for r in reports]
    middle = sorted(reports, key=lambda r: r["fps_steady"])[len(reports) // 2]
    ms = []
    for stage in stages:
        entry = middle["stages"].get(stage)
        ms.append(f"{entry['median_ms']:.1f} ({entry['runs']})" if entry and entry["runs"] else "–")
    print(f"| {labels[config]} | {statistics.median(fps):.1f} ({', '.join(f'{f:.1f}' for f in fps)}) | " + " | ".join(ms) + " |")
    rows.append([config, f"{statistics.median(fps):.2f}"] + [str(middle["stages"].get(s, {}).get("median_ms", "")) for s in stages])
print("\nStage cells: median ms (runs) in the median round; a stage that did not run shows –.")
if csv_path:
    with open(csv_path, "w") as f:
        f.write("run,fps_steady," + ",".join(f"{s}_ms" for s in stages) + "\n")
        for row in rows:
            f.write(",".join(row) + "\n")
EOF

bench=${PROBELIGHT_BENCH:-build/probelight_bench}
if [[ -x $bench ]]; then
  "$bench" --benchmark_filter='^ratio/' 2>/dev/null | sed -n '/^Each stage against its limit/,$p'
else
  echo "bench-pipeline: $bench not built: no stage ratios (scripts/build.sh probelight_bench)" >&2
fi
