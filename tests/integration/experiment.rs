//! `vcm experiment`: an experiment file rendered into images, CSVs, plots, a table and a
//! report; finished runs are read back rather than rendered again; bad files are named.

use std::path::Path;

use crate::command::{arg, stderr, vcm, vcm_ok};

/// An experiment of two runs on the Cornell box at 24 pixels wide, `budget` each, with a
/// rendered reference; the scene path is absolute so the file may live anywhere.
fn experiment(budget: &str) -> String {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf");
    format!(
        r#"title = "Two runs"
width = 24
{budget}
baseline = "vcm"

[reference]
options = "--algo pt --seed 99"
spp = 16

[[scenes]]
path = "{}"

[[runs]]
name = "pt, 1 sample"
options = "--algo pt"

[[runs]]
name = "vcm"
options = "--algo vcm --connections 2"
"#,
        scene.display()
    )
}

#[test]
fn an_experiment_writes_its_results_and_resumes_finished_runs() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("two.toml");
    std::fs::write(&file, experiment("spp = 3")).unwrap();
    vcm_ok(&["experiment", arg(&file)]);
    let results = dir.path().join("two");
    let scene = results.join("cornell-box");
    for name in [
        "reference.exr",
        "relmse.png",
        "pt--1-sample.exr",
        "pt--1-sample.png",
        "pt--1-sample.error.png",
        "pt--1-sample.csv",
        "vcm.totals.csv",
        "reference.crop.png",
        "pt--1-sample.crop.png",
        "vcm.error-crop.png",
    ] {
        assert!(scene.join(name).is_file(), "{name} is missing");
    }
    let table = std::fs::read_to_string(results.join("table.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 3, "{table}");
    assert!(
        rows[1].starts_with("cornell-box,\"pt, 1 sample\",3,"),
        "{table}"
    );
    // The baseline's speed-up is 1.
    assert!(rows[2].starts_with("cornell-box,vcm,3,") && rows[2].ends_with(",1.000"));
    let report = std::fs::read_to_string(results.join("report.md")).unwrap();
    assert!(report.contains("# Two runs") && report.contains("speed-up vs vcm"));
    assert!(
        report.contains("![](cornell-box/vcm.error.png)"),
        "{report}"
    );
    // The crop: a quarter of the 24 pixels, made 8 (the least), shown 16× larger.
    assert!(
        report.contains("The 8×8 pixels at (")
            && report.contains("![](cornell-box/vcm.error-crop.png)"),
        "{report}"
    );
    let crop = image::open(scene.join("vcm.crop.png")).unwrap();
    assert_eq!((crop.width(), crop.height()), (128, 128));

    // Run again with one run's totals gone: only that run is rendered.
    std::fs::remove_file(scene.join("vcm.totals.csv")).unwrap();
    let again = vcm_ok(&["experiment", arg(&file)]);
    let said = String::from_utf8_lossy(&again.stdout);
    assert!(said.contains("finished earlier"), "{said}");
    assert_eq!(said.matches("finished earlier").count(), 1, "{said}");
    assert!(scene.join("vcm.totals.csv").is_file());

    // Everything finished: the report is written again without a reference.
    std::fs::remove_file(scene.join("reference.exr")).unwrap();
    std::fs::remove_file(results.join("report.md")).unwrap();
    vcm_ok(&["experiment", arg(&file)]);
    assert!(results.join("report.md").is_file());
    assert!(!scene.join("reference.exr").exists());
}

/// The mean of the red, green and blue means of `exr`.
fn mean_radiance(exr: &Path) -> f32 {
    let image = vcm::image_io::RgbImage::read_exr(exr).unwrap();
    let sum: f32 = image.pixels.iter().map(|p| p.element_sum()).sum();
    sum / (3 * image.pixels.len()) as f32
}

/// `lights = "bulb-and-sky"` adds a point light and a sky to the box (its ceiling light
/// stays, being part of the mesh): the reference, rendered with the same seed, is brighter.
#[test]
fn an_experiment_may_light_a_scene_by_a_bulb_and_a_sky() {
    let dir = tempfile::tempdir().unwrap();
    let reference_mean = |name: &str, text: String| {
        let file = dir.path().join(format!("{name}.toml"));
        std::fs::write(&file, text).unwrap();
        vcm_ok(&["experiment", arg(&file)]);
        mean_radiance(&dir.path().join(name).join("cornell-box/reference.exr"))
    };
    let plain = reference_mean("plain", experiment("spp = 1"));
    let lit = experiment("spp = 1").replace(".gltf\"\n", ".gltf\"\nlights = \"bulb-and-sky\"\n");
    let lit = reference_mean("lit", lit);
    assert!(lit > 1.2 * plain, "lit {lit}, plain {plain}");
}

#[test]
fn bad_experiment_files_are_named_with_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            experiment("spp = 2\nseconds = 1"),
            "give `seconds` or `spp`",
        ),
        (experiment("colour = 3\nspp = 2"), "colour"),
        (
            experiment("spp = 2").replace("--connections 2", "--connections two"),
            "run `vcm`",
        ),
        (
            experiment("spp = 2").replace("baseline = \"vcm\"", "baseline = \"mlt\""),
            "the baseline `mlt` is not a run",
        ),
        (
            experiment("spp = 2").replace("name = \"vcm\"", "name = \"pt, 1 sample\""),
            "names the files of another run",
        ),
        (
            experiment("spp = 2").replace(".gltf\"\n", ".gltf\"\ncrop = [20, 0, 8]\n"),
            "the crop [20, 0, 8] does not lie inside the 24×24 image",
        ),
        (
            experiment("spp = 2").replace(".gltf\"\n", ".gltf\"\nlights = \"candles\"\n"),
            "unknown variant `candles`",
        ),
    ];
    for (text, expected) in cases {
        let file = dir.path().join("bad.toml");
        std::fs::write(&file, &text).unwrap();
        let output = vcm(&["experiment", arg(&file)]);
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{message}");
        assert!(
            message.contains("bad.toml") && message.contains(expected),
            "{expected}: {message}"
        );
    }
}
