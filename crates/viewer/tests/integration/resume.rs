//! `vcm-viewer --resume FILE` in a window under Xvfb: a render state written as `vcm render
//! --state` writes it continues there, and a state given with a scene of other content is
//! refused (skipped like the screenshot test when no window can be opened).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use vcm_rs::Backend;
use vcm_rs::integrators::{self, Algorithm, IntegratorOptions};
use vcm_rs::state::{RenderSettings, RenderState, scene_hash};
use vcm_scene::Scene;

use crate::screenshot::under_xvfb;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// A 16 × 12 path-traced state of the Cornell box holding samples 0..2, written to `dir`.
fn cornell_box_state(dir: &Path) -> PathBuf {
    let path = scene_path("cornell-box.gltf");
    let scene = Arc::new(Scene::load(&path).unwrap());
    let settings = RenderSettings {
        algorithm: Algorithm::Pt,
        width: 16,
        height: 12,
        camera: None,
        options: IntegratorOptions {
            seed: 5,
            ..IntegratorOptions::default()
        },
    };
    let traversal = Backend::Cpu.traversal(&scene).unwrap();
    let size = (settings.width, settings.height);
    let mut integrator = integrators::build(
        settings.algorithm,
        &scene,
        traversal,
        size,
        &settings.options,
    )
    .unwrap();
    let mut state = RenderState::new(settings, scene_hash(&scene), path);
    for sample in 0..2 {
        integrator.render_frame(&mut state.film, sample);
    }
    state.samples.insert(0..2);
    let file = dir.join("box.state");
    state.save(&file).unwrap();
    file
}

#[test]
fn a_state_continues_in_the_window_at_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let state = cornell_box_state(dir.path());
    let shot = dir.path().join("resumed.png");
    let args = [
        "--resume".as_ref(),
        state.as_os_str(),
        "--frames".as_ref(),
        "1".as_ref(),
    ];
    let screenshot = ["--screenshot".as_ref(), shot.as_os_str()];
    let Some(output) = under_xvfb(&[&args[..], &screenshot[..]].concat()) else {
        return;
    };
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    assert!(output.status.success(), "{stderr}");
    assert!(stdout.contains("size 16x12"), "{stdout}");
}

#[test]
fn a_state_with_a_scene_of_other_content_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let state = cornell_box_state(dir.path());
    let other = scene_path("cornell-specular.gltf");
    let shot = dir.path().join("refused.png");
    let Some(output) = under_xvfb(&[
        other.as_os_str(),
        "--resume".as_ref(),
        state.as_os_str(),
        "--frames".as_ref(),
        "1".as_ref(),
        "--screenshot".as_ref(),
        shot.as_os_str(),
    ]) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cornell-specular.gltf") && stderr.contains("differs"),
        "{stderr}"
    );
    assert!(!shot.exists());
}
