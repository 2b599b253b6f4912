#!/usr/bin/env bash
# The web view in a real browser: headless Chromium (Debian's package) driven by
# puppeteer-core (tests/web/test.mjs) against `cargo host serve`, which is linked
# to a machine behind a pty. Exits non-zero on any failure.
#
# Usage: tests/web/run.sh [--speed N] [--shots DIR] [SERVE COMMAND...]
#   SERVE COMMAND opens the machine's pty; the script adds `--link PATH --speed N`.
#   Default: the simulator, `inkstep-sim serve` (as `cargo sim serve`); the
#   emulator runs the same tests with e.g. `tests/web/run.sh cargo emu serve`.
# Installs what it needs when missing: chromium (apt), puppeteer-core (npm).
set -euo pipefail
cd "$(dirname "$0")/../.."
SPEED=4
SHOTS=
while [ $# -gt 0 ]; do
  case "$1" in
    --speed) SPEED=$2; shift 2 ;;
    --shots) SHOTS=$(realpath "$2"); shift 2 ;;
    *) break ;;
  esac
done

command -v chromium >/dev/null || {
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
}
[ -d tests/web/node_modules/puppeteer-core ] ||
  (cd tests/web && npm install --no-audit --no-fund --silent)

cargo build -q -p inkstep-host -p inkstep-sim --target host-tuple --profile host
BIN=target/$(rustc -vV | awk '/^host:/ { print $2 }')/host
if [ $# -eq 0 ]; then set -- "$BIN/inkstep-sim" serve; fi

dir=$(mktemp -d)
pids=()
cleanup() {
  local rc=$?
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; wait "$p" 2>/dev/null || true; done
  # A failed run shows what the machine and the web server logged (the only trace
  # of a race between them once the directory is gone).
  if [ "$rc" != 0 ]; then
    for f in machine serve; do echo "--- $f.log (last 60 lines)"; tail -n 60 "$dir/$f.log" 2>/dev/null || true; done
  fi
  rm -rf "$dir"
}
trap cleanup EXIT

"$@" --link "$dir/tty" --speed "$SPEED" >"$dir/machine.log" 2>&1 &
pids+=($!)
# For the test that takes the machine away and brings it back.
export INKSTEP_MACHINE_PID=$!
printf '%s\n' "$@" --link "$dir/tty" --speed "$SPEED" >"$dir/machine.cmd"
export INKSTEP_MACHINE_CMD="$dir/machine.cmd"
for _ in $(seq 200); do [ -e "$dir/tty" ] && break; sleep 0.1; done
[ -e "$dir/tty" ] || { echo "FAIL: no pty from: $*"; cat "$dir/machine.log"; exit 1; }

# An ephemeral port on loopback (open mode: the page may control).
"$BIN/inkstep-host" serve --port "$dir/tty" --listen 127.0.0.1:0 >"$dir/serve.log" 2>&1 &
pids+=($!)
url=
for _ in $(seq 100); do
  url=$(grep -o 'http://127.0.0.1:[0-9]*/' "$dir/serve.log" || true)
  [ -n "$url" ] && break
  sleep 0.1
done
[ -n "$url" ] || { echo "FAIL: serve did not start"; cat "$dir/serve.log"; exit 1; }
echo "machine: $* (--speed $SPEED); web view: $url"

start=$SECONDS
node tests/web/test.mjs "$url" "$PWD" $SHOTS
echo "browser tests: $((SECONDS - start)) s"
