#!/usr/bin/env bash
# The test job on a fresh machine: install, build, run every test (ctest),
# tier by tier: unit (pure CPU), gpu (passes against their CPU references),
# e2e (the binary through its commands), accuracy (against the simulator's
# truth), vm (the package and the board VM's host-side checks). Each test's
# tier is in tests/tiers.cmake. Prints each tier's wall time at the end.
#
#   scripts/test.sh            every tier
#   scripts/test.sh --quick    unit and gpu (in the three GPU contexts) only: a developer's loop
#
# Under CI=true the benchmarks are not built (scripts/test-sanitizers.sh
# compile-checks them).
set -euo pipefail
cd "$(dirname "$0")/.."
# gpu@PROFILE: the gpu tier again in one of the GPU contexts of
# scripts/gpu-profiles.sh (the Pi 4's, a bare GLES2 one).
tiers=(unit gpu gpu@pi4 gpu@gles2 e2e accuracy vm)
case "${1:-}" in
  "") ;;
  --quick) tiers=(unit gpu gpu@pi4 gpu@gles2) ;;
  *) echo "usage: scripts/test.sh [--quick]" >&2; exit 2 ;;
esac
# PROBELIGHT_TEST_TIERS="unit gpu ...": those tiers only (scripts/debian13-check).
[[ -n ${PROBELIGHT_TEST_TIERS:-} ]] && read -ra tiers <<<"$PROBELIGHT_TEST_TIERS"
# PROBELIGHT_TIMES=FILE (.ci/run's time table): each step's "NAME SECONDS STATUS" appended.
record() {
  [[ -n ${PROBELIGHT_TIMES:-} ]] && printf '%s\t%s\t%s\n' "$1" "$2" "$3" >>"$PROBELIGHT_TIMES"
  return 0
}
start=$(date +%s)
scripts/install-deps.sh
bench=${PROBELIGHT_BUILD_BENCH:-ON}
[[ ${CI:-} == true ]] && bench=OFF
PROBELIGHT_BUILD_BENCH=$bench scripts/build.sh
record "test.sh: install and build" "$(($(date +%s) - start))" 0
cd build
failed=()
table=()
source ../scripts/gpu-profiles.sh
for tier in "${tiers[@]}"; do
  start=$(date +%s)
  status=0
  label=${tier%@*}
  profile=
  [[ $tier == *@* ]] && profile=${tier#*@}
  excluded=()
  # llvmpipe (Mesa 22.3, LLVM 15) crashes in LLVM's EarlyCSE pass compiling
  # this test's model shader when the maps are 8-bit in a context that
  # keeps highp and the depth textures (as it did before the ES 3 work, with
  # only OES_texture_half_float taken away): a driver fault, not ours, left
  # out of that run only. The test runs in the plain gpu tier and
  # under the in-process 8-bit mask.
  [[ $profile == gles2 ]] && excluded=(-E '^GpuTest\.AModelHidesTheFloorsLightFromItself$')
  (
    [[ -n $profile ]] && gpu_profile_export "$profile"
    ctest --output-on-failure -j"$(nproc)" --timeout 900 -L "^${label}\$" "${excluded[@]}"
  ) || status=$?
  seconds=$(($(date +%s) - start))
  count=$(ctest -N -L "^${label}\$" "${excluded[@]}" | sed -n 's/^Total Tests: //p')
  table+=("$(printf '| %-9s | %5s | %4d s | %s |' "$tier" "$count" "$seconds" "$([ $status = 0 ] && echo passed || echo FAILED)")")
  [ $status = 0 ] || failed+=("$tier")
  record "tier $tier ($count tests)" "$seconds" "$status"
done
echo
echo "| tier      | tests |   wall | result |"
echo "|-----------|-------|--------|--------|"
printf '%s\n' "${table[@]}"
if ((${#failed[@]})); then
  echo "test.sh: failed in ${failed[*]}" >&2
  exit 1
fi
