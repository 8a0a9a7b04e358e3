#!/usr/bin/env python3
"""Crops the same rectangle out of two PNG frames, enlarges each by a whole
factor (nearest neighbour: every pixel stays a pixel, noise and edges as
they are) and writes them side by side as one PNG, with the standard
library only. For the README's camera-match picture
(scripts/camera-match-picture.sh).

usage: side_by_side.py LEFT.png RIGHT.png X Y WIDTH HEIGHT SCALE OUT.png
"""
import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from png_to_ppm import read_png  # noqa: E402

GAP_PX = 6
GAP_RGB = (255, 255, 255)


def crop(path, x, y, w, h):
    width, height, rgb = read_png(path)
    if not (0 <= x and 0 <= y and x + w <= width and y + h <= height):
        raise ValueError(f"{path}: {width}x{height} does not hold the rectangle {x},{y} {w}x{h}")
    return [rgb[((y + row) * width + x) * 3:((y + row) * width + x + w) * 3] for row in range(h)]


def enlarge(rows, scale):
    out = []
    for row in rows:
        line = bytearray()
        for i in range(0, len(row), 3):
            line += row[i:i + 3] * scale
        out.extend([bytes(line)] * scale)
    return out


def write_png(path, width, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + row for row in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, len(rows), 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def main():
    if len(sys.argv) != 9:
        sys.exit(__doc__)
    left, right = sys.argv[1], sys.argv[2]
    x, y, w, h, scale = (int(v) for v in sys.argv[3:8])
    a = enlarge(crop(left, x, y, w, h), scale)
    b = enlarge(crop(right, x, y, w, h), scale)
    gap = bytes(GAP_RGB) * GAP_PX
    rows = [ra + gap + rb for ra, rb in zip(a, b)]
    write_png(sys.argv[8], 2 * w * scale + GAP_PX, rows)


if __name__ == "__main__":
    main()
