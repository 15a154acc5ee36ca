#!/usr/bin/env bash
# launcher_test.sh LAUNCHER CHECK: checks one promise of hil/vcan/run-with-vcan.sh.
#   status    CMD's exit status, arguments, environment, directory, stdout and stderr come
#             through, and vcan0 is up for CMD (one guest boot where vcan is not native)
#   settings  bad usage or settings are launcher failures (125) with a message, before any boot
#   timeout   HMPC_VCAN_TIMEOUT stops a command that runs too long, with status 124
set -euo pipefail

launcher=$1
check=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }
expect_status() {  # EXPECTED ACTUAL WHAT
  [ "$2" = "$1" ] || fail "$3: expected status $1, got $2; stderr was: $(cat "$work/err")"
}

case $check in
  status)
    cd "$work"
    # stdout to a file and stderr through a pipe: both ways the launcher forwards output.
    status=0
    HMPC_LAUNCHER_PROBE="x y" "$launcher" sh -c '
      [ "$1" = "two words" ] && [ "$2" = "it'\''s \$HOME" ] || { echo "arguments changed: $*"; exit 10; }
      [ "$HMPC_LAUNCHER_PROBE" = "x y" ] || { echo "environment lost"; exit 11; }
      [ "$(pwd)" = "$3" ] || { echo "directory changed to $(pwd)"; exit 12; }
      [ "$(cat /sys/class/net/vcan0/type)" = 280 ] || { echo "no vcan0"; exit 13; }
      echo to-stdout
      echo to-stderr >&2
      exit 3' probe "two words" "it's \$HOME" "$work" 2>&1 > "$work/out" | cat > "$work/err" ||
      status=$?
    expect_status 3 "$status" "probe command"
    [ "$(cat "$work/out")" = to-stdout ] || fail "stdout was: $(cat "$work/out")"
    grep -qx to-stderr "$work/err" || fail "stderr was: $(cat "$work/err")"
    ;;
  settings)
    status=0
    "$launcher" 2> "$work/err" || status=$?
    expect_status 125 "$status" "no command"
    grep -q usage "$work/err" || fail "no usage message: $(cat "$work/err")"
    for setting in HMPC_VCAN_MODE=sideways HMPC_VCAN_TIMEOUT=soon; do
      status=0
      env "$setting" "$launcher" true 2> "$work/err" || status=$?
      expect_status 125 "$status" "$setting"
      grep -q "${setting%%=*}" "$work/err" || fail "$setting: message does not name it: $(cat "$work/err")"
    done
    ;;
  timeout)
    started=$SECONDS
    status=0
    HMPC_VCAN_TIMEOUT=1 "$launcher" sleep 120 2> "$work/err" || status=$?
    expect_status 124 "$status" "sleep 120 with HMPC_VCAN_TIMEOUT=1"
    grep -q "timed out" "$work/err" || fail "no timeout message: $(cat "$work/err")"
    (( SECONDS - started < 60 )) || fail "took $((SECONDS - started)) s to time out"
    ;;
  *) fail "unknown check '$check'" ;;
esac
echo "launcher $check: ok"
