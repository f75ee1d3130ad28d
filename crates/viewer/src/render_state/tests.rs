//! Render states in the viewer: a saved render is the state of a direct render of the same
//! samples, an opened state continues bit for bit, a render that could not be reproduced is
//! not saved, and foreign or damaged states are errors naming the file.

use std::sync::Arc;
use std::time::{Duration, Instant};

use vcm_rs::integrators::{Algorithm, AlgorithmOption};
use vcm_rs::state::SampleRanges;
use vcm_scene::FileCamera;

use super::*;
use crate::camera_controller::CameraController;
use crate::renderer::Resume;
use crate::renderer::tests::{
    cornell_box, direct_film, film_copy, frames, job, settings, spawn, wait_for,
};
use crate::resolution::ResolutionSwitch;

/// `scene` as the app holds it after loading, rendered at `size`.
fn loaded(scene: &Arc<Scene>, size: (u32, u32)) -> LoadedScene {
    LoadedScene {
        scene: Arc::clone(scene),
        hash: scene_hash(scene),
        choice: None,
        serial: 1,
        controller: CameraController::new(scene.camera, &scene.features.bounds),
        home: scene.camera,
        resolution: ResolutionSwitch::new(size),
    }
}

/// The outcome of `save`, waiting up to a minute.
fn finish(save: &mut PendingSave) -> Result<String, String> {
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        if let Some(outcome) = save.poll() {
            return outcome;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!(
        "saving {} did not finish within a minute",
        save.path().display()
    );
}

/// The cornell box with more cameras: a second camera placed by two nodes (index 1 twice),
/// and a camera whose name repeats the second's.
fn many_cameras() -> Scene {
    let scene = cornell_box();
    let first = scene.cameras[0].clone();
    let moved = |dx: f32| Camera {
        position: first.camera.position + glam::Vec3::X * dx,
        ..first.camera
    };
    let camera = |index, name: Option<&str>, node: Option<&str>, dx| FileCamera {
        index,
        name: name.map(String::from),
        node: node.map(String::from),
        camera: moved(dx),
    };
    Scene {
        cameras: vec![
            first.clone(),
            camera(1, Some("Top"), None, 0.1),
            camera(1, None, Some("Second"), 0.2),
            camera(2, Some("Top"), Some("Third"), 0.3),
        ],
        ..Scene::clone(&scene)
    }
}

#[test]
fn file_cameras_are_picked_as_the_scene_picks_them() {
    let scene = many_cameras();
    for choice in ["0", "1", "2", "3", "Top", "Second", "Third", "none", ""] {
        let mut picked = scene.clone();
        let expected = picked.use_camera(choice).ok().map(|()| picked.camera);
        assert_eq!(file_camera(&scene, choice), expected, "{choice:?}");
    }
}

#[test]
fn the_camera_choice_reproduces_the_camera_or_the_render_is_refused() {
    let scene = many_cameras();
    let cameras: Vec<Camera> = scene.cameras.iter().map(|c| c.camera).collect();
    assert_eq!(camera_choice(&scene, None, &cameras[0]), Ok(None));
    assert_eq!(
        camera_choice(&scene, Some("0"), &cameras[0]),
        Ok(Some("0".into()))
    );
    assert_eq!(
        camera_choice(&scene, None, &cameras[1]),
        Ok(Some("1".into()))
    );
    assert_eq!(
        camera_choice(&scene, Some("Top"), &cameras[1]),
        Ok(Some("Top".into()))
    );
    // "1" and "Top" pick others: only its node's name picks the third camera.
    assert_eq!(
        camera_choice(&scene, None, &cameras[2]),
        Ok(Some("Second".into()))
    );
    assert_eq!(
        camera_choice(&scene, Some("Top"), &cameras[3]),
        Ok(Some("2".into()))
    );
    let mut controller = CameraController::new(cameras[1], &scene.features.bounds);
    controller.orbit(0.01, 0.0);
    let error = camera_choice(&scene, Some("1"), &controller.camera()).unwrap_err();
    assert!(error.contains("camera was moved"), "{error}");
    // A file without cameras has only the camera that frames it.
    let framed = Scene {
        cameras: Vec::new(),
        ..scene.clone()
    };
    assert_eq!(camera_choice(&framed, None, &framed.camera), Ok(None));
    assert!(camera_choice(&framed, None, &cameras[1]).is_err());
}

#[test]
fn a_moved_camera_or_a_preview_is_not_saved() {
    let scene = cornell_box();
    let mut loaded = loaded(&scene, (16, 10));
    let view = job(1, &scene, (16, 10), None).view;
    let state = state_to_save(&loaded, (&view, None), None).unwrap();
    assert_eq!(state.settings.camera, None);
    assert_eq!((state.output, state.target_spp), (None, None));
    let origin = Origin {
        output: Some("water.exr".into()),
        target_spp: Some(64),
    };
    let state = state_to_save(&loaded, (&view, None), Some(&origin)).unwrap();
    assert_eq!(
        state.output, origin.output,
        "a continued state keeps its output"
    );
    assert_eq!(state.target_spp, Some(64));

    let preview = View {
        size: (4, 2),
        ..view.clone()
    };
    let error = state_to_save(&loaded, (&preview, None), None).unwrap_err();
    assert!(error.contains("preview"), "{error}");
    loaded.controller.pan(glam::Vec2::new(0.1, 0.0));
    let moved = View {
        camera: loaded.controller.camera(),
        ..preview
    };
    let error = state_to_save(&loaded, (&moved, None), None).unwrap_err();
    assert_eq!(error, MOVED_CAMERA);
}

#[test]
fn an_auto_render_is_saved_with_the_algorithm_it_chose() {
    let scene = cornell_box();
    let loaded = loaded(&scene, (16, 10));
    let mut view = job(1, &scene, (16, 10), None).view;
    view.settings.algorithm = AlgorithmOption::Auto;
    let error = state_to_save(&loaded, (&view, None), None).unwrap_err();
    assert!(error.contains("still being chosen"), "{error}");
    let state = state_to_save(&loaded, (&view, Some(Algorithm::Bpt)), None).unwrap();
    assert_eq!(state.settings.algorithm, Algorithm::Bpt);
    // A fixed algorithm is the one saved.
    view.settings.algorithm = AlgorithmOption::Fixed(Algorithm::Vcm);
    let state = state_to_save(&loaded, (&view, Some(Algorithm::Vcm)), None).unwrap();
    assert_eq!(state.settings.algorithm, Algorithm::Vcm);
}

/// Saving after n frames gives the state of a direct render of samples 0..n; opening that
/// file again and rendering on gives the direct render of the longer range, bit for bit.
#[test]
fn a_saved_render_is_a_direct_render_and_continues_as_one() {
    let scene = cornell_box();
    let size = (16, 10);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("box.state");
    let (renderer, woken) = spawn(None);
    let first = job(1, &scene, size, Some(2));
    let view = first.view.clone();
    renderer.submit(first);
    wait_for(&renderer, &woken, |u| frames(u, 1, 4));
    let state = state_to_save(&loaded(&scene, size), (&view, None), None).unwrap();
    let mut save = PendingSave::start(&renderer, 1, state, file.clone(), || {});
    let note = finish(&mut save).unwrap();
    assert!(
        note.contains("box.state") && note.contains("samples 0..4"),
        "{note}"
    );

    let saved = read(&file).unwrap();
    let mut direct = RenderState::new(
        state::RenderSettings {
            algorithm: Algorithm::Vcm,
            width: size.0,
            height: size.1,
            camera: None,
            options: view.settings.integrator.clone(),
        },
        scene_hash(&scene),
        scene.path.clone(),
    );
    direct.film = direct_film(&scene, size, 0..4);
    direct.samples = SampleRanges::from_range(0..4);
    assert_eq!(saved, direct);

    // Opened with the scene on screen: the same scene, the same camera.
    let current = Some((Arc::clone(&scene), scene_hash(&scene)));
    let opened = open(&file, saved, None, current).unwrap();
    assert!(
        Arc::ptr_eq(&opened.scene, &scene),
        "the scene is not loaded again"
    );
    assert_eq!((opened.camera, opened.choice), (scene.camera, None));
    let Opened { path, state } = opened.state.unwrap();
    assert_eq!(path, file);
    let mut continued = job(2, &opened.scene, size, Some(3));
    continued.resume = Some(Box::new(Resume {
        film: state.film,
        samples: state.samples,
    }));
    renderer.submit(continued);
    wait_for(&renderer, &woken, |u| frames(u, 2, 6));
    let copy = film_copy(&renderer);
    assert_eq!(copy.samples.to_string(), "0..10");
    assert_eq!(copy.film, direct_film(&scene, size, 0..10));
}

#[test]
fn saving_a_render_that_restarted_or_failed_is_an_error() {
    let scene = cornell_box();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("none.state");
    let (renderer, woken) = spawn(None);
    let state = state_to_save(
        &loaded(&scene, (8, 8)),
        (&job(1, &scene, (8, 8), None).view, None),
        None,
    );
    // Nothing renders: the worker has no film to give.
    let mut save = PendingSave::start(&renderer, 1, state.clone().unwrap(), file.clone(), || {});
    let error = finish(&mut save).unwrap_err();
    assert!(
        error.contains("none.state") && error.contains("restarted"),
        "{error}"
    );
    // Another render than the one asked for.
    renderer.submit(job(2, &scene, (8, 8), Some(1)));
    wait_for(&renderer, &woken, |u| frames(u, 2, 2));
    let mut save = PendingSave::start(&renderer, 1, state.unwrap(), file.clone(), || {});
    assert!(finish(&mut save).unwrap_err().contains("restarted"));
    assert!(!file.exists(), "nothing is written");
}

/// A state of the Cornell box at 8 × 6 holding samples 0..2, saved to `dir`.
fn box_state(dir: &Path) -> (PathBuf, RenderState) {
    let scene = cornell_box();
    let size = (8, 6);
    let mut state = RenderState::new(
        state::RenderSettings {
            algorithm: Algorithm::Vcm,
            width: size.0,
            height: size.1,
            camera: None,
            options: settings(Algorithm::Vcm).integrator,
        },
        scene_hash(&scene),
        scene.path.clone(),
    );
    state.film = direct_film(&scene, size, 0..2);
    state.samples = SampleRanges::from_range(0..2);
    let file = dir.join("box.state");
    state.save(&file).unwrap();
    (file, state)
}

#[test]
fn a_state_of_another_scene_is_refused_naming_both() {
    let dir = tempfile::tempdir().unwrap();
    let (file, state) = box_state(dir.path());
    let other = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-specular.gltf");
    let error = open(&file, state.clone(), Some(&other), None).unwrap_err();
    assert!(
        error.contains("cornell-specular.gltf")
            && error.contains("box.state")
            && error.contains("cornell-box.gltf")
            && error.contains("differs"),
        "{error}"
    );
    // A scene on screen of other content is not taken: the state's own is loaded and checked.
    let specular = Arc::new(Scene::load(&other).unwrap());
    let current = Some((Arc::clone(&specular), scene_hash(&specular)));
    let opened = open(&file, state.clone(), None, current).unwrap();
    assert!(!Arc::ptr_eq(&opened.scene, &specular));
    assert_eq!(opened.hash, state.scene_hash);
    // The file the state names has changed since.
    let edited = RenderState {
        scene_hash: state.scene_hash ^ 1,
        ..state.clone()
    };
    let error = open(&file, edited, None, None).unwrap_err();
    assert!(error.contains("differs"), "{error}");
}

#[test]
fn a_missing_scene_or_camera_is_an_error_naming_the_state() {
    let dir = tempfile::tempdir().unwrap();
    let (file, state) = box_state(dir.path());
    let missing = RenderState {
        scene_path: "no-such-scene.gltf".into(),
        ..state.clone()
    };
    let error = open(&file, missing, None, None).unwrap_err();
    assert!(
        error.contains("box.state") && error.contains("no-such-scene.gltf"),
        "{error}"
    );
    let mut other_camera = state.clone();
    other_camera.settings.camera = Some("Top".into());
    let error = open(&file, other_camera.clone(), None, None).unwrap_err();
    assert!(
        error.contains("box.state") && error.contains("'Top'"),
        "{error}"
    );
    let scene = cornell_box();
    let current = Some((Arc::clone(&scene), scene_hash(&scene)));
    let error = open(&file, other_camera, None, current).unwrap_err();
    assert!(
        error.contains("box.state") && error.contains("'Top'"),
        "{error}"
    );
}

#[test]
fn a_relative_scene_is_also_looked_for_beside_the_state() {
    let dir = tempfile::tempdir().unwrap();
    let (file, state) = box_state(dir.path());
    std::fs::copy(&state.scene_path, dir.path().join("beside.gltf")).unwrap();
    let beside = RenderState {
        scene_path: "beside.gltf".into(),
        ..state
    };
    let opened = open(&file, beside, None, None).unwrap();
    assert_eq!(opened.scene.path, dir.path().join("beside.gltf"));
}

#[test]
fn damaged_and_missing_state_files_are_errors_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = box_state(dir.path());
    let bytes = std::fs::read(&file).unwrap();
    let truncated = dir.path().join("truncated.state");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let flipped = dir.path().join("flipped.state");
    let mut damaged = bytes.clone();
    let last = damaged.len() - 1;
    damaged[last] ^= 1;
    std::fs::write(&flipped, damaged).unwrap();
    let text = dir.path().join("text.state");
    std::fs::write(&text, "not a render state").unwrap();
    let missing = dir.path().join("missing.state");
    for path in [
        &truncated,
        &flipped,
        &text,
        &missing,
        &dir.path().to_path_buf(),
    ] {
        let error = read(path).unwrap_err();
        assert!(error.contains(&path.display().to_string()), "{error}");
    }
    // Through the loader thread, as the panel and --resume open them: an error, no panic.
    for path in [&truncated, &missing] {
        let load = crate::loader::SceneLoad::open_state(path, None, None, None, || {});
        let deadline = Instant::now() + Duration::from_secs(60);
        let outcome = loop {
            if let Some(outcome) = load.poll() {
                break outcome;
            }
            assert!(Instant::now() < deadline, "the loader did not finish");
            std::thread::sleep(Duration::from_millis(5));
        };
        let error = outcome.expect_err("an error");
        assert!(error.contains(&path.display().to_string()), "{error}");
    }
}
