#!/usr/bin/env bash
# Builds and runs every test, one preset after another (one build at a time on this 2-core
# class of machine; ninja uses both cores):
#   host-release  Release: every test, the long ones (whole motions, learning, the 10 s HIL
#                 strategies, the main job) included, and the benchmarks
#   host-asan     clang, AddressSanitizer and UndefinedBehaviorSanitizer; bounded libFuzzer runs
#                 of every decoder of outside input; format check, clang-tidy and cppcheck
#   host-tsan     clang, ThreadSanitizer over the threaded code (thread pool and the MPC on it,
#                 DDS, the CAN programs)
#   cortex-m7, cortex-m4   bare-metal firmware images under qemu-system-arm
#   aarch64       ARM64 Linux, tests under qemu-aarch64
# The sanitizer and cross presets leave out the long tests, which host-release runs once.
# Installs missing Debian packages first (toolchains/setup-debian.sh). Prints each step's time
# and, at the end, a table of them.
set -euo pipefail
cd "$(dirname "$0")/.."

timings=()
started=$SECONDS
step() {  # step NAME COMMAND...: runs COMMAND, records its time
  local name=$1 start=$SECONDS
  shift
  echo "==== ${name} ===="
  "$@"
  local took=$((SECONDS - start))
  timings+=("$(printf '%-22s %4d min %02d s' "$name" $((took / 60)) $((took % 60)))")
  echo "==== ${name}: ${took} s ===="
}
report() {
  echo "==== times ===="
  printf '%s\n' "${timings[@]}"
  local total=$((SECONDS - started))
  printf '%-22s %4d min %02d s\n' total $((total / 60)) $((total % 60))
}
trap report EXIT

step setup bash toolchains/setup-debian.sh
presets=(host-release host-asan host-tsan cortex-m7 cortex-m4 aarch64)
for preset in "${presets[@]}"; do
  step "${preset} configure" cmake --preset "${preset}"
  step "${preset} build" cmake --build --preset "${preset}"
  step "${preset} test" ctest --preset "${preset}"
done
echo "==== all presets passed: ${presets[*]} ===="
