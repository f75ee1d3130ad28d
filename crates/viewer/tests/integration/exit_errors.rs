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

#[test]
fn a_missing_or_damaged_state_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let damaged = dir.path().join("damaged.state");
    std::fs::write(&damaged, b"\x10\0\0\0\0\0\0\0{\"truncated").unwrap();
    let missing = dir.path().join("missing.state");
    for (state, says) in [
        (&damaged, "not a vcm-rs render state"),
        (&missing, "cannot read"),
    ] {
        let Output { status, stderr, .. } = viewer(&["--resume", state.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&stderr);
        assert_eq!(status.code(), Some(1), "{stderr}");
        let names = format!("{}: {says}", state.display());
        assert!(stderr.contains(&names), "{stderr}");
    }
}

#[test]
fn settings_beside_resume_are_refused() {
    let Output { status, stderr, .. } = viewer(&["--resume", "a.state", "--algo", "vcm"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&stderr);
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--resume") && stderr.contains("--algo"),
        "{stderr}"
    );
}
