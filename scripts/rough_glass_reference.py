#!/usr/bin/env python3
"""Mitsuba 3 references of rough glass with a volume (roughdielectric), for tests/rough_glass.rs.

Three fixtures, each built from the data below; tests/rough_glass.rs builds the same glTF (the
same corners, faces, materials and camera) and renders it with penumbra:

  cubes  three glass cubes (ior 1.5, roughness 0.1, 0.3, 0.6, white, no absorption) under a
         uniform white sky of radiance 1, seen from above and in front: a white furnace. Rough
         single-scattering GGX loses energy at each interface; Mitsuba has the same loss.
  sphere a flat-faced glass sphere (ior 1.5, roughness 0.6; 32 rings, 64 segments) under the
         white sky: the white furnace of a rough sphere.
  slab   two glass slabs (ior 1.5, roughness 0.1 and 0.5) in front of a square emitter of
         radiance 4 on a black sky: the emitter seen blurred through each slab.

    python3 scripts/rough_glass_reference.py --fixture cubes --spp 4096 \
        --out tests/references/rough-glass-cubes-mitsuba.exr
    python3 scripts/rough_glass_reference.py --fixture slab --spp 4096 \
        --out tests/references/rough-glass-slab-mitsuba.exr
    python3 scripts/rough_glass_reference.py --fixture sphere --spp 4096 \
        --out tests/references/rough-glass-sphere-mitsuba.exr

Needs: pip install mitsuba==3.9.1 drjit==1.5.0  (the default variant scalar_rgb needs no LLVM;
       made with it on 2 CPU cores: 114 s for cubes, 75 s for slab, 36 s for sphere)

Mapping (glTF -> Mitsuba):
  * metallic 0, KHR_materials_transmission 1, KHR_materials_ior n, KHR_materials_volume
    thickness > 0 (no attenuation), roughness r, base color white
        -> 'roughdielectric', distribution 'ggx', alpha = r^2, int_ior n, ext_ior 1,
           sample_visible. (Mitsuba's Fresnel is the exact dielectric one, penumbra's glTF
           BSDF uses Schlick's approximation: at ior 1.5 the reflectances differ by 0.008 at
           45 degrees of incidence and 0.019 at 60.)
  * emissive quad, single-sided, emissiveFactor x strength, black base color
        -> mesh with an 'area' emitter of that radiance and a black 'diffuse' BSDF
  * penumbra --sky 1,1,1 -> 'constant' emitter of radiance 1; --sky 0,0,0 -> no emitter
  * glTF camera (looks along -Z, +Y up), yfov -> 'perspective', fov_axis 'y', the same eye
    and target through look_at
  * penumbra --bounces N -> 'path' max_depth N + 2, Russian roulette off (rr_depth > depth)
  * film: 'hdrfilm', 'box' filter, linear RGB float32 EXR
Triangles have no vertex normals in either renderer: the faces are flat.
"""

import argparse
import math
import os
import sys
import tempfile
import time

import drjit as dr
import mitsuba as mi

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

WIDTH, HEIGHT = 128, 64
BOUNCES = 24


def cuboid(lo, hi):
    """An axis-aligned box from lo to hi: 8 corners and 12 outward-wound triangles (the same
    as tests/common/mod.rs `cuboid`)."""
    p = [[hi[k] if (i >> k) & 1 else lo[k] for k in range(3)] for i in range(8)]
    quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]]
    idx = [v for q in quads for v in (q[0], q[1], q[2], q[0], q[2], q[3])]
    return p, idx


def sphere(radius, rings, segments):
    """A UV sphere at the origin: corners and outward-wound triangles (the same as
    tests/common/mod.rs `sphere`, whose normals the fixture leaves out: flat faces)."""
    p = []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2.0 * math.pi * s / segments
            p.append([radius * math.sin(theta) * math.cos(phi), radius * math.cos(theta),
                      radius * math.sin(theta) * math.sin(phi)])
    idx = []
    w = segments + 1
    for r in range(rings):
        for s in range(segments):
            a = r * w + s
            b = a + w
            idx += [a, a + 1, b, a + 1, b + 1, b]
    return p, idx


def fixture(name):
    """The fixture's objects (corners, triangles, material), sky radiance and camera."""
    if name == "cubes":
        objects = []
        for x, r in ((-1.1, 0.1), (0.0, 0.3), (1.1, 0.6)):
            p, i = cuboid([x - 0.4, -0.4, -0.4], [x + 0.4, 0.4, 0.4])
            objects.append((p, i, {"glass": r}))
        camera = {"eye": [0.0, 1.6, 3.2], "target": [0.0, 0.0, 0.0], "yfov_deg": 30.0}
        return objects, 1.0, camera
    if name == "slab":
        objects = []
        for x0, x1, r in ((-1.05, -0.03, 0.1), (0.03, 1.05, 0.5)):
            p, i = cuboid([x0, -0.6, -0.1], [x1, 0.6, 0.1])
            objects.append((p, i, {"glass": r}))
        # The emitter: a square in z = -0.5 facing +z (counter-clockwise seen from +z).
        p = [[-0.35, -0.35, -0.5], [0.35, -0.35, -0.5], [0.35, 0.35, -0.5], [-0.35, 0.35, -0.5]]
        objects.append((p, [0, 1, 2, 0, 2, 3], {"emission": 4.0}))
        camera = {"eye": [0.0, 0.0, 2.4], "target": [0.0, 0.0, 0.0], "yfov_deg": 34.0}
        return objects, 0.0, camera
    if name == "sphere":
        p, i = sphere(1.0, 32, 64)
        camera = {"eye": [0.0, 0.0, 4.0], "target": [0.0, 0.0, 0.0], "yfov_deg": 40.0}
        return [(p, i, {"glass": 0.6})], 1.0, camera
    raise SystemExit(f"unknown fixture {name!r} (cubes, slab or sphere)")


def make_mesh(path, positions, indices, material):
    """A Mitsuba shape of one fixture object, through an OBJ file at `path` (flat faces)."""
    with open(path, "w") as f:
        f.writelines(f"v {p[0]!r} {p[1]!r} {p[2]!r}\n" for p in positions)
        f.writelines(f"f {indices[t] + 1} {indices[t + 1] + 1} {indices[t + 2] + 1}\n"
                     for t in range(0, len(indices), 3))
    shape = {"type": "obj", "filename": path, "face_normals": True}
    if "glass" in material:
        r = material["glass"]
        shape["bsdf"] = {"type": "roughdielectric", "distribution": "ggx", "alpha": r * r,
                         "int_ior": 1.5, "ext_ior": 1.0, "sample_visible": True}
    else:
        shape["bsdf"] = {"type": "diffuse",
                         "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
        shape["emitter"] = {"type": "area",
                            "radiance": {"type": "rgb", "value": [material["emission"]] * 3}}
    return shape


def build_scene(name, spp_per_pass, tmp):
    objects, sky, cam = fixture(name)
    import mitsuba_reference  # same directory; imported once the variant is set

    d = mitsuba_reference.scene_dict(WIDTH, HEIGHT, spp_per_pass, BOUNCES, cam["eye"],
                                     cam["target"], [0.0, 1.0, 0.0], cam["yfov_deg"], 0.01,
                                     100.0)
    if sky > 0.0:
        d["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": [sky] * 3}}
    for k, (p, i, m) in enumerate(objects):
        d[f"object{k}"] = make_mesh(os.path.join(tmp, f"object{k}.obj"), p, i, m)
    return mi.load_dict(d)


def main(argv=None):
    ap = argparse.ArgumentParser(description="Mitsuba 3 references of rough glass")
    ap.add_argument("--fixture", required=True, choices=["cubes", "slab", "sphere"])
    ap.add_argument("--spp", type=int, default=16384, help="total samples per pixel")
    ap.add_argument("--pass-spp", type=int, default=256, help="samples per pixel per pass")
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--out", required=True, help="output .exr")
    args = ap.parse_args(argv)
    mi.set_variant(args.variant)

    passes = math.ceil(args.spp / args.pass_spp)
    with tempfile.TemporaryDirectory() as tmp:
        scene = build_scene(args.fixture, args.pass_spp, tmp)
    t0 = time.time()
    acc = acc2 = None
    for i in range(passes):
        img = mi.render(scene, seed=i, spp=args.pass_spp)
        acc = img if acc is None else acc + img
        acc2 = img * img if acc2 is None else acc2 + img * img
        dr.eval(acc, acc2)
    seconds = time.time() - t0
    mean = acc / passes
    dr.eval(mean)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    mi.Bitmap(mean, pixel_format=mi.Bitmap.PixelFormat.RGB).write(args.out)

    flat = [float(v) for v in mean.array]
    flat2 = [float(v) for v in acc2.array]
    n = len(flat) // 3
    channel_mean = [sum(flat[c::3]) / n for c in range(3)]
    print(f"wrote {args.out} ({os.path.getsize(args.out)} bytes)")
    print(f"mitsuba {mi.__version__}, drjit {dr.__version__}, variant {mi.variant()}, "
          f"{WIDTH}x{HEIGHT}, bounces {BOUNCES} (max_depth {BOUNCES + 2}), "
          f"spp {passes * args.pass_spp} ({passes} passes x {args.pass_spp}), {seconds:.1f} s")
    print(f"mean RGB: {channel_mean[0]:.6f} {channel_mean[1]:.6f} {channel_mean[2]:.6f}")
    if passes > 1:
        var = [max(0.0, s2 / passes - mu * mu) * passes / (passes - 1)
               for s2, mu in zip(flat2, flat)]
        se = sorted(math.sqrt(v / passes) / mu for v, mu in zip(var, flat) if mu > 1e-3)
        print(f"per-pixel relative standard error: median {se[len(se) // 2]:.2e}, "
              f"max {se[-1]:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
