#!/usr/bin/env python3
"""Embree's ray throughput inside Mitsuba 3 (llvm_ad_rgb) on the 1 M-triangle bunnies, for
comparison with `penumbra bench trace --wide --device cpu target/peers/bunnies-lambert.glb`.

The scene is mitsuba_compare.py's (bunny_scene(..., 7)); the rays are bench trace's kinds:
primary rays through pixel centres of BUNNY_CAMERA (W x H), then cosine-distributed diffuse
rays from the primary hits (ray i from hit i % hits, around the face normal turned towards the
camera ray). Each set is intersected with scene.ray_intersect_preliminary (Embree alone:
rtcIntersect16 under Dr.Jit) and scene.ray_intersect (what Mitsuba's path tracer calls, with
the surface interaction), `--runs` times after a warm-up that compiles the kernels; reported:
wall and process CPU time of the median run, M rays/s per wall and per CPU second.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 PENUMBRA_SCENES=... \
        python scripts/experiments/embree_rays.py --size 1024
"""

import argparse
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "peers"))
import mitsuba_compare as mc  # noqa: E402  (sets the llvm_ad_rgb variant)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402


def primary_rays(cam, w, h):
    eye = np.array(cam["eye"], np.float32)
    fwd = np.array(cam["forward"], np.float32)
    up = np.array(cam["up"], np.float32)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    th = math.tan(math.radians(cam["yfov_deg"]) / 2)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    sx = ((xs + 0.5) / w * 2 - 1) * th * (w / h)
    sy = (1 - (ys + 0.5) / h * 2) * th
    d = fwd[None, :] + sx.reshape(-1, 1) * right[None, :] + sy.reshape(-1, 1) * up[None, :]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.broadcast_to(eye, d.shape)
    return o.astype(np.float32), d.astype(np.float32)


def to_ray(o, d):
    return mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))


def timed(fn, runs):
    walls, cpus = [], []
    for _ in range(runs):
        w, c = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
    i = sorted(range(runs), key=lambda k: walls[k])[runs // 2]
    return walls[i], cpus[i]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--shuffle", action="store_true",
                    help="rays in a random order (no coherence between neighbours)")
    args = ap.parse_args()
    src = os.path.join(os.environ["PENUMBRA_SCENES"], "StanfordBunny", "bunny.glb")
    sc = mc.bunny_scene(src, 7)
    scene = mc.mitsuba_scene(sc, 64, 64, 6, twosided=True)
    n = args.size * args.size
    o, d = primary_rays(sc["camera"], args.size, args.size)
    ray = to_ray(o, d)
    si = scene.ray_intersect(ray)
    dr.eval(si)
    t = si.t.numpy()
    hit = np.isfinite(t)
    p = (o + d * t[:, None])[hit]
    nrm = np.stack([si.n.x.numpy(), si.n.y.numpy(), si.n.z.numpy()], 1)[hit]
    nrm *= -np.sign(np.sum(nrm * d[hit], 1))[:, None]  # towards the camera ray (two-sided)
    idx = np.arange(n) % len(p)
    rng = np.random.default_rng(0)
    u1, u2 = rng.random(n, np.float32), rng.random(n, np.float32)
    frame = mi.Frame3f(mi.Vector3f(nrm[idx, 0], nrm[idx, 1], nrm[idx, 2]))
    local = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u1, u2))
    dd = frame.to_world(local)
    dd = np.stack([dd.x.numpy(), dd.y.numpy(), dd.z.numpy()], 1).astype(np.float32)
    # The origin a little off the surface, as Mitsuba's spawn_ray does.
    po = (p[idx] + nrm[idx] * 1e-4).astype(np.float32)
    sets = {"primary": (o, d), "diffuse": (po, dd)}
    if args.shuffle:
        perm = np.random.default_rng(1).permutation(n)
        sets = {k: (a[perm].copy(), b[perm].copy()) for k, (a, b) in sets.items()}
    print(f"{n} rays a set, {hit.sum()} primary hits, Mitsuba {mi.__version__} {mi.variant()}")
    print("| rays | call | wall s | CPU s | M rays/s | M rays per CPU s | hits |")
    print("|---|---|---|---|---|---|---|")
    for name, (ro, rd) in sets.items():
        for call in ("ray_intersect_preliminary", "ray_intersect"):
            f = getattr(scene, call)
            hits = [0]

            r = to_ray(ro, rd)
            dr.eval(r)
            dr.sync_thread()

            def run():
                res = f(r)
                dr.eval(res)
                dr.sync_thread()  # the LLVM backend runs kernels asynchronously
                hits[0] = res.t

            run()  # warm-up: the kernel compiles here
            run()
            w, c = timed(run, args.runs)
            nh = int(np.isfinite(hits[0].numpy()).sum())
            print(f"| {name} | {call} | {w:.3f} | {c:.3f} | {n / w / 1e6:.2f} | "
                  f"{n / c / 1e6:.2f} | {nh} |")


if __name__ == "__main__":
    main()
