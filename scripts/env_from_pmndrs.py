#!/usr/bin/env python3
"""Converts Poly Haven HDRIs (CC0) from the npm package @pmndrs/assets into the Radiance .hdr
files penumbra bundles as its default environments (assets/env/).

The package stores each HDRI as `hdri/NAME.exr.js`: a JavaScript module whose default export is a
base64 data URL of a 512 x 256 EXR with DWAB compression, which the `exr` crate cannot read.
DWAB is lossy: around the sun its DCT blocks ring into large negative values and false colours
(a blue square in `park`). Texels within 3 of such ringing are replaced by a grey of the 5 x 5
box-filtered signed luminance (the ringing cancels, the energy stays; the false colour goes),
then negatives elsewhere are clamped to 0.

usage (OpenEXR and numpy in a virtual environment):
    npm pack @pmndrs/assets@1.7.0 && tar xzf pmndrs-assets-1.7.0.tgz
    python3 -m venv venv && venv/bin/pip install OpenEXR numpy
    venv/bin/python scripts/env_from_pmndrs.py package/hdri assets/env studio park:outdoor
"""
import base64
import math
import sys
from pathlib import Path

import numpy as np
import OpenEXR

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def decode(js_path):
    """The RGB pixels (H x W x 3, float32, row 0 at the top) of one `.exr.js` module."""
    text = js_path.read_text()
    data = base64.b64decode(text.split("base64,", 1)[1].split("'", 1)[0])
    tmp = Path("/tmp") / (js_path.name + ".exr")
    tmp.write_bytes(data)
    with OpenEXR.File(str(tmp)) as f:
        channels = f.channels()
        if "RGB" in channels:
            rgb = channels["RGB"].pixels
        else:
            rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
    tmp.unlink()
    return np.nan_to_num(rgb.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)


def box(image, radius):
    """Box filter with edge clamping (wrapping in x would be more exact; the sun is not at the seam)."""
    padded = np.pad(image, ((radius, radius), (radius, radius), (0, 0)), mode="edge")
    out = np.zeros_like(image)
    h, w = image.shape[:2]
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out += padded[dy : dy + h, dx : dx + w]
    return out / (2 * radius + 1) ** 2


def repair(rgb):
    """Replaces the ringing DWAB leaves around very bright texels, then clamps negatives."""
    ringing = (rgb < -1.0).any(axis=-1)
    mask = ringing.copy()
    for _ in range(3):  # dilate by 3 texels
        m = mask.copy()
        m[1:] |= mask[:-1]
        m[:-1] |= mask[1:]
        m[:, 1:] |= mask[:, :-1]
        m[:, :-1] |= mask[:, 1:]
        mask = m
    grey = np.repeat(box(rgb, 2) @ LUMINANCE, 3).reshape(rgb.shape)
    out = np.where(mask[..., None], grey, rgb)
    return np.maximum(out, 0.0), int(ringing.sum())


def write_hdr(path, rgb):
    """A flat (not run-length encoded) RGBE file, as `image` reads it."""
    h, w, _ = rgb.shape
    m = rgb.max(axis=-1)
    e = np.zeros_like(m, dtype=np.int32)
    mant, exp = np.frexp(m)
    e[m > 1e-32] = exp[m > 1e-32]
    scale = np.where(m > 1e-32, np.ldexp(1.0, -e) * 256.0, 0.0)
    rgbe = np.zeros((h, w, 4), dtype=np.uint8)
    rgbe[..., :3] = np.clip(rgb * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(m > 1e-32, e + 128, 0).astype(np.uint8)
    header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w)
    path.write_bytes(header + rgbe.tobytes())


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    src, dst = Path(sys.argv[1]), Path(sys.argv[2])
    dst.mkdir(parents=True, exist_ok=True)
    for spec in sys.argv[3:]:
        name, _, out = spec.partition(":")
        rgb, fixed = repair(decode(src / f"{name}.exr.js"))
        lum = rgb @ LUMINANCE
        h = rgb.shape[0]
        sin = np.sin((np.arange(h) + 0.5) / h * math.pi)[:, None]
        mean = float((lum * sin).sum() / (sin.sum() * rgb.shape[1]))
        target = dst / f"{out or name}.hdr"
        write_hdr(target, rgb)
        print(f"{name} -> {target}: {rgb.shape[1]}x{h}, {fixed} ringing texels repaired, "
              f"mean luminance {mean:.3f}, max {lum.max():.1f}")


if __name__ == "__main__":
    main()
