//! Render states in the viewer (see `vcm_rs::state` and `docs/render-state.md`): saving the
//! render on screen as a state that `vcm render --resume` continues, and opening a state of
//! `vcm render --state` (or of the viewer) to continue it here, bit for bit as the command
//! line would.
//!
//! A state must be reproducible from its scene and settings: the camera it records is one of
//! the file's cameras (or the file's default), so a render from a camera moved interactively
//! cannot be saved.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};

use vcm_rs::integrators::Algorithm;
use vcm_rs::state::{self, RenderState, scene_hash};
use vcm_scene::{Camera, Scene};

use crate::app::LoadedScene;
use crate::loader::Loaded;
use crate::renderer::{FilmCopy, Renderer};
use crate::session::View;

/// Why a render from a camera moved interactively cannot be saved.
pub const MOVED_CAMERA: &str = "cannot save the render state: the camera was moved, so the \
     render matches none of the file's cameras and could not be reproduced from the scene and \
     settings; choose a camera of the file (or Reset camera) and save that render";

/// What a continued state holds besides its film and settings, kept when it is saved again.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Origin {
    /// The image file the command-line render wrote (where `vcm render --resume` writes).
    pub output: Option<PathBuf>,
    /// The samples per pixel the command-line render was asked for.
    pub target_spp: Option<u32>,
}

/// A state file opened to be continued.
#[derive(Clone, Debug)]
pub struct Opened {
    /// The file.
    pub path: PathBuf,
    /// Its contents.
    pub state: RenderState,
}

/// The file camera `choice` names, picked as [`Scene::use_camera`] picks it: by index in
/// the glTF `cameras` array, else by its name or its node's name; the first match wins.
pub fn file_camera(scene: &Scene, choice: &str) -> Option<Camera> {
    let by_index = choice
        .parse::<usize>()
        .ok()
        .and_then(|index| scene.cameras.iter().find(|c| c.index == index));
    by_index
        .or_else(|| scene.cameras.iter().find(|c| c.is_named(choice)))
        .map(|c| c.camera)
}

/// The camera a render without a camera choice uses: the file's first, else the one the
/// loader framed the scene with (a file without cameras cannot have had another chosen).
pub fn default_camera(scene: &Scene) -> Camera {
    scene.cameras.first().map_or(scene.camera, |c| c.camera)
}

/// The camera choice that reproduces `camera` (`vcm render --camera`): `preferred` (the one
/// the scene was opened with) if it does, `None` for the default camera, else the first of
/// the index, name or node name of a file camera equal to it that picks it. An error when
/// `camera` is no camera of the file (it was moved).
pub fn camera_choice(
    scene: &Scene,
    preferred: Option<&str>,
    camera: &Camera,
) -> Result<Option<String>, String> {
    if let Some(choice) = preferred
        && file_camera(scene, choice).as_ref() == Some(camera)
    {
        return Ok(Some(choice.to_string()));
    }
    if default_camera(scene) == *camera {
        return Ok(None);
    }
    scene
        .cameras
        .iter()
        .filter(|c| c.camera == *camera)
        .flat_map(|c| [Some(c.index.to_string()), c.name.clone(), c.node.clone()])
        .flatten()
        .find(|choice| file_camera(scene, choice).as_ref() == Some(camera))
        .map(Some)
        .ok_or_else(|| MOVED_CAMERA.to_string())
}

/// The state (without its film and samples, which the worker has) that saving the render of
/// `view` on `loaded` writes, with `origin`'s output and target when it continues a state;
/// `rendering` is the algorithm the render's frames so far came from (with `auto`, the one
/// chosen). An error, for the panel, when the render cannot be saved: its camera was moved,
/// it is a preview, or `auto` has not chosen yet.
pub fn state_to_save(
    loaded: &LoadedScene,
    (view, rendering): (&View, Option<Algorithm>),
    origin: Option<&Origin>,
) -> Result<RenderState, String> {
    if view.scene != loaded.serial {
        return Err("cannot save the render state: the scene has not started rendering".into());
    }
    let camera = camera_choice(&loaded.scene, loaded.choice.as_deref(), &view.camera)?;
    if view.size != loaded.resolution.full() {
        return Err(
            "cannot save the render state: the render is a preview while the camera moves; \
             save once it has settled"
                .into(),
        );
    }
    let algorithm = view.settings.algorithm.fixed().or(rendering).ok_or(
        "cannot save the render state: the algorithm is still being chosen (auto); save once \
         the first frame is shown",
    )?;
    let (width, height) = view.size;
    let settings = state::RenderSettings {
        algorithm,
        width,
        height,
        camera,
        options: view.settings.integrator.clone(),
    };
    let mut state = RenderState::new(settings, loaded.hash, loaded.scene.path.clone());
    if let Some(origin) = origin {
        state.output.clone_from(&origin.output);
        state.target_spp = origin.target_spp;
    }
    Ok(state)
}

/// A render state being saved: first the worker's copy of the film is awaited (it comes
/// between two frames), then the file is written on a thread of its own, so the window never
/// waits for either.
pub struct PendingSave {
    path: PathBuf,
    stage: Stage,
}

enum Stage {
    /// Waiting for the film of render `generation`.
    Film {
        generation: u64,
        state: Box<RenderState>,
        copy: Receiver<FilmCopy>,
        notify: Box<dyn FnOnce() + Send>,
    },
    /// The state is being written; the note or the error arrives here.
    Writing(Receiver<Result<String, String>>),
    /// The outcome was handed out.
    Done,
}

impl PendingSave {
    /// Starts saving `state` (settings and scene, from [`state_to_save`]) with the film of
    /// render `generation` to `path`; `notify` is called once the file is written (to wake
    /// the UI).
    pub fn start(
        renderer: &Renderer,
        generation: u64,
        state: RenderState,
        path: PathBuf,
        notify: impl FnOnce() + Send + 'static,
    ) -> PendingSave {
        PendingSave {
            path,
            stage: Stage::Film {
                generation,
                state: Box::new(state),
                copy: renderer.request_film(),
                notify: Box::new(notify),
            },
        }
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The outcome, once there is one: a note saying what was saved, or why nothing was (the
    /// message names the file). `None` while it goes on.
    pub fn poll(&mut self) -> Option<Result<String, String>> {
        let (stage, outcome) = match std::mem::replace(&mut self.stage, Stage::Done) {
            Stage::Film {
                generation,
                state,
                copy,
                notify,
            } => match copy.try_recv() {
                Ok(copy) => self.write(generation, *state, copy, notify),
                Err(TryRecvError::Empty) => (
                    Stage::Film {
                        generation,
                        state,
                        copy,
                        notify,
                    },
                    None,
                ),
                Err(TryRecvError::Disconnected) => (Stage::Done, Some(Err(self.restarted()))),
            },
            Stage::Writing(written) => match written.try_recv() {
                Ok(outcome) => (Stage::Done, Some(outcome)),
                Err(TryRecvError::Empty) => (Stage::Writing(written), None),
                Err(TryRecvError::Disconnected) => (
                    Stage::Done,
                    Some(Err(format!(
                        "{}: the render state writer stopped without a result",
                        self.path.display()
                    ))),
                ),
            },
            Stage::Done => (Stage::Done, None),
        };
        self.stage = stage;
        outcome
    }

    /// Puts the film `copy` into `state` and starts writing it, if it is render
    /// `generation`'s and holds samples.
    fn write(
        &self,
        generation: u64,
        mut state: RenderState,
        copy: FilmCopy,
        notify: Box<dyn FnOnce() + Send>,
    ) -> (Stage, Option<Result<String, String>>) {
        if copy.generation != generation {
            return (Stage::Done, Some(Err(self.restarted())));
        }
        if copy.samples.is_empty() {
            let message = format!(
                "{}: not saved: no frame of the render has finished yet",
                self.path.display()
            );
            return (Stage::Done, Some(Err(message)));
        }
        state.film = copy.film;
        state.samples = copy.samples;
        let (sender, written) = std::sync::mpsc::channel();
        let path = self.path.clone();
        let spawned = std::thread::Builder::new()
            .name("render state writer".into())
            .spawn(move || {
                let outcome = state
                    .save(&path)
                    .map(|()| {
                        format!(
                            "saved the render state {} (samples {})",
                            path.display(),
                            state.samples
                        )
                    })
                    .map_err(|e| e.to_string());
                let _ = sender.send(outcome);
                notify();
            });
        match spawned {
            Ok(_) => (Stage::Writing(written), None),
            Err(e) => (
                Stage::Done,
                Some(Err(format!(
                    "{}: cannot start writing the render state: {e}",
                    self.path.display()
                ))),
            ),
        }
    }

    fn restarted(&self) -> String {
        format!(
            "{}: not saved: the render restarted (or failed) before its film could be copied; \
             save again",
            self.path.display()
        )
    }
}

/// Reads the state file `path` (the error names the file and says what is wrong).
pub fn read(path: &Path) -> Result<RenderState, String> {
    RenderState::load(path).map_err(|e| e.to_string())
}

/// Makes the opened `state` (read from `file`) ready to continue: its scene, checked by
/// content, and the camera it was rendered from. The scene is `scene` when given (the
/// command line's); else `current` (the scene on screen, with its hash) when its content is
/// the state's; else the file the state names (relative to the working folder or, failing
/// that, to the state's folder).
pub fn open(
    file: &Path,
    state: RenderState,
    scene: Option<&Path>,
    current: Option<(Arc<Scene>, u64)>,
) -> Result<Loaded, String> {
    let reused = current.filter(|(_, hash)| scene.is_none() && *hash == state.scene_hash);
    let (scene, camera) = match reused {
        Some((scene, _)) => {
            let camera = match &state.settings.camera {
                Some(choice) => file_camera(&scene, choice).ok_or_else(|| {
                    format!(
                        "{}: the render was made from the camera '{choice}', which {} lacks",
                        file.display(),
                        scene.path.display()
                    )
                })?,
                None => default_camera(&scene),
            };
            (scene, camera)
        }
        None => {
            let path = scene.map_or_else(|| recorded_scene(file, &state), Path::to_path_buf);
            let mut loaded = Scene::load(&path).map_err(|e| {
                format!(
                    "{}: cannot load the scene of the render state: {e}; open that scene \
                     first, or give it with the state (vcm-viewer SCENE --resume FILE)",
                    file.display()
                )
            })?;
            if scene_hash(&loaded) != state.scene_hash {
                return Err(format!(
                    "{}: its content differs from the scene the render state {} was made from \
                     ({}); open that scene",
                    path.display(),
                    file.display(),
                    state.scene_path.display()
                ));
            }
            if let Some(choice) = &state.settings.camera {
                loaded
                    .use_camera(choice)
                    .map_err(|e| format!("{}: {e}", file.display()))?;
            }
            let camera = loaded.camera;
            (Arc::new(loaded), camera)
        }
    };
    Ok(Loaded {
        scene,
        hash: state.scene_hash,
        camera,
        choice: state.settings.camera.clone(),
        state: Some(Opened {
            path: file.to_path_buf(),
            state,
        }),
    })
}

/// The scene file `state` names: as recorded when it exists or is absolute, else relative to
/// the folder of the state `file` when it is there.
fn recorded_scene(file: &Path, state: &RenderState) -> PathBuf {
    let recorded = &state.scene_path;
    if recorded.is_relative() && !recorded.exists() {
        let beside = file.parent().map(|folder| folder.join(recorded));
        if let Some(beside) = beside.filter(|path| path.exists()) {
            return beside;
        }
    }
    recorded.clone()
}

#[cfg(test)]
mod tests;
