//! Replays the fuzzing seeds and every input the fuzzers ever crashed on (`fuzz/seeds/`,
//! `fuzz/regressions/`): each must load or fail with an error, never panic.

use std::path::{Path, PathBuf};

use vcm_scene::loader::{load_gltf_from_bytes, obj::load_obj_from_reader};
use vcm_scene::{Scene, SceneError};

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

/// Feeds every input of `kind` to `load` under the name `/nonexistent-fuzz-dir/<name>`:
/// each must load or fail with an error that names that file.
fn replay(kind: &str, name: &str, load: impl Fn(&Path, Vec<u8>) -> Result<Scene, SceneError>) {
    let files = inputs(kind);
    assert!(!files.is_empty(), "no {kind} fuzz inputs found");
    let path = Path::new("/nonexistent-fuzz-dir").join(name);
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        if let Err(e) = load(&path, bytes) {
            assert!(e.to_string().contains(name), "{}: {e}", file.display());
        }
    }
}

#[test]
fn gltf_fuzz_inputs_never_panic() {
    replay("gltf", "input.gltf", |path, bytes| {
        load_gltf_from_bytes(path, &bytes)
    });
}

#[test]
fn obj_fuzz_inputs_never_panic() {
    replay("obj", "input.obj", |path, bytes| {
        load_obj_from_reader(path, &mut std::io::Cursor::new(bytes))
    });
}
