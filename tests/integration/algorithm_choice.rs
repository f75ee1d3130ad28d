//! `--algo auto` ([`vcm_rs::integrators::choice`]): the pilots on the committed scenes, and
//! the choice on the command line (tells why; renders what the chosen algorithm renders;
//! the same in every shard).

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use vcm_rs::integrators::choice::{self, Choice, Pilots};
use vcm_rs::integrators::{self, Algorithm, IntegratorOptions, image_size};
use vcm_rs::scene::Scene;
use vcm_rs::traversal::Traversal;
use vcm_rs::vcm::Film;
use vcm_rs::vcm::StopFlag;

use crate::command::{arg, render_shards, stderr, vcm_ok};

/// The choice for scene `name` of `scenes/` at 512 pixels wide with seed `seed`.
fn choose(name: &str, seed: u64) -> Choice {
    let options = IntegratorOptions {
        seed,
        ..IntegratorOptions::default()
    };
    choose_with(name, (512, 0), &options)
}

/// The choice for scene `name` of `scenes/` at `width` × `height` (0: from the camera) with
/// `options`, piloted on the CPU.
fn choose_with(name: &str, (width, height): (u32, u32), options: &IntegratorOptions) -> Choice {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let scene = Arc::new(Scene::load(&path).unwrap_or_else(|e| panic!("{e}")));
    let traversal: Arc<dyn Traversal> = Arc::new(vcm_rs::cpu_traversal(&scene).unwrap());
    let size = image_size(&scene, width, (height > 0).then_some(height));
    let pilots = Pilots::Cpu(&traversal);
    choice::choose(&scene, pilots, size, options, &StopFlag::new()).unwrap()
}

fn algorithms(choice: &Choice) -> Vec<Algorithm> {
    choice.candidates.iter().map(|c| c.algorithm).collect()
}

/// Counts measure the cost, so the same inputs choose the same from the same numbers; VCM is
/// a candidate only where merging has specular surfaces to serve.
#[test]
fn the_choice_is_a_function_of_the_inputs_and_vcm_runs_only_where_it_merges() {
    let box_choice = choose("cornell-box.gltf", 0);
    assert_eq!(algorithms(&box_choice), [Algorithm::Pt, Algorithm::Bpt]);
    assert_eq!(box_choice.pilot_size, (128, 128));
    let again = choose("cornell-box.gltf", 0);
    for (a, b) in box_choice.candidates.iter().zip(&again.candidates) {
        assert_eq!(a.measured, b.measured);
        assert_eq!(a.relative_variance, b.relative_variance);
        assert_eq!(a.cost.to_bits(), b.cost.to_bits());
    }
    for candidate in &box_choice.candidates {
        let v = candidate.relative_variance;
        assert!(v.value > 0.0 && v.upper().is_finite(), "{candidate:?}");
        // The pixels' terms are many: the estimate is tight on a diffuse room.
        assert!(v.standard_error < 0.1 * v.value, "{candidate:?}");
        // A path costs at least its camera ray and one light sample.
        assert!(candidate.cost >= 2.0, "{candidate:?}");
    }
}

/// On a plain diffuse room path tracing is the most efficient at equal time (its direct
/// light gains most from the stratified samples, and its samples cost a third of BPT's); the
/// pilots see both, across seeds.
#[test]
fn a_plain_diffuse_room_is_left_to_path_tracing() {
    for seed in [0, 1, 2] {
        let choice = choose("cornell-box.gltf", seed);
        assert_eq!(choice.algorithm, Algorithm::Pt, "{choice:?}");
        let [pt, bpt] = &choice.candidates[..] else {
            unreachable!()
        };
        // Stratification lowers path tracing's variance per sample more than BPT's, whose
        // light paths land in pixels at random.
        assert!(pt.stratification > bpt.stratification, "{choice:?}");
        // The candidates are compared at equal time: BPT renders fewer samples in it.
        assert_eq!(pt.samples, choice::COMPARED_AT_SPP);
        assert!((bpt.samples * bpt.cost - pt.samples * pt.cost).abs() < 1e-9 * pt.cost);
    }
}

/// With 1,024 connections per camera vertex a BPT sample costs hundreds of path-tracing
/// samples: its pilot stops after one frame, and the candidates piloted choose.
#[test]
fn a_candidate_too_costly_to_compare_is_left_out_after_one_frame() {
    let options = IntegratorOptions {
        connections: 1024,
        ..IntegratorOptions::default()
    };
    let choice = choose_with("cornell-box.gltf", (64, 64), &options);
    assert_eq!(algorithms(&choice), [Algorithm::Pt]);
    assert_eq!(choice.algorithm, Algorithm::Pt);
    let [left_out] = &choice.too_costly[..] else {
        panic!("{choice:?}")
    };
    assert_eq!(left_out.algorithm, Algorithm::Bpt);
    assert!(left_out.cost > choice::COMPARED_AT_SPP * choice.candidates[0].cost);
    assert!(choice.time() >= left_out.time);
    // With the default connection, BPT is compared as usual.
    let usual = choose_with("cornell-box.gltf", (64, 64), &IntegratorOptions::default());
    assert!(usual.too_costly.is_empty());
    assert_eq!(algorithms(&usual), [Algorithm::Pt, Algorithm::Bpt]);
}

/// Through water, path tracing meets the caustics only by chance: its fireflies make its
/// variance × cost tens of times VCM's (measured 84 against 2.6 at seed 0), across seeds.
#[test]
fn caustics_through_water_are_not_left_to_path_tracing() {
    for seed in [0, 1] {
        let choice = choose("cornell-water.gltf", seed);
        assert_eq!(
            algorithms(&choice),
            [Algorithm::Pt, Algorithm::Bpt, Algorithm::Vcm]
        );
        let [pt, _, vcm] = &choice.candidates[..] else {
            unreachable!()
        };
        assert!(pt.inefficiency() > 5.0 * vcm.inefficiency(), "{choice:?}");
        assert_ne!(choice.algorithm, Algorithm::Pt);
    }
}

/// The Khronos avocado under a point light and a dim sky: a point light and smooth
/// (delta) lobes, so path tracing and BPT may miss light that only merging finds — but its
/// shine carries next to nothing of the bulb into the camera. The pilots measure that they
/// miss next to nothing (path tracing's relMSE at 10 s was 10× lower than VCM's,
/// docs/algorithms.md), and auto renders path tracing.
#[test]
fn light_that_only_merging_finds_is_measured_before_it_decides() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/scenes/khronos-samples/Avocado/glTF/Avocado.gltf");
    let scene = vcm_rs::scene::relight::lit_by_bulb_and_sky(Scene::load(&path).unwrap());
    let scene = Arc::new(scene);
    assert!(choice::only_merging_finds_all_light(&scene));
    let traversal: Arc<dyn Traversal> = Arc::new(vcm_rs::cpu_traversal(&scene).unwrap());
    let options = IntegratorOptions {
        seed: 1,
        ..IntegratorOptions::default()
    };
    let pilots = Pilots::Cpu(&traversal);
    let size = image_size(&scene, 256, None);
    let choice = choice::choose(&scene, pilots, size, &options, &StopFlag::new()).unwrap();
    assert_eq!(choice.algorithm, Algorithm::Pt, "{choice:?}");
    let [pt, _, vcm] = &choice.candidates[..] else {
        panic!("{choice:?}")
    };
    // What path tracing misses is within noise of nothing, and far below its variance.
    let b2 = pt.missed_light.expect("measured");
    assert!(
        b2.value.abs() < 3.0 * b2.standard_error + 1e-5,
        "{choice:?}"
    );
    assert!(
        b2.value * pt.samples < 0.1 * pt.relative_variance.value,
        "{choice:?}"
    );
    assert_eq!(vcm.missed_light, None);
}

/// Mean over `frames` frames (one sample per pixel each) of the `region` (rows, columns)
/// of a `size` image of `scene` rendered with `algorithm`, and its standard error.
fn region_mean(
    scene: &Arc<Scene>,
    algorithm: Algorithm,
    (size, region): ((u32, u32), (Range<u32>, Range<u32>)),
    frames: u32,
) -> (f64, f64) {
    let traversal: Arc<dyn Traversal> = Arc::new(vcm_rs::cpu_traversal(scene).unwrap());
    let options = IntegratorOptions::default();
    let mut integrator = integrators::build(algorithm, scene, traversal, size, &options).unwrap();
    let (rows, columns) = region;
    let means: Vec<f64> = (0..frames)
        .map(|frame| {
            let mut film = Film::new(size.0, size.1);
            integrator.render_frame(&mut film, frame);
            let image = film.mean();
            let pixels = rows
                .clone()
                .flat_map(|y| columns.clone().map(move |x| (x, y)));
            let values: Vec<f64> = pixels
                .map(|(x, y)| f64::from(image[(y * size.0 + x) as usize].element_sum()))
                .collect();
            values.iter().sum::<f64>() / values.len() as f64
        })
        .collect();
    let n = f64::from(frames);
    let mean = means.iter().sum::<f64>() / n;
    let variance = means.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// On `cornell-point` a point light shines through a glass sphere under a mirror: path
/// tracing cannot find that light (no light sample passes the glass, no BSDF sample hits the
/// point), and BPT cannot find it where it is seen in the mirror. VCM's pilot measures what
/// they miss, a relMSE no number of samples lowers, and auto renders VCM (an image too small
/// for pilots renders VCM without them, and says why). The floor under the sphere, lit only
/// through the glass, comes out far darker with path tracing than with BPT's light paths,
/// whatever the samples.
#[test]
fn light_from_a_point_through_glass_is_left_to_merging() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-point.gltf");
    let scene = Arc::new(Scene::load(&path).unwrap());
    assert!(choice::only_merging_finds_all_light(&scene));
    for other in [
        "cornell-box.gltf",
        "cornell-water.gltf",
        "cornell-specular.gltf",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(other);
        assert!(!choice::only_merging_finds_all_light(
            &Scene::load(&path).unwrap()
        ));
    }
    let choice = choose("cornell-point.gltf", 0);
    assert_eq!(choice.algorithm, Algorithm::Vcm);
    assert_eq!(choice.unpiloted, None);
    let [pt, bpt, vcm] = &choice.candidates[..] else {
        panic!("{choice:?}")
    };
    // Both miss light, beyond any doubt the pilots leave (measured 10 and 5 standard errors).
    let [pt_b2, bpt_b2] = [pt, bpt].map(|c| c.missed_light.expect("measured"));
    for b2 in [pt_b2, bpt_b2] {
        assert!(b2.value > 4.0 * b2.standard_error, "{choice:?}");
    }
    // Path tracing misses more than BPT, which finds the caustics seen directly.
    assert!(pt_b2.value > 2.0 * bpt_b2.value, "{choice:?}");
    assert_eq!(vcm.missed_light, None);
    // The floor under the sphere, at 64²: rows 50–61, columns 18–45.
    let under_the_sphere = ((64, 64), (50..62, 18..46));
    let pt = region_mean(&scene, Algorithm::Pt, under_the_sphere.clone(), 64);
    let bpt = region_mean(&scene, Algorithm::Bpt, under_the_sphere, 64);
    let gap = bpt.0 - pt.0;
    let error = (pt.1 * pt.1 + bpt.1 * bpt.1).sqrt();
    assert!(
        gap > 10.0 * error && gap > 0.2 * bpt.0,
        "pt {pt:?}, bpt {bpt:?}"
    );
    // An image too small for pilots renders VCM unpiloted, and says why.
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("small.exr");
    let args = ["--width", "32", "--spp", "1", "-o", arg(&exr)];
    let output = vcm_ok(&[&["render", "scenes/cornell-point.gltf"], &args[..]].concat());
    let told = stderr(&output);
    assert!(
        told.contains("algorithm: vcm (not piloted: a point, spot or directional light")
            && told.contains("the image is too small for pilots to measure how much"),
        "{told}"
    );
}

/// An image of fewer than 64² pixels is not piloted: path tracing renders it.
#[test]
fn small_images_are_path_traced_unpiloted() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("small.exr");
    let args = [
        "--width",
        "63",
        "--height",
        "64",
        "--spp",
        "1",
        "-o",
        arg(&exr),
    ];
    let output = vcm_ok(&[&["render", "scenes/cornell-water.gltf"], &args[..]].concat());
    let told = stderr(&output);
    assert!(
        told.contains("algorithm: pt (an image of fewer than 4096 pixels is not piloted"),
        "{told}"
    );
}

/// A stop raised before the pilots leaves nothing to choose from: path tracing.
#[test]
fn a_stop_before_the_pilots_leaves_path_tracing() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-water.gltf");
    let scene = Arc::new(Scene::load(&path).unwrap());
    let traversal: Arc<dyn Traversal> = Arc::new(vcm_rs::cpu_traversal(&scene).unwrap());
    let stop = StopFlag::new();
    stop.raise();
    let options = IntegratorOptions::default();
    let choice =
        choice::choose(&scene, Pilots::Cpu(&traversal), (64, 64), &options, &stop).unwrap();
    assert_eq!(choice.algorithm, Algorithm::Pt);
    assert!(choice.candidates.is_empty());
}

/// `vcm render` without `--algo` pilots, says what it chose, and renders exactly what that
/// algorithm renders; with `--explain` it lists every candidate. Shards choose alike (a
/// shard is always piloted), so their states merge into the whole render.
#[test]
fn the_command_line_chooses_says_why_and_shards_agree() {
    let dir = tempfile::tempdir().unwrap();
    let water = "scenes/cornell-water.gltf";
    let common = [water, "--width", "64", "--seed", "3"];
    let spp = ["--spp", "4"];
    let auto = dir.path().join("auto.exr");
    let output = vcm_ok(&[&["render"], &common[..], &spp, &["-o", arg(&auto)]].concat());
    let told = stderr(&output);
    let line = told
        .lines()
        .find(|l| l.starts_with("algorithm: "))
        .unwrap_or_else(|| panic!("no choice told in\n{told}"));
    let name = line["algorithm: ".len()..].split(' ').next().unwrap();
    assert!(line.contains("variance × cost: pt "), "{line}");
    let fixed = dir.path().join("fixed.exr");
    let args = ["--algo", name, "-o", arg(&fixed)];
    vcm_ok(&[&["render"], &common[..], &spp, &args[..]].concat());
    assert_eq!(
        std::fs::read(&auto).unwrap(),
        std::fs::read(&fixed).unwrap()
    );

    let args = ["--explain", "-o", arg(&auto)];
    let explained = vcm_ok(&[&["render"], &common[..], &spp, &args[..]].concat());
    let report = String::from_utf8_lossy(&explained.stdout);
    assert!(
        report.contains(&format!("algorithm: {name}, the least")),
        "{report}"
    );
    for candidate in ["pt", "bpt", "vcm"] {
        assert!(
            report.contains(&format!("\n  {candidate:<4} variance")),
            "{report}"
        );
    }
    assert_eq!(report.matches("← chosen").count(), 1, "{report}");

    let states = render_shards(dir.path(), &common, &["0..1", "1..4"]);
    let merged = dir.path().join("merged.exr");
    vcm_ok(&[
        "merge",
        arg(&states[0]),
        arg(&states[1]),
        "-o",
        arg(&merged),
    ]);
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&fixed).unwrap()
    );
}
