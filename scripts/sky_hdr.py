#!/usr/bin/env python3
"""Writes a small synthetic sky as a Radiance .hdr (equirectangular, 512 x 256): a blue gradient
above the horizon, brown ground below and a sun of radiance ~2000 at 26 degrees elevation. It is
the environment the docs/images renders use (`--env sky.hdr`); no other file is needed.

usage: scripts/sky_hdr.py OUT.hdr
"""
import math
import sys

W, H = 512, 256
SUN = (0.5, 0.45, -0.74)  # direction towards the sun (normalized below)


def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return bytes([0, 0, 0, 0])
    e = math.frexp(m)[1]
    scale = math.ldexp(1.0, -e) * 256.0
    return bytes([min(255, int(r * scale)), min(255, int(g * scale)), min(255, int(b * scale)), e + 128])


def main():
    n = math.sqrt(sum(c * c for c in SUN))
    sun = [c / n for c in SUN]
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
    for y in range(H):
        theta = math.pi * (y + 0.5) / H
        for x in range(W):
            phi = 2.0 * math.pi * ((x + 0.5) / W - 0.5)
            # penumbra's convention: the centre column looks along -Z, u grows towards +X.
            d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
            if d[1] > 0.0:
                t = 1.0 - d[1]
                c = (0.25 + 0.45 * t, 0.45 + 0.35 * t, 0.95 + 0.05 * t)
            else:
                c = (0.22, 0.18, 0.14)
            if sum(a * b for a, b in zip(d, sun)) > 0.9995:
                c = (2000.0, 1850.0, 1600.0)
            out += rgbe(*c)
    with open(sys.argv[1], "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main()
