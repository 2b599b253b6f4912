"""Reference polylines from vpype (the independent reader the host tool's SVG
reader is compared with in tests/real_svgs.rs).

Run from the repository root with vpype 1.15 installed (CI: .ci/venv-vpype):
    .ci/venv-vpype/bin/python host/tests/data/svg-real/vpype_ref.py
For every *.svg here it writes vpype/NAME.txt: one polyline per line, points
"x,y" in millimetres in the SVG's own frame (y down), read with
vpype.read_svg(crop=False) at a 0.2 mm quantization (chords of at most 0.2 mm,
so the reference lies within 0.001 mm of a curve of 5 mm radius).
"""
import glob
import os

import vpype

HERE = os.path.dirname(os.path.abspath(__file__))
PX = 96 / 25.4
for path in sorted(glob.glob(os.path.join(HERE, "*.svg"))):
    name = os.path.basename(path)[:-4]
    try:
        lc, _, _ = vpype.read_svg(path, quantization=0.2 * PX, crop=False)
    except Exception as e:  # noqa: BLE001 (recursive <use>: vpype overflows)
        print(f"{name}: vpype failed: {e}")
        continue
    with open(os.path.join(HERE, "vpype", name + ".txt"), "w") as f:
        for line in lc:
            if len(line) > 1:
                f.write(" ".join(f"{z.real / PX:.4f},{z.imag / PX:.4f}" for z in line) + "\n")
