#!/usr/bin/env python3
"""inkstep end-to-end checks with a real Python sender: grbl-streamer 2.0.2 (PyPI).

Usage: grbl_streamer_check.py PORT REPO_ROOT

Streams bench/star.nc and tests/e2e/senders/segments.nc in both of grbl-streamer's
flow-control modes: incremental (send-response: one line, wait for its `ok`) and its
default (character counting against Grbl's 128-byte receive buffer). Each run must have
every line answered `ok`, no `error:` or `ALARM` line, and end exactly where the program
ends. Each check runs on its own; the last line is 'N passed, M failed'.
"""

import os
import re
import sys
import threading
import time

from grbl_streamer import GrblStreamer


class Fail(Exception):
    pass


def check(cond, msg):
    if not cond:
        raise Fail(msg)


def milli(v):
    """A coordinate as integer thousandths of a mm (the controller prints three decimals)."""
    return round(float(v) * 1000)


class Sender:
    """grbl-streamer with its callbacks recorded, as an application would wire them."""

    def __init__(self, port):
        self.lock = threading.Condition()
        self.events = []  # (event, data) for everything but the chatty ones
        self.processed = 0  # lines answered `ok`
        self.problems = []  # error: and ALARM lines
        self.completed = False
        self.booted = False
        self.g = GrblStreamer(self.on_event)
        self.g.cnect(port, 115200)
        self.until(lambda: self.booted, 10, "the welcome line")
        self.g.poll_start()
        # After the welcome line grbl-streamer asks for `$$`, `$#` and `$G` outside its
        # stream (their `ok`s would count as a job's): let them be answered first.
        time.sleep(1.0)

    def on_event(self, event, *data):
        with self.lock:
            if event == "on_boot":
                self.booted = True
            elif event == "on_processed_command":
                self.processed += 1
            elif event in ("on_error", "on_alarm"):
                self.problems.append((event,) + data)
            elif event == "on_job_completed":
                self.completed = True
            if event not in ("on_log", "on_processed_command", "on_rx_buffer_percent", "on_progress_percent", "on_line_sent", "on_line_number_change", "on_write"):
                self.events.append((event, data))
            self.lock.notify_all()

    def until(self, cond, timeout, what):
        deadline = time.monotonic() + timeout
        with self.lock:
            while not cond():
                left = deadline - time.monotonic()
                if left <= 0:
                    raise Fail("timed out after %g s waiting for %s; last events %s" % (timeout, what, self.events[-5:]))
                self.lock.wait(min(left, 0.1))

    def run(self, path, incremental, timeout):
        """Streams a file and waits for the machine to stand still at its end."""
        with self.lock:
            self.processed = 0
            self.problems = []
            self.completed = False
        self.g.job_new()
        self.g.incremental_streaming = incremental
        self.g.load_file(path)
        lines = self.g.buffer_size
        t0 = time.monotonic()
        self.g.job_run()
        self.until(lambda: self.completed or self.problems, timeout, "the job to complete")
        check(not self.problems, "%s: %s" % (os.path.basename(path), self.problems))
        check(self.processed == lines, "%s: %d of %d lines answered" % (path, self.processed, lines))
        # Then the machine at rest: grbl-streamer polls `?` every 0.2 s and keeps the last
        # report; two polls after the last `ok`, then Idle for two more.
        poll = self.g.poll_interval
        time.sleep(2.5 * poll)
        self.until(lambda: self.g.cmode == "Idle", timeout, "Idle")
        time.sleep(2.5 * poll)
        check(self.g.cmode == "Idle", "%s: %s again after Idle" % (path, self.g.cmode))
        return self.g.cmpos, lines, time.monotonic() - t0

    def close(self):
        self.g.disconnect()


def expected_end(path):
    """A program's end from its first line `(... ends at X95.000 Y5.000)`, or 0,0."""
    with open(path) as f:
        m = re.search(r"ends at X(-?[\d.]+) Y(-?[\d.]+)", f.readline())
    return (milli(m.group(1)), milli(m.group(2))) if m else (0, 0)


def main():
    port, root = sys.argv[1], sys.argv[2]
    here = os.path.dirname(os.path.abspath(__file__))
    programs = [os.path.join(root, "bench/star.nc"), os.path.join(here, "segments.nc")]
    s = Sender(port)
    print("grbl-streamer connected to %s" % port)
    passed = failed = 0
    try:
        for incremental, mode in ((True, "send-response"), (False, "character counting")):
            for path in programs:
                name = "%s, %s" % (os.path.basename(path), mode)
                try:
                    want = expected_end(path)
                    pos, lines, dt = s.run(path, incremental, 300)
                    end = (milli(pos[0]), milli(pos[1]))
                    check(end == want, "%s: ended at %.3f,%.3f, not %.3f,%.3f" % (name, end[0] / 1000, end[1] / 1000, want[0] / 1000, want[1] / 1000))
                    print("  %s: %d lines answered ok, no error, ended %.3f,%.3f (%.1f s)" % (name, lines, end[0] / 1000, end[1] / 1000, dt))
                    passed += 1
                except Fail as e:
                    print("  FAIL: %s" % e)
                    failed += 1
    finally:
        s.close()
    print("grbl-streamer: %d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
