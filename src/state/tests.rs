//! Render states: resumed and sharded renders equal one process bit for bit, and every kind
//! of damaged, foreign or mismatched state file is refused with a clear error.

use std::path::Path;
use std::sync::Arc;

use super::*;
use crate::integrators::{self, Algorithm, IntegratorOptions, SamplerKind};
use vcm::Integrator;
use vcm_scene::Scene;

const SCENE: &str = "scenes/cornell-water.gltf";

fn scene() -> Arc<Scene> {
    Arc::new(Scene::load(SCENE).expect("the test scene loads"))
}

fn settings(algorithm: Algorithm, sampler: SamplerKind) -> RenderSettings {
    RenderSettings {
        algorithm,
        width: 24,
        height: 18,
        camera: None,
        options: IntegratorOptions {
            seed: 11,
            sampler,
            ..IntegratorOptions::default()
        },
    }
}

fn integrator(scene: &Arc<Scene>, settings: &RenderSettings) -> Box<dyn Integrator> {
    let traversal = Arc::new(crate::cpu_traversal(scene).expect("a BVH"));
    let size = (settings.width, settings.height);
    integrators::build(
        settings.algorithm,
        scene,
        traversal,
        size,
        &settings.options,
    )
    .expect("an integrator")
}

/// A state holding global samples `range`, rendered one sample per frame by one integrator.
fn render(
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    range: std::ops::Range<u32>,
) -> RenderState {
    let mut state = RenderState::new(settings.clone(), scene_hash(scene), SCENE.into());
    let mut integrator = integrator(scene, settings);
    for sample in range.clone() {
        integrator.render_frame(&mut state.film, sample);
    }
    state.samples.insert(range);
    state
}

#[test]
fn resumed_and_merged_renders_equal_one_process_bit_for_bit() {
    let scene = scene();
    let dir = tempfile::tempdir().unwrap();
    for algorithm in [
        Algorithm::Pt,
        Algorithm::Bpt,
        Algorithm::Vcm,
        Algorithm::Ppm,
    ] {
        for sampler in [SamplerKind::Sobol, SamplerKind::Independent] {
            let what = format!("{} {sampler:?}", algorithm.name());
            let settings = settings(algorithm, sampler);
            let whole = render(&scene, &settings, 0..6);
            // Resume: save after 0..2, load, continue with 2..6 in frames of two samples.
            let path = dir.path().join("resume.state");
            render(&scene, &settings, 0..2).save(&path).unwrap();
            let mut resumed = RenderState::load(&path).unwrap();
            let mut integrator = integrator(&scene, &settings);
            let schedule = vcm::Schedule {
                samples_per_frame: 2,
                ..vcm::Schedule::default()
            };
            integrator.set_schedule(schedule).unwrap();
            for first in [2, 4] {
                integrator.render_frame(&mut resumed.film, first);
            }
            resumed.samples.insert(2..6);
            assert_eq!(resumed, whole, "{what}: resumed");
            // Shards, merged in another order through files.
            let mut merged = render(&scene, &settings, 4..5);
            for (i, range) in [2..4, 5..6, 0..2].into_iter().enumerate() {
                let path = dir.path().join(format!("shard{i}.state"));
                render(&scene, &settings, range).save(&path).unwrap();
                let shard = RenderState::load(&path).unwrap();
                merged.merge(&shard, "merged", "shard").unwrap();
            }
            assert_eq!(merged.film, whole.film, "{what}: merged");
            assert_eq!(merged.samples.to_string(), "0..6");
            assert!(whole.film.mean().iter().any(|p| p.max_element() > 0.0));
        }
    }
}

#[test]
fn merging_refuses_overlaps_other_settings_and_other_scenes() {
    let scene = scene();
    let settings = settings(Algorithm::Pt, SamplerKind::Sobol);
    let mut a = render(&scene, &settings, 0..2);
    let b = render(&scene, &settings, 1..3);
    let error = a.merge(&b, "a.state", "b.state").unwrap_err().to_string();
    assert!(error.contains("both hold samples 1..2"), "{error}");
    let mut other = settings.clone();
    other.options.seed = 12;
    other.options.max_depth = Some(4);
    let c = render(&scene, &other, 2..3);
    let error = a.merge(&c, "a.state", "c.state").unwrap_err().to_string();
    assert!(error.contains("seed 12 instead of 11"), "{error}");
    assert!(error.contains("max_depth 4 instead of none"), "{error}");
    let mut elsewhere = render(&scene, &settings, 2..3);
    elsewhere.scene_hash ^= 1;
    let error = a
        .merge(&elsewhere, "a.state", "d.state")
        .unwrap_err()
        .to_string();
    assert!(error.contains("another scene"), "{error}");
    // Nothing was merged by the refused calls.
    assert_eq!(a, render(&scene, &settings, 0..2));
}

/// A small saved state and its bytes.
fn saved(dir: &Path) -> (std::path::PathBuf, Vec<u8>) {
    let path = dir.join("good.state");
    let mut state = render(
        &scene(),
        &settings(Algorithm::Bpt, SamplerKind::Sobol),
        0..2,
    );
    state.target_spp = Some(16);
    state.output = Some("out.exr".into());
    state.save(&path).unwrap();
    assert_eq!(
        RenderState::load(&path).unwrap(),
        state,
        "a state reads back"
    );
    let bytes = std::fs::read(&path).unwrap();
    (path, bytes)
}

#[test]
fn truncated_and_bit_flipped_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes) = saved(dir.path());
    let damaged = dir.path().join("damaged.state");
    // Truncated at 20 points over the whole file, the empty file included.
    for i in 0..20 {
        let length = bytes.len() * i / 20;
        std::fs::write(&damaged, &bytes[..length]).unwrap();
        let error = RenderState::load(&damaged).unwrap_err().to_string();
        assert!(error.starts_with(&damaged.display().to_string()), "{error}");
    }
    // One bit flipped at 40 places: in the length, the header and the tensors.
    for i in 0..40 {
        let at = (bytes.len() - 1) * i / 39;
        let mut flipped = bytes.clone();
        flipped[at] ^= 1 << (i % 8);
        std::fs::write(&damaged, &flipped).unwrap();
        let error = RenderState::load(&damaged).unwrap_err().to_string();
        assert!(
            error.starts_with(&damaged.display().to_string()),
            "byte {at}: {error}"
        );
    }
}

#[test]
fn foreign_files_newer_versions_and_non_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes) = saved(dir.path());
    // A scene file, and a safetensors file that is not a render state.
    let error = RenderState::load(SCENE).unwrap_err();
    assert!(matches!(error, StateError::NotAState { .. }), "{error}");
    let foreign = dir.path().join("weights.safetensors");
    let data = [0u8; 16];
    let view = safetensors::tensor::TensorView::new(safetensors::Dtype::F32, vec![4], &data);
    std::fs::write(
        &foreign,
        safetensors::serialize([("w", view.unwrap())], None).unwrap(),
    )
    .unwrap();
    let error = RenderState::load(&foreign).unwrap_err().to_string();
    assert!(error.contains("not a vcm-rs render state"), "{error}");
    // A newer format version: said so before the checksum is looked at.
    let newer = replaced(
        &bytes,
        "\"format_version\":\"1\"",
        "\"format_version\":\"9\"",
    );
    let newer_path = dir.path().join("newer.state");
    std::fs::write(&newer_path, newer).unwrap();
    let error = RenderState::load(&newer_path).unwrap_err().to_string();
    assert!(
        error.contains("newer vcm-rs") && error.contains("version 9"),
        "{error}"
    );
    // A folder and a missing file.
    let error = RenderState::load(dir.path()).unwrap_err().to_string();
    assert!(error.contains("not a regular file"), "{error}");
    let error = RenderState::load(dir.path().join("missing.state")).unwrap_err();
    assert!(matches!(error, StateError::Read { .. }), "{error}");
}

#[test]
fn edited_metadata_fails_the_checksum() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = saved(dir.path());
    // Same length, so the header stays well formed: only the checksum can tell.
    let edited = replaced(&bytes, "\"seed\":\"11\"", "\"seed\":\"12\"");
    std::fs::write(&path, edited).unwrap();
    let error = RenderState::load(&path).unwrap_err().to_string();
    assert!(error.contains("checksum does not match"), "{error}");
}

/// `bytes` with the first `from` replaced by `to`, of the same length (panics if absent).
fn replaced(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("`{from}` is in the file"));
    let mut edited = bytes.to_vec();
    edited[at..at + to.len()].copy_from_slice(to.as_bytes());
    edited
}

#[test]
fn bytes_read_back_as_the_file_does_and_are_checked() {
    let scene = scene();
    let mut state = render(&scene, &settings(Algorithm::Vcm, SamplerKind::Sobol), 0..2);
    state.target_spp = Some(4);
    let bytes = state.to_bytes().unwrap();
    assert_eq!(RenderState::from_bytes(&bytes, "sent").unwrap(), state);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("state.safetensors");
    state.save(&path).unwrap();
    // The same encoding as the file (whose metadata may come in another order).
    let file = std::fs::read(&path).unwrap();
    assert_eq!(file.len(), bytes.len());
    assert_eq!(RenderState::from_bytes(&file, "file").unwrap(), state);
    let error = RenderState::from_bytes(&bytes[..bytes.len() - 1], "sent").unwrap_err();
    assert!(error.to_string().starts_with("sent: "), "{error}");
}

#[test]
fn saving_with_a_film_in_progress_writes_the_state_that_film_makes() {
    let scene = scene();
    let settings = settings(Algorithm::Bpt, SamplerKind::Sobol);
    let before = render(&scene, &settings, 0..2);
    let after = render(&scene, &settings, 0..4);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("state.safetensors");
    // The earlier state's settings and samples, the later film with samples 2..4 added.
    before.save_with(&after.film, 2..4, &path).unwrap();
    assert_eq!(RenderState::load(&path).unwrap(), after);
    assert_eq!(
        before.samples.to_string(),
        "0..2",
        "the state itself is unchanged"
    );
}
