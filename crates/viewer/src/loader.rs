//! Scene loading on a background thread, so a large file never stalls the window.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};

use vcm_scene::Scene;

/// A scene being loaded.
pub struct SceneLoad {
    path: PathBuf,
    result: Receiver<Result<Scene, String>>,
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
        let (sender, result) = std::sync::mpsc::channel();
        let file = path.to_path_buf();
        // If the thread cannot start, the closure and its sender are dropped and `poll`
        // reports that the loader ended without a result.
        let _ = std::thread::Builder::new()
            .name("scene loader".into())
            .spawn(move || {
                let loaded = Scene::load(&file)
                    .and_then(|mut scene| {
                        if let Some(choice) = &camera {
                            scene.use_camera(choice)?;
                        }
                        Ok(scene)
                    })
                    .map_err(|e| e.to_string());
                let _ = sender.send(loaded);
                notify();
            });
        SceneLoad {
            path: path.to_path_buf(),
            result,
        }
    }

    /// The file being loaded.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The scene or the reason it failed (the message names the file), once loading is done.
    pub fn poll(&self) -> Option<Result<Arc<Scene>, String>> {
        match self.result.try_recv() {
            Ok(loaded) => Some(loaded.map(Arc::new)),
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
                return result;
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
