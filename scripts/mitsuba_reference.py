#!/usr/bin/env python3
"""Render the bundled Cornell box with Mitsuba 3 as a reference image for penumbra.

The Mitsuba scene is built from the same data that writes assets/cornell-box.glb
(scripts/cornell_box.py: `cornell_box.scene()`), not from a second description.

    python3 scripts/mitsuba_reference.py --width 64 --height 64 --bounces 8 \
        --spp 65536 --out tests/references/cornell-box-mitsuba-64.exr

Compare with:  penumbra render assets/cornell-box.glb --width 64 --height 64 --bounces 8 \
                   --hard-shadows -o OUT.exr

Needs: pip install mitsuba  (tested: mitsuba 3.9.1, drjit 1.5.0, variant llvm_ad_rgb)
       apt-get install -y libllvm19   (Dr.Jit finds /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1;
       set DRJIT_LIBLLVM_PATH to a libLLVM.so if it does not)

Mapping (glTF -> Mitsuba):
  * baseColorFactor (metallic 0, roughness 1, specularFactor 0)  -> 'diffuse' reflectance
    (Mitsuba's diffuse is one-sided; with this closed, correctly oriented geometry no back
    face is ever seen, so this equals glTF single-sided)
  * emissiveFactor x emissiveStrength on a single-sided material -> 'area' emitter with that
    radiance; it emits along the triangles' front side (CCW winding / NORMAL), like glTF
  * KHR_lights_punctual point, intensity I W/sr, color c          -> 'point', intensity c*I
  * glTF camera node (looks along its -Z, +Y up), yfov            -> 'perspective',
    fov_axis 'y', to_world = look_at(eye, eye + forward, up). Mitsuba's look_at maps the
    image's left edge to cross(up, forward) = -X here, the same as glTF (checked by render:
    the red wall at x = 0 is on the left).
  * penumbra --bounces N (N bounces after the first hit; 0 = direct light only)
                                                                  -> 'path' max_depth N + 2
  * film: 'hdrfilm', 'box' reconstruction filter, linear RGB float32 EXR (no tone mapping)
Russian roulette is switched off (rr_depth > max_depth) so every path runs its full depth.
"""

import argparse
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cornell_box  # noqa: E402  (same directory)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

# The variant of this script; one that imports it may have chosen its own first.
if mi.variant() is None:
    mi.set_variant("llvm_ad_rgb")


def _rgb(c):
    return {"type": "rgb", "value": [float(v) for v in c]}


def make_mesh(obj, material, twosided=False):
    """A Mitsuba triangle mesh from one cornell_box mesh dict (positions/normals/indices);
    `twosided` wraps a non-emissive material's diffuse BSDF so both faces scatter."""
    props = mi.Properties()
    bsdf = {"type": "diffuse", "reflectance": _rgb(material["color"])}
    if twosided and "emissive_factor" not in material:
        bsdf = {"type": "twosided", "bsdf": bsdf}
    props["bsdf"] = mi.load_dict(bsdf)
    if "emissive_factor" in material:
        radiance = [f * material["emissive_strength"] for f in material["emissive_factor"]]
        props["emitter"] = mi.load_dict({"type": "area", "radiance": _rgb(radiance)})
    nv, nf = len(obj["positions"]), len(obj["indices"]) // 3
    mesh = mi.Mesh(obj["name"], nv, nf, props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float([c for p in obj["positions"] for c in p])
    params["vertex_normals"] = mi.Float([c for n in obj["normals"] for c in n])
    params["faces"] = mi.UInt32(obj["indices"])
    params.update()
    return mesh


def scene_dict(width, height, spp_per_pass, bounces, eye, target, up, yfov_deg, near, far):
    """A Mitsuba scene dict with penumbra's settings and no shapes: a 'path' integrator of
    max_depth bounces + 2 with Russian roulette off, a pinhole 'perspective' sensor from eye
    towards target (vertical fov yfov_deg) and a linear RGB 'hdrfilm' with a box filter."""
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": bounces + 2, "rr_depth": bounces + 100,
                       "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": yfov_deg,
            "near_clip": near,
            "far_clip": far,
            "to_world": mi.ScalarTransform4f().look_at(origin=list(eye), target=list(target),
                                                       up=list(up)),
            "sampler": {"type": "independent", "sample_count": spp_per_pass},
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb",
                     "component_format": "float32"},
        },
    }


def build_scene(width, height, spp_per_pass, bounces, sc=None, twosided=False):
    """The Mitsuba scene of a cornell_box.scene()-style description (the Cornell box itself
    when `sc` is None); `twosided` as in make_mesh."""
    sc = sc or cornell_box.scene()
    cam = sc["camera"]
    eye = cam["eye"]
    target = tuple(e + f for e, f in zip(eye, cam["forward"]))
    d = scene_dict(width, height, spp_per_pass, bounces, eye, target, cam["up"],
                   cam["yfov_deg"], cam["znear"], cam["zfar"])
    for obj in sc["meshes"]:
        d["mesh_" + obj["name"]] = make_mesh(obj, sc["materials"][obj["material"]], twosided)
    for i, pl in enumerate(sc["point_lights"]):
        d[f"point_{i}"] = {"type": "point", "position": list(pl["position"]),
                           "intensity": _rgb([c * pl["intensity"] for c in pl["color"]])}
    return mi.load_dict(d)


def main(argv=None):
    ap = argparse.ArgumentParser(description="Mitsuba 3 reference render of the Cornell box")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--height", type=int, default=64)
    ap.add_argument("--spp", type=int, default=65536, help="total samples per pixel")
    ap.add_argument("--bounces", type=int, default=8,
                    help="penumbra --bounces (bounces after the first hit); max_depth = N + 2")
    ap.add_argument("--pass-spp", type=int, default=0,
                    help="samples per pixel per pass (default: about 4M paths per pass)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first pass")
    ap.add_argument("--out", default="cornell-box-mitsuba.exr", help="output .exr")
    ap.add_argument("--png", default=None,
                    help="PNG preview (sRGB, clamped; default: OUT with .png, upscaled)")
    ap.add_argument("--preview-scale", type=int, default=4,
                    help="nearest-neighbour upscaling of the PNG preview")
    args = ap.parse_args(argv)

    glb = os.path.join(os.path.dirname(HERE), "assets", "cornell-box.glb")
    if not cornell_box.file_is_current(glb):
        print(f"warning: {glb} is not what scripts/cornell_box.py generates now; "
              "rerun it so the asset and the reference agree", file=sys.stderr)

    pixels = args.width * args.height
    pass_spp = args.pass_spp or max(1, min(args.spp, (1 << 22) // pixels))
    passes = math.ceil(args.spp / pass_spp)
    total_spp = passes * pass_spp
    scene = build_scene(args.width, args.height, pass_spp, args.bounces)

    t0 = time.time()
    acc = None
    acc2 = None  # sum of squared per-pass means: per-pixel standard error of the result
    for i in range(passes):
        img = mi.render(scene, seed=args.seed + i, spp=pass_spp)
        acc = img if acc is None else acc + img
        acc2 = img * img if acc2 is None else acc2 + img * img
        dr.eval(acc, acc2)
        dr.sync_thread()
        if passes > 1 and (i + 1) % max(1, passes // 10) == 0:
            print(f"  pass {i + 1}/{passes}  {time.time() - t0:.1f} s", file=sys.stderr)
    seconds = time.time() - t0
    mean = acc / passes
    dr.eval(mean)

    bmp = mi.Bitmap(mean, pixel_format=mi.Bitmap.PixelFormat.RGB)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    bmp.write(args.out)

    # Statistics (plain Python over the flat array).
    flat = [float(v) for v in mean.array]
    flat2 = [float(v) for v in acc2.array]
    n = len(flat) // 3
    channel_mean = [sum(flat[c::3]) / n for c in range(3)]
    rel_se = block_se = None
    if passes > 1:
        # standard error of each pixel's mean from the spread of the pass means
        var = [max(0.0, (s2 / passes - mu * mu)) * passes / (passes - 1)
               for s2, mu in zip(flat2, flat)]
        se = [math.sqrt(v / passes) for v in var]
        lum = [sum(flat[3 * p: 3 * p + 3]) for p in range(n)]
        se_lum = [math.sqrt(sum(se[3 * p + c] ** 2 for c in range(3))) for p in range(n)]
        rel = sorted(s / l for s, l in zip(se_lum, lum) if l > 0)
        rel_se = (sum(rel) / len(rel), rel[len(rel) // 2], rel[-1])
        # the same for the means of 4x4 pixel blocks
        W, H, B = args.width, args.height, 4
        brel = []
        for by in range(0, H - B + 1, B):
            for bx in range(0, W - B + 1, B):
                ps = [y * W + x for y in range(by, by + B) for x in range(bx, bx + B)]
                bl = sum(lum[p] for p in ps)
                if bl > 0:
                    brel.append(math.sqrt(sum(se_lum[p] ** 2 for p in ps)) / bl)
        brel.sort()
        block_se = (sum(brel) / len(brel), brel[-1]) if brel else None

    png = args.png or os.path.splitext(args.out)[0] + ".png"
    k = max(1, args.preview_scale)
    big = [flat[3 * ((y // k) * args.width + x // k) + c]
           for y in range(args.height * k) for x in range(args.width * k) for c in range(3)]
    prev = mi.Bitmap(mi.TensorXf(big, shape=(args.height * k, args.width * k, 3)),
                     pixel_format=mi.Bitmap.PixelFormat.RGB)
    prev.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(png)

    print(f"wrote {args.out} ({os.path.getsize(args.out)} bytes) and {png}")
    print(f"mitsuba {mi.__version__}, drjit {dr.__version__}, variant {mi.variant()}, "
          f"{args.width}x{args.height}, bounces {args.bounces} (max_depth "
          f"{args.bounces + 2}), spp {total_spp} ({passes} passes x {pass_spp}), "
          f"{seconds:.1f} s")
    print(f"mean RGB: {channel_mean[0]:.6f} {channel_mean[1]:.6f} {channel_mean[2]:.6f}")
    if rel_se:
        print(f"per-pixel relative standard error (RGB sum): mean {rel_se[0]:.2e}, "
              f"median {rel_se[1]:.2e}, max {rel_se[2]:.2e}")
        if block_se:
            print(f"4x4-block relative standard error: mean {block_se[0]:.2e}, "
                  f"max {block_se[1]:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
