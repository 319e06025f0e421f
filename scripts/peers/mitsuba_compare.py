#!/usr/bin/env python3
"""penumbra against Mitsuba 3's CPU path tracer (llvm_ad_rgb), side by side, in one run on one
machine: the same scene, resolution, path depth and samples per pixel.

The scenes, each defined once here as plain data and given to both renderers:

  cornell  the bundled Lambertian Cornell box (assets/cornell-box.glb, built by
           scripts/cornell_box.py; the Mitsuba side is scripts/mitsuba_reference.py's
           build_scene): quad area light + point light. Reference:
           tests/references/cornell-box-mitsuba-128.exr (Mitsuba, 49152 spp) at 128x128.
  bunny    StanfordBunny ($PENUMBRA_SCENES/StanfordBunny/bunny.glb, 144,046 triangles) on a
           floor in front of a back wall, all Lambertian, lit by one point light. Written as a
           GLB for penumbra (flat shading: every triangle its own three vertices, so both
           renderers shade with the geometric normal) and handed to Mitsuba as the same
           arrays. Mitsuba's `diffuse` is one-sided; penumbra scatters from both faces, so the
           Mitsuba BSDFs are wrapped in `twosided`. Reference: Mitsuba at --ref-spp, cached in
           --work.
  bunnies  seven such bunnies side by side (1,008,326 triangles), the same floor, wall and
           light: the 1 M-triangle scene, most paths leaving it after a bounce or two.
  bunnies-room  the seven bunnies in a closed room (side and front walls, a ceiling) lit only
           by an emissive panel under the ceiling: no path escapes, every one can find the
           light (1 M triangles, long paths).
  terrain-room  a 709x709 heightfield (a smooth procedural terrain, 1,002,540 triangles) in
           the same closed room: one large, well-behaved mesh.
  spheres-room  357 UV spheres of random sizes and places (seed 13, overlapping, 1,002,470
           triangles) in the same closed room: many objects whose boxes overlap, the hard
           case for a BVH.

Settings on both sides: --size x --size pixels, box pixel filter, penumbra --bounces B =
Mitsuba max_depth B + 2, Russian roulette off, hard shadows (point light radius 0), MIS.

Measured (wall clock, on this machine, one after the other, nothing else of ours running):
  * time for the same spp: `penumbra render --spp S` ("seconds": rendering only, kernel build
    excluded) against mi.render(spp=S) after a warm-up render (the JIT compile is reported
    separately); with --timing-only also each side's process CPU time for it (penumbra's
    `cpu_seconds`, Python's process_time() around mi.render), the fair measure on a machine
    shared with other work;
  * error against the reference as samples double (penumbra: `bench converge --configs mis`,
    progressive; Mitsuba: an independent render per spp count), and the time each needs to
    reach the relMSE Mitsuba reaches at S spp (log-log interpolation on each curve).

    python3 scripts/peers/mitsuba_compare.py                      # cornell and bunny, defaults
    python3 scripts/peers/mitsuba_compare.py --scenes cornell --spp 64 --max-spp 256
    python3 scripts/peers/mitsuba_compare.py --timing-only --rounds 5 --scenes bunnies,bunnies-room \
        --size 256 --bounces 6 --spp 16    # medians of 5 interleaved renders a side

Needs: mitsuba 3 (pip install mitsuba; see scripts/README.md), a release build of penumbra
(cargo build --release), PENUMBRA_SCENES for the bunny. Prints a Markdown table and writes
the raw figures as JSON (--json).
"""

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import cornell_box  # noqa: E402
import mitsuba_reference  # noqa: E402  (sets the llvm_ad_rgb variant)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402


# ---------------------------------------------------------------------------------------
# The bunny scene, as plain data in cornell_box.scene()'s format
# ---------------------------------------------------------------------------------------

BUNNY_MATERIALS = [
    {"name": "Bunny", "color": (0.8, 0.76, 0.7)},
    {"name": "Floor", "color": (0.5, 0.5, 0.5)},
    {"name": "Wall", "color": (0.6, 0.62, 0.65)},
]
# The closed room's ceiling panel (bunnies-room): radiance 6 W/(m^2 sr), single-sided.
BUNNY_PANEL = {"name": "Panel", "color": (0.78, 0.78, 0.78), "emissive_factor": (1.0, 1.0, 1.0),
               "emissive_strength": 6.0}
BUNNY_CAMERA = {"name": "Camera", "eye": (-0.15, 0.85, 3.4), "forward": (0.0, 0.0, -1.0),
                "up": (0.0, 1.0, 0.0), "yfov_deg": 40.0, "aspect": 1.0, "znear": 0.01,
                "zfar": 100.0}
BUNNY_LIGHT = {"name": "Key", "position": (1.2, 2.6, 1.8), "color": (1.0, 1.0, 1.0),
               "intensity": 10.0}


def _flat_mesh(name, material, positions, triangles):
    """A flat-shaded mesh: every triangle gets its own vertices with the face normal."""
    pos, nrm = [], []
    for a, b, c in triangles:
        pa, pb, pc = positions[a], positions[b], positions[c]
        n = cornell_box._normalize(cornell_box._cross(cornell_box._sub(pb, pa),
                                                      cornell_box._sub(pc, pa)))
        pos += [pa, pb, pc]
        nrm += [n, n, n]
    return {"name": name, "material": material, "positions": pos, "normals": nrm,
            "indices": list(range(len(pos)))}


def bunny_scene(glb_path, copies=1, room=False):
    gltf, bin_data = cornell_box.read_glb(glb_path)
    prim = gltf["meshes"][0]["primitives"][0]
    positions = cornell_box.read_accessor(gltf, bin_data, prim["attributes"]["POSITION"])
    idx = cornell_box.read_accessor(gltf, bin_data, prim["indices"])
    tris = [(idx[i], idx[i + 1], idx[i + 2]) for i in range(0, len(idx), 3)]
    # Drop zero-area triangles: neither renderer can hit them and a zero normal is invalid.
    tris = [t for t in tris if any(abs(c) > 0 for c in cornell_box._cross(
        cornell_box._sub(positions[t[1]], positions[t[0]]),
        cornell_box._sub(positions[t[2]], positions[t[0]])))]
    y0 = min(p[1] for p in positions)
    floor = cornell_box._quad([(-3.0, y0, -1.5), (3.0, y0, -1.5), (3.0, y0, 4.0),
                               (-3.0, y0, 4.0)], (0, 1, 0))
    wall = cornell_box._quad([(-3.0, y0, -1.5), (3.0, y0, -1.5), (3.0, 4.0, -1.5),
                              (-3.0, 4.0, -1.5)], (0, 0, 1))
    # Copies side by side and behind (the 1 M-triangle scene: 7 copies), the first in place.
    offsets = [(0.0, 0.0, 0.0), (-1.1, 0.0, -0.6), (1.1, 0.0, -0.6), (-2.0, 0.0, -1.0),
               (2.0, 0.0, -1.0), (-0.55, 0.0, -1.2), (0.55, 0.0, -1.2)][:copies]
    meshes = [_flat_mesh(f"Bunny{i}" if i else "Bunny", 0,
                         [(p[0] + o[0], p[1] + o[1], p[2] + o[2]) for p in positions], tris)
              for i, o in enumerate(offsets)]
    # Closed: side walls, a front wall behind the camera and a ceiling with a panel light under
    # it (facing down), so that no path escapes and every one can find the light.
    parts = [("Floor", 1, [floor])] + (_room(y0) if room else [("Wall", 2, [wall])])
    for name, mat, quads in parts:
        p, n, i = cornell_box._merge(quads)
        meshes.append({"name": name, "material": mat, "positions": p, "normals": n,
                       "indices": i})
    if room:
        return {"meshes": meshes, "materials": BUNNY_MATERIALS + [BUNNY_PANEL],
                "camera": BUNNY_CAMERA, "point_lights": []}
    return {"meshes": meshes, "materials": BUNNY_MATERIALS, "camera": BUNNY_CAMERA,
            "point_lights": [BUNNY_LIGHT]}


def _room(y0, top=4.0):
    """The closed room of bunnies-room (back, side and front walls, a ceiling) and its panel
    light under the ceiling, as (name, material, quads) parts; the floor is the caller's."""
    walls = [
        cornell_box._quad([(-3.0, y0, -1.5), (3.0, y0, -1.5), (3.0, top, -1.5),
                           (-3.0, top, -1.5)], (0, 0, 1)),
        cornell_box._quad([(-3.0, y0, -1.5), (-3.0, y0, 4.0), (-3.0, top, 4.0),
                           (-3.0, top, -1.5)], (1, 0, 0)),
        cornell_box._quad([(3.0, y0, -1.5), (3.0, y0, 4.0), (3.0, top, 4.0),
                           (3.0, top, -1.5)], (-1, 0, 0)),
        cornell_box._quad([(-3.0, y0, 4.0), (3.0, y0, 4.0), (3.0, top, 4.0),
                           (-3.0, top, 4.0)], (0, 0, -1)),
        cornell_box._quad([(-3.0, top, -1.5), (3.0, top, -1.5), (3.0, top, 4.0),
                           (-3.0, top, 4.0)], (0, -1, 0))]
    panel = cornell_box._quad([(-1.0, top - 0.001, 0.0), (1.0, top - 0.001, 0.0),
                               (1.0, top - 0.001, 2.0), (-1.0, top - 0.001, 2.0)], (0, -1, 0))
    return [("Wall", 2, walls), ("Panel", 3, [panel])]


def _scene_in_room(meshes, y0, floor=True):
    parts = _room(y0)
    if floor:
        parts.insert(0, ("Floor", 1, [cornell_box._quad(
            [(-3.0, y0, -1.5), (3.0, y0, -1.5), (3.0, y0, 4.0), (-3.0, y0, 4.0)], (0, 1, 0))]))
    for name, mat, quads in parts:
        p, n, i = cornell_box._merge(quads)
        meshes.append({"name": name, "material": mat, "positions": p, "normals": n,
                       "indices": i})
    return {"meshes": meshes, "materials": BUNNY_MATERIALS + [BUNNY_PANEL],
            "camera": BUNNY_CAMERA, "point_lights": []}


def terrain_room_scene(n=709):
    """A rolling heightfield of 2 (n-1)^2 triangles (1,002,528 for n = 709: one dense mesh,
    no copies) as the floor of bunnies-room's closed room, lit by its panel: 1 M triangles
    unlike the bunnies' (no instancing to find, small triangles everywhere the camera looks)."""
    def h(x, z):
        return (0.35 + 0.25 * math.sin(2.1 * x) * math.cos(1.7 * z)
                + 0.1 * math.sin(5.3 * x + 1.3 * z) + 0.04 * math.sin(13.0 * x) * math.sin(11.0 * z))
    xs = [-3.0 + 6.0 * i / (n - 1) for i in range(n)]
    zs = [-1.5 + 5.5 * j / (n - 1) for j in range(n)]
    positions = [(x, h(x, z), z) for z in zs for x in xs]
    tris = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            tris += [(a, a + n, a + 1), (a + 1, a + n, a + n + 1)]
    return _scene_in_room([_flat_mesh("Terrain", 0, positions, tris)], 0.0, floor=False)


def spheres_room_scene(count=357, stacks=27, slices=54):
    """`count` UV spheres of 2 slices (stacks - 1) triangles each (2,808; 1,002,456 in all),
    of random radii at random places in bunnies-room's room (a fixed seed): many separate
    objects, some overlapping, each its own mesh."""
    import random
    rng = random.Random(13)
    unit = [(math.sin(math.pi * t / stacks) * math.cos(2 * math.pi * s / slices),
             math.cos(math.pi * t / stacks),
             math.sin(math.pi * t / stacks) * math.sin(2 * math.pi * s / slices))
            for t in range(stacks + 1) for s in range(slices)]
    tris = []
    for t in range(stacks):
        for s in range(slices):
            a, b = t * slices + s, t * slices + (s + 1) % slices
            c, d = a + slices, b + slices
            if t > 0:
                tris.append((a, b, c))
            if t < stacks - 1:
                tris.append((b, d, c))
    meshes = []
    for k in range(count):
        r = rng.uniform(0.08, 0.28)
        o = (rng.uniform(-2.7, 2.7), rng.uniform(r, 3.2), rng.uniform(-1.3, 1.8))
        pts = [(o[0] + r * u[0], o[1] + r * u[1], o[2] + r * u[2]) for u in unit]
        meshes.append(_flat_mesh(f"Sphere{k}", 0, pts, tris))
    return _scene_in_room(meshes, 0.0)


def closed_box_scene(splits=0):
    """The bundled box with closed blocks (a bottom face each, as in Mitsuba's own `cbox`: 36
    triangles), every triangle then split into four at its edge midpoints `splits` times (144,
    576, ...): boxes other than the bundled one's 32 triangles, for the small-scene path's limit."""
    sc = cornell_box.scene()
    meshes = []
    for m in sc["meshes"]:
        pos, nrm = list(m["positions"]), list(m["normals"])
        idx = list(m["indices"])
        if m["name"].endswith("Block"):
            bottom = sorted({p for p in pos if p[1] == 0.0})
            # The four bottom corners as the top's; order them around their centre.
            cx = sum(p[0] for p in bottom) / 4.0
            cz = sum(p[2] for p in bottom) / 4.0
            bottom.sort(key=lambda p: math.atan2(p[2] - cz, p[0] - cx))
            q, n, i = cornell_box._quad(bottom, (0.0, -1.0, 0.0))
            idx += [len(pos) + k for k in i]
            pos += q
            nrm += n
        tris = [(pos[idx[k]], pos[idx[k + 1]], pos[idx[k + 2]], nrm[idx[k]])
                for k in range(0, len(idx), 3)]
        for _ in range(splits):
            mid = lambda a, b: tuple((x + y) / 2.0 for x, y in zip(a, b))  # noqa: E731
            tris = [t for a, b, c, n in tris
                    for t in ((a, mid(a, b), mid(c, a), n), (mid(a, b), b, mid(b, c), n),
                              (mid(c, a), mid(b, c), c, n), (mid(a, b), mid(b, c), mid(c, a), n))]
        meshes.append(dict(m, positions=[p for t in tris for p in t[:3]],
                           normals=[t[3] for t in tris for _ in range(3)],
                           indices=list(range(3 * len(tris)))))
    return dict(sc, meshes=meshes)


def mitsuba_scene(sc, width, height, bounces, twosided):
    """The Mitsuba scene of a cornell_box.scene()-style description, one sample per pass."""
    return mitsuba_reference.build_scene(width, height, 1, bounces, sc=sc, twosided=twosided)


# ---------------------------------------------------------------------------------------
# Measurements
# ---------------------------------------------------------------------------------------

def relmse(img, ref):
    """Mean over pixels and channels of (x - r)^2 / (r^2 + 0.01), as penumbra computes it."""
    x, r = img.array, ref.array
    return float(dr.mean(dr.square(x - r) / (dr.square(r) + 0.01))[0])


LAST_MITSUBA_CPU_SECONDS = [0.0]


def mitsuba_render(scene, spp, seed):
    """Renders and waits; returns (image, seconds). The render's process CPU time (all threads)
    is left in LAST_MITSUBA_CPU_SECONDS[0]."""
    t = time.perf_counter()
    c = time.process_time()
    img = mi.render(scene, seed=seed, spp=spp)
    dr.eval(img)
    dr.sync_thread()
    LAST_MITSUBA_CPU_SECONDS[0] = time.process_time() - c
    return img, time.perf_counter() - t


def mitsuba_reference_image(scene, spp, seed0, pass_spp):
    acc = None
    passes = max(1, spp // pass_spp)
    for i in range(passes):
        img, _ = mitsuba_render(scene, pass_spp, seed0 + i)
        acc = img if acc is None else acc + img
        dr.eval(acc)
    return acc / passes


def read_exr_tensor(path):
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                  srgb_gamma=False)
    return mi.TensorXf(bmp)


def time_to_reach(curve, target):
    """Seconds at which a (seconds, relmse) curve, interpolated in log-log, reaches `target`;
    extrapolated with slope -1 from the last point when it ends above it."""
    pts = sorted(curve)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            a = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(t0) + a * (math.log(t1) - math.log(t0))), False
    if pts and target >= pts[0][1]:
        return pts[0][0], False
    t, e = pts[-1]
    return t * e / target, True


def run_penumbra(binary, args):
    out = subprocess.run([binary] + args, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"penumbra {' '.join(args)} failed:\n{out.stderr}")
    return json.loads([line for line in out.stdout.splitlines() if line.startswith("{")][-1])


def compare(name, glb, msc, reference, args, results):
    print(f"== {name}: {glb}", file=sys.stderr)
    size, bounces = str(args.size), str(args.bounces)
    common = ["--width", size, "--height", size, "--bounces", bounces, "--hard-shadows",
              "--device", args.device] + (["--kernel", args.kernel] if args.kernel else [])
    # penumbra: time for S spp (kernels built before the clock starts), then the error curve.
    render = ["render", glb, "-o", os.path.join(args.work, f"{name}-penumbra.exr"), "--spp",
              str(args.spp), "--no-russian-roulette"] + common
    pen_render = run_penumbra(args.penumbra, render)
    if args.timing_only:
        _, compile_s = mitsuba_render(msc, 1, 10_000)
        _, mit_same_spp = mitsuba_render(msc, args.spp, 77)
        mit_cpu = LAST_MITSUBA_CPU_SECONDS[0]
        # More rounds, the two renderers one after the other in each: the medians (a shared
        # machine moves both by 10-20 % from one minute to the next).
        if args.rounds > 1:
            runs = [(pen_render, mit_same_spp, mit_cpu)]
            for k in range(1, args.rounds):
                pen = run_penumbra(args.penumbra, render)
                _, secs = mitsuba_render(msc, args.spp, 77 + k)
                runs.append((pen, secs, LAST_MITSUBA_CPU_SECONDS[0]))
            median = lambda xs: sorted(xs)[len(xs) // 2]  # noqa: E731
            pen_render = dict(pen_render)
            pen_render["seconds"] = median([r[0]["seconds"] for r in runs])
            pen_render["samples_per_second"] = median([r[0]["samples_per_second"]
                                                       for r in runs])
            pen_render["cpu_seconds"] = median([r[0]["cpu_seconds"] for r in runs])
            mit_same_spp = median([r[1] for r in runs])
            mit_cpu = median([r[2] for r in runs])
        pixels = args.size * args.size
        r = {"scene": name, "glb": glb, "size": args.size, "bounces": args.bounces,
             "spp": args.spp, "triangles": pen_render["triangles"],
             "penumbra_device": pen_render["device"], "penumbra_kernel": pen_render["kernel"],
             "penumbra_seconds": pen_render["seconds"],
             "penumbra_kernel_build_ms": pen_render["kernel_build_ms"],
             "penumbra_samples_per_second": pen_render["samples_per_second"],
             "mitsuba_seconds": mit_same_spp, "mitsuba_compile_seconds": compile_s,
             "mitsuba_samples_per_second": pixels * args.spp / mit_same_spp,
             "penumbra_cpu_seconds": pen_render.get("cpu_seconds"),
             "mitsuba_cpu_seconds": mit_cpu, "rounds": args.rounds}
        results.append(r)
        print(f"   penumbra {r['penumbra_seconds']:.3f} s ({r['penumbra_cpu_seconds']} CPU s), "
              f"Mitsuba {mit_same_spp:.3f} s ({mit_cpu:.2f} CPU s) for {args.spp} spp",
              file=sys.stderr)
        return
    pen_conv = run_penumbra(args.penumbra, ["bench", "converge", glb, "--reference", reference,
                                            "--configs", "mis", "--spp", str(args.max_spp),
                                            "--json"] + common)
    pen_curve = [(s["seconds"], s["relmse"]) for s in pen_conv["curves"][0]["steps"]]

    # Mitsuba: compile (first render), then independent renders at each spp count.
    ref = read_exr_tensor(reference)
    _, compile_s = mitsuba_render(msc, 1, 10_000)
    mit_curve, mit_steps = [], []
    spp = 1
    while spp <= args.max_spp:
        img, secs = mitsuba_render(msc, spp, spp)
        e = relmse(img, ref)
        mit_curve.append((secs, e))
        mit_steps.append({"spp": spp, "seconds": secs, "relmse": e})
        spp *= 2
    _, mit_same_spp = mitsuba_render(msc, args.spp, 77)
    target = next(s["relmse"] for s in mit_steps if s["spp"] == args.spp)
    mit_t, _ = time_to_reach(mit_curve, target)
    pen_t, extrapolated = time_to_reach(pen_curve, target)
    pixels = args.size * args.size
    r = {
        "scene": name, "glb": glb, "reference": reference, "size": args.size,
        "bounces": args.bounces, "spp": args.spp,
        "triangles": pen_render["triangles"],
        "penumbra_device": pen_render["device"],
        "penumbra_seconds": pen_render["seconds"],
        "penumbra_kernel_build_ms": pen_render["kernel_build_ms"],
        "penumbra_samples_per_second": pen_render["samples_per_second"],
        "mitsuba_seconds": mit_same_spp,
        "mitsuba_compile_seconds": compile_s,
        "mitsuba_samples_per_second": pixels * args.spp / mit_same_spp,
        "target_relmse": target,
        "penumbra_seconds_to_target": pen_t,
        "penumbra_extrapolated": extrapolated,
        "mitsuba_seconds_to_target": mit_t,
        "penumbra_slope_time": pen_conv["curves"][0]["slope_time"],
        "penumbra_steps": pen_conv["curves"][0]["steps"],
        "mitsuba_steps": mit_steps,
    }
    results.append(r)
    print(f"   penumbra {r['penumbra_seconds']:.3f} s, Mitsuba {mit_same_spp:.3f} s for "
          f"{args.spp} spp", file=sys.stderr)



def cached_reference(args, name, msc):
    """The Mitsuba reference of scene `name` (Mitsuba scene dict `msc`) at --ref-spp, rendered
    into --work unless it is there already (or --timing-only, which needs none)."""
    reference = os.path.join(args.work,
                             f"{name}-mitsuba-{args.size}-{args.bounces}-{args.ref_spp}.exr")
    if not os.path.exists(reference) and not args.timing_only:
        print(f"rendering {reference} ({args.ref_spp} spp)", file=sys.stderr)
        t = time.perf_counter()
        mi.Bitmap(mitsuba_reference_image(msc, args.ref_spp, 1000, 256)).write(reference)
        print(f"   {time.perf_counter() - t:.0f} s", file=sys.stderr)
    return reference

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--penumbra", default=os.path.join(ROOT, "target", "release", "penumbra"))
    ap.add_argument("--device", default="cpu", help="penumbra --device (default cpu: PoCL)")
    ap.add_argument("--scenes", default="cornell,bunny")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--bounces", type=int, default=8)
    ap.add_argument("--spp", type=int, default=256, help="spp of the same-spp timing")
    ap.add_argument("--max-spp", type=int, default=1024, help="last spp of the error curves")
    ap.add_argument("--ref-spp", type=int, default=16384, help="bunny reference spp")
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "peers"),
                    help="scratch folder (scenes, cached references)")
    ap.add_argument("--json", default=None, help="write the raw figures here")
    ap.add_argument("--timing-only", action="store_true",
                    help="only the time for the same spp (no error curves, no references)")
    ap.add_argument("--rounds", type=int, default=1,
                    help="with --timing-only: this many renders on each side, interleaved; "
                         "medians reported")
    ap.add_argument("--kernel", default=None,
                    help="penumbra --kernel (wavefront, megakernel; default: penumbra's auto)")
    args = ap.parse_args(argv)
    os.makedirs(args.work, exist_ok=True)
    if not os.path.exists(args.penumbra):
        sys.exit(f"{args.penumbra}: no penumbra binary (cargo build --release)")

    results = []
    for name in args.scenes.split(","):
        if name == "cornell":
            glb = os.path.join(ROOT, "assets", "cornell-box.glb")
            reference = os.path.join(ROOT, "tests", "references",
                                     f"cornell-box-mitsuba-{args.size}.exr")
            msc = mitsuba_scene(cornell_box.scene(), args.size, args.size, args.bounces,
                                twosided=False)
            if not os.path.exists(reference):
                reference = os.path.join(args.work, f"cornell-mitsuba-{args.size}.exr")
                if not os.path.exists(reference) and not args.timing_only:
                    print(f"rendering {reference}", file=sys.stderr)
                    mi.Bitmap(mitsuba_reference_image(msc, args.ref_spp, 1000, 256)).write(
                        reference)
        elif name in ("cornell36", "cornell144", "cornell576"):
            sc = closed_box_scene({"cornell36": 0, "cornell144": 1, "cornell576": 2}[name])
            glb = os.path.join(args.work, f"{name}.glb")
            cornell_box.write_glb(glb, *cornell_box.build_gltf(sc))
            msc = mitsuba_scene(sc, args.size, args.size, args.bounces, twosided=False)
            reference = os.path.join(args.work, f"{name}-mitsuba-{args.size}.exr")
            if not os.path.exists(reference) and not args.timing_only:
                print(f"rendering {reference}", file=sys.stderr)
                mi.Bitmap(mitsuba_reference_image(msc, args.ref_spp, 1000, 256)).write(
                    reference)
        elif name in ("bunny", "bunnies", "bunnies-room"):
            scenes = os.environ.get("PENUMBRA_SCENES")
            src = os.path.join(scenes or "", "StanfordBunny", "bunny.glb")
            if not scenes or not os.path.exists(src):
                sys.exit("bunny: set PENUMBRA_SCENES to the folder holding StanfordBunny/")
            sc = bunny_scene(src, 1 if name == "bunny" else 7, room=name == "bunnies-room")
            glb = os.path.join(args.work, f"{name}-lambert.glb")
            cornell_box.write_glb(glb, *cornell_box.build_gltf(sc))
            msc = mitsuba_scene(sc, args.size, args.size, args.bounces, twosided=True)
            reference = cached_reference(args, name, msc)
        elif name in ("terrain-room", "spheres-room"):
            sc = terrain_room_scene() if name == "terrain-room" else spheres_room_scene()
            glb = os.path.join(args.work, f"{name}-lambert.glb")
            cornell_box.write_glb(glb, *cornell_box.build_gltf(sc))
            msc = mitsuba_scene(sc, args.size, args.size, args.bounces, twosided=True)
            reference = cached_reference(args, name, msc)
        else:
            sys.exit(f"unknown scene '{name}' (cornell, cornell36, cornell144, cornell576, bunny, "
                     "bunnies, bunnies-room, terrain-room, spheres-room)")
        compare(name, glb, msc, reference, args, results)

    cpu = platform.processor() or platform.machine()
    meta = {"date": time.strftime("%Y-%m-%d", time.gmtime()), "host": cpu,
            "cores": os.cpu_count(), "mitsuba": mi.__version__, "drjit": dr.__version__,
            "variant": mi.variant()}
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"meta": meta, "results": results}, f, indent=1)
    print(f"penumbra ({results[0]['penumbra_device'] if results else '?'}) against Mitsuba "
          f"{mi.__version__} {mi.variant()}, {meta['cores']} cores, {meta['date']}; "
          f"{args.size}x{args.size}, {args.bounces} bounces (max_depth {args.bounces + 2}), "
          f"no Russian roulette, hard shadows, MIS")
    print()
    if args.timing_only:
        print("| scene | triangles | spp | penumbra s | Mitsuba s (compile) | penumbra M samples/s "
              "| Mitsuba M samples/s | penumbra / Mitsuba | penumbra CPU s | Mitsuba CPU s "
              "| per CPU second, penumbra / Mitsuba |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in results:
            pc, mc = r["penumbra_cpu_seconds"], r["mitsuba_cpu_seconds"]
            per_cpu = f"{mc / pc:.2f}×" if pc and mc else "—"
            print(f"| {r['scene']} | {r['triangles']:,} | {r['spp']} "
                  f"| {r['penumbra_seconds']:.3f} "
                  f"| {r['mitsuba_seconds']:.3f} ({r['mitsuba_compile_seconds']:.1f}) "
                  f"| {r['penumbra_samples_per_second'] / 1e6:.2f} "
                  f"| {r['mitsuba_samples_per_second'] / 1e6:.2f} "
                  f"| {r['penumbra_samples_per_second'] / r['mitsuba_samples_per_second']:.2f}× "
                  f"| {f'{pc:.2f}' if pc is not None else '—'} | {mc:.2f} | {per_cpu} |")
        return 0
    print("| scene | triangles | spp | penumbra s | Mitsuba s (compile) | penumbra M samples/s "
          "| Mitsuba M samples/s | target relMSE | penumbra s to target | Mitsuba s to target "
          "| penumbra slope |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        ext = " (extrapolated)" if r["penumbra_extrapolated"] else ""
        print(f"| {r['scene']} | {r['triangles']:,} | {r['spp']} | {r['penumbra_seconds']:.3f} "
              f"| {r['mitsuba_seconds']:.3f} ({r['mitsuba_compile_seconds']:.1f}) "
              f"| {r['penumbra_samples_per_second'] / 1e6:.2f} "
              f"| {r['mitsuba_samples_per_second'] / 1e6:.2f} | {r['target_relmse']:.3e} "
              f"| {r['penumbra_seconds_to_target']:.3f}{ext} "
              f"| {r['mitsuba_seconds_to_target']:.3f} | {r['penumbra_slope_time']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
