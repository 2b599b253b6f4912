#!/usr/bin/env bash
# End-to-end: a third-party Grbl client (pyserial, tests/e2e/grbl_client.py) drives the
# simulator's virtual serial port (`inkstep-sim serve`). Exits non-zero on any failure.
# Usage: tests/e2e/run.sh [--speed X]   (run from anywhere; builds the simulator once)
set -euo pipefail
cd "$(dirname "$0")/../.."
SPEED=100
if [ "${1:-}" = "--speed" ]; then SPEED=$2; fi

# pyserial's `serial.Serial`: a bare `import serial` run here would find the repository's
# own serial/ folder (the inkstep-serial crate) as a namespace package and pass.
if ! python3 -c 'import serial; serial.Serial' 2>/dev/null; then
  python3 -m pip install --quiet pyserial || python3 -m pip install --quiet --break-system-packages pyserial
fi

cargo build -q -p inkstep-sim --target host-tuple --profile host
SIM=target/$(rustc -vV | awk '/^host:/ { print $2 }')/host/inkstep-sim

. tests/e2e/serve.sh
start_board "$SIM" serve --speed "$SPEED"

start=$SECONDS
python3 tests/e2e/checks.py "$SERVE_PORT" "$PWD"
board_alive
echo "end-to-end checks: $((SECONDS - start)) s at --speed $SPEED"
