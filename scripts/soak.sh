#!/usr/bin/env bash
# A long run on replayed frames (no simulator in the loop) with the button
# pressed on a schedule, watching for leaks: the process's resident memory
# (VmRSS) and open file descriptors, sampled every 2 s. After the first tenth
# of the run (start-up, the first fit, the caches filling) neither may grow by
# more than 1%; the script exits 1 when one does.
#
# Schedule, on the key button's FIFO: a press (a recalibration: bracket or
# single-frame fit, new lights and shadows) every 20 s, a long press (the
# maps remade from scratch) every 90 s.
#
# Writes OUT/samples.csv (elapsed_s, rss_kib, open_fds), OUT/soak.png (gnuplot)
# and OUT/run/report.json. Needs gnuplot (Debian's gnuplot-nox). Not part of CI: 100,000 frames take 10-20 minutes
# on this project's 2-core machine.
#
# usage: scripts/soak.sh [FRAMES] [OUT]   (default 100000, out/soak)
#   PROBELIGHT=path/to/probelight (default build/probelight)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-100000}
out=${2:-out/soak}
probelight=${PROBELIGHT:-build/probelight}
rm -rf "$out"
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

scripts/replay-frames.sh "$probelight" "$work" "$frames"
mkfifo "$work/button"

"$probelight" run --source images --images "$work/replay" --camera "$work/capture/camera.yaml" \
  --rig "$work/capture/rig.yaml" --display headless --save-every 0 --frames "$frames" \
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

echo "elapsed_s,rss_kib,open_fds" >"$out/samples.csv"
start_ns=$(date +%s%N)
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l || true)
  elapsed_ms=$((($(date +%s%N) - start_ns) / 1000000))
  [[ -n "$rss" ]] && printf '%d.%03d,%s,%s\n' $((elapsed_ms / 1000)) $((elapsed_ms % 1000)) "$rss" "$fds" >>"$out/samples.csv"
  sleep 2
done
status=0
wait "$pid" || status=$?
kill "$presser" 2>/dev/null || true
wait "$presser" 2>/dev/null || true
if ((status != 0)); then
  echo "soak: probelight exited $status (log: $out/run.log)" >&2
  exit 1
fi

python3 - "$out" <<'EOF'
import csv, json, sys
out = sys.argv[1]
rows = [(float(r["elapsed_s"]), int(r["rss_kib"]), int(r["open_fds"])) for r in csv.DictReader(open(f"{out}/samples.csv"))]
report = json.load(open(f"{out}/run/report.json"))
if len(rows) < 10:
    sys.exit(f"soak: only {len(rows)} samples: run more frames")
settled = rows[len(rows) // 10]
last = rows[-1]
rss_growth = (last[1] - settled[1]) / settled[1]
fd_growth = (last[2] - settled[2]) / settled[2]
counters = report.get("counters", {})
print(f"soak: {report['frames']} frames in {report['elapsed_s']:.0f} s ({report['fps']:.1f} fps), "
      f"{counters.get('calibrations_completed', 0)} recalibrations")
print(f"soak: RSS {settled[1]} KiB at {settled[0]:.0f} s -> {last[1]} KiB at {last[0]:.0f} s ({100 * rss_growth:+.2f}%), "
      f"peak {max(r[1] for r in rows)} KiB")
print(f"soak: open file descriptors {settled[2]} -> {last[2]} ({100 * fd_growth:+.2f}%)")
if rss_growth > 0.01 or fd_growth > 0.01:
    sys.exit("soak: grew by more than 1% after the first tenth of the run")
EOF

gnuplot <<EOF
set terminal pngcairo size 900,420
set output "$out/soak.png"
set datafile separator ","
set key autotitle columnhead top left
set xlabel "elapsed (s)"
set ylabel "resident memory (MiB)"
set y2label "open file descriptors"
set y2tics
set ytics nomirror
set yrange [0:*]
set y2range [0:*]
plot "$out/samples.csv" using 1:(\$2/1024) with lines title "VmRSS", \
     "" using 1:3 axes x1y2 with lines title "open fds"
EOF
echo "soak: $out/samples.csv, $out/soak.png"
