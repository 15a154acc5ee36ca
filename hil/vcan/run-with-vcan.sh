#!/usr/bin/env bash
# run-with-vcan.sh CMD [ARGS...]
#
# Runs CMD with the virtual CAN buses vcan0 and vcan1 up and exits with CMD's exit status.
# vcan0 is the robot's bus (host and boards); vcan1 the HIL's I/O bus, on which a plant node
# emulates the boards' local sensors and valves where the robot bus must not carry them.
#
# Where this kernel has vcan (both are already up, or we are root and can create them), CMD runs
# right here. Otherwise it runs in a throw-away QEMU guest booting Debian's stock kernel, which
# has CAN. The guest sees this machine's whole filesystem at the same paths (virtio-9p,
# read-write) and runs CMD in the same directory, with the same environment and user id, so a
# binary built here runs there unchanged. CMD's stdout and stderr come back as ours (through
# pipes, at about 100 kB/s: write bulk output to files); its stdin is /dev/null.
#
# Exit status: CMD's own; 124 when HMPC_VCAN_TIMEOUT expired; 125 when the launcher or the
# guest failed before CMD could report a status (a message on stderr says why).
#
# Environment:
#   HMPC_VCAN_MODE        auto (default) | native | vm: force one way of getting the buses
#   HMPC_VCAN_TIMEOUT     seconds before CMD (with its guest) is killed; 0 = never (default)
#   HMPC_VCAN_CACHE       where the guest kernel and initramfs are kept; delete it to move to
#                         a newer Debian kernel (default ${XDG_CACHE_HOME:-~/.cache}/hmpc-vcan)
#   HMPC_VCAN_KERNEL_PKG  Debian kernel package to boot (default: linux-image-amd64's choice)
#   HMPC_VCAN_ACCEL       auto (default) | kvm | tcg
#   HMPC_VCAN_CPUS        guest CPUs (default 1)
#   HMPC_VCAN_MEM         guest memory in MiB (default 512)
#   HMPC_VCAN_VERBOSE     1: say how the buses were obtained, time the guest, show its kernel log
#
# The guest needs qemu-system-x86 and busybox-static; building its image once needs apt-get
# (download only: nothing is installed, no root needed), dpkg-deb, kmod and xz-utils/zstd.
# toolchains/setup-debian.sh installs them all.
set -euo pipefail

readonly launcher_failed=125
readonly timed_out=124
# What the guest loads: raw CAN sockets, vcan, and the 9p transport to reach our filesystem.
# Dependencies (can, can-dev, netfs, virtio, ...) are resolved from the kernel package itself.
readonly guest_modules=(can_raw vcan 9pnet_virtio 9p virtio_pci)

say() { echo "run-with-vcan: $*" >&2; }
fail() { say "$*"; exit "$launcher_failed"; }
verbose() { [ "${HMPC_VCAN_VERBOSE:-0}" != 1 ] || say "$*"; }

[ $# -ge 1 ] || fail "usage: run-with-vcan.sh CMD [ARGS...]"

mode=${HMPC_VCAN_MODE:-auto}
timeout_s=${HMPC_VCAN_TIMEOUT:-0}
[[ $timeout_s =~ ^[0-9]+$ ]] || fail "HMPC_VCAN_TIMEOUT must be a whole number of seconds, got '$timeout_s'"

# Directories to remove however we exit.
temporary_dirs=()
trap 'rm -rf "${temporary_dirs[@]}"' EXIT

# ---------------------------------------------------------------------------------- native

readonly buses=(vcan0 vcan1)

vcan_is_up() {
  local type flags
  type=$(cat "/sys/class/net/$1/type" 2>/dev/null) || return 1
  flags=$(cat "/sys/class/net/$1/flags" 2>/dev/null) || return 1
  [ "$type" = 280 ] && (( flags & 0x1 ))  # ARPHRD_CAN, IFF_UP
}

buses_are_up() {
  local bus
  for bus in "${buses[@]}"; do vcan_is_up "$bus" || return 1; done
}

bring_up_native_buses() {
  [ "$(id -u)" = 0 ] && command -v ip >/dev/null || return 1
  # vcan may be built in, or modprobe absent: only `ip` tells whether the kernel has it.
  modprobe vcan 2>/dev/null || true
  local bus
  for bus in "${buses[@]}"; do
    # A concurrent launcher may create it between our check and our add: either way it exists.
    ip link add dev "$bus" type vcan 2>/dev/null || [ -e "/sys/class/net/$bus" ] || return 1
    ip link set "$bus" up 2>/dev/null && vcan_is_up "$bus" || return 1
  done
}

# The buses are left up afterwards: other commands may be using them concurrently.
run_natively() {
  verbose "vcan0 and vcan1 are native; running $1 here"
  (( timeout_s > 0 )) || exec "$@"
  local status=0
  timeout --kill-after=5 "$timeout_s" "$@" || status=$?
  [ "$status" != "$timed_out" ] || say "$1 timed out after ${timeout_s} s (HMPC_VCAN_TIMEOUT)"
  exit "$status"
}

# ------------------------------------------------------------------------ the guest image

# Sets $image_dir to a directory with the guest kernel (bzImage, and vmlinux when it could be
# unpacked) and base.cpio (busybox and the kernel modules), building it on first use.
prepare_guest_image() {
  local cache=${HMPC_VCAN_CACHE:-${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/hmpc-vcan}
  mkdir -p "$cache" || fail "cannot create the cache directory $cache (set HMPC_VCAN_CACHE)"
  local package=${HMPC_VCAN_KERNEL_PKG:-}
  # The first image built becomes the default, so runs do not depend on apt lists later.
  if [ -z "$package" ] && [ -L "$cache/default" ]; then package=$(readlink "$cache/default"); fi
  if [ -n "$package" ] && image_is_current "$cache/$package"; then
    image_dir=$cache/$package
    return
  fi

  # Concurrent first runs (parallel ctest) build once; the others wait here.
  local lock_fd
  exec {lock_fd}>"$cache/lock"
  flock "$lock_fd"
  if [ -z "$package" ]; then
    package=$(apt-cache depends linux-image-amd64 2>/dev/null |
              awk '$1 == "Depends:" && $2 ~ /^linux-image-/ { print $2; exit }')
    [ -n "$package" ] ||
      fail "cannot tell which kernel linux-image-amd64 is: run apt-get update, or set HMPC_VCAN_KERNEL_PKG"
  fi
  image_is_current "$cache/$package" || build_guest_image "$cache" "$package"
  [ -n "${HMPC_VCAN_KERNEL_PKG:-}" ] || ln -sfn "$package" "$cache/default"
  exec {lock_fd}>&-
  image_dir=$cache/$package
}

# An image built for another module list (an older launcher) is rebuilt.
image_is_current() {
  [ -f "$1/base.cpio" ] && [ "$(cat "$1/modules" 2>/dev/null)" = "${guest_modules[*]}" ]
}

build_guest_image() {
  local cache=$1 package=$2
  local tool
  for tool in apt-get dpkg-deb depmod modprobe busybox; do
    command -v "$tool" >/dev/null || fail "building the guest image needs $tool: run toolchains/setup-debian.sh"
  done
  say "building the guest image from $package in $cache (once)"
  local work
  work=$(mktemp -d "$cache/build.XXXXXX")
  temporary_dirs+=("$work")

  # apt-get drops to the _apt user to download, which cannot write to root's cache directory.
  local apt_options=()
  [ "$(id -u)" != 0 ] || apt_options=(-o APT::Sandbox::User=root)
  (cd "$work" && apt-get download -q=2 "${apt_options[@]}" "$package") >&2 ||
    fail "apt-get download $package failed: run apt-get update, or set HMPC_VCAN_KERNEL_PKG"
  local debs=("$work"/*.deb)
  mkdir "$work/tree"
  dpkg-deb --fsys-tarfile "${debs[0]}" |
    tar -x -C "$work/tree" --wildcards '*/boot/vmlinuz-*' '*/lib/modules/*' ||
    fail "cannot unpack ${debs[0]}"
  rm -f "${debs[@]}"

  local modules_dir version base
  modules_dir=$(dirname "$(find "$work/tree" -path '*/lib/modules/*/modules.order' | head -n 1)")
  version=${modules_dir##*/}
  base=${modules_dir%/lib/modules/*}
  # The package ships no modules.dep (its postinst makes it): make one to resolve dependencies.
  depmod -b "$base" "$version" || fail "depmod failed on $package"

  local root=$work/initramfs
  mkdir -p "$root"/{bin,dev,proc,sys,host,modules}
  cp /bin/busybox "$root/bin/busybox"
  ln -s busybox "$root/bin/sh"

  # Modules go in load order: the file name's number is its position.
  local module kind path loaded=" " count=0
  for module in "${guest_modules[@]}"; do
    local plan
    plan=$(modprobe -d "$base" -S "$version" --show-depends "$module" 2>&1) ||
      fail "$package has no module $module: $plan"
    while read -r kind path _; do
      [ "$kind" = insmod ] || continue  # "builtin NAME": nothing to load
      [[ $loaded != *" $path "* ]] || continue
      loaded+="$path "
      local name=${path##*/}
      name=${name%%.ko*}
      local target
      target=$root/modules/$(printf '%02d' "$count")-$name.ko
      # busybox insmod takes plain ELF only.
      case $path in
        *.ko) cp "$path" "$target" ;;
        *.ko.xz) xz -dc "$path" > "$target" ;;
        *.ko.zst) zstd -dcq "$path" > "$target" ;;
        *.ko.gz) gzip -dc "$path" > "$target" ;;
        *) fail "unknown module format: $path" ;;
      esac
      count=$((count + 1))
    done <<< "$plan"
  done

  local image=$work/image
  mkdir "$image"
  (cd "$root" && find . | busybox cpio -o -H newc 2>/dev/null) > "$image/base.cpio" ||
    fail "cannot pack the initramfs"
  local bzimage
  bzimage=$(find "$work/tree" -path '*/boot/vmlinuz-*' | head -n 1)
  cp "$bzimage" "$image/bzImage"
  unpack_elf_kernel "$image/bzImage" "$image/vmlinux" ||
    say "could not unpack vmlinux from $package; booting the compressed kernel (slower)"

  echo "${guest_modules[*]}" > "$image/modules"
  rm -rf "${cache:?}/$package"
  mv "$image" "$cache/$package"
}

# QEMU boots an ELF vmlinux through its PVH entry point, which skips the kernel's
# self-decompression: under TCG that costs seconds on every boot, so pay it once here.
# The boot header says where the compressed payload is; its last 4 bytes are the unpacked size.
unpack_elf_kernel() {
  local bzimage=$1 elf=$2
  local setup_sectors payload_offset payload_length expected_size
  setup_sectors=$(od -An -tu1 -j $((0x1f1)) -N1 "$bzimage")
  read -r payload_offset payload_length < <(od -An -tu4 -j $((0x248)) -N8 "$bzimage")
  local start=$(( (setup_sectors + 1) * 512 + payload_offset ))
  local decompress
  case $(od -An -tx1 -j "$start" -N4 "$bzimage" | tr -d ' ') in
    fd377a58) decompress=(xz -dc) ;;
    28b52ffd) decompress=(zstd -dcq) ;;
    1f8b*) decompress=(gzip -dc) ;;
    *) return 1 ;;
  esac
  command -v "${decompress[0]}" >/dev/null || return 1
  dd if="$bzimage" iflag=skip_bytes,count_bytes skip="$start" count=$((payload_length - 4)) \
    status=none | "${decompress[@]}" > "$elf" 2>/dev/null || { rm -f "$elf"; return 1; }
  expected_size=$(od -An -tu4 -j $((start + payload_length - 4)) -N4 "$bzimage")
  if [ "$(stat -c %s "$elf")" -ne "$expected_size" ] || [ "$(head -c 4 "$elf")" != $'\x7fELF' ]; then
    rm -f "$elf"
    return 1
  fi
}

# ----------------------------------------------------------------------------- the guest

run_in_guest() {
  [ "$(uname -m)" = x86_64 ] ||
    fail "no vcan0 here and the QEMU fallback supports x86_64 hosts only: load the vcan module (modprobe vcan) as root"
  command -v qemu-system-x86_64 >/dev/null ||
    fail "no vcan0 in this kernel and no qemu-system-x86_64 to boot one that has it: run toolchains/setup-debian.sh"
  # The initramfs has no libraries: a dynamically linked busybox would not start.
  if [ ! -x /bin/busybox ] || ldd /bin/busybox >/dev/null 2>&1; then
    fail "the guest needs a static /bin/busybox: install busybox-static"
  fi
  prepare_guest_image

  local xfer
  xfer=$(mktemp -d "${TMPDIR:-/tmp}/hmpc-vcan.XXXXXX")
  temporary_dirs+=("$xfer")
  # The path is written into the guest's init script unquoted.
  [[ $xfer =~ ^[A-Za-z0-9/._-]+$ ]] || fail "TMPDIR must be a plain path, got '$xfer'"

  write_command_script "$xfer/command.sh" "$@"

  # CMD's stderr has its own serial port. QEMU reopens our stderr by path when it is a pipe or
  # a terminal, so it streams. A regular file reopened would be written at a second offset,
  # over our own messages; a socket, or another user's pipe, cannot be reopened: those get a
  # file here instead, copied to our stderr when the guest stops.
  local stderr_path=$xfer/stderr
  if { [ -p /dev/stderr ] || [ -c /dev/stderr ]; } && (: >> "/proc/$$/fd/2") 2>/dev/null; then
    stderr_path=/proc/self/fd/2
  fi

  write_guest_init "$xfer" > "$xfer/init"
  chmod +x "$xfer/init"
  # Appended to the cached base archive: the kernel unpacks both into one root filesystem.
  (cd "$xfer" && echo init | busybox cpio -o -H newc 2>/dev/null) > "$xfer/init.cpio"
  cat "$image_dir/base.cpio" "$xfer/init.cpio" > "$xfer/initrd"

  local accel=${HMPC_VCAN_ACCEL:-auto}
  if [ "$accel" = auto ]; then
    # Some nested hypervisors offer /dev/kvm without hardware virtualisation (no vmx/svm in
    # cpuinfo); a stock kernel does not boot on them, so they get emulation too.
    accel=tcg
    if [ -r /dev/kvm ] && [ -w /dev/kvm ] && grep -qwE 'vmx|svm' /proc/cpuinfo; then accel=kvm; fi
  fi
  local cpu_options
  case $accel in
    kvm) cpu_options=(-accel kvm -cpu host) ;;
    tcg) cpu_options=(-accel tcg -cpu max) ;;
    *) fail "HMPC_VCAN_ACCEL must be auto, kvm or tcg, got '$accel'" ;;
  esac
  # One CPU by default: emulated CPUs compete with the host's own work, and wake-ups across
  # them are slow. Measured on a busy 2-core machine, one CPU boots in about half the time and
  # halves the CAN round trip.
  local cpus=${HMPC_VCAN_CPUS:-1}
  local kernel=$image_dir/vmlinux
  [ -f "$kernel" ] || kernel=$image_dir/bzImage
  local timeout_command=()
  (( timeout_s == 0 )) || timeout_command=(timeout --kill-after=5 "$timeout_s")
  verbose "no native vcan0; booting $kernel under $accel with $cpus CPUs"

  local started=$SECONDS
  # Kernel arguments: the kernel log goes to the third serial port (kept for diagnosis); a
  # panic ends QEMU at once; the rest skips probing, self-tests and hardening this guest has no
  # use for.
  local kernel_log=quiet
  [ "${HMPC_VCAN_VERBOSE:-0}" != 1 ] || kernel_log=
  "${timeout_command[@]}" qemu-system-x86_64 \
    -nodefaults -no-user-config -display none -no-reboot \
    -machine pc "${cpu_options[@]}" -smp "$cpus" -m "${HMPC_VCAN_MEM:-512}" \
    -kernel "$kernel" -initrd "$xfer/initrd" \
    -append "console=ttyS2 $kernel_log panic=-1 mitigations=off cryptomgr.notests i8042.noaux i8042.nokbd" \
    -chardev stdio,id=stdout -serial chardev:stdout \
    -chardev "file,id=stderr,path=$stderr_path,append=on" -serial chardev:stderr \
    -serial "file:$xfer/console.log" \
    -virtfs local,path=/,mount_tag=host,security_model=none,multidevs=remap \
    < /dev/null &
  local qemu_pid=$!
  # Signals reach us, not QEMU in the background: pass them on so no guest outlives us.
  trap 'stop_guest '"$qemu_pid"' 130' INT
  trap 'stop_guest '"$qemu_pid"' 143' TERM
  trap 'stop_guest '"$qemu_pid"' 129' HUP
  local qemu_status=0
  wait "$qemu_pid" || qemu_status=$?
  trap - INT TERM HUP
  [ ! -f "$xfer/stderr" ] || cat "$xfer/stderr" >&2
  verbose "guest ran for $((SECONDS - started)) s"
  [ "${HMPC_VCAN_VERBOSE:-0}" != 1 ] || cat "$xfer/console.log" >&2

  local status
  status=$(cat "$xfer/status" 2>/dev/null) || true
  [[ $status =~ ^[0-9]+$ ]] && exit "$status"
  if (( timeout_s > 0 )) && [ "$qemu_status" = "$timed_out" ]; then
    say "$1 timed out after ${timeout_s} s (HMPC_VCAN_TIMEOUT), guest included"
    exit "$timed_out"
  fi
  # QEMU creates the log file as it starts.
  if [ -s "$xfer/console.log" ]; then
    say "the guest stopped before $1 reported a status (QEMU status $qemu_status); its log ends:"
    tail -n 20 "$xfer/console.log" >&2
  elif [ -f "$xfer/console.log" ]; then
    local hint="too little memory (HMPC_VCAN_MEM)?"
    [ "$accel" != kvm ] || hint="a KVM that cannot run this kernel? HMPC_VCAN_ACCEL=tcg avoids it"
    say "the guest stopped before its kernel logged anything (QEMU status $qemu_status): $hint"
  else
    say "QEMU failed to start the guest (status $qemu_status; its message is above)"
  fi
  exit "$launcher_failed"
}

stop_guest() {
  kill -TERM "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
  exit "$2"
}

# The script the guest runs, chrooted into our filesystem, under our bash: our environment,
# our directory, our user id, then CMD.
write_command_script() {
  local script=$1
  shift
  {
    local name
    for name in $(compgen -e); do
      case $name in _ | SHLVL | PWD | OLDPWD | SHELLOPTS | BASHOPTS | BASH_*) continue ;; esac
      printf 'export %s=%q\n' "$name" "${!name}"
    done
    printf 'cd -- %q || exit %d\n' "$PWD" "$launcher_failed"
    printf 'exec'
    # The guest's init is root; CMD runs as whoever ran us, so files it creates are ours.
    [ "$(id -u)" = 0 ] || printf ' setpriv --reuid=%d --regid=%d --clear-groups --' "$(id -u)" "$(id -g)"
    printf ' %q' "$@"
    printf '\n'
  } > "$script"
}

# PID 1 of the guest. Its messages go to the kernel log port; without a status file the host
# reports a guest failure and shows that log.
write_guest_init() {
  cat <<EOF
#!/bin/sh
xfer=$1
EOF
  cat <<'EOF'
/bin/busybox --install -s /bin
export PATH=/bin
mount -t devtmpfs devtmpfs /dev
exec < /dev/null > /dev/console 2>&1
give_up() { echo "run-with-vcan guest: $*"; reboot -f; }
mount -t proc proc /proc
mount -t sysfs sysfs /sys
for module in /modules/*.ko; do insmod "$module" || give_up "cannot load $module"; done
# cache=mmap: reads and writes stay coherent with the host, yet programs can map files (a
# looser cache measured no faster for test binaries).
mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144,cache=mmap host /host ||
  give_up "cannot mount the host filesystem"
# The host's /dev, /proc, /sys and /run describe the host: give the command the guest's own.
mount -t proc proc /host/proc && mount -t sysfs sysfs /host/sys &&
  mount -t devtmpfs devtmpfs /host/dev && mkdir -p /host/dev/pts /host/dev/shm &&
  mount -t devpts devpts /host/dev/pts && mount -t tmpfs tmpfs /host/dev/shm &&
  mount -t tmpfs tmpfs /host/run || give_up "cannot mount /proc, /sys, /dev or /run"
ip link set lo up
for bus in vcan0 vcan1; do
  ip link add dev $bus type vcan && ip link set $bus up || give_up "cannot bring $bus up"
done
# Raw mode: bytes pass unchanged (no \n -> \r\n).
stty -F /dev/ttyS0 raw -echo && stty -F /dev/ttyS1 raw -echo
# Through pipes, not straight to the serial ports: on a terminal, programs would colour and
# buffer their output as if a person were watching.
mkfifo /stdout /stderr
cat /stdout > /dev/ttyS0 &
cat /stderr > /dev/ttyS1 &
chroot /host /bin/bash "$xfer/command.sh" < /dev/null > /stdout 2> /stderr
status=$?
wait
echo $status > "/host$xfer/status"
sync
reboot -f
EOF
}

# --------------------------------------------------------------------------------- choose

case $mode in
  auto)
    if buses_are_up || bring_up_native_buses; then run_natively "$@"; else run_in_guest "$@"; fi ;;
  native)
    buses_are_up || bring_up_native_buses ||
      fail "HMPC_VCAN_MODE=native but vcan0 and vcan1 are not up and cannot be created here (needs root and a kernel with vcan)"
    run_natively "$@" ;;
  vm) run_in_guest "$@" ;;
  *) fail "HMPC_VCAN_MODE must be auto, native or vm, got '$mode'" ;;
esac
