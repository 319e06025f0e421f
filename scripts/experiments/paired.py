#!/usr/bin/env python3
"""Paired, interleaved renders of one scene under two settings: the fair way to compare two
kernels on a shared, noisy machine, where the same render moves by 10 % within minutes.

Each round renders A then B (B then A in odd rounds), the same settings as mitsuba_compare.py's
1 M-triangle timings (256², 16 spp, 6 bounces, hard shadows, no Russian roulette, the CPU
device), and prints both process CPU times (the summary's cpu_seconds) and their ratio B/A; at
the end the ratios' mean, median and range, and whether the last two images are identical
byte for byte. A setting is environment variables, e.g.:

    python3 scripts/experiments/paired.py target/peers/bunnies-room-lambert.glb --rounds 8 \\
        --a "PENUMBRA_LANES_SHADE=0" --b ""
    python3 scripts/experiments/paired.py SCENE --a "PENUMBRA_KERNEL_DIR=/tmp/old" \\
        --b "PENUMBRA_KERNEL_DIR=." --out /tmp/pair

(a kernel directory holds kernels/..., read at run time: no rebuild). One warm-up render a side
first, so that neither pays for a kernel build.
"""

import argparse
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kernel_blocks  # noqa: E402  (its render(): the same command line)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--penumbra", default="target/release/penumbra")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--bounces", type=int, default=6)
    ap.add_argument("--a", default="", help="setting A: NAME=VALUE ... (environment)")
    ap.add_argument("--b", default="", help="setting B")
    ap.add_argument("--out", default="/tmp/paired", help="image path prefix")
    args = ap.parse_args()

    def render(spec, tag):
        env = dict(os.environ)
        for kv in spec.split():
            k, v = kv.split("=", 1)
            env[k] = v
        d = kernel_blocks.render(args, env, args.size, args.spp, f"{args.out}-{tag}.exr")
        return d["cpu_seconds"], d["seconds"]

    render(args.a, "a")
    render(args.b, "b")
    ratios = []
    for i in range(args.rounds):
        if i % 2 == 0:
            a = render(args.a, "a")
            b = render(args.b, "b")
        else:
            b = render(args.b, "b")
            a = render(args.a, "a")
        ratios.append(b[0] / a[0])
        print(f"round {i}: A {a[0]:.2f} CPU s ({a[1]:.3f} s)  B {b[0]:.2f} ({b[1]:.3f})  "
              f"B/A {ratios[-1]:.3f}", flush=True)
    print(f"B/A mean {statistics.mean(ratios):.3f}, median {statistics.median(ratios):.3f}, "
          f"min {min(ratios):.3f}, max {max(ratios):.3f}")
    with open(f"{args.out}-a.exr", "rb") as fa, open(f"{args.out}-b.exr", "rb") as fb:
        print("images identical" if fa.read() == fb.read() else "images differ")


if __name__ == "__main__":
    main()
