//! Replays the fuzzing seeds and every input the fuzzers ever crashed on (`fuzz/seeds/`,
//! `fuzz/regressions/`): each must load or fail with an error, never panic.

use std::path::{Path, PathBuf};

use vcm_scene::loader::{load_gltf_from_bytes, obj::load_obj_from_reader};

fn inputs(kind: &str) -> Vec<PathBuf> {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = Vec::new();
    for folder in ["seeds", "regressions"] {
        if let Ok(entries) = std::fs::read_dir(fuzz.join(folder).join(kind)) {
            files.extend(entries.map(|e| e.unwrap().path()));
        }
    }
    files.sort();
    files
}

#[test]
fn gltf_fuzz_inputs_never_panic() {
    let files = inputs("gltf");
    assert!(!files.is_empty(), "no glTF fuzz inputs found");
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        let path = Path::new("/nonexistent-fuzz-dir/input.gltf");
        if let Err(e) = load_gltf_from_bytes(path, &bytes) {
            assert!(
                e.to_string().contains("input.gltf"),
                "{}: {e}",
                file.display()
            );
        }
    }
}

#[test]
fn obj_fuzz_inputs_never_panic() {
    let files = inputs("obj");
    assert!(!files.is_empty(), "no OBJ fuzz inputs found");
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        let path = Path::new("/nonexistent-fuzz-dir/input.obj");
        if let Err(e) = load_obj_from_reader(path, &mut std::io::Cursor::new(bytes)) {
            assert!(
                e.to_string().contains("input.obj"),
                "{}: {e}",
                file.display()
            );
        }
    }
}
