#!/usr/bin/env bash
# Runs each libFuzzer target (fuzz/*_fuzzer.cpp) for SECONDS on its corpus,
# fuzz/corpus/<target>/, one target per core at a time, and prints how many
# inputs each ran. The targets are built into ./build-asan first (clang,
# ASan + UBSan; as scripts/test-sanitizers.sh builds it). New inputs the
# fuzzer finds go to a scratch folder, not the repository's corpus;
# FUZZ_MERGE=1 merges the ones that add coverage into it. Exits 1 if a
# target crashed, with the input that did it in build-asan/fuzz-crashes/.
#
# usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (default 30 s, every target;
#        a target is a name such as camera_yaml; FUZZ_JOBS targets at once,
#        default the core count)
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
for name in "${targets[@]}"; do
  [[ -d fuzz/corpus/$name ]] || { echo "fuzz: no corpus folder fuzz/corpus/$name" >&2; exit 2; }
done
if [[ ! -f build-asan/CMakeCache.txt ]]; then
  CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPROBELIGHT_FUZZ=ON
fi
cmake --build build-asan -j"$(nproc)" --target fuzzers
source scripts/sanitizer-options.sh
mkdir -p build-asan/fuzz-crashes
jobs=${FUZZ_JOBS:-$(nproc)}

# One target's run; its status file says whether it crashed.
fuzz_one() {
  local name=$1 corpus=fuzz/corpus/$1 log=build-asan/fuzz-$1.log scratch status=0
  scratch=$(mktemp -d)
  # -timeout: an input that takes 10 s is a hang; -rss_limit_mb: one that
  # needs 2 GB is a memory bomb (a frame's header claiming 65535^2 px was one).
  build-asan/fuzz_"$name" -max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix=build-asan/fuzz-crashes/"$name"- "$scratch" "$corpus" >"$log" 2>&1 || status=$?
  if [[ $status = 0 && ${FUZZ_MERGE:-0} = 1 ]]; then
    build-asan/fuzz_"$name" -merge=1 "$corpus" "$scratch" >>"$log" 2>&1
  fi
  rm -rf "$scratch"
  echo "$status" >build-asan/fuzz-$name.status
}

running=0
for name in "${targets[@]}"; do
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
  fuzz_one "$name" &
  running=$((running + 1))
done
wait || true

printf '| target | seconds | inputs run | corpus files |\n|---|---|---|---|\n'
crashed=()
for name in "${targets[@]}"; do
  log=build-asan/fuzz-$name.log
  status=$(cat build-asan/fuzz-"$name".status 2>/dev/null || echo missing)
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  printf '| %s | %s | %s | %s |\n' "$name" "$seconds" "${runs:-?}" "$(ls fuzz/corpus/"$name" | wc -l)"
  [[ $status = 0 ]] || crashed+=("$name")
done
for name in "${crashed[@]}"; do
  tail -40 build-asan/fuzz-"$name".log >&2
  echo "fuzz: $name crashed; the input is in build-asan/fuzz-crashes/ (log: build-asan/fuzz-$name.log)" >&2
done
((${#crashed[@]} == 0)) || exit 1
