//! Scene loading on a background thread, so a large file never stalls the window: a scene
//! file, or the scene of a render state to continue.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};

use vcm_rs::state::{RenderState, scene_hash};
use vcm_scene::{Camera, Scene};

use crate::render_state::{self, Opened};

/// A scene ready to render.
#[derive(Debug)]
pub struct Loaded {
    /// The scene as loaded.
    pub scene: Arc<Scene>,
    /// Its content hash (`vcm_rs::state::scene_hash`), for the render states saved from it.
    pub hash: u64,
    /// The camera to start from.
    pub camera: Camera,
    /// The file camera it was chosen as (`--camera`, or a state's camera), `None` for the
    /// file's default.
    pub choice: Option<String>,
    /// The render state to continue, when one was opened.
    pub state: Option<Opened>,
}

/// A scene being loaded.
pub struct SceneLoad {
    path: PathBuf,
    result: Receiver<Result<Loaded, String>>,
}

impl SceneLoad {
    /// Starts loading `path`, to be seen from its camera `camera` (an index or a name, see
    /// [`Scene::use_camera`]; `None`: the file's first); `notify` is called when it is done
    /// (to wake the UI).
    pub fn start(
        path: &Path,
        camera: Option<String>,
        notify: impl FnOnce() + Send + 'static,
    ) -> SceneLoad {
        let file = path.to_path_buf();
        SceneLoad::spawn(path, notify, move || {
            let mut scene = Scene::load(&file).map_err(|e| e.to_string())?;
            if let Some(choice) = &camera {
                scene.use_camera(choice).map_err(|e| e.to_string())?;
            }
            Ok(Loaded {
                hash: scene_hash(&scene),
                camera: scene.camera,
                choice: camera,
                scene: Arc::new(scene),
                state: None,
            })
        })
    }

    /// Starts opening the render state `file` to continue it: reads it (unless `state`
    /// holds it already), then loads its scene as [`render_state::open`] says, from `scene`
    /// if given, else `current` if it has the state's content, else the file the state names.
    pub fn open_state(
        file: &Path,
        state: Option<RenderState>,
        scene: Option<PathBuf>,
        current: Option<(Arc<Scene>, u64)>,
        notify: impl FnOnce() + Send + 'static,
    ) -> SceneLoad {
        let path = file.to_path_buf();
        SceneLoad::spawn(file, notify, move || {
            let state = match state {
                Some(state) => state,
                None => render_state::read(&path)?,
            };
            render_state::open(&path, state, scene.as_deref(), current)
        })
    }

    /// Runs `load` on a thread of its own, then `notify`.
    fn spawn(
        path: &Path,
        notify: impl FnOnce() + Send + 'static,
        load: impl FnOnce() -> Result<Loaded, String> + Send + 'static,
    ) -> SceneLoad {
        let (sender, result) = std::sync::mpsc::channel();
        // If the thread cannot start, the closure and its sender are dropped and `poll`
        // reports that the loader ended without a result.
        let _ = std::thread::Builder::new()
            .name("scene loader".into())
            .spawn(move || {
                let _ = sender.send(load());
                notify();
            });
        SceneLoad {
            path: path.to_path_buf(),
            result,
        }
    }

    /// The file being loaded (the scene, or the render state).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The scene or the reason it failed (the message names the file), once loading is done.
    pub fn poll(&self) -> Option<Result<Loaded, String>> {
        match self.result.try_recv() {
            Ok(loaded) => Some(loaded),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(format!(
                "{}: the loader stopped without a result",
                self.path.display()
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait(load: &SceneLoad) -> Result<Arc<Scene>, String> {
        for _ in 0..2000 {
            if let Some(result) = load.poll() {
                return result.map(|loaded| loaded.scene);
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        panic!("loading {} did not finish in 10 s", load.path().display());
    }

    #[test]
    fn loads_a_scene_in_the_background() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
        let scene = wait(&SceneLoad::start(&path, None, || {})).unwrap();
        assert!(scene.features.triangles > 0);
    }

    #[test]
    fn a_camera_the_file_lacks_is_an_error_naming_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
        let scene = wait(&SceneLoad::start(&path, Some("0".into()), || {})).unwrap();
        assert_eq!(scene.camera, scene.cameras[0].camera);
        let error = wait(&SceneLoad::start(&path, Some("top".into()), || {})).unwrap_err();
        assert!(
            error.contains("cornell-box.gltf: no camera 'top'"),
            "{error}"
        );
    }

    #[test]
    fn a_missing_file_is_an_error_naming_it() {
        let path = Path::new("no-such-scene.gltf");
        let error = wait(&SceneLoad::start(path, None, || {})).unwrap_err();
        assert!(error.contains("no-such-scene.gltf"), "{error}");
    }
}
