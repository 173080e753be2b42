#!/usr/bin/env python3
"""Writes the Cornell box (cornell-box.obj and .mtl, written by generate.py) in the interchange
formats photonwave reads, for the tests that render the same box from each and compare per
pixel, and as examples: interchange/cornell-box.gltf (glTF 2.0, buffer embedded as a data URI,
with the camera of cornell-box.toml) and the same as binary glTF (cornell-box.glb) and interchange/*.ply (binary PLY, one file per material)
with interchange/cornell-box-ply.toml. Run from this folder after generate.py:
python3 interchange.py
"""
import base64
import json
import math
import struct

KD = {"white": (0.73, 0.73, 0.73), "red": (0.63, 0.06, 0.05), "green": (0.15, 0.45, 0.09), "light": (0.78, 0.78, 0.78)}
KE = {"light": (15.0, 11.0, 6.0)}
EYE, FOV = (0.0, 0.273, 1.0796), 39.3


def read_obj(path):
    """Triangles per material, fanned as tobj fans OBJ polygons, in file order."""
    verts, groups, material = [], [], None
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append(tuple(float(x) for x in w[1:4]))
        elif w[0] == "usemtl":
            material = w[1]
        elif w[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in w[1:]]
            tris = [(idx[0], idx[i - 1], idx[i]) for i in range(2, len(idx))]
            groups.append((material, [[verts[i] for i in t] for t in tris]))
    return groups


def write_gltf(groups, path):
    """One mesh per OBJ object (each of one material), one node each, and a camera node."""
    names = list(KD)
    blob, meshes, accessors, views, nodes = b"", [], [], [], []
    for k, (material, tris) in enumerate(groups):
        pts = [p for t in tris for p in t]
        data = b"".join(struct.pack("<3f", *p) for p in pts)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        accessors.append({"bufferView": k, "componentType": 5126, "count": len(pts), "type": "VEC3", "min": lo, "max": hi})
        blob += data
        meshes.append({"primitives": [{"attributes": {"POSITION": k}, "material": names.index(material)}]})
        nodes.append({"mesh": k})
    materials = []
    for name in names:
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(KD[name]) + [1.0], "metallicFactor": 0.0,
                                                   "roughnessFactor": 1.0}}
        if name in KE:
            strength = max(KE[name])
            m["emissiveFactor"] = [c / strength for c in KE[name]]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        materials.append(m)
    nodes.append({"name": "camera", "camera": 0, "translation": list(EYE)})
    doc = {
        "asset": {"version": "2.0", "generator": "photonwave scenes/interchange.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(FOV), "znear": 0.01, "aspectRatio": 1.0}}],
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    with open(path, "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")
    # The same model as binary glTF: the buffer moves into the GLB's BIN chunk.
    doc["buffers"] = [{"byteLength": len(blob)}]
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    with open(path.replace(".gltf", ".glb"), "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def write_ply(tris, path):
    """Binary little-endian PLY: shared corners are not merged (each triangle its own three)."""
    head = (f"ply\nformat binary_little_endian 1.0\ncomment photonwave scenes/interchange.py\n"
            f"element vertex {3 * len(tris)}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = b"".join(struct.pack("<3f", *p) for t in tris for p in t)
    body += b"".join(struct.pack("<B3i", 3, 3 * i, 3 * i + 1, 3 * i + 2) for i in range(len(tris)))
    with open(path, "wb") as f:
        f.write(head.encode() + body)


groups = read_obj("cornell-box.obj")
write_gltf(groups, "interchange/cornell-box.gltf")
by_material = {}
for material, tris in groups:
    by_material.setdefault(material, []).extend(tris)
toml = ["# The Cornell box from PLY meshes, one per material (written by scenes/interchange.py)."]
for material, tris in by_material.items():
    write_ply(tris, f"interchange/{material}.ply")
    toml += ["", "[[mesh]]", f'file = "{material}.ply"', f'material = "{material}"']
toml += ["", "[camera]", f"eye = [{EYE[0]}, {EYE[1]}, {EYE[2]}]", "target = [0.0, 0.273, 0.0]", f"fov = {FOV}"]
for material in by_material:
    toml += ["", f"[materials.{material}]", 'type = "lambert"', "kd = [%s]" % ", ".join(str(c) for c in KD[material])]
    if material in KE:
        toml.append("emission = [%s]" % ", ".join(str(c) for c in KE[material]))
toml += ["", "[render]", "width = 320", "height = 320", "spp = 16"]
with open("interchange/cornell-box-ply.toml", "w") as f:
    f.write("\n".join(toml) + "\n")

