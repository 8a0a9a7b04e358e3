#!/bin/bash
# What an exposure bracket costs a recalibration, and the frame-rate stages
# with it on and off (docs/benchmarks.md): 60-frame simulated runs per world,
# lights.bracket_max_stops 12 (the default) and 0, 3 runs each, medians read
# from each run's report.json. Needs build/probelight (scripts/build.sh).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$(mktemp -d)}
mkdir -p "$out"
for env in sun_sky studio "$repo/tests/data/env/KernerEnvLatLong.exr"; do
  name=$(basename "$env" .exr)
  for rep in 1 2 3; do
    for mode in on off; do
      stops=12; [ "$mode" = off ] && stops=0
      printf "lights:\n  bracket_max_stops: %s\n" "$stops" > "$out/$mode.yaml"
      "$repo/build/probelight" run --env "$env" --path static --frames 60 --save-every 0 --quiet \
        --config "$out/$mode.yaml" --out "$out/$name-$mode-$rep" > /dev/null
    done
  done
done
python3 - "$out" <<'PY'
import glob, json, statistics, sys
rows = {}
for path in sorted(glob.glob(sys.argv[1] + '/*/report.json')):
    env, mode, _ = path.split('/')[-2].rsplit('-', 2)
    report = json.load(open(path))
    row = rows.setdefault((env, mode), {k: [] for k in ('wall', 'own', 'frames', 'merge', 'fit', 'rescale', 'render', 'detect')})
    stages = report['stages']
    if 'hdr' in report:
        row['wall'].append(report['hdr']['wall_ms'])
        row['own'].append(report['hdr']['own_ms'])
        row['frames'].append(report['hdr']['camera_frames'])
    for key, stage in (('merge', 'bracket_merge'), ('fit', 'fit_lights'), ('rescale', 'clipped_rescale'),
                       ('render', 'render'), ('detect', 'detect_pose')):
        if stage in stages:
            row[key].append(stages[stage]['median_ms'])
median = lambda v: '%.1f' % statistics.median(v) if v else '-'
for (env, mode), row in sorted(rows.items()):
    print(f"{env:20s} bracket {mode:3s}: hdr.wall_ms {median(row['wall'])} (own {median(row['own'])}; {median(row['frames'])} camera frames), "
          f"bracket_merge {median(row['merge'])} ms, fit_lights {median(row['fit'])} ms, "
          f"clipped_rescale {median(row['rescale'])} ms, render {median(row['render'])} ms, detect_pose {median(row['detect'])} ms")
PY
