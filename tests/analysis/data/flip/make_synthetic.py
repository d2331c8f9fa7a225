#!/usr/bin/python3
"""Writes the synthetic FLIP test pair of tests/analysis/test_flip.cpp.

    python3 tests/analysis/data/flip/make_synthetic.py OUTPUT_FOLDER

colour-reference.exr / colour-test.exr: linear RGB up to 24 (HDR-FLIP);
colour-reference.png / colour-test.png: the same divided by 4, clamped to
[0, 1] and sRGB-encoded to 8 bits (LDR-FLIP). 72 x 56 pixels: smooth
colour ramps, a bright disc, a checker of 2-pixel squares, thin lines and a
black corner in the reference; in the test, noise in one quadrant, a hue
shift in another, the disc moved by one pixel and a 3 x 3 box blur over the
checker. Standard library only; the EXRs go through oiiotool (Debian's
openimageio-tools) from a PFM.
"""

import math
import os
import struct
import subprocess
import sys
import zlib

W, H = 72, 56


def reference_pixel(x, y):
    if x < 10 and y < 8:
        return (0.0, 0.0, 0.0)  # a black corner: luminance 0
    r = 0.5 + 0.5 * math.sin(2 * math.pi * x / W)
    g = y / (H - 1)
    b = 0.5 + 0.5 * math.cos(2 * math.pi * (x + y) / 40)
    gain = 0.25 + 3.0 * x / (W - 1)  # a ramp across the HDR range
    c = [gain * r, gain * g, gain * b]
    if (x - 50) ** 2 + (y - 16) ** 2 <= 25:
        c = [24.0, 20.0, 12.0]  # a bright disc
    if 8 <= x < 24 and 32 <= y < 48:
        v = 1.5 if ((x // 2) + (y // 2)) % 2 else 0.05
        c = [v, v * 0.8, v * 0.6]  # a checker of 2-pixel squares
    if y == 28 or x == 40:
        c = [0.02, 0.3, 1.2]  # thin blue lines
    return tuple(c)


def noise(x, y):
    """Deterministic noise in [-1, 1] (an integer hash)."""
    h = (x * 73856093) ^ (y * 19349663) ^ 0x5bd1e995
    h = (h * 1103515245 + 12345) & 0x7fffffff
    return (h % 20001) / 10000.0 - 1.0


def test_image(ref):
    out = [[list(ref[y][x]) for x in range(W)] for y in range(H)]
    for y in range(H):
        for x in range(W):
            if x >= W // 2 and y >= H // 2:  # noise, 15 %
                out[y][x] = [c * (1.0 + 0.15 * noise(x + 7 * k, y)) for k, c in enumerate(out[y][x])]
            if x < W // 2 and y < H // 2 and not (8 <= x < 24 and 32 <= y < 48):  # hue shift
                r, g, b = out[y][x]
                out[y][x] = [0.8 * r + 0.2 * g, 0.8 * g + 0.2 * b, 0.8 * b + 0.2 * r]
            if (x - 51) ** 2 + (y - 16) ** 2 <= 25:  # the disc, one pixel right
                out[y][x] = [24.0, 20.0, 12.0]
            elif (x - 50) ** 2 + (y - 16) ** 2 <= 25:
                out[y][x] = list(ref[y][x + 6]) if x + 6 < W else [0.0, 0.0, 0.0]
    for y in range(32, 48):  # 3 x 3 box blur over the checker
        for x in range(8, 24):
            out[y][x] = [sum(ref[y + j][x + i][k] for j in (-1, 0, 1) for i in (-1, 0, 1)) / 9
                         for k in range(3)]
    return out


def srgb8(linear):
    v = min(max(linear, 0.0), 1.0)
    e = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return int(round(e * 255))


def write_png(path, img):
    raw = b''.join(b'\0' + bytes(srgb8(c / 4.0) for px in row for c in px) for row in img)
    def chunk(tag, data):
        return (struct.pack('>I', len(data)) + tag + data +
                struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff))
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', W, H, 8, 2, 0, 0, 0)) +
                chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))


def write_exr(path, img):
    pfm = path + '.pfm'
    with open(pfm, 'wb') as f:  # PFM rows run from the bottom
        f.write(b'PF\n%d %d\n-1.0\n' % (W, H))
        for row in reversed(img):
            f.write(struct.pack('<%df' % (3 * W), *[c for px in row for c in px]))
    subprocess.run(['oiiotool', pfm, '-d', 'float', '--compression', 'zip', '-o', path], check=True)
    os.remove(pfm)


def main():
    out = sys.argv[1]
    ref = [[reference_pixel(x, y) for x in range(W)] for y in range(H)]
    test = test_image(ref)
    for name, img in (('colour-reference', ref), ('colour-test', test)):
        write_png(os.path.join(out, name + '.png'), img)
        write_exr(os.path.join(out, name + '.exr'), img)


if __name__ == '__main__':
    main()
