#!/bin/bash
# The kiosk with and without the probe over views (environment_maps.merge_views),
# on the simulator's camera paths, against its truth: docs/accuracy.md's
# "In the kiosk" table. Each world is turned so that its brightest light lies
# behind the ball as the camera's start sees it.
#   scripts/probe-merge-table.sh [OUT_DIR]   (default /tmp/probe-merge-table; build/probelight must exist)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/probe-merge-table}
frames=${FRAMES:-90}
mkdir -p "$out"
run() {  # name config path
  [[ -f $out/$1/report.json ]] && return 0
  printf '%b' "$2" > "$out/$1.yaml"
  build/probelight run --frames "$frames" --save-every 0 --path "$3" --config "$out/$1.yaml" --out "$out/$1" \
    > "$out/$1.log" 2>&1 || { echo "run $1 failed: see $out/$1.log" >&2; return 1; }
}
# sunrise's sun at azimuth -120 deg, the night street's first lamp at 60 deg;
# the camera starts at -90 deg, so behind the ball is +90 deg.
for spec in "sunrise 210" "night_street 30" "studio 0"; do
  read -r env rotation <<< "$spec"
  for path in static slow_wobble orbit hand_held_sweep; do
    base="sim:\n  env: $env\n  environment_rotation_deg: $rotation\n"
    run "${env}_${path}_probe" "$base" "$path"
    run "${env}_${path}_single" "${base}environment_maps:\n  merge_views: false\n" "$path"
  done
done
python3 - "$out" <<'PY'
import json, os, statistics, sys
out = sys.argv[1]
def checks(name):
    report = json.load(open(os.path.join(out, name, "report.json")))
    # After the start-up fit: every 10th frame from frame 20.
    values = [100 * c["lit_irradiance_rel_error_vs_hdr"] for c in report["map_updates"]["truth_checks"]
              if c["frame"] >= 20 and c["lit_irradiance_rel_error_vs_hdr"] is not None]
    return values, report["stages"]["diffuse_blur"]["runs"]
all_probe, all_single = [], []
for env in ["sunrise", "night_street", "studio"]:
    for path in ["static", "slow_wobble", "orbit", "hand_held_sweep"]:
        probe, probe_runs = checks(f"{env}_{path}_probe")
        single, single_runs = checks(f"{env}_{path}_single")
        all_probe += probe
        all_single += single
        print(f"| {env} | {path} | {statistics.mean(probe):.1f}% / {max(probe):.1f}% | "
              f"{statistics.mean(single):.1f}% / {max(single):.1f}% | {probe_runs} / {single_runs} |")
print(f"| **all** | | **{statistics.mean(all_probe):.2f}% / {max(all_probe):.1f}%** | "
      f"**{statistics.mean(all_single):.2f}% / {max(all_single):.1f}%** | |")
PY
