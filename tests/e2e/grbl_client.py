#!/usr/bin/env python3
"""A small Grbl 1.1 client over a serial port (pyserial), for inkstep's end-to-end tests.

Written for this project from Grbl's documented interface (the "Interface" and
"Streaming" notes of the Grbl 1.1 wiki), not from any Grbl source:

- every line sent is answered by exactly one `ok` or `error:N`, in order;
- send-response: send a line, wait for its answer, send the next;
- character counting: the controller has a receive buffer of RX bytes; the sender keeps
  the sum of the lengths of the lines sent but not yet answered (newline included) at
  most RX, and each `ok` / `error:N` frees the oldest line of that sum;
- real-time bytes (`?`, `!`, `~`, 0x18) are not lines: they take no buffer space and get
  no `ok`; `?` is answered by one `<State|MPos:x,y,z|...>` report.

Everything else the controller prints (`ALARM:N`, `[MSG:...]`, the welcome line) is
collected in `GrblClient.events`.
"""

import collections
import queue
import re
import threading
import time

import serial  # pyserial

WELCOME = re.compile(r"^Grbl 1\.1\w* \['\$' for help\]$")
STATUS = re.compile(r"^<([A-Za-z]+)(?::(\d+))?\|(.*)>$")


class GrblError(Exception):
    pass


class Status:
    """A parsed `<State|MPos:x,y,z|...>` report."""

    def __init__(self, raw):
        m = STATUS.match(raw)
        if not m:
            raise GrblError("not a status report: %r" % raw)
        self.raw = raw
        self.state = m.group(1)
        self.substate = m.group(2)
        self.fields = {}
        for part in m.group(3).split("|"):
            key, _, value = part.partition(":")
            self.fields[key] = value
        # Kept as the controller's text too, so positions can be compared exactly.
        self.mpos_text = self.fields.get("MPos")
        self.mpos = tuple(float(v) for v in self.mpos_text.split(",")) if self.mpos_text else None

    def __repr__(self):
        return self.raw


class GrblClient:
    def __init__(self, port, rx_size=128, timeout=10.0, baudrate=115200):
        self.rx_size = rx_size
        self.timeout = timeout
        self.ser = serial.Serial(port, baudrate=baudrate, timeout=0.05)
        self.answers = queue.Queue()  # "ok" / "error:N", in arrival order
        self.reports = queue.Queue()  # status report lines
        self.welcomes = queue.Queue()
        self.events = []  # (time, line) for ALARM, [MSG:...], anything else
        self.alarms = []
        self._stop = False
        self._reader = threading.Thread(target=self._read_loop, daemon=True)
        self._reader.start()

    # ---- input side --------------------------------------------------------------
    def _read_loop(self):
        pending = b""
        while not self._stop:
            try:
                # read(1) returns as soon as a byte is there (or after the timeout);
                # then take whatever else has arrived.
                chunk = self.ser.read(1)
                if chunk and self.ser.in_waiting:
                    chunk += self.ser.read(self.ser.in_waiting)
            except (serial.SerialException, OSError, TypeError):
                if self._stop:
                    return
                raise
            if not chunk:
                continue
            pending += chunk
            while True:
                i = pending.find(b"\n")
                if i < 0:
                    break
                line = pending[:i].rstrip(b"\r").decode("ascii", "replace").strip()
                pending = pending[i + 1 :]
                if line:
                    self._dispatch(line)

    def _dispatch(self, line):
        if line == "ok" or line.startswith("error:"):
            self.answers.put(line)
        elif line.startswith("<") and line.endswith(">"):
            self.reports.put(line)
        elif WELCOME.match(line):
            self.welcomes.put(line)
        else:
            if line.startswith("ALARM:"):
                self.alarms.append(line)
            self.events.append((time.monotonic(), line))

    def _next_answer(self, what):
        try:
            return self.answers.get(timeout=self.timeout)
        except queue.Empty:
            raise GrblError("no answer within %.1f s for %s" % (self.timeout, what)) from None

    def close(self):
        self._stop = True
        self._reader.join(timeout=1.0)
        self.ser.close()

    # ---- real-time bytes ---------------------------------------------------------
    def realtime(self, byte):
        self.ser.write(bytes([byte]) if isinstance(byte, int) else byte)
        self.ser.flush()

    def reset(self):
        """Soft reset (0x18); waits for the welcome line and drops stale answers."""
        self.realtime(0x18)
        try:
            w = self.welcomes.get(timeout=self.timeout)
        except queue.Empty:
            raise GrblError("no welcome line after a soft reset") from None
        time.sleep(0.05)
        while not self.answers.empty():
            self.answers.get_nowait()
        return w

    def status(self):
        """Sends `?` and returns the next report with the time it took."""
        while not self.reports.empty():
            self.reports.get_nowait()
        t0 = time.monotonic()
        self.realtime(b"?")
        try:
            raw = self.reports.get(timeout=self.timeout)
        except queue.Empty:
            raise GrblError("no status report") from None
        s = Status(raw)
        s.latency = time.monotonic() - t0
        return s

    def wait_idle(self, timeout=60.0, poll=0.02):
        """Polls `?` until two reports in a row say Idle; returns the last one."""
        end = time.monotonic() + timeout
        idle_seen = 0
        while time.monotonic() < end:
            s = self.status()
            idle_seen = idle_seen + 1 if s.state == "Idle" else 0
            if idle_seen >= 2:
                return s
            time.sleep(poll)
        raise GrblError("not Idle after %.0f s (last: %s)" % (timeout, s.raw))

    # ---- lines -------------------------------------------------------------------
    @staticmethod
    def clean(line):
        """What a sender sends: the line without its end, and nothing for blank lines."""
        return line.strip()

    def command(self, line):
        """Send-response for one line; returns `ok` or `error:N`."""
        self.ser.write((line + "\n").encode("ascii"))
        self.ser.flush()
        return self._next_answer(repr(line))

    def stream(self, lines, mode="count", on_answer=None):
        """Streams lines; returns the list of answers, one per line sent, in order.

        mode "response": send-response. mode "count": character counting against
        `rx_size` bytes. `on_answer(index, line, answer)` is called for each answer.
        """
        lines = [self.clean(l) for l in lines]
        lines = [l for l in lines if l]
        answers = []
        in_flight = collections.deque()  # lengths of sent, unanswered lines
        used = 0
        out = bytearray()

        def take_one():
            nonlocal used
            a = self._next_answer("line %d" % (len(answers) + 1))
            i = len(answers)
            answers.append(a)
            used -= in_flight.popleft()
            if on_answer:
                on_answer(i, lines[i], a)

        for line in lines:
            data = (line + "\n").encode("ascii")
            if len(data) > self.rx_size:
                raise GrblError("line longer than the receive buffer: %r" % line)
            if mode == "response":
                while in_flight:
                    take_one()
            elif mode == "count":
                while used + len(data) > self.rx_size:
                    if out:
                        self.ser.write(out)
                        out.clear()
                    take_one()
            else:
                raise ValueError(mode)
            in_flight.append(len(data))
            used += len(data)
            out += data
            if mode == "response":
                self.ser.write(out)
                out.clear()
        if out:
            self.ser.write(out)
        while in_flight:
            take_one()
        # Anything left over would be an answer to a line never sent: a duplicate.
        time.sleep(0.05)
        extra = []
        while not self.answers.empty():
            extra.append(self.answers.get_nowait())
        if extra:
            raise GrblError("%d answers beyond the %d lines sent: %r" % (len(extra), len(lines), extra[:5]))
        return answers


def main():
    import argparse
    import sys

    ap = argparse.ArgumentParser(description="Stream a G-code file to a Grbl 1.1 controller.")
    ap.add_argument("port")
    ap.add_argument("file")
    ap.add_argument("--mode", choices=["count", "response"], default="count")
    ap.add_argument("--rx", type=int, default=128, help="receive buffer size for character counting")
    args = ap.parse_args()
    c = GrblClient(args.port, rx_size=args.rx)
    try:
        print(c.reset())
        with open(args.file) as f:
            lines = f.readlines()
        answers = c.stream(lines, mode=args.mode)
        bad = [(i + 1, a) for i, a in enumerate(answers) if a != "ok"]
        for n, a in bad:
            print("line %d: %s" % (n, a))
        print(c.wait_idle())
        print("%d lines, %d errors, alarms: %s" % (len(answers), len(bad), c.alarms))
        return 1 if bad or c.alarms else 0
    finally:
        c.close()


if __name__ == "__main__":
    raise SystemExit(main())
