#!/usr/bin/env python3
"""inkstep end-to-end checks: a pyserial Grbl client against `cargo sim serve`'s pty.

Usage: checks.py PORT REPO_ROOT. Exits 1 on the first failed check.
"""

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from grbl_client import GrblClient, GrblError  # noqa: E402

STEPS_PER_MM = 80  # $100/$101 defaults; every target below is a whole number of steps


class Fail(Exception):
    pass


def check(cond, msg):
    if not cond:
        raise Fail(msg)


def mpos_milli(s):
    """MPos as integer thousandths of a mm (the controller prints three decimals)."""
    return tuple(int(v.replace(".", "")) for v in s.mpos_text.split(","))


def read_lines(path):
    with open(path) as f:
        return [l.strip() for l in f if l.strip()]


def check_alarms(c):
    check(not c.alarms, "alarm raised: %s" % c.alarms)


def check_files(c, root):
    for name in ("bench/star.nc", "bench/circle.nc"):
        lines = read_lines(os.path.join(root, name))
        for mode in ("response", "count"):
            t0 = time.monotonic()
            answers = c.stream(lines, mode=mode)
            end = c.wait_idle()
            dt = time.monotonic() - t0
            check(len(answers) == len(lines), "%s: %d answers for %d lines" % (name, len(answers), len(lines)))
            bad = [(i + 1, a) for i, a in enumerate(answers) if a != "ok"]
            check(not bad, "%s (%s): %s" % (name, mode, bad))
            check_alarms(c)
            check(mpos_milli(end)[:2] == (0, 0), "%s (%s): ended at %s, not 0,0" % (name, mode, end.mpos_text))
            print("  %-16s %-8s %3d lines, all ok, ended %s, %.2f s" % (name, mode, len(lines), end.mpos_text, dt))


# Malformed lines and the error Grbl 1.1 gives each (its error-code table).
MALFORMED = [
    ("G5 X1", 20),  # unsupported G code
    ("M100", 20),  # unsupported M code
    ("G1 X1 Q5", 20),  # a word letter Grbl does not use
    ("G1 X", 2),  # axis letter without a value: bad number format
    ("G1 Y--1", 2),  # bad number format
    ("hello", 2),  # H then no number
    ("G1 X1 @", 1),  # not a letter where a word must start
    ("G1 X1 X2", 25),  # word repeated
    ("G0 G1 X1", 21),  # two motion modes: modal group violation
    ("G1 F-5", 4),  # negative value
    ("G2 X10 Y0 I1 J0", 33),  # arc end far off the circle: invalid target
    ("G2 X0 Y0 R5", 33),  # R-form arc with end = start: invalid target
    ("G2 X5 Y5", 35),  # arc without I/J in the plane
    ("G4", 28),  # dwell without P: value word missing
    ("G10 L2 P9 X0", 29),  # no such coordinate system
]


def check_malformed(c, root):
    good = read_lines(os.path.join(root, "bench/star.nc"))
    # Interleave: after every third good line (from the first motion on) a bad one.
    first_motion = next(i for i, l in enumerate(good) if l.startswith("G1"))
    lines, expect = [], []
    bad = list(MALFORMED)
    for i, l in enumerate(good):
        lines.append(l)
        expect.append("ok")
        if i >= first_motion and bad and (i - first_motion) % 3 == 0:
            b, code = bad.pop(0)
            lines.append(b)
            expect.append("error:%d" % code)
    for b, code in bad:  # any left over go before a final move
        lines.append(b)
        expect.append("error:%d" % code)
    lines.append("G90 G1 X12.5 Y-7.25 F3000")
    expect.append("ok")
    for mode in ("count", "response"):
        answers = c.stream(lines, mode=mode)
        end = c.wait_idle()
        check(len(answers) == len(lines), "malformed: %d answers for %d lines" % (len(answers), len(lines)))
        wrong = [(i + 1, lines[i], a, e) for i, (a, e) in enumerate(zip(answers, expect)) if a != e]
        check(not wrong, "malformed (%s): line, text, got, expected: %s" % (mode, wrong))
        check_alarms(c)
        check(mpos_milli(end)[:2] == (12500, -7250), "malformed (%s): ended at %s" % (mode, end.mpos_text))
        print(
            "  %-8s %d lines: the %d malformed ones got exactly their errors (%s), the rest ok; ended %s"
            % (mode, len(lines), len(MALFORMED), ",".join(sorted({str(c_) for _, c_ in MALFORMED}, key=int)), end.mpos_text)
        )


def check_hold_resume(c):
    start = c.wait_idle()
    s0 = mpos_milli(start)
    # 20 x 10 mm at 10 mm/min: over two minutes of virtual time, about a second at --speed 100.
    check(c.command("G91 G1 X20 Y10 F10") == "ok", "hold: the move was refused")
    check(c.command("G90") == "ok", "hold: G90 refused")
    latencies = []
    run = None
    for _ in range(20):
        s = c.status()
        latencies.append(s.latency)
        if s.state == "Run":
            run = s
            break
        time.sleep(0.005)
    check(run is not None, "hold: never saw Run (last %s)" % s.raw)
    for _ in range(10):
        s = c.status()
        latencies.append(s.latency)
        check(s.state == "Run", "hold: expected Run, got %s" % s.raw)
    c.realtime(b"!")
    held = None
    for _ in range(200):
        s = c.status()
        if s.state == "Hold" and s.substate == "0":
            held = s
            break
        time.sleep(0.005)
    check(held is not None, "hold: never reached Hold:0 (last %s)" % s.raw)
    time.sleep(0.3)  # 30 s of virtual time: any motion would show
    again = c.status()
    check(again.state == "Hold" and again.mpos_text == held.mpos_text, "hold: moved while held: %s -> %s" % (held.raw, again.raw))
    check(mpos_milli(held)[:2] != (s0[0] + 20000, s0[1] + 10000), "hold: the move was already over")
    c.realtime(b"~")
    s = c.status()
    check(s.state == "Run", "resume: expected Run, got %s" % s.raw)
    end = c.wait_idle()
    check(mpos_milli(end)[:2] == (s0[0] + 20000, s0[1] + 10000), "hold: ended at %s, from %s + 20,10" % (end.mpos_text, start.mpos_text))
    check_alarms(c)
    latencies.sort()
    print(
        "  Run seen, held at %s, resumed, ended %s; '?' answered in %.1f ms median, %.1f ms max (%d queries)"
        % (held.mpos_text, end.mpos_text, 1000 * latencies[len(latencies) // 2], 1000 * latencies[-1], len(latencies))
    )


def check_long_stream(c, n=100_000):
    start = c.wait_idle()
    s0 = mpos_milli(start)
    # Collinear diagonal moves of 1..4 x 0.0625 mm (5..20 steps, exact in binary), so the
    # planner keeps speed across them and a lost or repeated line would move the end.
    ks = [1, 2, 3, 4, 3, 1, 4, 2]
    lines = ["G91 G1 F6000"]
    total = 0
    for i in range(n - 2):
        k = ks[i % len(ks)]
        total += k
        d = "%g" % (k * 0.0625)
        lines.append("X%s Y%s" % (d, d))
    lines.append("G90")
    check(len(lines) == n, "generated %d lines" % len(lines))
    total_milli = total * 625 // 10  # k * 0.0625 mm
    check(total * 625 % 10 == 0, "end position not a whole thousandth")
    answered = [0]
    order_ok = [True]

    def on_answer(i, line, a):
        if i != answered[0]:
            order_ok[0] = False
        answered[0] += 1

    t0 = time.monotonic()
    answers = c.stream(lines, mode="count", on_answer=on_answer)
    t_stream = time.monotonic() - t0
    end = c.wait_idle(timeout=300)
    t_all = time.monotonic() - t0
    oks = sum(1 for a in answers if a == "ok")
    check(oks == n and len(answers) == n and order_ok[0], "long stream: %d answers, %d ok, for %d lines" % (len(answers), oks, n))
    check_alarms(c)
    want = (s0[0] + total_milli, s0[1] + total_milli)
    check(mpos_milli(end)[:2] == want, "long stream: ended at %s, expected %.3f,%.3f" % (end.mpos_text, want[0] / 1000, want[1] / 1000))
    print(
        "  %d lines, %d ok, in order, none extra; ended %s (expected %.3f,%.3f); streamed in %.1f s, idle after %.1f s"
        % (n, oks, end.mpos_text, want[0] / 1000, want[1] / 1000, t_stream, t_all)
    )


def main():
    port, root = sys.argv[1], sys.argv[2]
    c = GrblClient(port, rx_size=128, timeout=20.0)
    try:
        w = c.reset()
        print("connected: %s" % w)
        checks = [
            ("1. bench files, send-response and character counting", lambda: check_files(c, root)),
            ("2. malformed lines get their error:N, the rest runs", lambda: check_malformed(c, root)),
            ("4. '?' while running, '!' hold and '~' resume", lambda: check_hold_resume(c)),
            ("3. 100,000-line character-counting stream", lambda: check_long_stream(c)),
        ]
        for name, f in checks:
            print(name)
            f()
        print("all end-to-end checks passed")
        return 0
    except (Fail, GrblError) as e:
        print("FAIL: %s" % e)
        for t, line in c.events[-10:]:
            print("  event: %s" % line)
        return 1
    finally:
        c.close()


if __name__ == "__main__":
    raise SystemExit(main())
