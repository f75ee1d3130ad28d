//! Running the `vcm` binary from the tests.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `vcm` with `args` in the package's folder and returns what it did.
pub fn vcm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the vcm binary runs")
}

/// Runs `vcm` and fails the test with its stderr unless it succeeds.
pub fn vcm_ok(args: &[&str]) -> Output {
    let output = vcm(args);
    assert!(output.status.success(), "vcm {args:?}: {}", stderr(&output));
    output
}

/// What a run of `vcm` printed on stderr.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// `path` as an argument.
pub fn arg(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 temporary path")
}
