//! Fuzzes the glTF loader (JSON and GLB) from memory. External URIs resolve against a folder that
//! does not exist, so every input is self-contained; only panics, hangs and crashes are findings.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-fuzz-dir/input.gltf");
    let _ = vcm_scene::loader::load_gltf_from_bytes(path, data);
});
