//! Render states through the command line: `--state`, `--resume`, `--samples` and
//! `vcm merge` give the image of one uninterrupted process bit for bit, mismatches are refused
//! with the setting named, and SIGTERM or SIGHUP leave a valid image and state.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use vcm_rs::state::RenderState;

use crate::command::{arg, render_shards, stderr, vcm, vcm_ok};

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

const WATER: &str = "scenes/cornell-water.gltf";

#[test]
fn a_resumed_render_equals_the_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.exr");
    let part = dir.path().join("part.exr");
    let state = dir.path().join("part.state");
    let common = [
        WATER,
        "--algo",
        "bpt",
        "--width",
        "40",
        "--sampler",
        "independent",
    ];
    vcm_ok(&[&["render"], &common[..], &["--spp", "6", "-o", arg(&whole)]].concat());
    vcm_ok(
        &[
            &["render"],
            &common[..],
            &[
                "-o",
                arg(&part),
                "--state",
                arg(&state),
                "--samples",
                "0..2",
            ],
        ]
        .concat(),
    );
    // The shard ran 0..2 only; resuming without --spp goes nowhere (no target recorded).
    let output = vcm(&["render", "--resume", arg(&state)]);
    assert!(!output.status.success());
    assert!(stderr(&output).contains("--spp"), "{}", stderr(&output));
    // Resume to 6 in frames of 2, written to the state's output (part.exr).
    vcm_ok(&[
        "render",
        "--resume",
        arg(&state),
        "--spp",
        "6",
        "--spp-per-frame",
        "2",
    ]);
    assert_eq!(bytes(&part), bytes(&whole), "resumed image");
    let resumed = RenderState::load(&state).unwrap();
    assert_eq!(resumed.samples.to_string(), "0..6");
    // Settings given with --resume must agree with the state's.
    let output = vcm(&[
        "render",
        "--resume",
        arg(&state),
        "--spp",
        "8",
        "--seed",
        "3",
    ]);
    assert!(!output.status.success());
    let message = stderr(&output);
    assert!(
        message.contains("seed 0") && message.contains("asks for 3"),
        "{message}"
    );
    // Another scene under the state's settings is refused by its content.
    let output = vcm(&[
        "render",
        "scenes/cornell-box.gltf",
        "--resume",
        arg(&state),
        "--spp",
        "8",
    ]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("content differs"),
        "{}",
        stderr(&output)
    );
    assert_eq!(
        RenderState::load(&state).unwrap(),
        resumed,
        "refusals write nothing"
    );
}

#[test]
fn shards_merged_equal_one_process() {
    let dir = tempfile::tempdir().unwrap();
    let common = [WATER, "--algo", "vcm", "--width", "40"];
    let whole = dir.path().join("whole.exr");
    vcm_ok(&[&["render"], &common[..], &["--spp", "8", "-o", arg(&whole)]].concat());
    let states = render_shards(dir.path(), &common, &["4..8", "0..1", "1..4"]);
    let merged = dir.path().join("merged.exr");
    let all = dir.path().join("all.state");
    let mut args = vec!["merge"];
    args.extend(states.iter().map(|s| arg(s)));
    args.extend(["-o", arg(&merged), "--state", arg(&all)]);
    vcm_ok(&args);
    assert_eq!(bytes(&merged), bytes(&whole), "merged image");
    assert_eq!(RenderState::load(&all).unwrap().samples.to_string(), "0..8");
    // Overlapping shards, and a shard of other settings, are refused.
    let output = vcm(&["merge", arg(&states[1]), arg(&all), "-o", arg(&merged)]);
    assert!(
        stderr(&output).contains("both hold samples 0..1"),
        "{}",
        stderr(&output)
    );
    let other = dir.path().join("other.state");
    let exr = dir.path().join("other.exr");
    vcm_ok(
        &[
            &["render"],
            &common[..],
            &["--radius", "0.02", "--samples", "8..9"],
            &["--state", arg(&other), "-o", arg(&exr)],
        ]
        .concat(),
    );
    let output = vcm(&["merge", arg(&all), arg(&other), "-o", arg(&merged)]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("radius 0.02 instead of"),
        "{}",
        stderr(&output)
    );
    assert_eq!(
        bytes(&merged),
        bytes(&whole),
        "a refused merge writes nothing"
    );
}

/// Starts a long render that writes its state after every frame.
fn start_long_render(dir: &Path) -> (Child, PathBuf, PathBuf) {
    let state = dir.join("long.state");
    let exr = dir.join("long.exr");
    let child = Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(["render", WATER, "--algo", "vcm", "--width", "64"])
        .args(["--spp", "1000000", "--checkpoint-every", "0.001"])
        .args(["--state", arg(&state), "-o", arg(&exr)])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the vcm binary runs");
    (child, state, exr)
}

/// Waits up to `limit` for `child` to end.
fn wait_for(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if let Some(status) = child.try_wait().expect("the child can be waited for") {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    None
}

#[test]
fn sigterm_and_sighup_stop_a_render_with_a_valid_image_and_state() {
    for signal in ["-TERM", "-HUP"] {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, state, exr) = start_long_render(dir.path());
        // Wait for the first checkpoint, so that at least one frame is done.
        let start = Instant::now();
        while !state.is_file() {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "no checkpoint written"
            );
            assert!(
                child.try_wait().unwrap().is_none(),
                "the render ended early"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let pid = child.id().to_string();
        let killed = Command::new("kill").args([signal, &pid]).status().unwrap();
        assert!(killed.success());
        let sent = Instant::now();
        let status = wait_for(&mut child, Duration::from_secs(30));
        let Some(status) = status else {
            let _ = child.kill();
            panic!("{signal}: the render did not stop within 30 s");
        };
        let stopped_after = sent.elapsed();
        let output = child.wait_with_output().unwrap();
        assert!(status.success(), "{signal}: {}", stderr(&output));
        assert!(
            stderr(&output).contains("interrupted"),
            "{}",
            stderr(&output)
        );
        assert!(
            stopped_after < Duration::from_secs(5),
            "{signal}: stopped after {stopped_after:?}"
        );
        // The state holds whole samples 0..k, and the image is the render of exactly those.
        let saved = RenderState::load(&state).unwrap();
        let ranges = saved.samples.ranges().to_vec();
        assert_eq!(ranges.len(), 1, "{}", saved.samples);
        assert_eq!(ranges[0].start, 0);
        let spp = ranges[0].end.to_string();
        let again = dir.path().join("again.exr");
        vcm_ok(&[
            "render",
            WATER,
            "--algo",
            "vcm",
            "--width",
            "64",
            "--spp",
            &spp,
            "-o",
            arg(&again),
        ]);
        assert_eq!(bytes(&exr), bytes(&again), "{signal}: {spp} spp");
        // Nothing else is left in the folder: no temporary file.
        let mut names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                "again.exr",
                "again.png",
                "long.exr",
                "long.png",
                "long.state"
            ]
        );
    }
}
