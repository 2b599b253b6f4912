#!/usr/bin/env bash
# End-to-end with real Grbl senders: cncjs 1.11.5 (npm, through its socket.io API) and
# grbl-streamer 2.0.2 (PyPI, send-response and character counting) drive a board's
# serial port. Installs both itself. Exits non-zero if any check failed.
#
# Usage: tests/e2e/senders.sh [--fast ARGS] [BOARD_CMD...]
#   BOARD_CMD  a command that serves the board's port at `--link PATH` (appended);
#              default: the simulator, `inkstep-sim serve` (built here).
#              For the emulator: tests/e2e/senders.sh --fast "" \
#                target/x86_64-unknown-linux-gnu/host/inkstep-emu serve
#              (the binary itself: stopping `cargo run` would leave its child running)
#   --fast     extra arguments for the runs whose outcome does not depend on real time
#              (streams); default `--speed 20` for the simulator, none otherwise.
# The %wait and pause/resume/stop checks run on BOARD_CMD as given (the simulator's
# default speed is real time): cncjs polls `?` every 250 ms of real time and acts on it.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
FAST=
fast_set=
if [ "${1:-}" = "--fast" ]; then FAST=$2; fast_set=1; shift 2; fi
if [ $# -eq 0 ]; then
  cargo build -q -p inkstep-sim --target host-tuple --profile host
  set -- "target/$(rustc -vV | awk '/^host:/ { print $2 }')/host/inkstep-sim" serve
  [ -n "$fast_set" ] || FAST="--speed 20"
fi

step() { printf -- '--- %s (%ss)\n' "$1" "$SECONDS"; }

step "install cncjs (npm) and grbl-streamer (PyPI)"
if [ ! -d tests/e2e/senders/node_modules/cncjs ]; then
  (cd tests/e2e/senders && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
fi
if ! python3 -c 'import grbl_streamer' 2>/dev/null; then
  python3 -m pip install --quiet grbl-streamer==2.0.2 ||
    python3 -m pip install --quiet --break-system-packages grbl-streamer==2.0.2
fi

. tests/e2e/serve.sh
failed=0

step "streams: $* $FAST"
# shellcheck disable=SC2086 # FAST is a list of arguments
start_board "$@" $FAST
node tests/e2e/senders/cncjs.js "$SERVE_PORT" "$ROOT" streams || failed=1
python3 tests/e2e/senders/grbl_streamer_check.py "$SERVE_PORT" "$ROOT" || failed=1
board_alive || failed=1
stop_board

step "timing: $*"
start_board "$@"
node tests/e2e/senders/cncjs.js "$SERVE_PORT" "$ROOT" timing || failed=1
board_alive || failed=1
stop_board

step "done"
[ "$failed" = 0 ] || { echo "FAIL: some sender checks failed (above)"; exit 1; }
echo "all sender checks passed"
