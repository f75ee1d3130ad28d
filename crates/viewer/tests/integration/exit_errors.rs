//! The viewer's errors before any window opens: a message naming the problem and exit
//! status 1, also when nobody reads the message (no display is needed for these).

use std::process::{Command, ExitStatus, Output};

fn viewer(args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_vcm-viewer"));
    command.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    command
}

const MISSING_REFERENCE: [&str; 3] = [
    "../../scenes/cornell-box.gltf",
    "--reference",
    "/nonexistent-folder/ref.exr",
];

#[test]
fn a_missing_reference_is_an_error_naming_it() {
    let Output { status, stderr, .. } = viewer(&MISSING_REFERENCE).output().unwrap();
    let stderr = String::from_utf8_lossy(&stderr);
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("/nonexistent-folder/ref.exr"), "{stderr}");
}

#[test]
fn an_error_into_a_closed_pipe_still_exits_with_status_1() {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let status: ExitStatus = viewer(&MISSING_REFERENCE).stderr(writer).status().unwrap();
    // `eprintln!` would panic on the broken pipe: status 101.
    assert_eq!(status.code(), Some(1), "{status}");
}
