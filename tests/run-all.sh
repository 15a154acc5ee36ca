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
# Two cores. The vcan tests are the longest chain: each runs in a QEMU guest on one core (where
# the kernel has no vcan), and a native vcan0 would be shared, so no two presets' vcan tests run
# at once. The Release ones start as soon as Release is built, in the background (their output
# is kept and printed when they end); every other preset builds beside them, then every test
# that needs no vcan runs beside them too, each ctest with a TMPDIR of its own, except the
# sanitizer's DDS tests (label threads), which wait with its vcan tests: the Release DDS tests
# use the same domain ids.
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
start_tests() {  # start_tests PRESET CTEST-ARGS...: a ctest in the background, output to a log
  background_name="$1 test $2 $3 (background)" background_start=$SECONDS
  background_log="build/$1-ctest.log"
  echo "==== ${background_name}: started, output in ${background_log} ===="
  ctest --preset "$@" > "$background_log" 2>&1 &
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

build() {  # build PRESET: configure and build
  step "$1 configure" cmake --preset "$1"
  step "$1 build" cmake --build --preset "$1"
}

beside_release() {  # beside_release NAME CTEST-ARGS...: a step with a TMPDIR of its own
  local name=$1 tmp
  shift
  tmp=$(mktemp -d)
  step "$name" env TMPDIR="$tmp" ctest "$@"
  rm -rf "$tmp"
}

step setup bash toolchains/setup-debian.sh
mkdir -p build
build host-release
start_tests host-release -L vcan
for preset in host-asan host-tsan cortex-m7 cortex-m4 aarch64; do
  build "$preset"
done
beside_release "host-release test -LE vcan" --preset host-release -LE vcan
# -LE replaces the preset's excluded label (long), so it is named again.
beside_release "host-asan test -LE 'long|vcan|threads'" --preset host-asan -LE 'long|vcan|threads'
for preset in cortex-m7 cortex-m4 aarch64; do
  beside_release "${preset} test" --preset "$preset"
done
finish_tests
step "host-asan test -L 'vcan|threads'" ctest --preset host-asan -L 'vcan|threads'
step "host-tsan test" ctest --preset host-tsan
echo "==== all presets passed: host-release host-asan host-tsan cortex-m7 cortex-m4 aarch64 ===="
