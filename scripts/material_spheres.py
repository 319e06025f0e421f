#!/usr/bin/env python3
"""Write a small glTF of material test spheres for one material extension.

Standard library only. A row of five smooth UV spheres (normals, TEXCOORD_0), each with one
setting of the extension, a camera in front of them and no lights (penumbra then lights them
with its studio environment, or with `--sky 1` as a white furnace):

    python3 scripts/material_spheres.py anisotropy -o aniso.gltf
    python3 scripts/material_spheres.py iridescence -o film.gltf
    python3 scripts/material_spheres.py diffuse_transmission -o leaf.gltf
    python3 scripts/material_spheres.py dispersion -o prism.gltf
    penumbra render aniso.gltf -o aniso.png --width 500 --height 120 --spp 64

The spheres are held-out fixtures for docs/materials.md: made here, never copied from the shared
scenes.
"""

import argparse
import base64
import json
import math
import struct


def sphere(rings=48, segments=96):
    pos, nrm, uv, idx = [], [], [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2.0 * math.pi * s / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            pos.append(n)
            nrm.append(n)
            uv.append((s / segments, r / rings))
    w = segments + 1
    for r in range(rings):
        for s in range(segments):
            a = r * w + s
            b = a + w
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, uv, idx


def materials(ext):
    """(name, material JSON) for the five spheres."""
    out = []
    if ext == "anisotropy":
        for k, (strength, rotation) in enumerate(
            [(0.0, 0.0), (0.4, 0.0), (0.8, 0.0), (1.0, 0.0), (0.8, math.pi / 2)]
        ):
            out.append(
                {
                    "name": f"anisotropy {strength} rotation {rotation:.2f}",
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [0.95, 0.64, 0.54, 1.0],
                        "metallicFactor": 1.0,
                        "roughnessFactor": 0.25,
                    },
                    "extensions": {
                        "KHR_materials_anisotropy": {
                            "anisotropyStrength": strength,
                            "anisotropyRotation": rotation,
                        }
                    },
                }
            )
    elif ext == "iridescence":
        for thickness, ior, metal in [(0, 1.3, 0), (250, 1.3, 0), (400, 1.3, 0), (600, 1.8, 0), (350, 1.5, 1)]:
            out.append(
                {
                    "name": f"film {ior} {thickness} nm",
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [0.05, 0.05, 0.05, 1.0] if not metal else [0.9, 0.9, 0.9, 1.0],
                        "metallicFactor": float(metal),
                        "roughnessFactor": 0.15,
                    },
                    "extensions": {
                        "KHR_materials_iridescence": {
                            "iridescenceFactor": 1.0,
                            "iridescenceIor": ior,
                            "iridescenceThicknessMaximum": thickness,
                        }
                    },
                }
            )
    elif ext == "diffuse_transmission":
        for factor in [0.0, 0.25, 0.5, 0.75, 1.0]:
            out.append(
                {
                    "name": f"diffuse transmission {factor}",
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [0.9, 0.9, 0.9, 1.0],
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.6,
                    },
                    "extensions": {
                        "KHR_materials_diffuse_transmission": {
                            "diffuseTransmissionFactor": factor,
                            "diffuseTransmissionColorFactor": [1.0, 0.5, 0.2],
                        }
                    },
                }
            )
    elif ext == "dispersion":
        # Clear glass balls of ior 1.7: none, crown glass (Abbe 59), polycarbonate (32), Abbe 20
        # and rutile (9.8).
        for dispersion in [0.0, 0.33, 0.625, 1.0, 2.04]:
            out.append(
                {
                    "name": f"dispersion {dispersion}",
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.0,
                    },
                    "extensions": {
                        "KHR_materials_dispersion": {"dispersion": dispersion},
                        "KHR_materials_ior": {"ior": 1.7},
                        "KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_volume": {"thicknessFactor": 2.0},
                    },
                }
            )
    else:
        raise SystemExit(f"unknown extension {ext}")
    return out


def write(ext, path):
    pos, nrm, uv, idx = sphere()
    blob = b"".join(struct.pack("<3f", *p) for p in pos)
    blob += b"".join(struct.pack("<3f", *n) for n in nrm)
    blob += b"".join(struct.pack("<2f", *t) for t in uv)
    blob += struct.pack(f"<{len(idx)}I", *idx)
    n = len(pos)
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 12 * n},
        {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12 * n},
        {"buffer": 0, "byteOffset": 24 * n, "byteLength": 8 * n},
        {"buffer": 0, "byteOffset": 32 * n, "byteLength": 4 * len(idx)},
    ]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
         "min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]},
        {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": n, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    mats = materials(ext)
    meshes = [
        {"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                         "indices": 3, "material": k}]}
        for k in range(len(mats))
    ]
    nodes = [{"mesh": k, "translation": [2.3 * (k - 2), 0.0, 0.0]} for k in range(len(mats))]
    nodes.append({"camera": 0, "translation": [0.0, 0.0, 14.0]})
    doc = {
        "asset": {"version": "2.0", "generator": "penumbra scripts/material_spheres.py"},
        "extensionsUsed": sorted({e for m in mats for e in m.get("extensions", {})}),
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.2, "aspectRatio": 4.0, "znear": 0.1}}],
        "meshes": meshes,
        "materials": mats,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    with open(path, "w") as f:
        json.dump(doc, f)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("extension", choices=["anisotropy", "iridescence", "diffuse_transmission", "dispersion"])
    p.add_argument("-o", "--output", required=True)
    a = p.parse_args()
    write(a.extension, a.output)


if __name__ == "__main__":
    main()
