#!/usr/bin/env bash
# Installs every Debian 12 package hmpc needs to build, test and run its demo: host and
# cross toolchains, libraries, emulators and plotting. Idempotent and non-interactive: only
# missing packages are installed, and nothing is fetched when none is missing.
set -euo pipefail

packages=(
  # host build
  g++ cmake ninja-build make pkgconf
  # sanitizer and fuzzing builds (clang with its ASan, UBSan, TSan and libFuzzer runtimes;
  # llvm-symbolizer for their stack traces) and the linters
  clang libclang-rt-14-dev llvm clang-tidy clang-format cppcheck
  # libraries
  libeigen3-dev googletest libgtest-dev libbenchmark-dev
  # rigid-body reference and HIL plants
  libsimbody-dev
  # DDS between the host programs (C API; cyclonedds-tools has idlc for idlc_generate)
  cyclonedds-dev cyclonedds-tools
  # bare-metal Cortex-M (newlib-nano, libstdc++ for newlib)
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  # ARM64 Linux cross toolchain
  g++-aarch64-linux-gnu
  # emulators: Cortex-M boards (mps2-an500/an386) and ARM64 user mode
  qemu-system-arm qemu-user
  # plots of the demo and scenarios
  gnuplot-nox
  # vcan launcher (hil/vcan): a guest booting Debian's stock kernel when the host kernel has
  # no CAN; kmod resolves the guest's module dependencies, and the kernel and its modules may
  # be xz- or zstd-compressed
  qemu-system-x86 busybox-static iproute2 kmod xz-utils zstd
  # CAN inspection tools (candump, cansend, cangen) for debugging on vcan or a real bus
  can-utils
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# The vcan launcher downloads (never installs) Debian's kernel package on first use, which
# needs package lists even when every package above is installed.
need_lists=0
apt-cache show linux-image-amd64 >/dev/null 2>&1 || need_lists=1

if [ ${#missing[@]} -eq 0 ] && [ $need_lists -eq 0 ]; then
  echo "setup-debian: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "setup-debian: missing packages (${missing[*]}) and neither root nor sudo" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup-debian: installing ${missing[*]}"
  "${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
