# shellcheck shell=bash
# Helpers for a board-vm payload, sourced by its run.sh inside the guest
# (bash; the image has no python). The host's side is
# scripts/board_vm/vmctl.py; the protocol is described there.
#
#   open_host_channel            once, before any request
#   host_request WORDS...        one request; the answer in HOST_REPLY;
#                                success when the answer starts with "ok"
#   report_check NAME PASS|FAIL DETAIL...
#   save_guest_logs              the journal and boot timing into $BOARD_VM_OUT

BOARD_VM_OUT=${BOARD_VM_OUT:-/run/board-vm/out}
HOST_REPLY=

open_host_channel() {
  local port=/dev/virtio-ports/board-vm.ctl
  # udev makes the by-name link; give it time on an emulated CPU.
  udevadm settle --timeout=60 || true
  for _ in $(seq 120); do [[ -e $port ]] && break; sleep 1; done
  exec {HOST_FD}<>"$port"
}

host_request() {
  local line="$*"
  line=${line//$'\n'/ }
  printf '%s\n' "${line:0:2000}" >&"$HOST_FD"
  HOST_REPLY=
  if ! IFS= read -r -t "${BOARD_VM_REQUEST_TIMEOUT:-300}" HOST_REPLY <&"$HOST_FD"; then
    HOST_REPLY="error: no answer from the host"
    return 1
  fi
  [[ $HOST_REPLY == ok* ]]
}

report_check() {
  local name=$1 status=$2
  shift 2
  echo "board-vm check: $status $name: $*"
  host_request check "$name" "$status" "$*" || echo "board-vm: the host did not take the check: $HOST_REPLY"
}

# pass_if NAME DETAIL COMMAND...: PASS when COMMAND succeeds.
pass_if() {
  local name=$1 detail=$2
  shift 2
  if "$@"; then report_check "$name" PASS "$detail"; else report_check "$name" FAIL "$detail"; fi
}

save_guest_logs() {
  journalctl -b --no-pager -o short-monotonic >"$BOARD_VM_OUT/journal.txt" 2>&1
  systemd-analyze time >"$BOARD_VM_OUT/systemd-analyze.txt" 2>&1
  systemd-analyze blame 2>&1 | head -n 30 >>"$BOARD_VM_OUT/systemd-analyze.txt"
  systemctl --failed --no-pager >"$BOARD_VM_OUT/failed-units.txt" 2>&1
  dmesg >"$BOARD_VM_OUT/dmesg.txt" 2>&1
  sync
}
