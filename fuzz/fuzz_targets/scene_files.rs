//! A scene as three files — TOML, OBJ, MTL — separated by 0xFF bytes in the fuzzer's input
//! (decoded by `photonwave::fuzzing::scene_files_input`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("photonwave-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    if let Err(e) = photonwave::fuzzing::scene_files_input(&dir, data) {
        panic!("{e}");
    }
});
