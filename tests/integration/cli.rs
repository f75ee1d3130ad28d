//! The `vcm` command line: renders write EXR and PNG, bad input gives a clear error and a
//! non-zero exit status, `compare` reports metrics.

use std::path::Path;
use std::process::Command;

use crate::command::{stderr, vcm};

#[test]
fn render_writes_exr_and_png_and_compare_measures_them() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("box.exr");
    let exr_arg = exr.to_str().unwrap();
    let output = vcm(&[
        "render", "--spp", "2", "--width", "48", "--height", "32", "-o", exr_arg,
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let summary = String::from_utf8_lossy(&output.stdout);
    assert!(
        summary.contains("samples/s") && summary.contains("dropped"),
        "{summary}"
    );
    let image = vcm::image_io::RgbImage::read_exr(&exr).unwrap();
    assert_eq!((image.width, image.height), (48, 32));
    let mean =
        image.pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / image.pixels.len() as f32;
    assert!(
        mean > 0.01 && mean.is_finite(),
        "the Cornell box renders light: mean {mean}"
    );
    assert!(exr.with_extension("png").is_file());

    let diff = dir.path().join("diff.png");
    let output = vcm(&[
        "compare",
        exr_arg,
        exr_arg,
        "--diff",
        diff.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(String::from_utf8_lossy(&output.stdout).contains("relmse 0.0"));
    assert!(diff.is_file());
}

#[test]
fn the_report_records_error_against_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference.exr");
    let common = ["--width", "24", "--height", "24"];
    let mut args = vec!["render", "--spp", "8", "-o", reference.to_str().unwrap()];
    args.extend(common);
    assert!(vcm(&args).status.success());
    let report = dir.path().join("conv.csv");
    let out = dir.path().join("short.exr");
    let mut args = vec![
        "render",
        "--spp",
        "1",
        "--seed",
        "7",
        "-o",
        out.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend(common);
    let output = vcm(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let csv = std::fs::read_to_string(&report).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("seconds,spp,rmse,relmse,mae"));
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(last[1], 1.0);
    assert!(last[3] > 0.0, "a 1 spp render differs from an 8 spp one");
    let plot = image::open(report.with_extension("png")).unwrap();
    assert_eq!((plot.width(), plot.height()), (800, 600));
}

#[test]
fn convergence_compares_algorithms_in_one_plot_csv_and_table() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("reference.exr");
    let size = ["--width", "16", "--height", "16"];
    let mut args = vec!["render", "--spp", "4", "-o", reference.to_str().unwrap()];
    args.extend(size);
    assert!(vcm(&args).status.success());
    let plot = dir.path().join("conv.png");
    let mut args = vec![
        "convergence",
        "scenes/cornell-box.gltf",
        "--algos",
        "pt,vcm",
        "--time",
        "0.3",
        "--reference",
        reference.to_str().unwrap(),
        "-o",
        plot.to_str().unwrap(),
    ];
    args.extend(size);
    let output = vcm(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let table = String::from_utf8_lossy(&output.stdout);
    assert!(table.contains("frames/s"), "{table}");
    let rows: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("pt ") || l.starts_with("vcm "))
        .collect();
    assert_eq!(rows.len(), 2, "{table}");
    let csv = std::fs::read_to_string(plot.with_extension("csv")).unwrap();
    assert!(csv.starts_with("algorithm,seconds,spp,rmse,relmse,mae\n"));
    assert!(
        csv.lines().any(|l| l.starts_with("pt,")) && csv.lines().any(|l| l.starts_with("vcm,"))
    );
    assert!(image::open(&plot).is_ok());
}

#[test]
fn every_algorithm_renders_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    for algo in ["pt", "lt", "bpt", "ppm", "bpm", "vcm"] {
        let exr = dir.path().join(format!("{algo}.exr"));
        let args = [
            "render",
            "--algo",
            algo,
            "--spp",
            "2",
            "--width",
            "16",
            "-o",
            exr.to_str().unwrap(),
        ];
        let output = vcm(&args);
        assert!(output.status.success(), "{algo}: {}", stderr(&output));
        let image = vcm::image_io::RgbImage::read_exr(&exr).unwrap();
        assert!(
            image.pixels.iter().any(|p| p.max_element() > 0.0),
            "{algo}: black image"
        );
    }
}

#[test]
fn bad_input_is_a_clear_error_with_non_zero_status() {
    let folder = std::env::temp_dir();
    let folder = folder.to_str().expect("a UTF-8 temporary folder");
    let cases: [(&[&str], &str); 20] = [
        (&["render", "no/such/scene.gltf"], "scene.gltf"),
        (&["render", "--spp", "0"], "--spp"),
        (
            &["render", "--algo", "vcm", "--connections", "0"],
            "connections",
        ),
        (
            &["render", "--algo", "vcm", "--light-paths", "17"],
            "light paths per pixel from 1/16 to 16",
        ),
        (
            &["render", "--algo", "bpt", "--light-paths", "none"],
            "--light-paths",
        ),
        (&["render", "--algo", "ppm", "--radius", "0"], "radius"),
        (&["render", "--algo", "vcm", "--radius", "-2px"], "radius"),
        (
            &["render", "--algo", "vcm", "--radius", "2 pixels"],
            "2 pixels",
        ),
        (&["render", "--algo", "bpm", "--alpha", "1.5"], "alpha"),
        (&["render", "-o", "/nonexistent-folder/out.exr"], "out.exr"),
        // The tone-mapped PNG would replace the EXR, the plot the CSV, the render its
        // reference: refused before rendering.
        (
            &["render", "-o", "x.png"],
            "both the EXR image and the tone-mapped PNG",
        ),
        (&["render", "-o", folder], "is a folder"),
        (
            &["render", "-o", "r.exr", "--reference", "./r.exr"],
            "would replace the input ./r.exr",
        ),
        (
            &[
                "convergence",
                "scenes/cornell-box.gltf",
                "--reference",
                "r.exr",
                "-o",
                "c.csv",
            ],
            "both the plot and the CSV",
        ),
        (&["render", "--width", "0"], "--width"),
        (
            &["compare", "a.exr", "b.exr", "--diff", "b.exr"],
            "would replace the input b.exr",
        ),
        (&["render", "--bogus-option"], "--bogus-option"),
        (&["render", "--spp-per-frame", "0"], "samples per frame"),
        (
            &["render", "--scheduler", "tile", "--tile-size", "0"],
            "tile size",
        ),
        (
            &["render", "--scheduler", "queue", "--queues", "0"],
            "at least 1 queue",
        ),
    ];
    for (args, needle) in cases {
        let output = vcm(args);
        assert!(!output.status.success(), "{args:?} succeeded");
        let message = stderr(&output);
        assert!(message.contains(needle), "{args:?}: {message}");
    }
    // The reason is said once, not repeated by the chain of error sources.
    let missing = stderr(&vcm(&["render", "no/such/scene.gltf"]));
    assert_eq!(missing.matches("No such file").count(), 1, "{missing}");
    assert!(!Path::new("/nonexistent-folder").exists());
}

/// The Cornell box with a second camera, "Close" (index 1), placed by node "close-up"
/// nearer the blocks; with `only_close` that camera replaces the file's own.
fn cornell_box_with_close_up(only_close: bool) -> String {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf"),
    )
    .unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let close = serde_json::json!({"type": "perspective", "name": "Close",
        "perspective": {"yfov": 0.45, "znear": 0.01}});
    doc["cameras"].as_array_mut().unwrap().push(close);
    let node = serde_json::json!({"name": "close-up", "camera": 1,
        "translation": [0.3, -0.2, 2.2], "rotation": [0.0, 0.0499792, 0.0, 0.9987503]});
    let nodes = doc["nodes"].as_array_mut().unwrap();
    if only_close {
        let own = nodes.iter_mut().find(|n| n["camera"] == 0).unwrap();
        *own = node;
    } else {
        nodes.push(node);
        let last = nodes.len() - 1;
        doc["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(last.into());
    }
    doc.to_string()
}

/// `--camera` renders from the file's camera of that index or name: the same image, bit for
/// bit, as a file whose only camera it is; a camera that is not there is named in the error
/// with those that are.
#[test]
fn another_camera_of_the_file_is_chosen_by_index_or_name() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |name: &str, only_close| {
        let path = dir.path().join(name);
        std::fs::write(&path, cornell_box_with_close_up(only_close)).unwrap();
        path.to_str().unwrap().to_string()
    };
    let (two, one) = (scene("two.gltf", false), scene("one.gltf", true));
    let render = |scene: &str, camera: Option<&str>, out: &str| {
        let out = dir.path().join(out);
        let mut args = vec![
            "render", scene, "--spp", "2", "--width", "24", "--height", "24",
        ];
        args.extend(camera.map(|c| ["--camera", c]).into_iter().flatten());
        args.extend(["-o", out.to_str().unwrap()]);
        let output = vcm(&args);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
        vcm::image_io::RgbImage::read_exr(&out).unwrap().pixels
    };
    let close = render(&one, None, "one.exr");
    assert_ne!(
        render(&two, None, "first.exr"),
        close,
        "the cameras see the same image"
    );
    for choice in ["1", "Close", "close-up"] {
        assert_eq!(
            render(&two, Some(choice), "chosen.exr"),
            close,
            "--camera {choice}"
        );
    }
    let output = vcm(&["render", &two, "--camera", "2", "-o", "never.exr"]);
    assert!(!output.status.success());
    let message = stderr(&output);
    assert!(
        message.contains("two.gltf: no camera '2': the file's cameras are 0 (node 'camera'), 1 'Close' (node 'close-up')"),
        "{message}"
    );
    assert!(
        !Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("never.exr")
            .exists()
    );
}

/// The tile and queue schedulers with several samples per frame render the same image as one
/// batch per pass with the same samples per frame: scheduling changes speed, not results. The
/// VCM family's frames of several samples are its iterations side by side, so its image does
/// not depend on the samples per frame either.
#[test]
fn schedulers_render_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let exr = dir.path().join(format!("{name}.exr"));
        let mut args = vec!["render", "--spp", "4", "--width", "40"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", exr.to_str().unwrap()]);
        let output = vcm(&args);
        assert!(output.status.success(), "{name}: {}", stderr(&output));
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(stdout.contains("rendered 4 spp"), "{name}: {stdout}");
        vcm::image_io::RgbImage::read_exr(&exr).unwrap().pixels
    };
    let none = render("none", &["--scheduler", "none", "--spp-per-frame", "2"]);
    // Frames of 3 stop at the 4 samples asked for: 3 + 1, the same samples.
    let threes = render("threes", &["--spp-per-frame", "3"]);
    let tiles = render(
        "tile",
        &[
            "--scheduler",
            "tile",
            "--tile-size",
            "8",
            "--spp-per-frame",
            "2",
        ],
    );
    let queues = [
        "--scheduler",
        "queue",
        "--queues",
        "3",
        "--tile-size",
        "8",
        "--spp-per-frame",
        "2",
    ];
    let queue = render("queue", &queues);
    assert!(none.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(none, tiles);
    assert_eq!(none, queue);
    assert_eq!(none, threes);
    let vcm_one = render("vcm-1", &["--algo", "vcm", "--scheduler", "none"]);
    let vcm_four = render(
        "vcm-4",
        &["--algo", "vcm", "--tile-size", "8", "--spp-per-frame", "4"],
    );
    assert!(vcm_one.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(vcm_one, vcm_four);
}

/// `--scheduler queue` with its default pool renders VCM's image too, and says so in the
/// summary like any other render.
#[test]
fn the_queue_scheduler_renders_vcm() {
    let dir = tempfile::tempdir().unwrap();
    let render = |scheduler: &str| {
        let exr = dir.path().join(format!("{scheduler}.exr"));
        let args = [
            "render",
            "--algo",
            "vcm",
            "--spp",
            "2",
            "--width",
            "24",
            "--scheduler",
            scheduler,
            "--tile-size",
            "8",
            "-o",
            exr.to_str().unwrap(),
        ];
        let output = vcm(&args);
        assert!(output.status.success(), "{scheduler}: {}", stderr(&output));
        let summary = String::from_utf8_lossy(&output.stdout);
        assert!(summary.contains("samples/s"), "{summary}");
        vcm::image_io::RgbImage::read_exr(&exr).unwrap().pixels
    };
    let queue = render("queue");
    assert!(queue.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(queue, render("tile"));
}

/// `--explain` names every part of the render with its verdict and reason; `--no-prune`
/// runs them all, and on the Cornell box (nothing but diffuse surfaces) the path tracer's
/// image does not change.
#[test]
fn explain_prints_what_runs_and_no_prune_runs_everything() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let exr = dir.path().join(format!("{name}.exr"));
        let mut args = vec!["render", "--spp", "2", "--width", "24", "--explain"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", exr.to_str().unwrap()]);
        let output = vcm(&args);
        assert!(output.status.success(), "{name}: {}", stderr(&output));
        let pixels = vcm::image_io::RgbImage::read_exr(&exr).unwrap().pixels;
        (String::from_utf8_lossy(&output.stdout).into_owned(), pixels)
    };
    let (vcm_plan, _) = render("vcm", &["--algo", "vcm"]);
    for line in [
        "light vertex cache: runs",
        "merging and hash grid: left out (no specular or near-specular surface",
        "normal maps and tangents: left out (no material has a normal map)",
        "alpha test in the cpu traversal: left out",
    ] {
        assert!(vcm_plan.contains(line), "missing {line:?} in\n{vcm_plan}");
    }
    let (full_plan, _) = render("vcm-full", &["--algo", "vcm", "--no-prune"]);
    assert!(
        full_plan.contains("merging and hash grid: runs ("),
        "{full_plan}"
    );
    assert!(
        full_plan.contains("normal maps and tangents: runs ("),
        "{full_plan}"
    );
    let (_, pruned) = render("pt", &["--algo", "pt"]);
    let (_, full) = render("pt-full", &["--algo", "pt", "--no-prune"]);
    assert!(pruned.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(pruned, full);
}

/// `--utilization` writes the CPU utilization over time as CSV (intervals of at least 0.25 s)
/// and a plot beside it.
#[test]
fn utilization_is_recorded_over_time() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("util.csv");
    let exr = dir.path().join("out.exr");
    let output = vcm(&[
        "render",
        "--time",
        "1",
        "--width",
        "64",
        "--utilization",
        csv.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("seconds,utilization"));
    let rows: Vec<(f64, f64)> = lines
        .map(|line| {
            let (t, u) = line.split_once(',').unwrap();
            (t.parse().unwrap(), u.parse().unwrap())
        })
        .collect();
    assert!(rows.len() >= 2, "{text}");
    let mut previous = 0.0;
    for (t, u) in rows {
        // The CSV rounds each time to the millisecond, so a difference can be 1 ms short
        // (and the subtraction of two rounded decimals a hair less).
        assert!(
            t - previous >= 0.249 - 1e-9,
            "interval shorter than 0.25 s: {text}"
        );
        // A busy renderer, measured in 10 ms ticks of all its threads' CPU time.
        assert!(u > 0.0 && u <= 105.0, "{text}");
        previous = t;
    }
    assert!(csv.with_extension("png").is_file());
    let summary = String::from_utf8_lossy(&output.stdout);
    assert!(summary.contains("cpu utilization: "), "{summary}");
}

/// Runs `vcm` with stdout and stderr going into pipes whose readers have already left (as in
/// `vcm compare a b | head -1` once `head` is done) and returns its exit status.
fn vcm_into_closed_pipes(args: &[&str]) -> std::process::ExitStatus {
    let (out_reader, out_writer) = std::io::pipe().unwrap();
    let (err_reader, err_writer) = std::io::pipe().unwrap();
    drop((out_reader, err_reader));
    Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(out_writer)
        .stderr(err_writer)
        .status()
        .expect("the vcm binary runs")
}

/// A reader that stops reading (a broken pipe on stdout and stderr) ends neither `compare` nor
/// `info` with a panic, and does not stop a render from writing its image.
#[test]
fn readers_that_leave_early_do_not_break_the_commands() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("box.exr");
    let exr_arg = exr.to_str().unwrap();
    let render = [
        "render",
        "--spp",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--explain",
        "-o",
        exr_arg,
    ];
    let status = vcm_into_closed_pipes(&render);
    assert!(status.success(), "render: {status}");
    assert!(exr.is_file() && exr.with_extension("png").is_file());
    let status = vcm_into_closed_pipes(&["compare", exr_arg, exr_arg]);
    assert!(status.success(), "compare: {status}");
    let status = vcm_into_closed_pipes(&["info"]);
    assert!(status.success(), "info: {status}");
}

#[test]
fn outputs_that_are_not_regular_files_are_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.exr");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let mut targets = vec![fifo];
    // A character device like /dev/null, made here (only root may): never the real one.
    let device = dir.path().join("null.exr");
    let mknod = Command::new("mknod")
        .arg(&device)
        .args(["c", "1", "3"])
        .output();
    if mknod.is_ok_and(|o| o.status.success()) {
        targets.push(device);
    }
    for target in &targets {
        let arg = target.to_str().unwrap();
        let render = vcm(&["render", "--spp", "1", "--width", "8", "-o", arg]);
        let compare = vcm(&[
            "compare",
            "tests/data/missing.exr",
            "tests/data/missing.exr",
            "--diff",
            arg,
        ]);
        for output in [render, compare] {
            assert!(!output.status.success(), "{arg}");
            assert!(
                stderr(&output).contains("not a regular file"),
                "{}",
                stderr(&output)
            );
        }
        let kind = std::fs::symlink_metadata(target).unwrap().file_type();
        assert!(!kind.is_file(), "{arg} is still what it was");
    }
    let names = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(names, targets.len(), "no temporary file is left");
}
