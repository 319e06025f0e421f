#!/usr/bin/env python3
"""How much adaptive sampling could gain on a view, and how much of it a render got
(docs/adaptive-sampling.md, "Where the time goes"). Needs numpy.

    penumbra render SCENE --width W --height H --spp 32 --seed $((100 + K)) -o var-K.exr  # K = 1..8
    penumbra render SCENE --width W --height H --spp 1 --aovs -o aov.exr
    penumbra render SCENE ... --spp 1024 --seed 1 --noise-threshold T --aovs -o adaptive.exr
    scripts/adaptive_bound.py --reference ref.exr --spp-each 32 --aovs aov.exr \\
        [--adaptive adaptive.exr --threshold T] var-*.exr

From the independent renders, each pixel's variance per sample weighted as relMSE weighs it,
v = σ² / (r² + 0.01) (the bench's relMSE, `src/bench/stats.rs`), and Cycles' error per sample
(|I − A| / √I squared, as `kernels/shared/adaptive.h` measures it). A sample costs 1 where the
camera ray missed (the 1-spp render's depth is infinite) and --cost-ratio where it hit.

For an allocation n of samples to pixels, the gain is the time uniform sampling needs to reach
its relMSE over the time it took, both with the costs above:
    gain = Σc · Σv / (Σ v/n · Σ c n).
Printed: the Neyman bound (n ∝ √(v / c), no minimum, no cap: nothing allocates better), Cycles'
rule on the exact variances (n = u / T² clamped to [minimum, cap]) for a few thresholds, the
Neyman split under the same minimum and cap, and with --adaptive the samples the render took.
"""

import argparse
import struct
import sys
import zlib

import numpy as np


def read_exr(path):
    """The channels of a tiled, uncompressed, RLE- or ZIP-compressed EXR (what penumbra
    writes, shards included), as {name: float64 array (height, width)}."""
    data = open(path, "rb").read()
    attrs, p = {}, 8
    while data[p] != 0:
        fields = []
        for _ in range(2):
            end = data.index(b"\0", p)
            fields.append(data[p:end].decode())
            p = end + 1
        (size,) = struct.unpack_from("<i", data, p)
        attrs[fields[0]] = data[p + 4 : p + 4 + size]
        p += 4 + size
    p += 1
    channels, q, raw = [], 0, attrs["channels"]
    while raw[q] != 0:
        end = raw.index(b"\0", q)
        (pixel_type,) = struct.unpack_from("<i", raw, end + 1)
        channels.append((raw[q:end].decode(), pixel_type))
        q = end + 17
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    compression = attrs["compression"][0]
    if "tiles" not in attrs or compression not in (0, 1, 2, 3):
        sys.exit(f"{path}: only tiled EXRs, uncompressed, RLE or ZIP, are read")
    tile_w, tile_h, _ = struct.unpack("<IIB", attrs["tiles"])
    tiles = -(-width // tile_w) * -(-height // tile_h)
    image = {name: np.zeros((height, width), np.float64) for name, _ in channels}
    sizes = {0: 4, 1: 2, 2: 4}  # uint, half, float
    dtypes = {0: np.uint32, 1: np.float16, 2: np.float32}
    for offset in struct.unpack_from(f"<{tiles}Q", data, p):
        tx, ty, _, _, size = struct.unpack_from("<5i", data, offset)
        block = data[offset + 20 : offset + 20 + size]
        w, h = min(tile_w, width - tx * tile_w), min(tile_h, height - ty * tile_h)
        expected = sum(sizes[t] for _, t in channels) * w * h
        if compression != 0 and size < expected:
            block = unpredict(unrle(block) if compression == 1 else zlib.decompress(block))
        q = 0
        for row in range(h):
            for name, pixel_type in channels:
                values = np.frombuffer(block, dtypes[pixel_type], count=w, offset=q)
                image[name][ty * tile_h + row, tx * tile_w : tx * tile_w + w] = values
                q += w * sizes[pixel_type]
    return image


def unrle(block):
    out, i = bytearray(), 0
    while i < len(block):
        (count,) = struct.unpack_from("b", block, i)
        i += 1
        if count < 0:
            out += block[i : i - count]
            i -= count
        else:
            out += bytes([block[i]]) * (count + 1)
            i += 1
    return bytes(out)


def unpredict(block):
    """Undo the EXR byte predictor and the split of even and odd bytes."""
    t = np.frombuffer(block, np.uint8).astype(np.int64)
    t = (np.cumsum(np.concatenate([t[:1], t[1:] - 128])) & 255).astype(np.uint8)
    half = (len(t) + 1) // 2
    out = np.empty(len(t), np.uint8)
    out[0::2], out[1::2] = t[:half], t[half:]
    return out.tobytes()


def rgb(path):
    image = read_exr(path)
    return np.stack([image["R"], image["G"], image["B"]], -1).astype(np.float64)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("images", nargs="+", help="independent renders of the same view")
    parser.add_argument("--reference", required=True)
    parser.add_argument("--spp-each", type=float, required=True)
    parser.add_argument("--aovs", required=True, help="a render with --aovs (its depth)")
    parser.add_argument("--cost-ratio", type=float, action="append",
                        help="cost of a sample that hits over one that misses (repeatable)")
    parser.add_argument("--adaptive", help="an adaptive render with --aovs (samples.Y)")
    parser.add_argument("--threshold", type=float, help="its --noise-threshold")
    parser.add_argument("--cap", type=float, default=1024)
    args = parser.parse_args()

    reference = rgb(args.reference)
    images = np.stack([rgb(p) for p in args.images])
    variance = images.var(axis=0, ddof=1) * args.spp_each  # per sample, per channel
    v = (variance / (reference**2 + 0.01)).mean(-1).ravel()
    sd = np.sqrt(variance).sum(-1)
    u = (sd / (1e-4 + np.sqrt(np.clip(reference.sum(-1), 0, None)))).ravel() ** 2
    hit = np.isfinite(read_exr(args.aovs)["depth.Z"]).ravel().astype(np.float64)
    ranked = np.sort(v)[::-1]
    top = lambda share: ranked[: max(1, int(len(v) * share))].sum() / v.sum()
    print(f"pixels hit {hit.mean():.3f}; relMSE in the noisiest 1 % / 10 % of pixels: "
          f"{top(0.01):.3f} / {top(0.1):.3f}")

    def gain(n, c):
        return c.sum() * v.sum() / ((v / n).sum() * (c * n).sum())

    def neyman(c, cost, lo_n, hi_n):
        """n ∝ √(v / c) clamped to [lo_n, hi_n], scaled to the total cost `cost`."""
        lo, hi = 0.0, 1e12
        for _ in range(200):
            k = (lo + hi) / 2
            if (c * np.clip(k * np.sqrt(v / c), lo_n, hi_n)).sum() > cost:
                hi = k
            else:
                lo = k
        return np.clip(lo * np.sqrt(v / c), lo_n, hi_n)

    for ratio in args.cost_ratio or [1.0]:
        c = 1 + (ratio - 1) * hit
        bound = c.sum() * v.sum() / np.sqrt(c * v).sum() ** 2
        print(f"cost ratio {ratio:g}: Neyman bound {bound:.2f}")
        for t in (0.1, 0.05, 0.02, 0.01):
            minimum = -(-max(4, 16 / t**0.3) // 16) * 16
            n = np.clip(u / t**2, minimum, args.cap)
            same = neyman(c, (c * n).sum(), minimum, args.cap)
            print(f"  T {t}: Cycles' rule {gain(n, c):.2f} (mean spp {n.mean():.0f}, "
                  f"{(n >= args.cap).mean():.2f} at the cap); Neyman at its cost "
                  f"{gain(same, c):.2f}")
        if args.adaptive:
            taken = read_exr(args.adaptive)["samples.Y"].ravel().astype(np.float64)
            line = f"  the adaptive render: {gain(taken, c):.2f} (mean spp {taken.mean():.0f})"
            if args.threshold:
                t = args.threshold
                rule = np.clip(u / t**2, taken.min(), args.cap)
                line += f"; Cycles' rule on the exact variances {gain(rule, c):.2f}"
            print(line)
    if args.adaptive and args.threshold:
        error = np.sqrt(u / taken)
        stopped = taken < args.cap
        print(f"stopped pixels with an exact error over T: {(stopped & (error > args.threshold)).mean():.3f}, "
              f"over 2T: {(stopped & (error > 2 * args.threshold)).mean():.3f}")


if __name__ == "__main__":
    main()
