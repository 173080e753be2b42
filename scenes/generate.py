#!/usr/bin/env python3
"""Writes photonwave's bundled scenes (OBJ + MTL; the interior as a Mitsuba file). Run from this folder: python3 generate.py

Geometry of the Cornell box is the measured data published by the Cornell Program of Computer
Graphics (dimensions in mm: a 556 x 548.8 x 559.2 room, a 130 x 105 light, two blocks),
converted to metres and turned 180 degrees about y so that the camera looks down -z:
x' = (278 - x)/1000, y' = y/1000, z' = (279.6 - z)/1000. Colours are rounded RGB reflectances.
Every face is wound counter-clockwise as seen from the side it faces (walls into the room,
blocks outward, the light downward), because emission leaves the front face only.
"""
import math

def conv(p):
    x, y, z = p
    return ((278.0 - x) / 1000.0, y / 1000.0, (279.6 - z) / 1000.0)

def sub(a, b): return tuple(a[i] - b[i] for i in range(3))
def cross(a, b): return (a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0])
def dot(a, b): return sum(a[i]*b[i] for i in range(3))

class Obj:
    def __init__(self, mtl, convert=conv):
        """`convert` maps quad corners to metres (the Cornell conversion unless told otherwise)."""
        self.lines = [f"# photonwave bundled scene, written by scenes/generate.py", f"mtllib {mtl}"]
        self.nv = 0
        self.nn = 0
        self.convert = convert

    def quad(self, name, material, pts, facing):
        """A planar polygon whose normal is turned toward `facing` (a direction)."""
        pts = [self.convert(p) for p in pts]
        n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
        if dot(n, facing) < 0:
            pts = pts[::-1]
        self.lines.append(f"o {name}")
        self.lines.append(f"usemtl {material}")
        for p in pts:
            self.lines.append("v %.6f %.6f %.6f" % p)
        k = len(pts)
        self.lines.append("f " + " ".join(str(self.nv + 1 + i) for i in range(k)))
        self.nv += k

    def sphere(self, name, material, centre, radius, inward=False, seg=48, rings=24):
        """A UV sphere with vertex normals; front faces outward (or inward)."""
        self.lines.append(f"o {name}")
        self.lines.append(f"usemtl {material}")
        self.lines.append("s 1")
        base_v, base_n = self.nv, self.nn
        verts = []
        for r in range(rings + 1):
            th = math.pi * r / rings
            for s in range(seg + 1):
                ph = 2 * math.pi * s / seg
                n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
                verts.append(n)
        for n in verts:
            self.lines.append("v %.6f %.6f %.6f" % tuple(centre[i] + radius * n[i] for i in range(3)))
        for n in verts:
            m = tuple(-c for c in n) if inward else n
            self.lines.append("vn %.6f %.6f %.6f" % m)
        self.nv += len(verts)
        self.nn += len(verts)
        idx = lambda r, s: r * (seg + 1) + s + 1
        for r in range(rings):
            for s in range(seg):
                a, b, c, d = idx(r, s), idx(r, s + 1), idx(r + 1, s + 1), idx(r + 1, s)
                tris = [(a, b, c), (a, c, d)]
                if r == 0:
                    tris = [(a, c, d)]          # pole: (a, b) coincide
                elif r == rings - 1:
                    tris = [(a, b, c)]          # pole: (c, d) coincide
                for t in tris:
                    if inward:
                        t = t[::-1]
                    self.lines.append("f " + " ".join(f"{base_v + i}//{base_n + i}" for i in t))

    def box(self, name, material, lo, hi):
        """An axis-aligned box, six quads facing outward."""
        c = tuple((lo[i] + hi[i]) / 2 for i in range(3))
        for axis in range(3):
            for side, v in (("lo", lo[axis]), ("hi", hi[axis])):
                u, w = (axis + 1) % 3, (axis + 2) % 3
                pts = []
                for a, b in ((lo[u], lo[w]), (hi[u], lo[w]), (hi[u], hi[w]), (lo[u], hi[w])):
                    p = [0.0, 0.0, 0.0]
                    p[axis], p[u], p[w] = v, a, b
                    pts.append(tuple(p))
                facing = [0.0, 0.0, 0.0]
                facing[axis] = v - c[axis]
                self.quad(f"{name}_{'xyz'[axis]}{side}", material, pts, tuple(facing))

    def write(self, path):
        with open(path, "w") as f:
            f.write("\n".join(self.lines) + "\n")

def mtl(path, materials):
    with open(path, "w") as f:
        f.write("# photonwave bundled materials, written by scenes/generate.py\n")
        for name, body in materials:
            f.write(f"\nnewmtl {name}\n{body.strip()}\n")

def scene_toml(path, comment, mesh, camera, middle="", render_extra=""):
    """Writes a bundled scene file: the comment, one [[mesh]], the [camera], then `middle` (lights,
    materials: TOML text that starts with a blank line) and a 32 x 32 [render] table with
    `render_extra` appended."""
    with open(path, "w") as f:
        f.write(f"{comment}\n[[mesh]]\n{mesh}\n\n[camera]\n{camera}\n{middle}\n[render]\nwidth = 32\nheight = 32\n{render_extra}")

INTO_ROOM = None  # sentinel: walls face the room centre

def cornell(obj, blocks=True):
    centre = (278.0, 274.4, 279.6)
    def wall(name, mat, pts):
        c = tuple(sum(p[i] for p in pts) / len(pts) for i in range(3))
        obj.quad(name, mat, pts, sub(conv(centre), conv(c)))
    wall("floor", "white", [(552.8, 0, 0), (0, 0, 0), (0, 0, 559.2), (549.6, 0, 559.2)])
    wall("ceiling", "white", [(556, 548.8, 0), (556, 548.8, 559.2), (0, 548.8, 559.2), (0, 548.8, 0)])
    wall("back", "white", [(549.6, 0, 559.2), (0, 0, 559.2), (0, 548.8, 559.2), (556, 548.8, 559.2)])
    wall("right", "green", [(0, 0, 559.2), (0, 0, 0), (0, 548.8, 0), (0, 548.8, 559.2)])
    wall("left", "red", [(552.8, 0, 0), (549.6, 0, 559.2), (556, 548.8, 559.2), (556, 548.8, 0)])
    obj.quad("light", "light", [(343, 548.7, 227), (343, 548.7, 332), (213, 548.7, 332), (213, 548.7, 227)], (0, -1, 0))
    if not blocks:
        return
    for name, top, h in [("short_block", [(130, 65), (82, 225), (240, 272), (290, 114)], 165.0),
                         ("tall_block", [(423, 247), (265, 296), (314, 456), (472, 406)], 330.0)]:
        cx = sum(p[0] for p in top) / 4; cz = sum(p[1] for p in top) / 4
        obj.quad(name + "_top", "white", [(x, h, z) for x, z in top], (0, 1, 0))
        for i in range(4):
            (x0, z0), (x1, z1) = top[i], top[(i + 1) % 4]
            mid = conv(((x0 + x1) / 2, h / 2, (z0 + z1) / 2))
            out = sub(mid, conv((cx, h / 2, cz)))
            obj.quad(f"{name}_side{i}", "white", [(x0, 0, z0), (x1, 0, z1), (x1, h, z1), (x0, h, z0)], out)

BOX_MATERIALS = [
    ("white", "illum 1\nKd 0.73 0.73 0.73"),
    ("red", "illum 1\nKd 0.63 0.06 0.05"),
    ("green", "illum 1\nKd 0.15 0.45 0.09"),
    ("light", "illum 1\nKd 0.78 0.78 0.78\nKe 15 11 6"),
]

o = Obj("cornell-box.mtl"); cornell(o); o.write("cornell-box.obj")
mtl("cornell-box.mtl", BOX_MATERIALS)

o = Obj("cornell-spheres.mtl"); cornell(o, blocks=False)
o.sphere("mirror_sphere", "mirror", (-0.12, 0.1, -0.1), 0.1)
o.sphere("glass_sphere", "glass", (0.13, 0.1, 0.08), 0.1)
o.write("cornell-spheres.obj")
mtl("cornell-spheres.mtl", BOX_MATERIALS + [
    ("mirror", "illum 5\nKs 0.95 0.95 0.95"),
    ("glass", "illum 7\nNi 1.5"),
])

# White furnace: a closed sphere of radius 1 whose inside emits Le = 1 and reflects albedo 0.5.
o = Obj("furnace.mtl"); o.sphere("enclosure", "furnace", (0, 0, 0), 1.0, inward=True, seg=32, rings=16)
o.write("furnace.obj")
mtl("furnace.mtl", [("furnace", "illum 1\nKd 0.5 0.5 0.5\nKe 1 1 1")])

# ---- hard cases (scenes/hard/): geometry in metres, no Cornell conversion -------------------

def RawObj(mtl):
    """An Obj whose points are written as given, in metres (no Cornell-box conversion)."""
    return Obj(mtl, convert=lambda p: tuple(float(c) for c in p))

def thin_wall(path):
    """A closed 2 x 1 x 1 room (x in [-1, 1], y in [0, 1], z in [-0.5, 0.5]) split at x = 0 by one
    zero-thickness quad. Every face of the room is split at x = 0 too, so the wall's edges are
    shared edges, not T-junctions. Faces point into their half of the room."""
    o = RawObj("thin-wall.mtl")
    for side, (x0, x1) in [("left", (-1.0, 0.0)), ("right", (0.0, 1.0))]:
        c = ((x0 + x1) / 2, 0.5, 0.0)
        def face(name, pts):
            m = tuple(sum(p[i] for p in pts) / 4 for i in range(3))
            o.quad(f"{side}_{name}", "white", pts, sub(c, m))
        face("floor", [(x0, 0, -0.5), (x1, 0, -0.5), (x1, 0, 0.5), (x0, 0, 0.5)])
        face("ceiling", [(x0, 1, -0.5), (x1, 1, -0.5), (x1, 1, 0.5), (x0, 1, 0.5)])
        face("back", [(x0, 0, -0.5), (x1, 0, -0.5), (x1, 1, -0.5), (x0, 1, -0.5)])
        face("front", [(x0, 0, 0.5), (x1, 0, 0.5), (x1, 1, 0.5), (x0, 1, 0.5)])
        end = x0 if side == "left" else x1
        face("end", [(end, 0, -0.5), (end, 0, 0.5), (end, 1, 0.5), (end, 1, -0.5)])
    o.quad("divider", "white", [(0, 0, -0.5), (0, 0, 0.5), (0, 1, 0.5), (0, 1, -0.5)], (-1, 0, 0))
    o.write(path)
    mtl(path.replace(".obj", ".mtl"), [("white", "illum 1\nKd 0.73 0.73 0.73")])

import os
os.makedirs("hard", exist_ok=True)
thin_wall("hard/thin-wall.obj")

def closed_room(folder):
    """Back-to-back surfaces: a closed 2 x 1.2 x 2 room (x, z in [-1, 1], y in [0, 1.2]) of
    zero-thickness walls (single quads facing in), lit inside by a 0.5 x 0.5 ceiling panel 1 cm
    below the ceiling (a gap f32 keeps where tests/hard.rs moves the room 3.7e4 out, whose spacing
    there is 2 mm: at 1 mm the panel fell into the ceiling's plane and was hidden where the two
    met), with a box on the floor. Three variants: the room alone (room.obj); the same room far above a 10 x 10
    ground lit by a sun (room-sunlit: ground at y = -4); and the same room 1 cm above the sunlit
    ground (room-on-ground: a floor thinner than any search radius). Nothing outside can reach the
    inside, so the inside must render the same in all three. The sun's power (its irradiance over
    the disk of the scene's bounding sphere, 37 W against the panel's 4.7 W) takes 89 % of the
    photons and of the light samples chosen by power: the inside holds fewer photons, which tests
    must allow for; everything else must be the same."""
    def room(o):
        c = (0.0, 0.6, 0.0)
        def face(name, pts):
            m = tuple(sum(p[i] for p in pts) / 4 for i in range(3))
            o.quad(name, "floor" if name == "floor" else "wall", pts, sub(c, m))
        face("floor", [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)])
        face("ceiling", [(-1, 1.2, -1), (1, 1.2, -1), (1, 1.2, 1), (-1, 1.2, 1)])
        face("back", [(-1, 0, -1), (1, 0, -1), (1, 1.2, -1), (-1, 1.2, -1)])
        face("front", [(-1, 0, 1), (1, 0, 1), (1, 1.2, 1), (-1, 1.2, 1)])
        face("left", [(-1, 0, -1), (-1, 0, 1), (-1, 1.2, 1), (-1, 1.2, -1)])
        face("right", [(1, 0, -1), (1, 0, 1), (1, 1.2, 1), (1, 1.2, -1)])
        o.quad("panel", "light", [(-0.25, 1.19, -0.25), (0.25, 1.19, -0.25), (0.25, 1.19, 0.25), (-0.25, 1.19, 0.25)], (0, -1, 0))
        o.box("box", "box", (0.1, 0.0, -0.6), (0.6, 0.5, -0.1))
    materials = [("wall", "illum 1\nKd 0.7 0.7 0.7"), ("floor", "illum 1\nKd 0.5 0.45 0.4"),
                 ("box", "illum 1\nKd 0.3 0.5 0.7"), ("light", "illum 1\nKd 0 0 0\nKe 6 6 6"),
                 ("ground", "illum 1\nKd 0.5 0.5 0.5")]
    camera = """eye = [-0.8, 0.9, 0.9]
target = [0.3, 0.3, -0.6]
fov = 60"""
    sun = """
[[light]]
type = "sun"
direction = [-0.3, -1.0, -0.4]
irradiance = [0.2, 0.2, 0.2]
"""
    comments = {
        "room": """# Back-to-back surfaces, written by scenes/generate.py: a closed room of zero-thickness walls
# lit by a ceiling panel, alone. With a sun outside (room-sunlit.toml, room-on-ground.toml) the
# inside renders the same: no light from outside can reach it (docs/src/hard-cases.md).""",
        "room-sunlit": """# Back-to-back surfaces, written by scenes/generate.py: a closed room of zero-thickness walls
# lit by a ceiling panel, 4 m above a 10 x 10 ground under a sun. No light from outside can
# reach the inside: it renders the same with or without the sun (tests/rooms.rs).""",
        "room-on-ground": """# Back-to-back surfaces, written by scenes/generate.py: a closed room of zero-thickness walls
# lit by a ceiling panel, 1 cm above a 10 x 10 ground under a sun: a floor thinner than any
# search radius. No light from outside can reach the inside: it renders the same with or
# without the sun (tests/rooms.rs).""",
    }
    for name, ground in [("room", None), ("room-sunlit", -4.0), ("room-on-ground", -0.01)]:
        o = RawObj(f"{name}.mtl")
        room(o)
        if ground is not None:
            o.quad("ground", "ground", [(-5, ground, -5), (5, ground, -5), (5, ground, 5), (-5, ground, 5)], (0, 1, 0))
        o.write(f"{folder}/{name}.obj")
        mtl(f"{folder}/{name}.mtl", materials)
        scene_toml(f"{folder}/{name}.toml", comments[name], f'file = "{name}.obj"', camera, sun if ground is not None else "")

closed_room("hard")

def grazing(folder):
    """A 2 x 2 Lambertian plane (kd 0.5) at y = 0 facing +y, seen from straight above, lit by a
    directional light of perpendicular irradiance 1 at theta = 0, 60, 85 and 89 degrees to the
    normal: the plane's irradiance is cos(theta), its radiance 0.5 cos(theta) / pi."""
    o = RawObj("grazing.mtl")
    o.quad("plane", "half", [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], (0, 1, 0))
    o.write(f"{folder}/grazing.obj")
    mtl(f"{folder}/grazing.mtl", [("half", "illum 1\nKd 0.5 0.5 0.5")])
    for deg in (0, 60, 85, 89):
        t = math.radians(deg)
        d = (math.sin(t), -math.cos(t), 0.0)
        scene_toml(f"{folder}/grazing-{deg}.toml", f'''# Grazing light, written by scenes/generate.py: a directional light {deg} degrees from the
# plane's normal. Irradiance on the plane is cos({deg} deg) = {math.cos(t):.6f} of the perpendicular
# irradiance (1), from light sampling and from photons alike; radiance 0.5 x that / pi.''', f'file = "grazing.obj"', f'''eye = [0.0, 1.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 40''', f'''
[[light]]
type = "directional"
direction = [{d[0]:.9f}, {d[1]:.9f}, {d[2]:.1f}]
irradiance = [1, 1, 1]
''')

grazing("hard")

def degenerate_light(folder):
    """A 2 x 2 floor (kd 0.5) under a 0.5 x 0.5 quad light facing down at y = 1; the `-degenerate`
    variant adds a zero-area triangle (three collinear points) to the light's mesh, last."""
    for variant in ("", "-degenerate"):
        name = f"emitter{variant}"
        o = RawObj(f"{name}.mtl")
        o.quad("floor", "half", [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], (0, 1, 0))
        o.quad("light", "light", [(-0.25, 1, -0.25), (0.25, 1, -0.25), (0.25, 1, 0.25), (-0.25, 1, 0.25)], (0, -1, 0))
        if variant:
            o.lines.append("v -0.25 1.0 0.3\nv 0.0 1.0 0.3\nv 0.25 1.0 0.3\nf %d %d %d" % (o.nv + 1, o.nv + 2, o.nv + 3))
            o.nv += 3
        o.write(f"{folder}/{name}.obj")
        mtl(f"{folder}/{name}.mtl", [("half", "illum 1\nKd 0.5 0.5 0.5"), ("light", "illum 1\nKd 0 0 0\nKe 4 4 4")])
        what = ("a quad light over a floor whose mesh also holds a\n# zero-area triangle; it must be "
                "sampled with probability zero and change nothing") if variant else \
               ("a quad light over a floor; the reference for\n# emitter-degenerate.toml, which must "
                "render the same image")
        scene_toml(f"{folder}/{name}.toml", f'# Degenerate emitter, written by scenes/generate.py: {what}.', f'file = "{name}.obj"', f'''eye = [0.0, 0.5, 1.8]
target = [0.0, 0.3, 0.0]
fov = 50''')

degenerate_light("hard")

def light_in_glass(folder):
    """A closed 2 x 2 x 2 white room (kd 0.5) centred on the origin, a glass sphere (n = 1.5,
    radius 0.2) centred on the origin, and (in the TOML) a point light at the origin."""
    o = RawObj("light-in-glass.mtl")
    c = (0.0, 0.0, 0.0)
    for name, pts in [("floor", [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)]),
                      ("ceiling", [(-1, 1, -1), (1, 1, -1), (1, 1, 1), (-1, 1, 1)]),
                      ("back", [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1)]),
                      ("front", [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]),
                      ("left", [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)]),
                      ("right", [(1, -1, -1), (1, -1, 1), (1, 1, 1), (1, 1, -1)])]:
        m = tuple(sum(p[i] for p in pts) / 4 for i in range(3))
        o.quad(name, "white", pts, sub(c, m))
    o.sphere("glass_sphere", "glass", c, 0.2, seg=96, rings=48)
    o.write(f"{folder}/light-in-glass.obj")
    mtl(f"{folder}/light-in-glass.mtl", [("white", "illum 1\nKd 0.5 0.5 0.5"), ("glass", "illum 7\nNi 1.5")])

light_in_glass("hard")

def scaled_cornell(folder):
    """The mirror-and-glass Cornell box (../cornell-spheres.obj) scaled by 1e-4, 1 and 1e5, camera
    scaled with it. Radiance does not change under a uniform scale (the light's radiance is fixed),
    so the three images must agree within noise."""
    for label, s in (("1e-4", 1e-4), ("1", 1.0), ("1e5", 1e5)):
        scene_toml(f"{folder}/scale-{label}.toml", f'''# Scale, written by scenes/generate.py: the Cornell box with a mirror and a glass sphere,
# scaled by {label} (camera too). Ray offsets and search radii are relative to the scene's size, so the
# image must equal scale-1's within noise: no acne, no black rows, no lost caustic.''', f'''file = "../cornell-spheres.obj"
scale = {s:.6g}''', f'''eye = [0.0, {0.273 * s:.6g}, {1.0796 * s:.6g}]
target = [0.0, {0.273 * s:.6g}, 0.0]
fov = 39.3''')

scaled_cornell("hard")

def ball_lens(folder):
    """A glass ball (n = 1.5, radius 1) at the origin; a black plate at z = 1.2 with a 0.2 x 0.2
    hole on the axis, so the directional light (down -z) reaches the ball as a narrow collimated
    beam; behind the ball, a white screen in the plane y = 0 along the axis (z from -1.02 to -2.2).
    Paraxial rays cross the axis at n R / (2 (n - 1)) = 1.5 from the centre, and every ray of the
    beam meets the screen where it crosses the plane y = 0: at the focus."""
    o = RawObj("ball-lens.mtl")
    o.sphere("ball", "glass", (0.0, 0.0, 0.0), 1.0, seg=192, rings=96)
    a, e, z = 0.1, 1.3, 1.2
    for name, (x0, x1, y0, y1) in [("top", (-e, e, a, e)), ("bottom", (-e, e, -e, -a)),
                                   ("left", (-e, -a, -a, a)), ("right", (a, e, -a, a))]:
        o.quad(f"plate_{name}", "black", [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)], (0, 0, 1))
    o.quad("screen", "white", [(-0.3, 0, -1.02), (0.3, 0, -1.02), (0.3, 0, -2.2), (-0.3, 0, -2.2)], (0, 1, 0))
    o.write(f"{folder}/ball-lens.obj")
    mtl(f"{folder}/ball-lens.mtl", [("glass", "illum 7\nNi 1.5"), ("black", "illum 1\nKd 0 0 0"),
                                    ("white", "illum 1\nKd 0.5 0.5 0.5")])
    scene_toml(f"{folder}/ball-lens.toml", '''# Ball lens, written by scenes/generate.py: a collimated beam (a directional light through a
# 0.2 x 0.2 hole in a black plate) through a glass ball (n = 1.5, R = 1) focuses on the axis at
# n R / (2 (n - 1)) = 1.5 from the centre (paraxial), where it meets the screen lying along the axis.''', 'file = "ball-lens.obj"', '''eye = [1.2, 0.8, -1.6]
target = [0.0, 0.0, -1.6]
fov = 50''', '''
[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [1, 1, 1]
''')

ball_lens("hard")

def total_internal_reflection(folder):
    """Two scenes of total internal reflection (n = 1.5, critical angle 41.8 degrees).

    light-pipe: a glass rod (0.5 x 0.5 x 2.5, z from 1 to -1.5) fed at its top end by a narrow spot
    (2 degrees) 30 degrees off the axis; inside, the beam meets the side faces at 70.5 degrees and
    is reflected whole; a white screen at z = -2 catches what leaves the far end.

    tir-slab: a spot inside a glass slab (4 x 0.2 x 1) aimed at its top face 50 degrees from the
    normal, past the critical angle; a white screen 0.01 above the top face must receive nothing."""
    o = RawObj("light-pipe.mtl")
    o.box("rod", "glass", (-0.25, -0.25, -1.5), (0.25, 0.25, 1.0))
    o.quad("screen", "white", [(-1, -1, -2), (1, -1, -2), (1, 1, -2), (-1, 1, -2)], (0, 0, 1))
    o.write(f"{folder}/light-pipe.obj")
    materials = [("glass", "illum 7\nNi 1.5"), ("white", "illum 1\nKd 0.5 0.5 0.5")]
    mtl(f"{folder}/light-pipe.mtl", materials)
    t = math.radians(30)
    scene_toml(f"{folder}/light-pipe.toml", f'''# Light pipe, written by scenes/generate.py: a spot 30 degrees off the axis of a glass rod
# (n = 1.5) lights its near end; inside, the beam meets the side faces at 70.5 degrees, past the
# critical angle (41.8), and is reflected whole. Flux out of the far end = flux in x T(30)^2 / (1 - R(30)^2).''', f'file = "light-pipe.obj"', f'''eye = [1.6, 0.9, -0.2]
target = [0.0, 0.0, -1.9]
fov = 50''', f'''
[[light]]
type = "spot"
position = [0.0, {0.5 * math.sin(t):.9f}, {1.0 + 0.5 * math.cos(t):.9f}]
target = [0.0, 0.0, 1.0]
intensity = [100, 100, 100]
angle = 2
''')
    o = RawObj("tir-slab.mtl")
    o.box("slab", "glass", (-2, 0, -0.5), (2, 0.2, 0.5))
    o.quad("screen", "white", [(-1.9, 0.21, -0.5), (1.9, 0.21, -0.5), (1.9, 0.21, 0.5), (-1.9, 0.21, 0.5)], (0, -1, 0))
    o.write(f"{folder}/tir-slab.obj")
    mtl(f"{folder}/tir-slab.mtl", materials)
    t = math.radians(50)
    scene_toml(f"{folder}/tir-slab.toml", f'''# Total internal reflection, written by scenes/generate.py: a spot inside a glass slab (n = 1.5)
# aimed at the top face 50 degrees from its normal, past the critical angle (41.8): all of it is
# reflected, and the screen just above the slab receives nothing.''', f'file = "tir-slab.obj"', f'''eye = [0.0, 1.5, 2.5]
target = [0.0, 0.1, 0.0]
fov = 50''', f'''
[[light]]
type = "spot"
position = [0.0, 0.1, 0.0]
target = [{math.sin(t):.9f}, {0.1 + math.cos(t):.9f}, 0.0]
intensity = [100, 100, 100]
angle = 2
''', f'''# No photon can reach a diffuse surface here, so each photon pass ends at its cap of 256 paths
# per photon asked: small maps keep that short.
photons = 1000
caustic_photons = 1000
''')

total_internal_reflection("hard")

def furnace_materials(folder):
    """The white furnace (a closed sphere of radius 1 whose inside emits Le = 1 and reflects 0.5)
    holding one sphere of each material: white Lambert (Kd 1), perfect mirror (Ks 1), glass (n = 1.5)
    and glossy (Kd 0.3 + Phong Ks 0.7, Ns 30). Radiance is Le / (1 - 0.5) = 2 wherever every surface
    is lossless; the glossy lobe loses what it sends below the horizon, so nothing may exceed 2."""
    o = RawObj("furnace-materials.mtl")
    o.sphere("enclosure", "furnace", (0, 0, 0), 1.0, inward=True, seg=32, rings=16)
    for name, c in [("white", (-0.3, 0.2, -0.35)), ("mirror", (0.3, 0.2, -0.35)),
                    ("glass", (-0.3, -0.2, -0.35)), ("glossy", (0.3, -0.2, -0.35))]:
        o.sphere(name, name, c, 0.17, seg=48, rings=24)
    o.write(f"{folder}/furnace-materials.obj")
    mtl(f"{folder}/furnace-materials.mtl", [
        ("furnace", "illum 1\nKd 0.5 0.5 0.5\nKe 1 1 1"), ("white", "illum 1\nKd 1 1 1"),
        ("mirror", "illum 3\nKs 1 1 1"), ("glass", "illum 7\nNi 1.5"),
        ("glossy", "illum 2\nKd 0.3 0.3 0.3\nKs 0.7 0.7 0.7\nNs 30")])
    scene_toml(f"{folder}/furnace-materials.toml", '''# Energy, written by scenes/generate.py: the white furnace (inside a closed sphere that emits
# Le = 1 and reflects 0.5) holding a white Lambertian, a mirror, a glass and a glossy sphere.
# Radiance is 2 wherever every surface is lossless; no surface may return more than it receives.''', 'file = "furnace-materials.obj"', '''eye = [0.0, 0.0, 0.6]
target = [0.0, 0.0, -0.35]
fov = 60''')

    scene_toml(f"{folder}/furnace-rough.toml", '''# Energy, written by scenes/generate.py: furnace-materials.obj's spheres made rough — a white
# rough plastic (the coat over a white base), a rough conductor whose photons are stored on it
# (roughness 0.5), a frosted glass (roughness 0.4) and a grey Lambertian (0.5). Lossless surfaces
# return Le / (1 - 0.5) = 2; the microfacets' shadowing loses a little; nothing may exceed 2.''', 'file = "furnace-materials.obj"', '''eye = [0.0, 0.0, 0.6]
target = [0.0, 0.0, -0.35]
fov = 60''', '''
[materials.white]
type = "rough_plastic"
kd = [1.0, 1.0, 1.0]
ior = 1.5
roughness = 0.3

[materials.mirror]
type = "rough_conductor"
ks = [1.0, 1.0, 1.0]
roughness = 0.5

[materials.glass]
type = "rough_dielectric"
ior = 1.5
roughness = 0.4

[materials.glossy]
type = "lambert"
kd = [0.5, 0.5, 0.5]
''')

furnace_materials("hard")

def watertight(folder):
    """A closed cube [-1, 1]^3 facing inward, every face a grid over the coordinates
    -1, -0.5, -1e-6, 0, 0.5, 1 (so a strip of sliver triangles 1e-6 wide runs along 0, and the
    grid lines lie on the planes where a ray's direction components are zero), split into
    triangles; plus, per face, a zero-area triangle along a grid line. The faces share every edge
    and vertex (no T-junctions): rays from inside must never get out."""
    o = RawObj("watertight.mtl")
    g = [-1.0, -0.5, -1e-6, 0.0, 0.5, 1.0]
    o.lines.append("o cube")
    o.lines.append("usemtl white")
    index = {}
    def vertex(p):
        if p not in index:
            o.lines.append("v %r %r %r" % p)
            o.nv += 1
            index[p] = o.nv
        return index[p]
    faces = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            u, w = (axis + 1) % 3, (axis + 2) % 3
            def at(a, b):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[w] = side, a, b
                return tuple(p)
            for i in range(len(g) - 1):
                for j in range(len(g) - 1):
                    q = [at(g[i], g[j]), at(g[i + 1], g[j]), at(g[i + 1], g[j + 1]), at(g[i], g[j + 1])]
                    # Wind so the normal points into the cube (toward -side along axis).
                    n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
                    if n[axis] * side > 0:
                        q = q[::-1]
                    faces += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
            faces.append((at(g[0], g[3]), at(g[1], g[3]), at(g[4], g[3])))  # zero area: collinear
    for f in faces:
        o.lines.append("f " + " ".join(str(vertex(p)) for p in f))
    o.write(f"{folder}/watertight.obj")
    mtl(f"{folder}/watertight.mtl", [("white", "illum 1\nKd 0.5 0.5 0.5")])
    scene_toml(f"{folder}/watertight.toml", '''# Watertight mesh, written by scenes/generate.py: a closed cube of grid-triangulated faces with
# a strip of 1e-6-wide sliver triangles and a zero-area triangle per face, lit from inside by a
# point light. Rays at its shared edges and vertices never slip out, packet and scalar traversal
# agree, and every photon lands inside.''', 'file = "watertight.obj"', '''eye = [0.6, 0.5, 0.7]
target = [-1.0, -1.0, -1.0]
fov = 70''', '''
[[light]]
type = "point"
position = [0.1, 0.2, 0.05]
intensity = [1, 1, 1]
''')

watertight("hard")

def corner(folder):
    """A floor (y = 0, x in [0, 2]) meeting a wall (x = 0, facing +x), both kd 0.5, under a
    directional light straight down: the floor is lit, the wall (parallel to the light) only by
    what the floor reflects."""
    o = RawObj("corner.mtl")
    o.quad("floor", "half", [(0, 0, -1), (2, 0, -1), (2, 0, 1), (0, 0, 1)], (0, 1, 0))
    o.quad("wall", "half", [(0, 0, -1), (0, 2, -1), (0, 2, 1), (0, 0, 1)], (1, 0, 0))
    o.write(f"{folder}/corner.obj")
    mtl(f"{folder}/corner.mtl", [("half", "illum 1\nKd 0.5 0.5 0.5")])
    scene_toml(f"{folder}/corner.toml", '''# Corner leak, written by scenes/generate.py: a lit floor meets a wall that the light (straight
# down, parallel to the wall) never reaches directly. No photon of the floor may be counted on the
# wall, or the wall's foot would glow with the floor's direct light.''', 'file = "corner.obj"', '''eye = [1.8, 1.0, 0.0]
target = [0.0, 0.3, 0.0]
fov = 60''', '''
[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [1, 1, 1]
''')

corner("hard")

def numerics(folder):
    """emitter.toml's floor and quad light, with every floor vertex normal of zero length and the
    light's emission 1e38 (its power, 7.9e37 W, still fits f32; four such samples do not)."""
    o = RawObj("numerics.mtl")
    o.quad("floor", "half", [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], (0, 1, 0))
    o.lines[-1] = "f " + " ".join(f"{i}//1" for i in range(1, 5))
    o.lines.insert(o.lines.index("o floor"), "vn 0 0 0")
    o.quad("light", "light", [(-0.25, 1, -0.25), (0.25, 1, -0.25), (0.25, 1, 0.25), (-0.25, 1, 0.25)], (0, -1, 0))
    o.write(f"{folder}/numerics.obj")
    mtl(f"{folder}/numerics.mtl", [("half", "illum 1\nKd 0.5 0.5 0.5"), ("light", "illum 1\nKd 0 0 0\nKe 1e38 1e38 1e38")])
    scene_toml(f"{folder}/numerics.toml", '''# NaN and Inf, written by scenes/generate.py: emitter.toml's floor and light, but every floor vertex
# normal has zero length (replaced by the face's normal, counted at load) and the light emits 1e38
# (a pixel's sum of samples overflows f32 and is averaged sample by sample, counted). The image
# must be 2.5e37 times emitter.toml's (emission 4), and finite.''', 'file = "numerics.obj"', '''eye = [0.0, 0.5, 1.8]
target = [0.0, 0.3, 0.0]
fov = 50''')

numerics("hard")

def nested(folder):
    """The white furnace (Le = 1, albedo 0.5) holding a glass slab (n = 1.5, y from -0.3 to -0.1)
    under water (n = 1.33, y from -0.1 to 0.2), 0.6 x 0.6 across. nested.obj models the boundary
    between them as one face (material water_on_glass, normal into the glass, given ior 1.33 and
    outside_ior 1.5 in nested.toml); nested-coincident.obj closes each slab on its own, so two
    faces coincide there."""
    a, y0, y1, y2 = 0.3, -0.3, -0.1, 0.2
    def slab(o, name, material, lo, hi, skip=None):
        c = (0.0, (lo + hi) / 2, 0.0)
        faces = {
            "bottom": [(-a, lo, -a), (a, lo, -a), (a, lo, a), (-a, lo, a)],
            "top": [(-a, hi, -a), (a, hi, -a), (a, hi, a), (-a, hi, a)],
            "xlo": [(-a, lo, -a), (-a, hi, -a), (-a, hi, a), (-a, lo, a)],
            "xhi": [(a, lo, -a), (a, hi, -a), (a, hi, a), (a, lo, a)],
            "zlo": [(-a, lo, -a), (a, lo, -a), (a, hi, -a), (-a, hi, -a)],
            "zhi": [(-a, lo, a), (a, lo, a), (a, hi, a), (-a, hi, a)],
        }
        for side, pts in faces.items():
            if side != skip:
                m = tuple(sum(p[i] for p in pts) / 4 for i in range(3))
                o.quad(f"{name}_{side}", material, pts, sub(m, c))
    for variant in ("", "-coincident"):
        o = RawObj(f"nested{variant}.mtl")
        o.sphere("enclosure", "furnace", (0, 0, 0), 1.0, inward=True, seg=32, rings=16)
        if variant:
            slab(o, "glass", "glass", y0, y1)
            slab(o, "water", "water", y1, y2)
        else:
            slab(o, "glass", "glass", y0, y1, skip="top")
            slab(o, "water", "water", y1, y2, skip="bottom")
            o.quad("boundary", "water_on_glass", [(-a, y1, -a), (a, y1, -a), (a, y1, a), (-a, y1, a)], (0, -1, 0))
        o.write(f"{folder}/nested{variant}.obj")
        mtl(f"{folder}/nested{variant}.mtl", [
            ("furnace", "illum 1\nKd 0.5 0.5 0.5\nKe 1 1 1"), ("glass", "illum 7\nNi 1.5"),
            ("water", "illum 7\nNi 1.33"), ("water_on_glass", "illum 7\nNi 1.33")])
        boundary = "" if variant else """
# The boundary between water and glass is one face whose normal points into the glass.
[materials.water_on_glass]
type = "glass"
ior = 1.33
outside_ior = 1.5
"""
        what = ("each slab closed on its own, so faces of glass and water coincide at y = -0.1: the\n# "
                "loader warns; which face a ray meets there is arbitrary") if variant else \
               ("the boundary between them one face with ior 1.33 and outside_ior 1.5: radiance is\n# "
                "2 through every path, as everywhere in the furnace")
        scene_toml(f"{folder}/nested{variant}.toml", f'''# Nested dielectrics, written by scenes/generate.py: in the white furnace (Le = 1, albedo 0.5), a
# glass slab (n = 1.5) under water (n = 1.33), {what}.''', f'file = "nested{variant}.obj"', f'''eye = [0.0, 0.55, 0.75]
target = [0.0, -0.1, 0.0]
fov = 50''', f'{boundary}')

nested("hard")

# ---- real-looking scenes (issue 17): textures, rough materials, sun and sky ------------------

import struct, zlib

def write_png(path, w, h, pixel):
    """An 8-bit RGB PNG whose texel (x, y) (row y from the top) is pixel(x, y) -> (r, g, b)."""
    raw = b"".join(b"\x00" + bytes(c for x in range(w) for c in pixel(x, y)) for y in range(h))
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))

def wood(x, y):
    """Planks along u: a warm brown with rings and a darker seam every 64 texels."""
    ring = 0.5 + 0.5 * math.sin(0.21 * y + 3.0 * math.sin(0.031 * x + 0.05 * y))
    seam = 0.55 if y % 64 in (0, 1) else 1.0
    k = (0.78 + 0.22 * ring) * seam
    return (int(150 * k), int(96 * k), int(54 * k))

def tiles(x, y):
    """Terracotta and cream tiles, 64 texels a side, with grey grout."""
    if x % 64 < 3 or y % 64 < 3:
        return (120, 118, 112)
    return (176, 92, 60) if (x // 64 + y // 64) % 2 else (222, 208, 180)

def box_faces(o, name, material, lo, hi, inward=False):
    """The six faces of an axis-aligned box, facing out (or in)."""
    c = tuple((lo[i] + hi[i]) / 2 for i in range(3))
    for axis in range(3):
        for v in (lo[axis], hi[axis]):
            u, w = (axis + 1) % 3, (axis + 2) % 3
            pts = []
            for a, b in [(lo[u], lo[w]), (hi[u], lo[w]), (hi[u], hi[w]), (lo[u], hi[w])]:
                p = [0.0, 0.0, 0.0]; p[axis], p[u], p[w] = v, a, b
                pts.append(tuple(p))
            facing = [0.0, 0.0, 0.0]; facing[axis] = (v - c[axis]) * (-1 if inward else 1)
            o.quad(f"{name}_{'xyz'[axis]}{'-' if v == lo[axis] else '+'}", material, pts, tuple(facing))

def wall_with_opening(o, name, span, rise, opening, place, facing, sides=("left", "right")):
    """A zero-thickness wall of material `wall` over `span` x `rise` (its own coordinates (a, b),
    put in space by `place(a, b)`) around a rectangular opening (a0, a1, b0, b1): four quads,
    `NAME_low`, `NAME_high` and one each side (named by `sides`)."""
    (s0, s1), (r0, r1) = span, rise
    a0, a1, b0, b1 = opening
    for part, pts in [("low", [(s0, r0), (s1, r0), (s1, b0), (s0, b0)]), ("high", [(s0, b1), (s1, b1), (s1, r1), (s0, r1)]),
                      (sides[0], [(s0, b0), (a0, b0), (a0, b1), (s0, b1)]), (sides[1], [(a1, b0), (s1, b0), (s1, b1), (a1, b1)])]:
        o.quad(f"{name}_{part}", "wall", [place(a, b) for a, b in pts], facing)

def textured_quad(o, name, material, pts, uvs, facing):
    """A quad with texture coordinates (one `vt` per corner)."""
    n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
    if dot(n, facing) < 0:
        pts, uvs = pts[::-1], uvs[::-1]
    o.lines += [f"o {name}", f"usemtl {material}"]
    o.lines += ["v %.6f %.6f %.6f" % p for p in pts]
    o.lines += ["vt %.6f %.6f" % t for t in uvs]
    base_t = sum(1 for l in o.lines if l.startswith("vt ")) - 4
    o.lines.append("f " + " ".join(f"{o.nv + 1 + i}/{base_t + 1 + i}" for i in range(4)))
    o.nv += 4

def cylinder(o, name, material, centre, radius, y0, y1, inward=False, seg=96):
    """The side of a vertical cylinder, facing out (or toward its axis)."""
    cx, cz = centre
    for s in range(seg):
        a0, a1 = 2 * math.pi * s / seg, 2 * math.pi * (s + 1) / seg
        p = [(cx + radius * math.cos(a), y, cz + radius * math.sin(a)) for a, y in [(a0, y0), (a1, y0), (a1, y1), (a0, y1)]]
        out = (math.cos(a0 + math.pi / seg), 0.0, math.sin(a0 + math.pi / seg))
        o.quad(f"{name}{s}", material, p, tuple(-c for c in out) if inward else out)

def annulus(o, name, material, centre, r0, r1, y, up, seg=96):
    """A flat ring (a disk when r0 = 0) at height y facing up or down."""
    cx, cz = centre
    for s in range(seg):
        a0, a1 = 2 * math.pi * s / seg, 2 * math.pi * (s + 1) / seg
        if r0 == 0:
            p = [(cx, y, cz), (cx + r1 * math.cos(a0), y, cz + r1 * math.sin(a0)), (cx + r1 * math.cos(a1), y, cz + r1 * math.sin(a1))]
        else:
            p = [(cx + r0 * math.cos(a0), y, cz + r0 * math.sin(a0)), (cx + r1 * math.cos(a0), y, cz + r1 * math.sin(a0)),
                 (cx + r1 * math.cos(a1), y, cz + r1 * math.sin(a1)), (cx + r0 * math.cos(a1), y, cz + r0 * math.sin(a1))]
        o.quad(f"{name}{s}", material, p, (0, 1 if up else -1, 0))

def real_scenes():
    raw = lambda p: p
    # A small glass ball in a large room: 8 x 3 x 6 m, a 0.5 m ceiling light, a 10 cm ball.
    o = Obj("glass-in-room.mtl", convert=raw)
    box_faces(o, "room", "wall", (-4, 0, -3), (4, 3, 3), inward=True)
    o.quad("light", "light", [(-0.25, 2.999, -0.25), (0.25, 2.999, -0.25), (0.25, 2.999, 0.25), (-0.25, 2.999, 0.25)], (0, -1, 0))
    o.sphere("ball", "glass", (0.5, 0.1, 0.5), 0.1)
    o.write("glass-in-room.obj")
    mtl("glass-in-room.mtl", [("wall", "illum 1\nKd 0.7 0.7 0.7"), ("light", "illum 1\nKd 0 0 0\nKe 40 36 30"),
                              ("glass", "illum 7\nNi 1.5")])
    with open("glass-in-room.toml", "w") as f:
        f.write('''# A 10 cm glass ball in an 8 x 3 x 6 m room under a 0.5 m ceiling light, written by
# scenes/generate.py: caustic photons emitted blindly almost never reach the ball; aimed ones do.
[[mesh]]
file = "glass-in-room.obj"

[camera]
eye = [0.5, 0.9, 1.6]
target = [0.5, 0.05, 0.45]
fov = 35
''')

    # A glass of water and a gold ring on a wooden table, under a sky and a low sun.
    o = Obj("table.mtl", convert=raw)
    textured_quad(o, "table", "wood", [(-0.4, -0.0005, -0.4), (0.4, -0.0005, -0.4), (0.4, -0.0005, 0.4), (-0.4, -0.0005, 0.4)],
                  [(0, 1), (1, 1), (1, 0), (0, 0)], (0, 1, 0))
    g, ro, ri, h, bottom, level = (0.09, -0.06), 0.035, 0.031, 0.11, 0.008, 0.075
    cylinder(o, "glass_out", "glass", g, ro, 0.0, h)
    annulus(o, "glass_base", "glass", g, 0.0, ro, 0.0, up=False)
    annulus(o, "glass_rim", "glass", g, ri, ro, h, up=True)
    cylinder(o, "glass_in_air", "glass_inside", g, ri, level, h, inward=True)
    cylinder(o, "glass_in_water", "water_on_glass", g, ri, bottom, level, inward=True)
    annulus(o, "glass_floor", "water_on_glass", g, 0.0, ri, bottom, up=True)
    annulus(o, "water_surface", "water", g, 0.0, ri, level, up=True)
    r, (rx, rz), rh, rt = 0.032, (-0.08, 0.05), 0.012, 0.0025
    cylinder(o, "ring_out", "gold", (rx, rz), r + rt, 0.0, rh)
    cylinder(o, "ring_in", "gold", (rx, rz), r, 0.0, rh, inward=True)
    annulus(o, "ring_top", "gold", (rx, rz), r, r + rt, rh, up=True)
    annulus(o, "ring_bottom", "gold", (rx, rz), r, r + rt, 0.0, up=False)
    o.write("table.obj")
    write_png("wood.png", 256, 256, wood)
    mtl("table.mtl", [("wood", "illum 1\nKd 1 1 1\nmap_Kd wood.png"), ("glass", "illum 7\nNi 1.5"),
                      ("glass_inside", "illum 7\nNi 1.5"), ("water", "illum 7\nNi 1.33"),
                      ("water_on_glass", "illum 7\nNi 1.33"), ("gold", "illum 3\nKs 1.0 0.78 0.34")])
    with open("table.toml", "w") as f:
        f.write('''# A glass of water and a gold ring on a wooden table (map_Kd wood.png) under a blue sky and a
# low sun, written by scenes/generate.py: the ring's cardioid, the glass's caustic, soft shadows.
[[mesh]]
file = "table.obj"

[camera]
eye = [0.0, 0.22, 0.36]
target = [0.0, 0.03, 0.0]
fov = 38

[[light]]
type = "sun"
direction = [0.45, -0.45, -0.77]
irradiance = [2.9, 2.75, 2.5]
angle = 0.27

[environment]
radiance = [0.2, 0.26, 0.38]

# The glass's inner wall below the water and its floor: one face between glass (inside, the
# side the normal points away from) and water.
[materials.water_on_glass]
type = "glass"
ior = 1.5
outside_ior = 1.33
''')

    # A room lit only through a glass window pane: sun and sky outside.
    o = Obj("window.mtl", convert=raw)
    W, H, D = 2.0, 2.6, 2.0
    textured_quad(o, "floor", "tiles", [(-W, 0, -D), (W, 0, -D), (W, 0, D), (-W, 0, D)],
                  [(0, 4), (4, 4), (4, 0), (0, 0)], (0, 1, 0))
    o.quad("ceiling", "wall", [(-W, H, -D), (W, H, -D), (W, H, D), (-W, H, D)], (0, -1, 0))
    o.quad("left", "wall", [(-W, 0, -D), (-W, H, -D), (-W, H, D), (-W, 0, D)], (1, 0, 0))
    o.quad("right", "wall", [(W, 0, -D), (W, H, -D), (W, H, D), (W, 0, D)], (-1, 0, 0))
    o.quad("front", "wall", [(-W, 0, D), (W, 0, D), (W, H, D), (-W, H, D)], (0, 0, -1))
    x0, x1, y0, y1 = -0.7, 0.7, 0.9, 2.0
    wall_with_opening(o, "back", (-W, W), (0, H), (x0, x1, y0, y1), lambda x, y: (x, y, -D), (0, 0, 1))
    # The pane: one sheet of thin glass in the wall's plane (TOML `thin_glass`: a window pane that
    # shadow rays and photons pass with its transmittance).
    o.quad("pane", "glass", [(x0, y0, -D), (x1, y0, -D), (x1, y1, -D), (x0, y1, -D)], (0, 0, 1))
    o.write("window.obj")
    write_png("tiles.png", 256, 256, tiles)
    mtl("window.mtl", [("wall", "illum 1\nKd 0.75 0.73 0.7"), ("tiles", "illum 1\nKd 1 1 1\nmap_Kd tiles.png"),
                       ("glass", "illum 7\nNi 1.5")])
    with open("window.toml", "w") as f:
        f.write('''# A closed room whose only opening is a glass window pane, written by scenes/generate.py: sun
# and sky reach the tiled floor (map_Kd tiles.png) only through the pane, a thin sheet of glass
# that shadow rays and photons pass with its transmittance (about 92 % head-on).
[[mesh]]
file = "window.obj"

[materials.glass]
type = "thin_glass"
ior = 1.5

[camera]
eye = [1.5, 1.5, 1.9]
target = [-0.2, 0.6, -1.0]
fov = 60

[[light]]
type = "sun"
direction = [0.25, -0.55, 0.8]
irradiance = [5.0, 4.8, 4.4]

[environment]
radiance = [0.8, 1.0, 1.4]

# The window marked as a portal: half the sky's light samples and photons go through it.
[[portal]]
corners = [[-0.7, 0.9, -2.0], [0.7, 0.9, -2.0], [0.7, 2.0, -2.0], [-0.7, 2.0, -2.0]]
''')

    with open("cornell-rough.toml", "w") as f:
        f.write('''# The Cornell spheres with a brushed-gold metal sphere (roughness 0.35: its photons are stored)
# and a frosted glass sphere (roughness 0.3: photons pass it as specular), written by
# scenes/generate.py.
[[mesh]]
file = "cornell-spheres.obj"

[camera]
eye = [0.0, 0.273, 1.0796]
target = [0.0, 0.273, 0.0]
fov = 39.3

[materials.mirror]
type = "rough_conductor"
ks = [1.0, 0.78, 0.34]
roughness = 0.35

[materials.glass]
type = "rough_dielectric"
ior = 1.5
roughness = 0.3
''')

real_scenes()

# ---- a bundled interior (issue 56): one Mitsuba file that photonwave and Mitsuba 3 both render ---

def interior():
    """Two rooms joined by a doorway, written as interior.xml (Mitsuba 3's format) over OBJ meshes in
    interior/, one per material: a near-mirror tiled floor (rough plastic, GGX alpha 0.01), thin
    floating stair treads, five small ceiling lights (three in the near room, two warm ones beyond
    the doorway), a terracotta far wall, a bench, and a standing glass pane whose glass absorbs (an
    interior homogeneous medium of albedo 0). Metres; y up; the near room is x < 0."""
    X, Z, H, T = 4.0, 2.5, 2.8, 0.05        # half length, half depth, height, half the partition
    meshes = {}
    def mesh(name):
        if name not in meshes:
            o = Obj("", convert=lambda p: p)
            o.lines = [f"# photonwave's bundled interior ({name}), written by scenes/generate.py"]
            meshes[name] = o
        return meshes[name]
    def block(name, material, lo, hi, skip=()):
        """An axis-aligned box facing out, without the faces in `skip` (e.g. 'y-': resting on the floor)."""
        o = mesh(material)
        c = tuple((lo[i] + hi[i]) / 2 for i in range(3))
        for axis in range(3):
            for v, sign in ((lo[axis], "-"), (hi[axis], "+")):
                if f"{'xyz'[axis]}{sign}" in skip:
                    continue
                u, w = (axis + 1) % 3, (axis + 2) % 3
                pts = []
                for a, b in [(lo[u], lo[w]), (hi[u], lo[w]), (hi[u], hi[w]), (lo[u], hi[w])]:
                    p = [0.0, 0.0, 0.0]; p[axis], p[u], p[w] = v, a, b
                    pts.append(tuple(p))
                facing = [0.0, 0.0, 0.0]; facing[axis] = v - c[axis]
                o.quad(f"{name}_{'xyz'[axis]}{sign}", material, pts, tuple(facing))
    # The shell: floor (tiles at 0.5 m), ceiling, four walls facing in; the wall at x = +X terracotta.
    textured_quad(mesh("floor"), "floor", "floor", [(-X, 0, -Z), (X, 0, -Z), (X, 0, Z), (-X, 0, Z)],
                  [(0, 0), (X, 0), (X, Z), (0, Z)], (0, 1, 0))
    mesh("walls").quad("ceiling", "walls", [(-X, H, -Z), (X, H, -Z), (X, H, Z), (-X, H, Z)], (0, -1, 0))
    mesh("walls").quad("back", "walls", [(-X, 0, -Z), (X, 0, -Z), (X, H, -Z), (-X, H, -Z)], (0, 0, 1))
    mesh("walls").quad("front", "walls", [(-X, 0, Z), (X, 0, Z), (X, H, Z), (-X, H, Z)], (0, 0, -1))
    mesh("walls").quad("left", "walls", [(-X, 0, -Z), (-X, H, -Z), (-X, H, Z), (-X, 0, Z)], (1, 0, 0))
    mesh("accent").quad("far", "accent", [(X, 0, -Z), (X, H, -Z), (X, H, Z), (X, 0, Z)], (-1, 0, 0))
    # The partition at x = 0 with a doorway (z from -1.6 to -0.6, 2.1 m high).
    d0, d1, dh = -1.6, -0.6, 2.1
    block("partition_back", "walls", (-T, 0, -Z), (T, H, d0), skip=("y-", "y+", "z-"))
    block("partition_front", "walls", (-T, 0, d1), (T, H, Z), skip=("y-", "y+", "z+"))
    block("lintel", "walls", (-T, dh, d0), (T, H, d1), skip=("y+", "z-", "z+"))
    # Ten floating treads, 4 cm thick, rising to the left along the back wall of the near room.
    for i in range(10):
        x1 = -1.0 - 0.28 * i
        y = 0.19 * (i + 1)
        block(f"tread{i}", "treads", (x1 - 0.28, y - 0.04, -Z), (x1, y, -Z + 0.9), skip=("z-",))
    # A bench, and a glass pane (2 cm thick, 2 cm above the floor) in front of the stair.
    block("bench", "bench", (-2.2, 0.0, 0.7), (-0.9, 0.45, 1.5), skip=("y-",))
    block("pane", "glass", (-3.4, 0.02, -1.42), (-1.6, 1.02, -1.40))
    # Small ceiling lights, facing down.
    for i, (x, z, s) in enumerate([(-3.0, 0.9, 0.1), (-1.4, 1.6, 0.1), (-2.0, -0.6, 0.1)]):
        mesh("lights_near").quad(f"light{i}", "lights_near", [(x - s, H - 0.001, z - s), (x + s, H - 0.001, z - s),
                                  (x + s, H - 0.001, z + s), (x - s, H - 0.001, z + s)], (0, -1, 0))
    for i, (x, z, s) in enumerate([(1.8, -1.2, 0.15), (2.8, 1.2, 0.15)]):
        mesh("lights_far").quad(f"light{i}", "lights_far", [(x - s, H - 0.001, z - s), (x + s, H - 0.001, z - s),
                                 (x + s, H - 0.001, z + s), (x - s, H - 0.001, z + s)], (0, -1, 0))
    import os
    os.makedirs("interior", exist_ok=True)
    for name, o in meshes.items():
        o.lines = [l for l in o.lines if not l.startswith("usemtl")]
        o.write(f"interior/{name}.obj")
    diffuse = lambda rgb: f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf>'
    bsdfs = {
        "floor": '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.01"/>'
                 '<float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/><boolean name="nonlinear" value="true"/>'
                 '<texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="tiles.png"/></texture></bsdf>',
        "walls": diffuse("0.72, 0.71, 0.68"),
        "accent": diffuse("0.62, 0.3, 0.2"),
        "treads": diffuse("0.5, 0.36, 0.22"),
        "bench": diffuse("0.2, 0.3, 0.5"),
        "glass": '<bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>',
        "lights_near": diffuse("0, 0, 0"),
        "lights_far": diffuse("0, 0, 0"),
    }
    extra = {
        "glass": '<medium name="interior" type="homogeneous"><rgb name="sigma_t" value="1, 0.25, 0.6"/><float name="scale" value="30"/>'
                 '<float name="albedo" value="0"/></medium>',
        "lights_near": '<emitter type="area"><rgb name="radiance" value="250, 240, 225"/></emitter>',
        "lights_far": '<emitter type="area"><rgb name="radiance" value="160, 120, 72"/></emitter>',
    }
    xml = ['<?xml version="1.0" encoding="utf-8"?>',
           '<!-- photonwave\'s bundled interior, written by scenes/generate.py: two rooms joined by a doorway, a near-mirror',
           '     tiled floor (GGX alpha 0.01), thin floating stair treads, five small ceiling lights, a glass pane that absorbs.',
           '     photonwave renders this file as it is; so does Mitsuba 3 (volpath: the pane\'s medium absorbs). -->',
           '<scene version="3.0.0">',
           '\t<integrator type="volpath"/>',
           '\t<sensor type="perspective">',
           '\t\t<float name="fov" value="62"/>',
           '\t\t<string name="fov_axis" value="y"/>',
           '\t\t<transform name="to_world">',
           '\t\t\t<lookat origin="-3.7, 1.55, 2.3" target="0.2, 0.75, -1.1" up="0, 1, 0"/>',
           '\t\t</transform>',
           '\t\t<film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="240"/><rfilter type="box"/></film>',
           '\t</sensor>']
    for name in meshes:
        xml += ['\t<shape type="obj">', f'\t\t<string name="filename" value="interior/{name}.obj"/>',
                '\t\t<boolean name="face_normals" value="true"/>', f'\t\t{bsdfs[name]}']
        if name in extra:
            xml.append(f'\t\t{extra[name]}')
        xml.append('\t</shape>')
    xml.append('</scene>')
    with open("interior.xml", "w") as f:
        f.write("\n".join(xml) + "\n")

interior()

def leaf(x, y):
    """A 64 x 64 leaf mask (white where the leaf is, read as opacity by map_d): a pointed
    ellipse along u with a notch-free edge."""
    u, v = (x - 31.5) / 31.0, (y - 31.5) / 31.0
    half_width = 0.42 * (1.0 - u * u) * (1.0 - 0.35 * u)
    return (255, 255, 255) if abs(v) < half_width else (0, 0, 0)

def daylight_sky(x, y):
    """A 256 x 128 lat-long sky (row 0 the zenith), read as linear: blue overhead, pale toward
    the horizon, a grey-green ground below it."""
    theta = math.pi * (y + 0.5) / 128
    if theta > math.pi / 2:
        return (60, 62, 52)
    t = theta / (math.pi / 2)
    return (int(90 + 140 * t ** 2), int(130 + 110 * t ** 2), int(235 + 15 * t))

def daylight():
    """A room lit by daylight: zero-thickness walls, a glass window (thin glass) and an open one,
    a sun and a sky map, a glossy wooden floor, a plant with alpha-masked leaves, both windows
    marked as portals."""
    raw = lambda p: p
    o = Obj("daylight.mtl", convert=raw)
    W, H, D = 2.0, 2.6, 2.5
    textured_quad(o, "floor", "floor", [(-W, 0, -D), (W, 0, -D), (W, 0, D), (-W, 0, D)],
                  [(0, 0), (2, 0), (2, 2.5), (0, 2.5)], (0, 1, 0))
    o.quad("ceiling", "wall", [(-W, H, -D), (W, H, -D), (W, H, D), (-W, H, D)], (0, -1, 0))
    o.quad("right", "wall", [(W, 0, -D), (W, H, -D), (W, H, D), (W, 0, D)], (-1, 0, 0))
    o.quad("front", "wall", [(-W, 0, D), (W, 0, D), (W, H, D), (-W, H, D)], (0, 0, -1))
    # Back wall (z = -D): a glazed window x in [-1.5, -0.1], y in [0.8, 2.0].
    bx0, bx1, by0, by1 = -1.5, -0.1, 0.8, 2.0
    wall_with_opening(o, "back", (-W, W), (0, H), (bx0, bx1, by0, by1), lambda x, y: (x, y, -D), (0, 0, 1))
    o.quad("pane", "pane", [(bx0, by0, -D), (bx1, by0, -D), (bx1, by1, -D), (bx0, by1, -D)], (0, 0, 1))
    # Left wall (x = -W): an open window z in [-0.9, 0.7], y in [0.7, 2.1].
    lz0, lz1, ly0, ly1 = -0.9, 0.7, 0.7, 2.1
    wall_with_opening(o, "left", (-D, D), (0, H), (lz0, lz1, ly0, ly1), lambda z, y: (-W, y, z), (1, 0, 0),
                      sides=("back", "front"))
    # The ground outside, a little below the floor (zero-thickness walls stand on it).
    o.quad("ground", "ground", [(-6, -0.02, -6), (6, -0.02, -6), (6, -0.02, 6), (-6, -0.02, 6)], (0, 1, 0))
    # A bench and a potted plant: a stem and ten leaves on alpha-masked quads.
    box_faces(o, "bench", "bench", (0.6, 0.0, 1.2), (1.9, 0.45, 1.9))
    box_faces(o, "pot", "pot", (0.95, 0.0, -1.75), (1.35, 0.38, -1.35))
    box_faces(o, "stem", "stem", (1.13, 0.38, -1.57), (1.17, 1.15, -1.53))
    for k in range(10):
        a = 2 * math.pi * k / 10 + 0.3 * (k % 3)
        y = 0.55 + 0.06 * k
        length, width = 0.42 - 0.015 * k, 0.2
        base = (1.15, y, -1.55)
        tip = (1.15 + length * math.cos(a), y + 0.12 + 0.03 * (k % 2), -1.55 + length * math.sin(a))
        side = (-math.sin(a) * width / 2, 0.0, math.cos(a) * width / 2)
        pts = [(base[0] - side[0], base[1], base[2] - side[2]), (tip[0] - side[0], tip[1], tip[2] - side[2]),
               (tip[0] + side[0], tip[1], tip[2] + side[2]), (base[0] + side[0], base[1], base[2] + side[2])]
        textured_quad(o, f"leaf{k}", "leaf", pts, [(0, 0), (1, 0), (1, 1), (0, 1)], (0, 1, 0))
    o.write("daylight.obj")
    write_png("leaf.png", 64, 64, leaf)
    write_png("daylight-sky.png", 256, 128, daylight_sky)
    mtl("daylight.mtl", [("wall", "illum 1\nKd 0.78 0.76 0.72"),
                         ("floor", "illum 2\nKd 1 1 1\nmap_Kd wood.png\nPr 0.3\nNi 1.5"),
                         ("pane", "illum 7\nNi 1.5"), ("ground", "illum 1\nKd 0.32 0.33 0.28"),
                         ("bench", "illum 1\nKd 0.55 0.58 0.66"), ("pot", "illum 1\nKd 0.62 0.32 0.2"),
                         ("stem", "illum 1\nKd 0.3 0.25 0.12"), ("leaf", "illum 1\nKd 0.12 0.42 0.1\nmap_d leaf.png")])
    with open("daylight.toml", "w") as f:
        f.write('''# A room lit by daylight, written by scenes/generate.py: zero-thickness walls, a glazed window
# (a thin glass pane) and an open one, a sun and a sky map (daylight-sky.png), a glossy wooden
# floor (rough plastic over map_Kd wood.png), a potted plant whose leaves are alpha-masked quads
# (map_d leaf.png), the ground outside; both windows are portals.
[[mesh]]
file = "daylight.obj"

[materials.pane]
type = "thin_glass"
ior = 1.5

[camera]
eye = [1.7, 1.45, 2.3]
target = [-0.7, 0.85, -1.3]
fov = 66

[[light]]
type = "sun"
direction = [0.62, -0.5, 0.6]
irradiance = [7.0, 6.6, 6.0]

[environment]
map = "daylight-sky.png"
scale = 1.6

# The glazed window and the open one.
[[portal]]
corners = [[-1.5, 0.8, -2.5], [-0.1, 0.8, -2.5], [-0.1, 2.0, -2.5], [-1.5, 2.0, -2.5]]

[[portal]]
corners = [[-2.0, 0.7, -0.9], [-2.0, 0.7, 0.7], [-2.0, 2.1, 0.7], [-2.0, 2.1, -0.9]]
''')

daylight()

