#!/usr/bin/env bash
# check_main_job.sh CMAKE BUILD_DIR: runs the README's main job (the build's demo target: the
# forearm HIL over vcan) and checks what it leaves in BUILD_DIR/demo: a summary table with a
# row of numbers per strategy, a CSV row of numbers per run, and every plot a non-empty PNG.
set -uo pipefail
cmake=$1 build=$2 out=$2/demo
strategies=(fine_4ms coarse_20ms two_stage)
rm -rf "$out"
"$cmake" --build "$build" --target demo || { echo "the main job failed"; exit 1; }
fail() { echo "main job output: $*"; exit 1; }
number='-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?'
for s in "${strategies[@]}"; do
  # | f | w_v | strategy | cost +- sd | RMS +- sd | max solve | median solve | misses | share |
  grep -Eq "^\| $number \| $number \| $s \| $number \+- $number \| $number \+- $number \| $number \| $number \| [0-9]+ \| $number % \|$" \
    "$out/hil_summary.md" || fail "no row of numbers for $s in hil_summary.md"
  row=$(grep "^$s," "$out/hil_runs.csv") || fail "no row for $s in hil_runs.csv"
  echo "$row" | tr ',' '\n' | tail -n +2 | grep -Evqx -- "$number" && fail "a field of $s's CSV row is not a number: $row"
done
[ "$(wc -l < "$out/hil_runs.csv")" -eq $((${#strategies[@]} + 1)) ] || fail "hil_runs.csv: not one row per run"
for png in hil_angle_1hz hil_torques hil_cost hil_error hil_solve_time; do
  f=$out/$png.png
  [ "$(head -c 8 "$f" 2>/dev/null | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "$png.png is not a PNG"
  [ "$(stat -c %s "$f")" -gt 2000 ] || fail "$png.png is too small to hold a plot"
done
echo "main job: table, CSV and ${#strategies[@]} runs' plots in $out"
