#!/usr/bin/env bash
# Builds and runs every test of every preset:
#   host-release  Release: every test, the long ones (whole motions, learning, the 10 s HIL
#                 strategies, the main job) included, and the benchmarks
#   host-asan     clang, AddressSanitizer and UndefinedBehaviorSanitizer; bounded libFuzzer runs
#                 of every decoder of outside input; format check, clang-tidy and cppcheck
#   host-tsan     clang, ThreadSanitizer over the threaded code (thread pool, DDS, the CAN
#                 programs)
#   cortex-m7, cortex-m4   bare-metal firmware images under qemu-system-arm
#   aarch64       ARM64 Linux (the firmware side), tests under qemu-aarch64
# The sanitizer and cross presets leave out the long tests, which host-release runs once.
#
# Two cores: a build uses both, but the Release tests run one at a time and spend most of their
# time in the vcan guest on one core, so every other preset builds while they test (their output
# is kept and printed when they end). Those builds run at the lowest priority (nice 19): the
# guest is the longest serial chain, and a build at equal priority (ninja's four jobs) slows it
# most (forearm_hil_faults_on_vcan: 406 s beside one, 169 s beside a niced one, 113 s alone),
# while niced builds still take every cycle the tests leave. Only one preset tests at a time:
# the vcan tests share vcan0.
# Installs missing Debian packages first (toolchains/setup-debian.sh). Prints each step's time
# and, at the end, a table of them.
set -euo pipefail
cd "$(dirname "$0")/.."

timings=()
started=$SECONDS
record() {  # record NAME SECONDS
  timings+=("$(printf '%-24s %4d min %02d s' "$1" $(($2 / 60)) $(($2 % 60)))")
}
step() {  # step NAME COMMAND...: runs COMMAND in the foreground, records its time
  local name=$1 start=$SECONDS
  shift
  echo "==== ${name} ===="
  "$@"
  record "$name" $((SECONDS - start))
  echo "==== ${name}: $((SECONDS - start)) s ===="
}
background=() background_name="" background_start=0 background_log=""
start_tests() {  # start_tests PRESET: its ctest in the background, output to a log
  background_name="$1 test (background)" background_start=$SECONDS
  background_log="build/$1-ctest.log"
  echo "==== ${background_name}: started, output in ${background_log} ===="
  ctest --preset "$1" > "$background_log" 2>&1 &
  background=($!)
}
finish_tests() {  # waits for the background ctest, prints its output, fails if it failed
  [ ${#background[@]} -gt 0 ] || return 0
  local status=0
  wait "${background[0]}" || status=$?
  background=()
  echo "==== ${background_name} ===="
  cat "$background_log"
  record "$background_name" $((SECONDS - background_start))
  echo "==== ${background_name}: $((SECONDS - background_start)) s, status ${status} ===="
  return "$status"
}
report() {
  if [ ${#background[@]} -gt 0 ]; then kill "${background[0]}" 2>/dev/null || true; fi
  echo "==== times ===="
  printf '%s\n' "${timings[@]}"
  local total=$((SECONDS - started))
  printf '%-24s %4d min %02d s\n' total $((total / 60)) $((total % 60))
}
trap report EXIT

build() {  # build PRESET [nice]: configure and build, with "nice" at the lowest priority
  local priority=()
  [ "${2:-}" != nice ] || priority=(nice -n 19)
  step "$1 configure" cmake --preset "$1"
  step "$1 build" "${priority[@]}" cmake --build --preset "$1"
}

step setup bash toolchains/setup-debian.sh
mkdir -p build
build host-release
start_tests host-release
for preset in host-asan host-tsan cortex-m7 cortex-m4 aarch64; do
  build "$preset" nice
done
finish_tests
for preset in host-asan host-tsan cortex-m7 cortex-m4 aarch64; do
  step "${preset} test" ctest --preset "${preset}"
done
echo "==== all presets passed: host-release host-asan host-tsan cortex-m7 cortex-m4 aarch64 ===="
