#!/bin/bash
# board-vm smoke: the board's hardware, checked from inside the guest (the
# payload's run.sh; scripts/board-vm smoke puts it there). Every check runs
# and reports, whatever the others did; the host decides the exit status.
set -uo pipefail
# shellcheck source=board-vm-lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/board-vm-lib.sh"
out=$BOARD_VM_OUT

open_host_channel
host_request hello "smoke on $(uname -r), up $(cut -d' ' -f1 /proc/uptime) s"

# systemd as PID 1, as on the board.
pid1=$(readlink /proc/1/exe)
pass_if systemd-pid1 "PID 1 is $(cat /proc/1/comm) ($pid1), $(systemctl --version | head -n 1)" \
  test "$(cat /proc/1/comm)" = systemd

# The camera: vimc (loaded at boot by modules-load.d), seen by libcamera.
udevadm settle --timeout=60
cam -l >"$out/cam-list.txt" 2>&1
camera=$(grep -m 1 -i 'vimc' "$out/cam-list.txt")
pass_if camera-list "${camera:-no vimc camera in cam -l (see guest/cam-list.txt)}" test -n "$camera"

# Three frames from it. Under emulation a frame takes a second or two.
host_request log "capturing 3 frames from the vimc camera"
timeout 300 cam -c 1 --capture=3 >"$out/cam-capture.txt" 2>&1
capture_status=$?
frames=$(grep -c 'seq:' "$out/cam-capture.txt")
format=$(grep -oE '[0-9]+x[0-9]+-[A-Za-z0-9_]+' "$out/cam-capture.txt" | head -n 1)
pass_if camera-capture "cam exit $capture_status, $frames frames, ${format:-format not printed}" \
  test "$capture_status" -eq 0 -a "$frames" -ge 3

# The KMS screen.
# The DRM driver's name as the kernel says it (card0's parent is the PCI device).
driver=$(dmesg | grep -m 1 -oE '\[drm\] Initialized [a-z0-9_]+' | awk '{ print $3 }')
mode=$(cat /sys/class/drm/card0-*/modes 2>/dev/null | head -n 1)
pass_if kms-card0 "/dev/dri/card0: driver ${driver:-none}, mode ${mode:-none}; $(ls /dev/dri 2>/dev/null | tr '\n' ' ')" \
  test -c /dev/dri/card0

# The GPIO header made through configfs at boot (board-vm-gpio-sim.service).
config=/sys/kernel/config/gpio-sim/header
chip=$(cat "$config/bank0/chip_name" 2>/dev/null)
gpiodetect >"$out/gpiodetect.txt" 2>&1
gpioinfo "${chip:-gpiochip0}" >"$out/gpioinfo.txt" 2>&1
detected=$(grep -m 1 "^${chip:-none} " "$out/gpiodetect.txt")
pass_if gpio-chip "configfs live=$(cat "$config/live" 2>/dev/null), ${detected:-${chip:-no chip} not in gpiodetect}; $(ls -l "/dev/${chip:-none}" 2>&1)" \
  test -n "$chip" -a -c "/dev/$chip" -a -n "$detected"

# The host presses the button: it has the guest's agent pull line 17 down,
# then back up; gpiomon, holding the line as a reader would, sees both edges.
gpiomon --num-events=2 "${chip:-gpiochip0}" 17 >"$out/gpiomon.txt" 2>&1 &
monitor=$!
for _ in $(seq 60); do
  gpioinfo "${chip:-gpiochip0}" 2>/dev/null | grep -q 'line  17:.*"gpiomon"' && break
  sleep 0.5
done
host_request gpio 17 pull-down
press="press: $HOST_REPLY"
sleep 1
host_request gpio 17 pull-up
release="release: $HOST_REPLY"
for _ in $(seq 60); do kill -0 "$monitor" 2>/dev/null || break; sleep 0.5; done
kill "$monitor" 2>/dev/null
wait "$monitor" 2>/dev/null
edges=$(grep -oE '(FALLING|RISING) EDGE' "$out/gpiomon.txt" | tr '\n' ',' | sed 's/,$//')
pass_if gpio-host-press "$press; $release; gpiomon saw: ${edges:-nothing}" \
  test "$edges" = "FALLING EDGE,RISING EDGE"

# The screen, through QMP: the console on tty1 (fbcon on virtio-gpu), with a
# line of ours on it.
printf '\033[2J\033[H\n  probelight board-vm smoke\n  %s\n  camera: %s\n  gpio: %s\n\n' \
  "$(uname -r)" "${camera:-none}" "${detected:-none}" >/dev/tty1
sleep 2
host_request screendump smoke
pass_if screendump "$HOST_REPLY" test "${HOST_REPLY%% *}" = ok

save_guest_logs
host_request 'done'
