# Sourced by the end-to-end scripts: starts and stops a board behind a serial port.
# The board is any command that takes `--link PATH` and then serves a Grbl port there:
# the simulator (`inkstep-sim serve`) today, the emulator (`cargo emu serve`) the same way.

SERVE_DIR=$(mktemp -d)
SERVE_PID=
SERVE_PORT=$SERVE_DIR/ttyINKSTEP

# start_board CMD...: runs `CMD... --link $SERVE_PORT` in the background and waits for
# the port to appear (at most 120 s: a command that builds first takes a while).
start_board() {
  rm -f "$SERVE_PORT"
  "$@" --link "$SERVE_PORT" >"$SERVE_DIR/serve.log" 2>&1 &
  SERVE_PID=$!
  for _ in $(seq 1200); do
    [ -e "$SERVE_PORT" ] && { cat "$SERVE_DIR/serve.log"; return 0; }
    kill -0 "$SERVE_PID" 2>/dev/null || { echo "FAIL: the board exited: $*"; cat "$SERVE_DIR/serve.log"; return 1; }
    sleep 0.1
  done
  echo "FAIL: no port at $SERVE_PORT after 120 s: $*"
  cat "$SERVE_DIR/serve.log"
  return 1
}

# board_alive: fails (and shows its log) if the board died.
board_alive() {
  kill -0 "$SERVE_PID" 2>/dev/null || { echo "FAIL: the board died"; cat "$SERVE_DIR/serve.log"; return 1; }
}

stop_board() {
  if [ -n "$SERVE_PID" ]; then
    kill "$SERVE_PID" 2>/dev/null || true
    wait "$SERVE_PID" 2>/dev/null || true
    SERVE_PID=
  fi
}

trap 'stop_board; rm -rf "$SERVE_DIR"' EXIT
