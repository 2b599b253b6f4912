#!/usr/bin/env bash
# End-to-end: a third-party Grbl client (pyserial, tests/e2e/grbl_client.py) drives the
# simulator's virtual serial port (`inkstep-sim serve`). Exits non-zero on any failure.
# Usage: tests/e2e/run.sh [--speed X]   (run from anywhere; builds the simulator once)
set -euo pipefail
cd "$(dirname "$0")/../.."
SPEED=100
if [ "${1:-}" = "--speed" ]; then SPEED=$2; fi

if ! python3 -c 'import serial' 2>/dev/null; then
  python3 -m pip install --quiet pyserial || python3 -m pip install --quiet --break-system-packages pyserial
fi

cargo build -q -p inkstep-sim --target host-tuple --profile host
SIM=target/$(rustc -vV | awk '/^host:/ { print $2 }')/host/inkstep-sim

dir=$(mktemp -d)
server=
cleanup() {
  if [ -n "$server" ]; then kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; fi
  rm -rf "$dir"
}
trap cleanup EXIT

"$SIM" serve --link "$dir/ttyINKSTEP" --speed "$SPEED" >"$dir/serve.log" 2>&1 &
server=$!
for _ in $(seq 100); do
  [ -e "$dir/ttyINKSTEP" ] && break
  kill -0 "$server" 2>/dev/null || { echo "FAIL: the simulator exited:"; cat "$dir/serve.log"; exit 1; }
  sleep 0.1
done
[ -e "$dir/ttyINKSTEP" ] || { echo "FAIL: no pty link after 10 s"; cat "$dir/serve.log"; exit 1; }
cat "$dir/serve.log"

start=$SECONDS
python3 tests/e2e/checks.py "$dir/ttyINKSTEP" "$PWD"
kill -0 "$server" 2>/dev/null || { echo "FAIL: the simulator died during the checks"; cat "$dir/serve.log"; exit 1; }
echo "end-to-end checks: $((SECONDS - start)) s at --speed $SPEED"
