#!/usr/bin/env python3
"""Writes the bench's programs of tiny moves (NAME.nc) and their ideal paths (NAME.json).

Each is 500-1,000 moves of a few steps at F5000 with the reference settings, streamed
one move per line: the case where the look-ahead, the junction speeds and how far ahead
steps are prepared decide the job time. Run from anywhere: python3 bench/short-segments.py
"""
import json
import math
import os

HEAD = """$100=80
$101=80
$110=5000
$111=5000
$120=500
$121=500
$11=0.010
$12=0.002
G21 G90 G17 G94
G0 X0 Y0
"""
# Keeps a streaming sender busy until motion ends (as in the other programs).
TAIL = "G4 P0\n" * 40


def zigzag(n, dx, dy):
    """n moves of (dx, +-dy) mm, up and down in turn."""
    return [(dx * i, dy * (i % 2)) for i in range(1, n + 1)]


PROGRAMS = {
    # 4 steps on each axis a move, 90 degree corners: the junction speeds decide.
    "zigzag": (zigzag(1000, 0.05, 0.05), "%.2f"),
    # One step on each axis a move.
    "zigzag-fine": (zigzag(1000, 0.0125, 0.0125), "%.4f"),
    # 4 steps along X and 1 along Y a move: turns of 28 degrees, fast junctions.
    "zigzag-shallow": (zigzag(1000, 0.05, 0.0125), "%.4f"),
    # A circle of R 5 mm as 500 chords of about 5 steps: the look-ahead decides.
    "polygon": (
        [
            (5 - 5 * math.cos(2 * math.pi * i / 500), 5 * math.sin(2 * math.pi * i / 500))
            for i in range(1, 501)
        ],
        "%.4f",
    ),
    # 1,000 moves of 4 steps on one straight line: only the look-ahead limits speed.
    "dashes": ([(0.05 * i, 0.0) for i in range(1, 1001)], "%.2f"),
}


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    for name, (pts, fmt) in PROGRAMS.items():
        # Printed as they are written (no "-0.0000").
        pts = [(float(fmt % x) + 0.0, float(fmt % y) + 0.0) for x, y in pts]
        lines = [HEAD]
        for i, (x, y) in enumerate(pts):
            feed = " F5000" if i == 0 else ""
            lines.append(f"G1 X{fmt % x} Y{fmt % y}{feed}\n")
        lines.append(TAIL)
        with open(os.path.join(here, name + ".nc"), "w") as f:
            f.write("".join(lines))
        ideal = [[0.0, 0.0]] + [[x, y] for x, y in pts]
        with open(os.path.join(here, name + ".json"), "w") as f:
            json.dump({"type": "poly", "pts": ideal}, f)


if __name__ == "__main__":
    main()
