#!/usr/bin/env bash
# Builds and runs every test: host (Release, then Debug with ASan/UBSan), the Cortex-M7 and
# Cortex-M4 firmware presets under qemu-system-arm, and the ARM64 build under qemu-aarch64.
# Installs missing Debian packages first (see toolchains/setup-debian.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

bash toolchains/setup-debian.sh

presets=(host-release host-asan cortex-m7 cortex-m4 aarch64)
for preset in "${presets[@]}"; do
  echo "==== workflow ${preset} ===="
  # One build at a time on this 2-core class of machine; ninja uses both cores.
  cmake --workflow --preset "${preset}"
done
echo "==== all workflows passed: ${presets[*]} ===="
