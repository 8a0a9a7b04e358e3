#!/usr/bin/env bash
# The unit and end-to-end tests again, built by clang with AddressSanitizer
# and UndefinedBehaviorSanitizer into ./build-asan, then each libFuzzer
# target (fuzz/) for a short run on its corpus: scripts/fuzz.sh, on the same
# build. Any sanitizer report aborts the process that met it, so its test or
# fuzz run fails. Needs what scripts/install-deps.sh installs.
#
# usage: scripts/test-sanitizers.sh [FUZZ_SECONDS]   (default 30 a target; 0: no fuzzing)
#        SANITIZER_BUILD_ONLY=1 scripts/test-sanitizers.sh   (the build alone: .ci/run
#        makes it beside the board VM, whose emulator keeps one core)
#
# Leaks: the fuzz runs check them (LeakSanitizer, on every input; no GL in
# those processes). The tests do not: Mesa's drivers are unloaded at exit,
# and what they allocated for the process's life is then reported from an
# "<unknown module>" that no suppression can name. The soak
# (scripts/soak.sh) watches the whole kiosk's memory instead.
set -euo pipefail
cd "$(dirname "$0")/.."
fuzz_seconds=${1:-30}
CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPROBELIGHT_FUZZ=ON \
  -DPROBELIGHT_BUILD_BENCH=OFF
cmake --build build-asan -j"$(nproc)"
[[ ${SANITIZER_BUILD_ONLY:-0} == 1 ]] && exit 0
source scripts/sanitizer-options.sh
# Every suite but `accuracy`: its tests hold numbers against path-traced
# truth, which the release run (scripts/test.sh) checks; the code they run
# (the stages, the passes, analyze and run through the binary) is run here
# by the app, stages, gles and ibl suites. Under the sanitizers the
# simulator's path tracing is about 10x slower: the accuracy suite took
# 1470 of the run's 3400 test-seconds (about 12 of its 28 minutes on 2
# cores, CI of 2026-12-05), and issue 17 holds CI to 75 minutes.
#
# Also left to the release run: seven tests whose time here is the
# simulator's rendering, each beside a shorter one that runs the same code
# under the sanitizers (CI of 2026-12-07: 690 of the run's 2630
# test-seconds; that CI took 86 of its 90 minutes):
#   ProbeMergeRun.AHandHeldSweep... (195 s): the probe merge over a moving
#     camera, as ProbeMergeRun.AMovingCamera... runs it;
#   ProbeMergeRun.ALampSwitchedOn... (72-79 s): a lamp switched on in a
#     still room, as ProbeMergeRun.AStillRoom... and
#     EndToEnd.LampSwitchingOnWithAStillCamera... run the merge and the
#     change;
#   EndToEnd.KeyButtonRecalibratesTheLights (63-85 s): a press's
#     recalibration, as WindowDisplayTest.KeysPressAndHold... runs it (by
#     the window's key, into the same kiosk code);
#   EndToEnd.LampSwitchingOnRefitsTheLightsWhenAsked (101 s): the refit on
#     a lamp, as EndToEnd.LampSwitchingOnWithAStillCamera... and
#     EndToEnd.KeyButtonRecalibratesTheLights run it;
#   EndToEndLamp's 30 degree spot (42 s): the point light's run is the
#     same code (the spot's weight is ibl's, in VirtualLamp.*);
#   MeshTruth.AWindowRenders... and .AMeshBoxCasts... (152 s, 42 s): the
#     simulator against itself, whose code every end-to-end test runs.
sanitizer_skips='^(ProbeMergeRun\.(AHandHeldSweepKeepsTheSunItsBracketMeasured|ALampSwitchedOnShowsInItsFirstFrame)'
sanitizer_skips+='|EndToEnd\.KeyButtonRecalibratesTheLights'
sanitizer_skips+='|EndToEnd\.LampSwitchingOnRefitsTheLightsWhenAsked'
sanitizer_skips+='|PointAndSpot/EndToEndLamp\.LightsTheGroundAsTheSimulatorsLampDoes/30'
sanitizer_skips+='|MeshTruth\.(AWindowRendersItsPixelsAsTheWholeFrameDoes|AMeshBoxCastsTheAnalyticBoxsShadow))$'
(cd build-asan && ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" ctest --output-on-failure -j"$(nproc)" --timeout 1800 \
  --label-exclude '^accuracy$' --exclude-regex "$sanitizer_skips")
if [[ $fuzz_seconds != 0 ]]; then
  scripts/fuzz.sh "$fuzz_seconds"
fi
