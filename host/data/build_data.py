#!/usr/bin/env python3
"""Rebuild host/data/*.z from the npm packages (run by hand, not at build time).

    npm pack hanzi-writer-data@2.0.1 hersheytext@2.0.0
    python3 host/data/build_data.py hanzi-writer-data-2.0.1.tgz hersheytext-2.0.0.tgz

hanzi_medians.bin.z (zlib), little endian:
    b"IKHZ" u32 count, then per character sorted by code point:
    u32 code point, u8 strokes, per stroke: u8 points, points as i16 x, i16 y
    (hanzi-writer's frame: a 1024 box, y up, baseline offset so y spans -124..900).
hershey.txt.z (zlib), text:
    "font NAME" lines, each followed by 94 glyph lines "HALF_ADVANCE PATH" for
    ASCII 33..126, PATH using only M and L in the font's units (y down).
"""
import json, struct, sys, tarfile, zlib, os

HERE = os.path.dirname(os.path.abspath(__file__))
FONTS = ["futural", "scripts", "cursive", "futuram"]


def hanzi(tgz):
    out = []
    with tarfile.open(tgz) as t:
        for m in t.getmembers():
            name = os.path.basename(m.name)
            ch = name[:-5]
            if not name.endswith(".json") or len(ch) != 1:
                continue
            d = json.load(t.extractfile(m))
            if "medians" not in d:
                continue
            out.append((ord(ch), d["medians"]))
    out.sort()
    buf = bytearray(b"IKHZ" + struct.pack("<I", len(out)))
    for cp, med in out:
        buf += struct.pack("<IB", cp, len(med))
        for stroke in med:
            buf += struct.pack("<B", len(stroke))
            for x, y in stroke:
                buf += struct.pack("<hh", round(x), round(y))
    return zlib.compress(bytes(buf), 9), len(out)


def hershey(tgz):
    with tarfile.open(tgz) as t:
        d = json.load(t.extractfile("package/hersheytext.json"))
    lines = []
    for f in FONTS:
        chars = d[f]["chars"]
        lines.append("font " + f)
        for c in chars[:94]:
            lines.append("%d %s" % (c["o"], c["d"]))
    return zlib.compress(("\n".join(lines) + "\n").encode(), 9)


if __name__ == "__main__":
    hz, n = hanzi(sys.argv[1])
    open(os.path.join(HERE, "hanzi_medians.bin.z"), "wb").write(hz)
    hs = hershey(sys.argv[2])
    open(os.path.join(HERE, "hershey.txt.z"), "wb").write(hs)
    print("hanzi: %d characters, %d bytes; hershey: %d bytes" % (n, len(hz), len(hs)))
