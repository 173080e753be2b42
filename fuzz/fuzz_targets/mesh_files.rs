//! A PLY, glTF, GLB or Mitsuba file (the first byte picks which), loaded alone and rendered small
//! (decoded by `photonwave::fuzzing::mesh_files_input`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("photonwave-fuzz-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    if let Err(e) = photonwave::fuzzing::mesh_files_input(&dir, data) {
        panic!("{e}");
    }
});
