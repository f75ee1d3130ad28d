//! Running the `vcm` binary from the tests.

use std::path::{Path, PathBuf};
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

/// Renders each of `ranges` (`"A..B"`) of the render `vcm render` with `common` makes, as
/// shards with their states in `dir`; the states' paths, in order.
pub fn render_shards(dir: &Path, common: &[&str], ranges: &[&str]) -> Vec<PathBuf> {
    let mut states = Vec::new();
    for range in ranges {
        let state = dir.join(format!("{range}.state"));
        let exr = dir.join(format!("{range}.exr"));
        let shard = ["--samples", range, "--state", arg(&state), "-o", arg(&exr)];
        vcm_ok(&[&["render"], common, &shard[..]].concat());
        states.push(state);
    }
    states
}
