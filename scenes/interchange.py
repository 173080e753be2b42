#!/usr/bin/env python3
"""Writes the Cornell box (cornell-box.obj and .mtl, written by generate.py) in the interchange
formats photonwave reads, for the tests that render the same box from each and compare per
pixel, and as examples: interchange/cornell-box.gltf (glTF 2.0, buffer embedded as a data URI,
with the camera of cornell-box.toml) and the same as binary glTF (cornell-box.glb) and interchange/*.ply (binary PLY, one file per material)
with interchange/cornell-box-ply.toml, and a Mitsuba scene over those (interchange/cornell-box.xml). Run from this folder after generate.py:
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

# The same box as a Mitsuba 0.6 scene over the PLY meshes (camelCase names, as Bitterli's
# scenes write them; photonwave reads 3.x's snake_case too).
xml = ['<?xml version="1.0" encoding="utf-8"?>',
       "<!-- The Cornell box as a Mitsuba scene, written by scenes/interchange.py. -->",
       '<scene version="0.6.0">',
       '\t<default name="spp" value="16"/>',
       '\t<integrator type="path"/>',
       '\t<sensor type="perspective">',
       f'\t\t<float name="fov" value="{FOV}"/>',
       '\t\t<string name="fovAxis" value="y"/>',
       '\t\t<transform name="toWorld">',
       f'\t\t\t<lookat origin="{EYE[0]}, {EYE[1]}, {EYE[2]}" target="0, 0.273, 0" up="0, 1, 0"/>',
       "\t\t</transform>",
       '\t\t<sampler type="independent"><integer name="sampleCount" value="$spp"/></sampler>',
       '\t\t<film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="320"/></film>',
       "\t</sensor>"]
for material in by_material:
    xml.append(f'\t<bsdf type="diffuse" id="{material}"><rgb name="reflectance" value="%s"/></bsdf>'
               % ", ".join(str(c) for c in KD[material]))
for material in by_material:
    xml += ['\t<shape type="ply">', f'\t\t<string name="filename" value="{material}.ply"/>', f'\t\t<ref id="{material}"/>']
    if material in KE:
        xml.append('\t\t<emitter type="area"><rgb name="radiance" value="%s"/></emitter>' % ", ".join(str(c) for c in KE[material]))
    xml.append("\t</shape>")
xml.append("</scene>")
with open("interchange/cornell-box.xml", "w") as f:
    f.write("\n".join(xml) + "\n")


# ---- gallery scenes: what the readers do beyond the plain box ---------------------------------

def uv_sphere(centre, radius, seg=48, rings=24):
    """Positions, normals and triangles (counter-clockwise seen from outside) of a UV sphere."""
    pos, nrm, tris = [], [], []
    for r in range(rings + 1):
        th = math.pi * r / rings
        for s in range(seg + 1):
            ph = 2 * math.pi * s / seg
            n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            nrm.append(n)
            pos.append(tuple(centre[i] + radius * n[i] for i in range(3)))
    idx = lambda r, s: r * (seg + 1) + s
    for r in range(rings):
        for s in range(seg):
            a, b, c, d = idx(r, s), idx(r, s + 1), idx(r + 1, s + 1), idx(r + 1, s)
            if r != 0:
                tris.append((a, b, c))
            if r != rings - 1:
                tris.append((a, c, d))
    return pos, nrm, tris


def write_pbr_glb(groups, path):
    """The box, a rough gold sphere (metallic 1, roughness 0.3) and a glass sphere
    (KHR_materials_transmission, KHR_materials_ior 1.5) as one GLB with its camera."""
    names = list(KD) + ["gold", "glass"]
    blob, meshes, accessors, views, nodes = b"", [], [], [], []

    def add(data, **acc):
        nonlocal blob
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        accessors.append(dict(bufferView=len(views) - 1, **acc))
        blob += data + b"\0" * (-len(data) % 4)
        return len(accessors) - 1

    def vec3s(pts):
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        return add(b"".join(struct.pack("<3f", *p) for p in pts), componentType=5126, count=len(pts), type="VEC3", min=lo, max=hi)

    for material, tris in groups:
        pts = [p for t in tris for p in t]
        meshes.append({"primitives": [{"attributes": {"POSITION": vec3s(pts)}, "material": names.index(material)}]})
    for material, centre in (("gold", (-0.12, 0.1, -0.1)), ("glass", (0.13, 0.1, 0.08))):
        pos, nrm, tris = uv_sphere((0.0, 0.0, 0.0), 0.1)
        p, n = vec3s(pos), vec3s(nrm)
        i = add(b"".join(struct.pack("<3I", *t) for t in tris), componentType=5125, count=3 * len(tris), type="SCALAR")
        meshes.append({"primitives": [{"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": names.index(material)}]})
        nodes.append({"mesh": len(meshes) - 1, "translation": list(centre), "name": material + " sphere"})
    nodes += [{"mesh": k} for k in range(len(groups))]
    materials = []
    for name in KD:
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(KD[name]) + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}
        if name in KE:
            m["emissiveFactor"] = [c / max(KE[name]) for c in KE[name]]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": max(KE[name])}}
        materials.append(m)
    materials.append({"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.78, 0.41, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3}})
    materials.append({"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
                      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5},
                                     # A solid ball (without a volume glTF's transmission is thin-walled).
                                     "KHR_materials_volume": {"thicknessFactor": 0.2}}})
    nodes.append({"name": "camera", "camera": 0, "translation": list(EYE)})
    doc = {
        "asset": {"version": "2.0", "generator": "photonwave scenes/interchange.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(FOV), "znear": 0.01, "aspectRatio": 1.0}}],
        "meshes": meshes, "materials": materials, "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


# The room alone: the walls, ceiling, floor and light, written first by generate.py's cornell().
room = groups[:6]
write_pbr_glb(room, "interchange/cornell-pbr.glb")
write_ply([t for m, tris in room if m == "white" for t in tris], "interchange/white-room.ply")

# A Mitsuba 3 scene of built-in shapes in the box's walls (the PLY meshes): a rough copper cube
# turned 30 degrees, a rough plastic sphere, a rectangle area light under the ceiling.
walls = {"white": "white-room.ply", "red": "red.ply", "green": "green.ply"}
xml = ['<?xml version="1.0" encoding="utf-8"?>',
       "<!-- Built-in shapes in the Cornell box, a Mitsuba 3 scene written by scenes/interchange.py. -->",
       '<scene version="3.0.0">',
       '\t<sensor type="perspective">',
       f'\t\t<float name="fov" value="{FOV}"/>',
       '\t\t<string name="fov_axis" value="y"/>',
       '\t\t<transform name="to_world">',
       f'\t\t\t<lookat origin="{EYE[0]}, {EYE[1]}, {EYE[2]}" target="0, 0.273, 0" up="0, 1, 0"/>',
       "\t\t</transform>",
       '\t\t<film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="320"/></film>',
       "\t</sensor>"]
for material, ply in walls.items():
    xml += [f'\t<bsdf type="diffuse" id="{material}"><rgb name="reflectance" value="%s"/></bsdf>' % ", ".join(str(c) for c in KD[material]),
            '\t<shape type="ply">', f'\t\t<string name="filename" value="{ply}"/>', f'\t\t<ref id="{material}"/>', "\t</shape>"]
xml += ['\t<shape type="cube">',
        '\t\t<transform name="to_world"><scale value="0.08"/><rotate y="1" angle="30"/><translate x="-0.1" y="0.08" z="-0.08"/></transform>',
        '\t\t<bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.15"/>'
        '<string name="distribution" value="ggx"/></bsdf>',
        "\t</shape>",
        '\t<shape type="sphere">',
        '\t\t<point name="center" x="0.12" y="0.1" z="0.08"/><float name="radius" value="0.1"/>',
        '\t\t<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.5"/><float name="alpha" value="0.1"/>'
        '<string name="distribution" value="ggx"/></bsdf>',
        "\t</shape>",
        '\t<shape type="rectangle">',
        '\t\t<transform name="to_world"><scale x="0.065" y="0.0525"/><rotate x="1" angle="90"/><translate y="0.5487"/></transform>',
        '\t\t<bsdf type="diffuse"><rgb name="reflectance" value="0.78"/></bsdf>',
        '\t\t<emitter type="area"><rgb name="radiance" value="15, 11, 6"/></emitter>',
        "\t</shape>",
        "</scene>"]
with open("interchange/cornell-shapes.xml", "w") as f:
    f.write("\n".join(xml) + "\n")

# The same room as Mitsuba's defaults would have it, with an absorbing interior and a smooth
# plastic: the cube and the sphere without a `distribution` (Beckmann, Mitsuba's default), a
# block of tinted glass (a `homogeneous` interior medium of albedo 0, σ_t = 12·(1, ⅓, ⅔) per
# metre) standing in front, and a smooth `plastic` ball hanging by the red wall.
media = [line.replace('<string name="distribution" value="ggx"/>', "") for line in xml[:-1]]
media[1] = "<!-- The gallery room with Beckmann microfacets, absorbing glass and smooth plastic, written by scenes/interchange.py. -->"
media += ['\t<shape type="cube">',
          '\t\t<transform name="to_world"><scale x="0.07" y="0.09" z="0.04"/><rotate y="1" angle="-20"/><translate y="0.095" z="0.2"/></transform>',
          '\t\t<bsdf type="dielectric"/>',
          '\t\t<medium name="interior" type="homogeneous"><rgb name="sigma_t" value="1, 0.3333333, 0.6666667"/>'
          '<float name="scale" value="12"/><float name="albedo" value="0"/></medium>',
          "\t</shape>",
          '\t<shape type="sphere">',
          '\t\t<point name="center" x="-0.16" y="0.32" z="0.02"/><float name="radius" value="0.07"/>',
          '\t\t<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.7, 0.6, 0.15"/><boolean name="nonlinear" value="true"/></bsdf>',
          "\t</shape>",
          "</scene>"]
with open("interchange/cornell-media.xml", "w") as f:
    f.write("\n".join(media) + "\n")
