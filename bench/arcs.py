#!/usr/bin/env python3
"""Writes bench/arcs-r.nc and bench/arcs-ij.nc: the same 24 arcs, once in R form and once
with I/J centres, with the reference settings.

Radii from 0.8 to 30 mm, sweeps from 30 to 270 degrees (negative R for the longer arc),
both directions, feeds 1500-4000 mm/min, each arc starting where the last ended (corners
between them). What it measures: job time on arcs of every size against Grbl 1.1's
(`cargo sim grbl-model`), and that the two forms draw the same. Deterministic (seed 7).
Run from anywhere: python3 bench/arcs.py
"""
import math
import os
import random

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
TAIL = "G0 X0 Y0\n" + "G4 P0\n" * 2


def arcs(n, seed):
    """(G2|G3, x, y, R, I, J, F) for n chained arcs from the origin."""
    rnd = random.Random(seed)
    x = y = 0.0
    out = []
    for _ in range(n):
        r = rnd.choice([0.8, 2.5, 6.0, 15.0, 30.0])
        sweep = rnd.choice([30, 60, 90, 135, 170, 200, 270])
        chord = 2 * r * math.sin(math.radians(sweep) / 2)
        th = rnd.uniform(0, 2 * math.pi)
        nx, ny = x + chord * math.cos(th), y + chord * math.sin(th)
        if abs(nx) > 60 or abs(ny) > 60:
            nx, ny = x - chord * math.cos(th), y - chord * math.sin(th)
        nx, ny = round(nx, 3), round(ny, 3)
        g = rnd.choice(["G2", "G3"])
        feed = rnd.choice([1500, 3000, 4000])
        big = sweep > 180
        # Centre on the chord's bisector: right of travel for a short clockwise arc.
        dx, dy = nx - x, ny - y
        d = math.hypot(dx, dy)
        h = math.sqrt(max(r * r - d * d / 4, 0.0))
        side = h if (g == "G2") != big else -h
        cx, cy = (x + nx) / 2 + side * dy / d, (y + ny) / 2 - side * dx / d
        out.append((g, nx, ny, -r if big else r, cx - x, cy - y, feed))
        x, y = nx, ny
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    moves = arcs(24, 7)
    with open(os.path.join(here, "arcs-r.nc"), "w") as f:
        f.write(HEAD)
        for g, x, y, r, _, _, feed in moves:
            f.write(f"{g} X{x:.3f} Y{y:.3f} R{r:.3f} F{feed}\n")
        f.write(TAIL)
    with open(os.path.join(here, "arcs-ij.nc"), "w") as f:
        f.write(HEAD)
        for g, x, y, _, i, j, feed in moves:
            f.write(f"{g} X{x:.3f} Y{y:.3f} I{i:.4f} J{j:.4f} F{feed}\n")
        f.write(TAIL)


if __name__ == "__main__":
    main()
