#!/usr/bin/env bash
# The test job on a fresh machine: install, build, run every test (ctest),
# tier by tier: unit (pure CPU), gpu (passes against their CPU references),
# e2e (the binary through its commands), accuracy (against the simulator's
# truth), vm (the package and the board VM's host-side checks). Each test's
# tier is in tests/tiers.cmake. Prints each tier's wall time at the end.
#
#   scripts/test.sh            every tier
#   scripts/test.sh --quick    unit and gpu only: a developer's loop
#
# Under CI=true the benchmarks are not built (scripts/test-sanitizers.sh
# compile-checks them).
set -euo pipefail
cd "$(dirname "$0")/.."
tiers=(unit gpu e2e accuracy vm)
case "${1:-}" in
  "") ;;
  --quick) tiers=(unit gpu) ;;
  *) echo "usage: scripts/test.sh [--quick]" >&2; exit 2 ;;
esac
# PROBELIGHT_TIMES=FILE (.ci/run's time table): each step's "NAME SECONDS STATUS" appended.
record() {
  [[ -n ${PROBELIGHT_TIMES:-} ]] && printf '%s\t%s\t%s\n' "$1" "$2" "$3" >>"$PROBELIGHT_TIMES"
  return 0
}
start=$(date +%s)
scripts/install-deps.sh
bench=ON
[[ ${CI:-} == true ]] && bench=OFF
PROBELIGHT_BUILD_BENCH=$bench scripts/build.sh
record "test.sh: install and build" "$(($(date +%s) - start))" 0
cd build
failed=()
table=()
for tier in "${tiers[@]}"; do
  start=$(date +%s)
  status=0
  ctest --output-on-failure -j"$(nproc)" --timeout 900 -L "^${tier}\$" || status=$?
  seconds=$(($(date +%s) - start))
  count=$(ctest -N -L "^${tier}\$" | sed -n 's/^Total Tests: //p')
  table+=("$(printf '| %-8s | %5s | %4d s | %s |' "$tier" "$count" "$seconds" "$([ $status = 0 ] && echo passed || echo FAILED)")")
  [ $status = 0 ] || failed+=("$tier")
  record "tier $tier ($count tests)" "$seconds" "$status"
done
echo
echo "| tier     | tests |   wall | result |"
echo "|----------|-------|--------|--------|"
printf '%s\n' "${table[@]}"
if ((${#failed[@]})); then
  echo "test.sh: failed in ${failed[*]}" >&2
  exit 1
fi
