//! Two triangles sharing an edge and a ray toward a point of it, from 18 floats of the input
//! (decoded by `photonwave::fuzzing::edge_rays_input`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: [f32; 18]| {
    if let Err(e) = photonwave::fuzzing::edge_rays_input(data) {
        panic!("{e}");
    }
});
