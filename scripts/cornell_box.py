#!/usr/bin/env python3
"""Generate assets/cornell-box.glb, penumbra's bundled default scene.

Standard library only. Run from anywhere:

    python3 scripts/cornell_box.py            # writes assets/cornell-box.glb, validates it
    python3 scripts/cornell_box.py -o X.glb   # somewhere else
    python3 scripts/cornell_box.py --check    # only validate an existing file

The scene data (geometry, materials, camera, lights) is exposed as plain Python data by
`scene()` so other scripts (scripts/mitsuba_reference.py) build their scene from exactly
the same definitions.

Conventions (see docs / DESIGN.md): meters, glTF Y-up, right-handed. This is the classic
Cornell box data (millimetres, camera looking along +Z) turned 180 degrees about Y and
shifted so that:

    x in [0, 0.556]     left wall (red) at x = 0, right wall (green) at x = 0.556
    y in [0, 0.5488]    floor at y = 0, ceiling at y = 0.5488
    z in [-0.5592, 0]   back wall at z = -0.5592, the open front at z = 0

    classic (X, Y, Z) mm  ->  (0.556 - X/1000, Y/1000, -Z/1000) m

The camera sits at (0.278, 0.273, 0.8) looking along -Z (+Y up), i.e. the classic eye
(278, 273, -800) mm, vertical field of view 39.3077 degrees, aspect 1.

Every triangle is wound counter-clockwise seen from its front side; front sides face the
interior of the room (walls, floor, ceiling), outward for the two blocks, and down (-Y)
for the area light. Vertex normals equal the geometric normals (flat shading).
"""

import argparse
import json
import math
import os
import struct
import sys

# ---------------------------------------------------------------------------------------
# Scene data
# ---------------------------------------------------------------------------------------

WIDTH = 0.556    # x extent (m)
HEIGHT = 0.5488  # y extent (m)
DEPTH = 0.5592   # z extent (m); the room spans z in [-DEPTH, 0]

#: Camera, in the glTF sense: the node's translation; it looks along the node's -Z.
CAMERA = {
    "name": "Camera",
    "eye": (0.278, 0.273, 0.8),
    "forward": (0.0, 0.0, -1.0),
    "up": (0.0, 1.0, 0.0),
    "yfov_deg": 39.3077,
    "aspect": 1.0,
    "znear": 0.01,
    "zfar": 100.0,
}

#: Area light (classic: 130 x 105 mm at x 213..343, z 227..332, on the ceiling), 1 mm below
#: the ceiling, single-sided, facing down.
AREA_LIGHT_Y = HEIGHT - 0.001
AREA_LIGHT_X = (0.556 - 0.343, 0.556 - 0.213)  # (0.213, 0.343)
AREA_LIGHT_Z = (-0.332, -0.227)
EMISSIVE_FACTOR = (1.0, 0.706, 0.235)
EMISSIVE_STRENGTH = 17.0  # radiance = factor * strength = (17, 12.002, 3.995) W/(m^2 sr)

#: Point light (KHR_lights_punctual): radiant intensity in W/sr, used 1:1.
POINT_LIGHT = {
    "name": "PointLight",
    "position": (0.15, 0.40, -DEPTH + 0.35),  # 0.15 from the left wall, 0.35 from the back
    "color": (1.0, 1.0, 1.0),
    "intensity": 0.05,
}

#: Lambertian materials: baseColorFactor (linear RGB) is the diffuse albedo.
MATERIALS = [
    {"name": "White", "color": (0.725, 0.71, 0.68)},
    {"name": "Red", "color": (0.63, 0.065, 0.05)},
    {"name": "Green", "color": (0.14, 0.45, 0.091)},
    {"name": "Light", "color": (0.78, 0.78, 0.78),
     "emissive_factor": EMISSIVE_FACTOR, "emissive_strength": EMISSIVE_STRENGTH},
]

# Classic Cornell block tops (mm, classic coordinates); the blocks stand on the floor.
_SHORT_BLOCK_TOP = [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0),
                    (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)]
_TALL_BLOCK_TOP = [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0),
                   (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)]


def classic_to_scene(p):
    """Classic Cornell millimetre coordinates -> this scene's metres (a rotation about Y)."""
    x, y, z = p
    return (WIDTH - x / 1000.0, y / 1000.0, -z / 1000.0)


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _normalize(a):
    n = math.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def _quad(corners, facing):
    """A planar quad (4 corners in order around it) as 2 triangles whose front face
    (counter-clockwise winding) has its normal along `facing` (any vector on that side).
    Returns (positions, normals, indices) with local indices 0..3."""
    corners = [tuple(float(c) for c in p) for p in corners]
    n = _cross(_sub(corners[1], corners[0]), _sub(corners[2], corners[0]))
    if _dot(n, facing) < 0.0:
        corners = corners[::-1]
        n = (-n[0], -n[1], -n[2])
    n = _normalize(n)
    return corners, [n] * 4, [0, 1, 2, 0, 2, 3]


def _merge(quads):
    positions, normals, indices = [], [], []
    for p, n, idx in quads:
        base = len(positions)
        positions += p
        normals += n
        indices += [base + i for i in idx]
    return positions, normals, indices


def _block(top_classic):
    """A block standing on the floor from its 4 classic top corners: top + 4 sides, facing out."""
    top = [classic_to_scene(p) for p in top_classic]
    bottom = [(p[0], 0.0, p[2]) for p in top]
    cx = sum(p[0] for p in top) / 4.0
    cz = sum(p[2] for p in top) / 4.0
    quads = [_quad(top, (0.0, 1.0, 0.0))]
    for i in range(4):
        j = (i + 1) % 4
        side = [bottom[i], bottom[j], top[j], top[i]]
        mx = (top[i][0] + top[j][0]) / 2.0
        mz = (top[i][2] + top[j][2]) / 2.0
        quads.append(_quad(side, (mx - cx, 0.0, mz - cz)))
    return _merge(quads)


def _box_faces():
    W, H, D = WIDTH, HEIGHT, DEPTH
    floor = _quad([(0, 0, 0), (W, 0, 0), (W, 0, -D), (0, 0, -D)], (0, 1, 0))
    ceiling = _quad([(0, H, 0), (W, H, 0), (W, H, -D), (0, H, -D)], (0, -1, 0))
    back = _quad([(0, 0, -D), (W, 0, -D), (W, H, -D), (0, H, -D)], (0, 0, 1))
    left = _quad([(0, 0, 0), (0, 0, -D), (0, H, -D), (0, H, 0)], (1, 0, 0))
    right = _quad([(W, 0, 0), (W, 0, -D), (W, H, -D), (W, H, 0)], (-1, 0, 0))
    return floor, ceiling, back, left, right


def _light_quad():
    (x0, x1), (z0, z1), y = AREA_LIGHT_X, AREA_LIGHT_Z, AREA_LIGHT_Y
    return _quad([(x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1)], (0, -1, 0))


def meshes():
    """The scene's objects: list of dicts {name, material (index into MATERIALS),
    positions [(x,y,z)], normals [(x,y,z)], indices [int] (triangles, CCW = front)}."""
    floor, ceiling, back, left, right = _box_faces()
    objects = [
        ("Floor", 0, _merge([floor])),
        ("Ceiling", 0, _merge([ceiling])),
        ("BackWall", 0, _merge([back])),
        ("LeftWall", 1, _merge([left])),
        ("RightWall", 2, _merge([right])),
        ("ShortBlock", 0, _block(_SHORT_BLOCK_TOP)),
        ("TallBlock", 0, _block(_TALL_BLOCK_TOP)),
        ("AreaLight", 3, _merge([_light_quad()])),
    ]
    return [{"name": n, "material": m, "positions": p, "normals": nn, "indices": i}
            for n, m, (p, nn, i) in objects]


def scene():
    """Everything a renderer needs, as plain data."""
    return {"meshes": meshes(), "materials": MATERIALS, "camera": CAMERA,
            "point_lights": [POINT_LIGHT]}


def area_light_radiance():
    return tuple(f * EMISSIVE_STRENGTH for f in EMISSIVE_FACTOR)


# ---------------------------------------------------------------------------------------
# glTF / GLB writing
# ---------------------------------------------------------------------------------------

FLOAT, UINT16, UINT32 = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def build_gltf(sc):
    """Return (gltf_json_dict, bin_bytes)."""
    bin_data = bytearray()
    buffer_views, accessors = [], []

    def add_view(data, target):
        while len(bin_data) % 4:
            bin_data.append(0)
        buffer_views.append({"buffer": 0, "byteOffset": len(bin_data),
                             "byteLength": len(data), "target": target})
        bin_data.extend(data)
        return len(buffer_views) - 1

    def add_vec3(vectors, with_bounds):
        data = b"".join(struct.pack("<3f", *v) for v in vectors)
        acc = {"bufferView": add_view(data, ARRAY_BUFFER), "componentType": FLOAT,
               "count": len(vectors), "type": "VEC3"}
        if with_bounds:
            # min/max of the values as stored (float32)
            stored = [struct.unpack("<3f", struct.pack("<3f", *v)) for v in vectors]
            acc["min"] = [min(v[k] for v in stored) for k in range(3)]
            acc["max"] = [max(v[k] for v in stored) for k in range(3)]
        accessors.append(acc)
        return len(accessors) - 1

    def add_indices(indices, vertex_count):
        ctype, fmt = (UINT16, "<H") if vertex_count <= 65535 else (UINT32, "<I")
        data = b"".join(struct.pack(fmt, i) for i in indices)
        accessors.append({"bufferView": add_view(data, ELEMENT_ARRAY_BUFFER),
                          "componentType": ctype, "count": len(indices), "type": "SCALAR",
                          "min": [min(indices)], "max": [max(indices)]})
        return len(accessors) - 1

    materials = []
    for m in sc["materials"]:
        mat = {
            "name": m["name"],
            "pbrMetallicRoughness": {"baseColorFactor": list(m["color"]) + [1.0],
                                     "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "doubleSided": False,
            "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
        }
        if "emissive_factor" in m:
            mat["emissiveFactor"] = list(m["emissive_factor"])
            mat["extensions"]["KHR_materials_emissive_strength"] = {
                "emissiveStrength": m["emissive_strength"]}
        materials.append(mat)

    gl_meshes, nodes = [], []
    for obj in sc["meshes"]:
        pos = add_vec3(obj["positions"], True)
        nrm = add_vec3(obj["normals"], False)
        idx = add_indices(obj["indices"], len(obj["positions"]))
        gl_meshes.append({"name": obj["name"], "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx,
            "material": obj["material"], "mode": 4}]})
        nodes.append({"name": obj["name"], "mesh": len(gl_meshes) - 1})

    cam = sc["camera"]
    assert cam["forward"] == (0.0, 0.0, -1.0) and cam["up"] == (0.0, 1.0, 0.0), \
        "camera node has no rotation: it looks along -Z with +Y up"
    cameras = [{"name": cam["name"], "type": "perspective", "perspective": {
        "aspectRatio": cam["aspect"], "yfov": math.radians(cam["yfov_deg"]),
        "znear": cam["znear"], "zfar": cam["zfar"]}}]
    nodes.append({"name": cam["name"], "camera": 0, "translation": list(cam["eye"])})

    lights = []
    for i, pl in enumerate(sc["point_lights"]):
        lights.append({"name": pl["name"], "type": "point", "color": list(pl["color"]),
                       "intensity": pl["intensity"]})
        nodes.append({"name": pl["name"], "translation": list(pl["position"]),
                      "extensions": {"KHR_lights_punctual": {"light": i}}})

    while len(bin_data) % 4:
        bin_data.append(0)
    gltf = {
        "asset": {"version": "2.0", "generator": "penumbra scripts/cornell_box.py",
                  "copyright": "Cornell box data: Cornell University Program of Computer "
                               "Graphics (public), simplified"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                           "KHR_materials_specular"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "CornellBox", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": materials,
        "cameras": cameras,
        "accessors": accessors,
        "bufferViews": buffer_views,
        "buffers": [{"byteLength": len(bin_data)}],
    }
    return gltf, bytes(bin_data)


def glb_bytes(gltf, bin_data):
    js = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    bin_data = bin_data + b"\0" * (-len(bin_data) % 4)
    total = 12 + 8 + len(js) + 8 + len(bin_data)
    out = bytearray()
    out += struct.pack("<4sII", b"glTF", 2, total)
    out += struct.pack("<I4s", len(js), b"JSON") + js
    out += struct.pack("<I4s", len(bin_data), b"BIN\0") + bin_data
    assert len(out) == total
    return bytes(out)


def write_glb(path, gltf, bin_data):
    out = glb_bytes(gltf, bin_data)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "wb") as f:
        f.write(out)
    return len(out)


def file_is_current(path):
    """True when `path` is byte-identical to what this script would write now."""
    try:
        with open(path, "rb") as f:
            return f.read() == glb_bytes(*build_gltf(scene()))
    except OSError:
        return False


# ---------------------------------------------------------------------------------------
# GLB reading / validation (independent of the writer above)
# ---------------------------------------------------------------------------------------

def read_glb(path):
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2, "not a GLB v2"
    assert length == len(data), f"header length {length} != file size {len(data)}"
    off = 12
    chunks = []
    while off < length:
        clen, ctype = struct.unpack_from("<I4s", data, off)
        assert clen % 4 == 0, "chunk length not 4-byte aligned"
        chunks.append((ctype, data[off + 8: off + 8 + clen]))
        off += 8 + clen
    assert off == length
    assert chunks[0][0] == b"JSON" and chunks[1][0] == b"BIN\0" and len(chunks) == 2
    gltf = json.loads(chunks[0][1].decode("utf-8"))
    return gltf, chunks[1][1]


_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_CFMT = {FLOAT: "f", UINT16: "H", UINT32: "I", 5121: "B"}


def read_accessor(gltf, bin_data, index):
    acc = gltf["accessors"][index]
    view = gltf["bufferViews"][acc["bufferView"]]
    n = _NCOMP[acc["type"]]
    fmt = _CFMT[acc["componentType"]]
    size = struct.calcsize("<" + fmt)
    stride = view.get("byteStride", n * size)
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    assert start % size == 0, "accessor not aligned to its component size"
    end = start + stride * (acc["count"] - 1) + n * size
    assert end <= view.get("byteOffset", 0) + view["byteLength"] <= len(bin_data)
    out = [struct.unpack_from("<%d%s" % (n, fmt), bin_data, start + i * stride)
           for i in range(acc["count"])]
    return out if n > 1 else [v[0] for v in out]


def validate(path, verbose=True):
    """Re-read the GLB and check its structure, bounds, winding against normals, and the
    expected camera/lights/materials. Raises AssertionError on any problem."""
    gltf, bin_data = read_glb(path)
    assert gltf["buffers"][0]["byteLength"] <= len(bin_data)
    for ext in gltf.get("extensionsRequired", []):
        assert ext in gltf["extensionsUsed"]
    tris = 0
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    node_of_mesh = {n["mesh"]: n for n in gltf["nodes"] if "mesh" in n}
    for mi_, mesh in enumerate(gltf["meshes"]):
        node = node_of_mesh[mi_]
        assert not any(k in node for k in ("translation", "rotation", "scale", "matrix")), \
            "mesh nodes carry no transform"
        for prim in mesh["primitives"]:
            assert prim.get("mode", 4) == 4
            pa = prim["attributes"]["POSITION"]
            pos = read_accessor(gltf, bin_data, pa)
            nrm = read_accessor(gltf, bin_data, prim["attributes"]["NORMAL"])
            idx = read_accessor(gltf, bin_data, prim["indices"])
            acc = gltf["accessors"][pa]
            for k in range(3):
                assert acc["min"][k] == min(p[k] for p in pos), "POSITION min"
                assert acc["max"][k] == max(p[k] for p in pos), "POSITION max"
                lo[k] = min(lo[k], acc["min"][k])
                hi[k] = max(hi[k], acc["max"][k])
            assert len(pos) == len(nrm)
            assert len(idx) % 3 == 0 and max(idx) < len(pos)
            for n in nrm:
                assert abs(_dot(n, n) - 1.0) < 1e-5, "unit normals"
            mat = gltf["materials"][prim["material"]]
            for t in range(0, len(idx), 3):
                a, b, c = (pos[idx[t]], pos[idx[t + 1]], pos[idx[t + 2]])
                g = _cross(_sub(b, a), _sub(c, a))
                area2 = math.sqrt(_dot(g, g))
                assert area2 > 1e-8, "degenerate triangle"
                g = (g[0] / area2, g[1] / area2, g[2] / area2)
                for v in idx[t:t + 3]:
                    assert _dot(g, nrm[v]) > 0.999, \
                        f"{mesh['name']}: winding disagrees with NORMAL"
                # Front faces face the interior (room) or the outside (blocks)
                centroid = tuple((a[k] + b[k] + c[k]) / 3 for k in range(3))
                if mesh["name"] in ("ShortBlock", "TallBlock"):
                    top = [p for p in pos if p[1] > 0.01]
                    ctr = (sum(p[0] for p in top) / len(top), centroid[1],
                           sum(p[2] for p in top) / len(top))
                    if g[1] < 0.5:
                        assert _dot(g, _sub(centroid, ctr)) > 0, "block face points inward"
                    else:
                        assert g[1] > 0.999, "block top must face up"
                elif mesh["name"] == "AreaLight":
                    assert g[1] < -0.999, "area light must face down"
                    assert "emissiveFactor" in mat
                else:
                    room_ctr = (WIDTH / 2, HEIGHT / 2, -DEPTH / 2)
                    assert _dot(g, _sub(room_ctr, centroid)) > 0, "wall faces outward"
            tris += len(idx) // 3
    for m in gltf["materials"]:
        pbr = m["pbrMetallicRoughness"]
        assert pbr["metallicFactor"] == 0.0 and pbr["roughnessFactor"] == 1.0
        assert m["extensions"]["KHR_materials_specular"]["specularFactor"] == 0.0
        assert m.get("doubleSided", False) is False
    cam_nodes = [n for n in gltf["nodes"] if "camera" in n]
    assert len(cam_nodes) == 1
    cam = gltf["cameras"][cam_nodes[0]["camera"]]
    light_nodes = [n for n in gltf["nodes"] if "KHR_lights_punctual" in n.get("extensions", {})]
    lights = gltf["extensions"]["KHR_lights_punctual"]["lights"]
    for n in light_nodes:
        p = n["translation"]
        assert 0 < p[0] < WIDTH and 0 < p[1] < HEIGHT and -DEPTH < p[2] < 0, "light inside room"
    emissive = [m for m in gltf["materials"] if "emissiveFactor" in m]
    if verbose:
        size = os.path.getsize(path)
        print(f"{path}: {size} bytes, OK")
        print(f"  meshes: {len(gltf['meshes'])}, triangles: {tris}, "
              f"bounds: min {[round(v, 4) for v in lo]} max {[round(v, 4) for v in hi]}")
        print(f"  camera: eye {cam_nodes[0]['translation']} looking -Z, up +Y, "
              f"yfov {math.degrees(cam['perspective']['yfov']):.4f} deg, "
              f"aspect {cam['perspective']['aspectRatio']}")
        for n in light_nodes:
            L = lights[n["extensions"]["KHR_lights_punctual"]["light"]]
            print(f"  point light '{L['name']}': at {[round(v, 4) for v in n['translation']]}, "
                  f"color {L['color']}, intensity {L['intensity']} W/sr "
                  f"(power {4 * math.pi * L['intensity']:.3f} W per channel)")
        for m in emissive:
            s = m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
            rad = [round(f * s, 4) for f in m["emissiveFactor"]]
            area = (AREA_LIGHT_X[1] - AREA_LIGHT_X[0]) * (AREA_LIGHT_Z[1] - AREA_LIGHT_Z[0])
            print(f"  area light '{m['name']}': {AREA_LIGHT_X[1] - AREA_LIGHT_X[0]:.3f} x "
                  f"{AREA_LIGHT_Z[1] - AREA_LIGHT_Z[0]:.3f} m at y = {AREA_LIGHT_Y}, facing -Y, "
                  f"radiance {rad} (power {[round(r * area * math.pi, 3) for r in rad]} W)")
    return gltf


def main(argv=None):
    here = os.path.dirname(os.path.abspath(__file__))
    default_out = os.path.join(os.path.dirname(here), "assets", "cornell-box.glb")
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--out", default=default_out, help="output .glb path")
    ap.add_argument("--check", action="store_true", help="only validate an existing file")
    args = ap.parse_args(argv)
    if not args.check:
        gltf, bin_data = build_gltf(scene())
        write_glb(args.out, gltf, bin_data)
    validate(args.out)
    if args.check and not file_is_current(args.out):
        print(f"  note: {args.out} differs from what this script generates now")
    return 0


if __name__ == "__main__":
    sys.exit(main())
