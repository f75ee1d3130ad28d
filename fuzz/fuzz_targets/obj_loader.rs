//! Fuzzes the OBJ loader from memory (MTL references resolve against a folder that does not
//! exist). Only panics, hangs and crashes are findings.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-fuzz-dir/input.obj");
    let _ = vcm_scene::loader::obj::load_obj_from_reader(path, &mut std::io::Cursor::new(data));
});
