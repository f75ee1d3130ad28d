//! Fuzzes the glTF loader (JSON and GLB) from memory. External URIs resolve against a folder that
//! does not exist, so every input is self-contained; only panics, hangs and crashes are findings.
//! The limits are small so that inputs that instance much geometry stay fast (the default
//! limits hold the same way, at a size that would only slow the fuzzer).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-fuzz-dir/input.gltf");
    let options = vcm_scene::LoadOptions {
        max_triangles: 100_000,
        max_texels: 1 << 20,
        ..vcm_scene::LoadOptions::default()
    };
    let _ = vcm_scene::loader::load_gltf_from_bytes_with(path, data, &options);
});
