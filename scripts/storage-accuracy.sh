#!/usr/bin/env bash
# The maps' 8-bit storage against half floats over the kiosk's runs in time:
# each scenario of the simulated kiosk run twice, in this machine's context
# (maps in RGBA16F) and in a bare OpenGL ES 2.0 context (gpu-profiles.sh
# gles2: maps in 8-bit sRGB), and tabled by the truth monitor's error of the
# lit irradiance against the HDR truth and of the diffuse map against the
# clipped truth (five normals each), averaged over its checks through the
# run (every 10th frame).
#
# usage: scripts/storage-accuracy.sh [OUT_DIR]   (default /tmp/probelight-storage-accuracy)
# Needs build/probelight (scripts/build.sh probelight).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/gpu-profiles.sh
out=${1:-/tmp/probelight-storage-accuracy}
binary=build/probelight
[[ -x $binary ]] || { echo "storage-accuracy: no $binary; run scripts/build.sh probelight" >&2; exit 2; }
mkdir -p "$out"

# name | flags | probelight.yaml (\n between lines; empty: none)
# "no merge": environment_maps.merge_views off, so that the diffuse map is
# blended over updates (at smoothing_new_weight) instead of remade from the
# merged probe, which is its own temporal filter.
no_merge='environment_maps:\n  merge_views: false'
scenarios=(
  "studio, still|--env studio --path static --frames 200|"
  "sun and sky (bracketed fit), still|--env sun_sky --path static --frames 200|"
  "sun moving 0.3 deg a frame|--env sun_sky --path static --frames 300|sim:\n  sun_azimuth_rate_deg_per_frame: 0.3"
  "sun moving 0.3 deg a frame, no merge|--env sun_sky --path static --frames 300|sim:\n  sun_azimuth_rate_deg_per_frame: 0.3\n$no_merge"
  "lamp switched on at frame 100|--env overcast --path static --frames 300|sim:\n  lamp_on_frame: 100"
  "lamp switched on at frame 100, no merge|--env overcast --path static --frames 300|sim:\n  lamp_on_frame: 100\n$no_merge"
  "sunrise, hand-held sweep|--env sunrise --path hand_held_sweep --frames 300|"
  "night street, hand-held sweep|--env night_street --path hand_held_sweep --frames 300|"
)

run_one() {
  local dir=$1 flags=$2 sim=$3 profile=$4
  local config=()
  mkdir -p "$dir"
  if [[ -n $sim ]]; then
    printf '%b\n' "$sim" >"$dir/probelight.yaml"
    config=(--config "$dir/probelight.yaml")
  fi
  # shellcheck disable=SC2086  # the flags are words
  (
    [[ -n $profile ]] && gpu_profile_export "$profile"
    "$binary" run $flags --save-every 0 --quiet "${config[@]}" --out "$dir" 2>"$dir/stderr.txt"
  ) || { echo "storage-accuracy: $dir failed:" >&2; tail -3 "$dir/stderr.txt" >&2; return 1; }
}

measure() {
  python3 - "$1" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1] + "/report.json"))
# The truth monitor's checks through the run (every 10th frame): their mean.
checks = r["map_updates"]["truth_checks"]
def mean(key):
    values = [c[key] for c in checks if c.get(key) is not None]
    return sum(values) / len(values)
lit = mean("lit_irradiance_rel_error_vs_hdr")
diffuse = mean("diffuse_irradiance_rel_error_vs_clipped")
storage = r.get("map_storage", "")
storage = "half float" if storage.startswith("half float") else "8-bit" if storage.startswith("8-bit") else "?"
print(f"{100 * lit:.2f} {100 * diffuse:.2f} {storage}")
EOF
}

echo "| scenario | lit vs HDR, half float | lit vs HDR, 8-bit | ratio | diffuse vs clipped, half float | diffuse vs clipped, 8-bit |"
echo "|---|---|---|---|---|---|"
index=0
for scenario in "${scenarios[@]}"; do
  IFS='|' read -r name flags sim <<<"$scenario"
  index=$((index + 1))
  run_one "$out/$index-half" "$flags" "$sim" ""
  run_one "$out/$index-8bit" "$flags" "$sim" gles2
  read -r half_lit half_diffuse half_storage <<<"$(measure "$out/$index-half")"
  read -r byte_lit byte_diffuse byte_storage <<<"$(measure "$out/$index-8bit")"
  [[ $half_storage == "half float" && $byte_storage == "8-bit" ]] ||
    { echo "storage-accuracy: $name: storage '$half_storage' and '$byte_storage', not half float and 8-bit" >&2; exit 1; }
  ratio=$(python3 -c "print(f'{$byte_lit / $half_lit:.2f}' if $half_lit > 0 else 'n/a')")
  echo "| $name | $half_lit% | $byte_lit% | $ratio | $half_diffuse% | $byte_diffuse% |"
done
