//! Mitsuba's texture orientation: texture coordinate v = 0 is an image's first (top) row in
//! Mitsuba 3, v = 1 in photonwave, so the built-in shapes carry Mitsuba's coordinates turned over
//! (v → 1 − v) and the Mitsuba reader turns over the files' coordinates that Mitsuba keeps (a
//! PLY's; an OBJ's Mitsuba turns itself). Held here to the (u, v) Mitsuba 3.9.1 reports
//! (`SurfaceInteraction3f::uv`, `scalar_rgb`) at points of its unit shapes.

mod common;

use common::scratch_dir;
use glam::{Vec2, Vec3};
use photonwave::formats::load_scene;

/// The texture coordinates photonwave finds where the ray `o + t·d` meets the Mitsuba shape
/// `shape` (an element, textured so that its coordinates are kept), in Mitsuba's orientation.
fn mitsuba_uv_at(dir: &std::path::Path, shape: &str, o: Vec3, d: Vec3) -> Vec2 {
    let xml = format!(
        "<scene version=\"3.0.0\">\n{}<bsdf type=\"diffuse\"><texture name=\"reflectance\" type=\"checkerboard\"/>\
</bsdf></shape>\n<emitter type=\"constant\"/>\n</scene>\n",
        shape.trim_end_matches("</shape>")
    );
    let path = dir.join("s.xml");
    std::fs::write(&path, xml).unwrap();
    let scene = load_scene(&path).unwrap().scene;
    let hit = scene.intersect(scene.to_frame(o), d, f32::INFINITY).expect("the ray meets the shape");
    let uv = scene.surface(&hit).uv;
    Vec2::new(uv.x, 1.0 - uv.y)
}

/// A shape, a ray's origin and direction, and Mitsuba's (u, v) where the ray meets it.
type Case = (&'static str, [f32; 3], [f32; 3], [f32; 2]);

#[test]
fn built_in_shapes_carry_mitsubas_texture_coordinates() {
    // (shape, ray origin, direction, Mitsuba 3's uv there). The sphere and the disk are
    // tessellated (48 rings, 96 segments), so their coordinates are the flat facets'
    // interpolation: within 2·10⁻³ of the round shapes'; the others are exact up to f32 rounding.
    let d = scratch_dir("mitsuba-uv-shapes");
    let cases: [Case; 15] = [
        ("rectangle", [0.3, 0.6, 1.0], [0.0, 0.0, -1.0], [0.65, 0.8]),
        ("rectangle", [-0.7, -0.2, 1.0], [0.0, 0.0, -1.0], [0.15, 0.4]),
        ("disk", [0.3, 0.6, 1.0], [0.0, 0.0, -1.0], [0.67082, 0.17621]),
        ("disk", [-0.5, -0.2, 1.0], [0.0, 0.0, -1.0], [0.53852, 0.56056]),
        ("disk", [0.5, -0.01, 1.0], [0.0, 0.0, -1.0], [0.50010, 0.99682]),
        ("sphere", [0.3, 0.5, 3.0], [0.0, 0.0, -1.0], [0.16399, 0.19816]),
        ("sphere", [3.0, 0.2, -0.4], [-1.0, 0.0, 0.0], [0.03501, 0.63099]),
        ("sphere", [0.1, 3.0, 0.3], [0.0, -1.0, 0.0], [0.23329, 0.40301]),
        ("cube", [0.3, 0.6, 3.0], [0.0, 0.0, -1.0], [0.8, 0.65]),
        ("cube", [3.0, 0.2, -0.4], [-1.0, 0.0, 0.0], [0.6, 0.7]),
        ("cube", [0.1, 3.0, 0.3], [0.0, -1.0, 0.0], [0.45, 0.35]),
        ("cube", [0.1, -3.0, 0.3], [0.0, 1.0, 0.0], [0.65, 0.55]),
        ("cube", [-3.0, 0.2, -0.4], [1.0, 0.0, 0.0], [0.6, 0.3]),
        ("cube", [0.3, 0.6, -3.0], [0.0, 0.0, 1.0], [0.2, 0.65]),
        ("cube", [-0.5, 0.25, 3.0], [0.0, 0.0, -1.0], [0.625, 0.25]),
    ];
    for (kind, o, dir, want) in cases {
        let got = mitsuba_uv_at(&d, &format!("<shape type=\"{kind}\">"), Vec3::from_array(o), Vec3::from_array(dir));
        let tol = if matches!(kind, "sphere" | "disk") { 2e-3 } else { 1e-5 };
        assert!((got - Vec2::from_array(want)).abs().max_element() < tol, "{kind} at {o:?}: {got}, Mitsuba {want:?}");
    }
}

#[test]
fn mesh_files_and_texture_transforms_follow_mitsuba() {
    // One triangle whose vertex (1, 0, 0) has file coordinates (0.75, 0.25), in OBJ and PLY, hit
    // at barycentrics (0.001, 0.998, 0.001): Mitsuba turns the OBJ's v over by default and keeps
    // the PLY's, `flip_tex_coords` choosing otherwise; a texture's scale and offset then act on
    // Mitsuba's (u, v). The expected values are Mitsuba 3.9.1's.
    let d = scratch_dir("mitsuba-uv-meshes");
    std::fs::write(d.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 0.75 0.25\nvt 0 1\nf 1/1 2/2 3/3\n")
        .unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0\n1 0 0 0.75 0.25\n0 1 0 0 1\n3 0 1 2\n";
    std::fs::write(d.join("t.ply"), ply).unwrap();
    // Just inside the vertex (1, 0, 0): barycentrics (0.001, 0.998, 0.001).
    let (o, dir) = (Vec3::new(0.998, 0.001, 1.0), Vec3::NEG_Z);
    let near = |a: Vec2, b: [f32; 2], what: &str| {
        assert!((a - Vec2::from_array(b)).abs().max_element() < 1e-5, "{what}: {a}, Mitsuba {b:?}");
    };
    let at = |shape: &str| mitsuba_uv_at(&d, shape, o, dir);
    near(at("<shape type=\"obj\"><string name=\"filename\" value=\"t.obj\"/>"), [0.7485, 0.7495], "OBJ");
    near(at("<shape type=\"ply\"><string name=\"filename\" value=\"t.ply\"/>"), [0.7485, 0.2505], "PLY");
    let flip = |kind: &str, on: bool| {
        format!(
            "<shape type=\"{kind}\"><string name=\"filename\" value=\"t.{kind}\"/><boolean name=\"flip_tex_coords\" value=\"{on}\"/>"
        )
    };
    near(at(&flip("ply", true)), [0.7485, 0.7495], "PLY, flip_tex_coords");
    near(at(&flip("obj", false)), [0.7485, 0.2505], "OBJ, no flip_tex_coords");
    // uscale 2, voffset 0.1 on the PLY: the lookup is at (2·0.7485, 0.2505 + 0.1).
    let xml = "<scene version=\"3.0.0\">\n<shape type=\"ply\"><string name=\"filename\" value=\"t.ply\"/><bsdf type=\"diffuse\">\
<texture name=\"reflectance\" type=\"checkerboard\"><float name=\"uscale\" value=\"2\"/><float name=\"voffset\" value=\"0.1\"/>\
</texture></bsdf></shape>\n<emitter type=\"constant\"/>\n</scene>\n";
    std::fs::write(d.join("m.xml"), xml).unwrap();
    let scene = load_scene(&d.join("m.xml")).unwrap().scene;
    let hit = scene.intersect(o, dir, f32::INFINITY).unwrap();
    let uv = scene.surface(&hit).uv;
    near(Vec2::new(uv.x, 1.0 - uv.y), [1.497, 0.3505], "PLY with uscale and voffset");
}
