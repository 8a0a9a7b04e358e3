#!/usr/bin/env bash
# Runs each libFuzzer target (fuzz/*_fuzzer.cpp) for SECONDS on its corpus,
# fuzz/corpus/<target>/, and prints how many inputs each ran. The targets
# are built into ./build-asan first (clang, ASan + UBSan; as
# scripts/test-sanitizers.sh builds it). New inputs the fuzzer finds go to a
# scratch folder, not the repository's corpus; FUZZ_MERGE=1 merges the ones
# that add coverage into it. Exits 1 at the first target that crashes, with
# the input that did it in build-asan/fuzz-crashes/.
#
# usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (default 30 s, every target;
#        a target is a name such as camera_yaml)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
targets=("$@")
if ((${#targets[@]} == 0)); then
  targets=()
  for source in fuzz/*_fuzzer.cpp; do
    name=$(basename "$source" _fuzzer.cpp)
    targets+=("$name")
  done
fi
if [[ ! -f build-asan/CMakeCache.txt ]]; then
  CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPROBELIGHT_FUZZ=ON \
    -DPROBELIGHT_BUILD_BENCH=OFF
fi
cmake --build build-asan -j"$(nproc)" --target fuzzers
source scripts/sanitizer-options.sh
mkdir -p build-asan/fuzz-crashes
printf '| target | seconds | inputs run | corpus files |\n|---|---|---|---|\n'
for name in "${targets[@]}"; do
  corpus=fuzz/corpus/$name
  [[ -d $corpus ]] || { echo "fuzz: no corpus folder $corpus" >&2; exit 2; }
  scratch=$(mktemp -d)
  log=build-asan/fuzz-$name.log
  # -timeout: an input that takes 10 s is a hang; -rss_limit_mb: one that
  # needs 2 GB is a memory bomb (a frame's header claiming 65535^2 px was one).
  if ! build-asan/fuzz_"$name" -max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix=build-asan/fuzz-crashes/"$name"- "$scratch" "$corpus" >"$log" 2>&1; then
    tail -40 "$log" >&2
    echo "fuzz: $name crashed; the input is in build-asan/fuzz-crashes/ (log: $log)" >&2
    rm -rf "$scratch"
    exit 1
  fi
  if [[ ${FUZZ_MERGE:-0} = 1 ]]; then
    build-asan/fuzz_"$name" -merge=1 "$corpus" "$scratch" >>"$log" 2>&1
  fi
  rm -rf "$scratch"
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  printf '| %s | %s | %s | %s |\n' "$name" "$seconds" "${runs:-?}" "$(ls "$corpus" | wc -l)"
done
