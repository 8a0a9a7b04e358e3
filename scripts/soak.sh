#!/usr/bin/env bash
# A long run on replayed frames (no simulator in the loop), watching for
# leaks while the kiosk is put through what a long day brings it:
#   - the button, on the key button's FIFO: a press (a recalibration: the
#     fit, new lights and shadows) every 20 s, a long press (back to the
#     stored lighting, the maps remade) every 90 s;
#   - camera losses: the camera is lost after every LOSS_EVERY frames
#     (default 10,000) and its first reconnect fails (faults.* in
#     probelight.yaml: the frames are replayed, so the loss is injected; the
#     reconnect restarts the replay, as a camera's restart would).
#   - exposure brackets: each press's recalibration takes one, as on a
#     camera: the frame is also replayed at BRACKET_STOPS (default
#     "-3 -6 -9 -12", the bracket's ladder) from exposure sets that
#     scripts/replay-frames.sh renders, and the source serves each rung from
#     the nearest set (ImageFrameSource).
#
# probelight itself samples after its first frame and every 1,000 frames
# (output.resources_every_frames): its resident memory (VmRSS), its open
# file descriptors and the GL objects the driver holds for it (glIs* over
# every name it was given). After the first 1,000 frames (start-up, the first
# fit, the caches filling) none may grow by more than 1%; the script exits 1
# when one does. The heap the program holds (mallinfo2's bytes in use) is
# plotted and printed beside it, to tell a leak (it grows with RSS) from the
# allocator keeping freed pages (only RSS grows); the last sample's includes
# the final frame's PNG on its way to disk.
#
# Writes OUT/resources.csv, OUT/soak.png (gnuplot: the three against frames)
# and OUT/run/report.json. Needs gnuplot (Debian's gnuplot-nox). Not part of
# CI: 100,000 frames take 10-20 minutes on this project's 2-core machine.
#
# usage: scripts/soak.sh [FRAMES] [OUT]   (default 100000, out/soak)
#   PROBELIGHT=path/to/probelight (default build/probelight)
#   LOSS_EVERY=frames between camera losses (default 10000; 0: none)
#   BRACKET_STOPS=the exposure sets to replay (default "-3 -6 -9 -12"; "": no brackets)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-100000}
out=${2:-out/soak}
probelight=${PROBELIGHT:-build/probelight}
loss_every=${LOSS_EVERY:-10000}
export BRACKET_STOPS=${BRACKET_STOPS--3 -6 -9 -12}
rm -rf "$out"
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

scripts/replay-frames.sh "$probelight" "$work" "$frames"
mkfifo "$work/button"
printf '%%YAML:1.0\n---\noutput:\n  save_every: 0\n  resources_every_frames: 1000\nfaults:\n  camera_loss_every_frames: %d\n  camera_loss_failed_restarts: 1\n' \
  "$loss_every" >"$work/soak.yaml"

"$probelight" run --source images --images "$work/replay" --calibration "$work/capture/camera.yaml" \
  --rig "$work/capture/rig.yaml" --config "$work/soak.yaml" --display headless --frames "$frames" \
  --button key --key-input "$work/button" --out "$out/run" --quiet 2>"$out/run.log" &
pid=$!

# The button: the FIFO is opened for each write, as `echo r > fifo` would.
(
  elapsed=0
  while kill -0 "$pid" 2>/dev/null; do
    sleep 10
    elapsed=$((elapsed + 10))
    if ((elapsed % 90 == 0)); then echo long >"$work/button"; elif ((elapsed % 20 == 0)); then echo r >"$work/button"; fi
  done
) &
presser=$!

status=0
wait "$pid" || status=$?
kill "$presser" 2>/dev/null || true
wait "$presser" 2>/dev/null || true
if ((status != 0)); then
  echo "soak: probelight exited $status (log: $out/run.log)" >&2
  exit 1
fi
cp "$out/run/resources.csv" "$out/resources.csv"

gnuplot <<GP
set terminal pngcairo size 900,420
set output "$out/soak.png"
set datafile separator ","
set key bottom right
set xlabel "frames"
set ylabel "resident memory (MiB)"
set y2label "open file descriptors, live GL objects"
set y2tics
set ytics nomirror
set yrange [0:*]
set y2range [0:*]
plot "$out/resources.csv" using 1:(\$3/1024) with lines lw 2 title "VmRSS (MiB)", \
     "" using 1:(\$13/1024) with lines lw 2 title "heap in use (MiB)", \
     "" using 1:4 axes x1y2 with lines lw 2 title "open fds", \
     "" using 1:5 axes x1y2 with lines lw 2 title "live GL objects"
GP

python3 - "$out" <<'PY'
import csv, json, os, sys
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/resources.csv")))
report = json.load(open(f"{out}/run/report.json"))
if len(rows) < 10:
    sys.exit(f"soak: only {len(rows)} samples: run more frames")
settled = next(r for r in rows if int(r["frames"]) >= 1000)
last = rows[-1]
counters = report.get("counters", {})
camera = report.get("camera", {})
print(f"soak: {report['frames']} frames in {report['elapsed_s']:.0f} s ({report['fps']:.1f} fps), "
      f"{counters.get('calibrations_completed', 0)} recalibrations, {counters.get('brackets_merged', 0)} brackets "
      f"merged, {camera.get('losses', 0)} camera losses, {camera.get('reconnects', 0)} reconnects")
if os.environ.get("BRACKET_STOPS", "").strip() and counters.get("brackets_merged", 0) == 0:
    sys.exit("soak: no bracket was merged although the replay has exposure sets")
failed = False
for column, name in (("rss_kib", "RSS (KiB)"), ("open_fds", "open file descriptors"), ("gl_objects", "live GL objects")):
    before, after = int(settled[column]), int(last[column])
    growth = (after - before) / before if before > 0 else float("inf")
    peak = max(int(r[column]) for r in rows)
    print(f"soak: {name} {before} at frame {settled['frames']} -> {after} at frame {last['frames']} "
          f"({100 * growth:+.2f}%), peak {peak}")
    failed = failed or growth > 0.01
if int(settled.get("heap_in_use_kib", -1)) > 0:  # -1: not glibc's allocator (a sanitizer's)
    before, late = int(settled["heap_in_use_kib"]), int(rows[-2]["heap_in_use_kib"])
    print(f"soak: heap in use (KiB) {before} at frame {settled['frames']} -> {late} at frame {rows[-2]['frames']} "
          f"({100 * (late - before) / before:+.2f}%; not a limit: RSS is)")
if failed:
    sys.exit(f"soak: grew by more than 1% after the first 1,000 frames (plot: {out}/soak.png)")
PY

echo "soak: $out/resources.csv, $out/soak.png"
