#!/usr/bin/env bash
# Long fuzz runs by CPU time, not wall time: each target runs in 5-minute slices (at low
# priority, so builds and tests go first) until the CPU seconds it has used, summed over every
# run of this script on this machine, reach the budget. The sums are kept in
# build/fuzz/long/cpu.tsv (target, CPU seconds, executions); findings go to
# build/fuzz/tests/fuzz/artifacts/<target>/ as with scripts/fuzz.sh.
#
# To time something else on a quiet machine: `touch build/fuzz/long/pause` holds the next slices
# back, and `pkill -TERM -f '^build/fuzz/tests/fuzz/fuzz_'` ends the running ones (a slice ended so
# is counted, not taken for a finding); `rm build/fuzz/long/pause` goes on. Never SIGSTOP a
# fuzzer: libFuzzer takes the pause for a timeout of the input it was running.
# Usage: scripts/fuzz_long.sh [CPU SECONDS per target, default 3600] [target ...]
set -euo pipefail
cd "$(dirname "$0")/.."
budget=${1:-3600}
shift || true
fuzz=build/fuzz/tests/fuzz
long=build/fuzz/long
mkdir -p "$long"
touch "$long/cpu.tsv"
# (One build at a time: two streams started together would otherwise race in one build tree.
# Quiet unless the build fails: then its errors, and no fuzzing — a run in the background would
# otherwise end without a word.)
if ! build_log=$(flock "$long/build.lock" sh -c 'cmake --preset fuzz >/dev/null && cmake --build --preset fuzz -j "$(nproc)" --target fuzzers' 2>&1); then
  echo "$build_log" | grep -E "error|FAILED" -A3 >&2
  echo "fuzz_long: the fuzz preset does not build (clang); nothing fuzzed" >&2
  exit 1
fi
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_shapefile fuzz_ply fuzz_gpkg_file fuzz_gpkg_blob fuzz_off fuzz_obj fuzz_stl fuzz_giscup fuzz_numbers)
used() { awk -v t="$1" '$1 == t { s += $2 } END { print s + 0 }' "$long/cpu.tsv"; }
for target in "${targets[@]}"; do
  mkdir -p "$fuzz/work/$target" "$fuzz/artifacts/$target"
  while [ "$(used "$target" | cut -d. -f1)" -lt "$budget" ]; do
    while [ -e "$long/pause" ]; do sleep 10; done
    status=0
    /usr/bin/time -f "%U %S" -o "$long/$target.time" nice -n 19 "$fuzz/$target" "$fuzz/work/$target" \
      "tests/fuzz/corpus/$target" -max_total_time=300 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$fuzz/artifacts/$target/" -print_final_stats=1 > "$long/$target.log" 2>&1 || status=$?
    # (time's last line is the CPU seconds; before it, a line on a non-zero exit.)
    read -r user system < <(tail -n 1 "$long/$target.time")
    runs=$(awk '/stat::number_of_executed_units/ { print $2 }' "$long/$target.log")
    printf "%s\t%s\t%s\n" "$target" "$(awk -v u="$user" -v s="$system" "BEGIN { print u + s }")" "${runs:-0}" >> "$long/cpu.tsv"
    if [ "$status" -ne 0 ] && ! grep -q "libFuzzer: run interrupted" "$long/$target.log"; then
      echo "$target: finding, see $fuzz/artifacts/$target/ and $long/$target.log"
      exit 1
    fi
  done
  echo "$target: $(used "$target") CPU seconds in all, no finding"
done
