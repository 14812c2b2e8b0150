#!/usr/bin/env bash
# Runs every fuzz target (or the ones named) for SECONDS each at the lowest CPU priority, then
# reports, per target, the executions, the coverage (libFuzzer's `cov`: instrumented edges hit;
# `ft`: features, edges with hit-count buckets), the corpus size and what libFuzzer found:
# crashes, out-of-memory and timeout inputs, which it saves in fuzz/artifacts/<target>/. New
# interesting inputs go to fuzz/work/<target>/ (ignored by git); the committed seeds in
# fuzz/corpus/<target>/ are read, never written.
#
#   fuzz/run-all.sh [SECONDS] [TARGET...]        (default: 60 seconds, every target)
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and a nightly toolchain (`rustup toolchain install
# nightly`). Exit status: 0 when no target found anything, 1 otherwise, 2 when the build fails.
set -uo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
if [ $# -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo +nightly fuzz list)
fi
# libFuzzer options: per-input time and memory limits, and inputs up to 64 KiB.
options=(-max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1)
nice -n 19 cargo +nightly fuzz build || exit 2
found=0
row='%-12s %10s %6s %6s %8s %s\n'
printf "$row" target runs cov ft corpus findings
for target in "${targets[@]}"; do
  mkdir -p "fuzz/work/$target" "fuzz/artifacts/$target"
  log="fuzz/artifacts/$target.log"
  before=$(find "fuzz/artifacts/$target" -type f | sort)
  nice -n 19 cargo +nightly fuzz run "$target" "fuzz/work/$target" "fuzz/corpus/$target" \
    -- "${options[@]}" >"$log" 2>&1
  after=$(find "fuzz/artifacts/$target" -type f | sort)
  new=$(comm -13 <(echo "$before") <(echo "$after") | grep -v '^$' || true)
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  # The last status line (`#N DONE cov: …`, or the last one before a crash).
  status=$(grep -E '^#[0-9]+[[:space:]].*cov: ' "$log" | tail -1)
  cov=$(echo "$status" | grep -o 'cov: [0-9]*' | grep -o '[0-9]*$' || echo '?')
  ft=$(echo "$status" | grep -o 'ft: [0-9]*' | grep -o '[0-9]*$' || echo '?')
  corpus=$(find "fuzz/work/$target" -type f | wc -l)
  if [ -n "$new" ]; then
    found=1
    printf "$row" "$target" "$runs" "$cov" "$ft" "$corpus" "$(echo "$new" | tr '\n' ' ')"
    grep -m1 -E 'panicked at|ERROR: libFuzzer|SUMMARY' "$log" | sed 's/^/             /'
  else
    printf "$row" "$target" "$runs" "$cov" "$ft" "$corpus" none
  fi
done
[ "$found" = 0 ] || echo "Reproduce: cargo +nightly fuzz run <target> <artifact>; log: fuzz/artifacts/<target>.log"
exit "$found"
