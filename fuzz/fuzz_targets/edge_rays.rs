//! Two triangles sharing an edge and a ray toward a point of it, from 18 floats of the input.
#![no_main]

use glam::Vec3;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: [f32; 18]| {
    let v = |i: usize| Vec3::new(data[i], data[i + 1], data[i + 2]);
    let (a, b, c1, c2, o) = (v(0), v(3), v(6), v(9), v(12));
    let s = data[15];
    let (scale, normalise) = (data[16], data[17] > 0.0);
    if !data.iter().all(|x| x.is_finite()) || !(0.0..=1.0).contains(&s) || !(scale > 0.0) {
        return;
    }
    let target = (a + (b - a) * s) * scale;
    if let Err(e) =
        photonwave::fuzzing::edge_ray(a * scale, b * scale, c1 * scale, c2 * scale, o * scale, target, normalise)
    {
        panic!("{e}");
    }
});
