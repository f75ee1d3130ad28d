//! The eframe application: it owns the render worker, the loaded scene with its camera and
//! resolution switch, and the image on screen, and ties them together once per UI frame.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use eframe::egui;
use vcm::image_io::RgbImage;
use vcm_rs::integrators::{AlgorithmOption, image_size};
use vcm_rs::state::RenderState;
use vcm_scene::{Camera, Scene};

use crate::camera_controller::CameraController;
use crate::image_out::tone_map;
use crate::loader::{Loaded, SceneLoad};
use crate::render_state::{Opened, Origin, PendingSave};
use crate::renderer::{Job, Renderer, Resume, Snapshot, Update};
use crate::resolution::ResolutionSwitch;
use crate::screenshot::ScreenshotScript;
use crate::session::{Session, View};
use crate::settings::RenderSettings;
use crate::stats::ErrorHistory;

/// What the app starts with.
pub struct Startup {
    /// The first scene to open; with `resume`, the scene to continue it with, if given.
    pub scene: Option<PathBuf>,
    /// The render state to continue (`--resume`), already read: its file and contents.
    pub resume: Option<Opened>,
    /// The camera of the first scene to start from (`--camera`), if not its first.
    pub camera: Option<String>,
    /// Render settings.
    pub settings: RenderSettings,
    /// `--width` and `--height`.
    pub width: u32,
    /// Height, or from the camera's aspect ratio.
    pub height: Option<u32>,
    /// Exposure in stops.
    pub exposure: f32,
    /// The reference image for the relMSE plot, when there is one.
    pub reference: Option<RgbImage>,
    /// The scripted screenshot (`--frames`, `--screenshot`).
    pub screenshot: Option<ScreenshotScript>,
}

/// A loaded scene and the interactive state that belongs to it.
pub struct LoadedScene {
    /// The scene as loaded.
    pub scene: Arc<Scene>,
    /// Its content hash, for the render states saved from it.
    pub hash: u64,
    /// The file camera the view started from (`--camera`, a state's camera), `None` for
    /// the file's default: the choice a saved state records when the camera is there.
    pub choice: Option<String>,
    /// Serial number of this load: every opened scene is a new one.
    pub serial: u64,
    /// The interactive camera.
    pub controller: CameraController,
    /// Where *Reset camera* returns to: the scene's camera, or the file's camera chosen
    /// since in the panel.
    pub home: Camera,
    /// Full or preview resolution.
    pub resolution: ResolutionSwitch,
}

/// The image on screen and the snapshot it shows.
pub struct Shown {
    /// The tone-mapped snapshot as a texture.
    pub texture: egui::TextureHandle,
    /// The snapshot shown.
    pub snapshot: Snapshot,
    /// The exposure the texture was tone mapped with.
    pub exposure: f32,
}

/// An opened render state, ready to continue.
pub struct PendingResume {
    /// The view the state was rendered with.
    pub view: View,
    /// Its film and samples.
    pub resume: Resume,
    /// What else it came with.
    pub origin: Origin,
}

/// The extension of render state files (`vcm render --state` takes any name).
pub const STATE_EXTENSION: &str = "state";

/// The scene file opened when none is given.
pub const DEFAULT_SCENE: &str = "scenes/cornell-box.gltf";

/// The viewer.
pub struct ViewerApp {
    /// The render worker.
    pub renderer: Renderer,
    /// Settings edited by the controls.
    pub settings: RenderSettings,
    /// Exposure in stops.
    pub exposure: f32,
    /// `--width`, `--height`.
    pub size_option: (u32, Option<u32>),
    /// The reference's size, if any.
    pub reference_size: Option<(usize, usize)>,
    /// A scene being loaded.
    pub loading: Option<SceneLoad>,
    /// The scene being rendered.
    pub scene: Option<LoadedScene>,
    /// Counts the scenes loaded (for [`LoadedScene::serial`]).
    pub scenes_loaded: u64,
    /// Restarts the accumulation when the view changes.
    pub session: Session,
    /// The image on screen.
    pub shown: Option<Shown>,
    /// An opened render state waiting for its first render: its film continues when that
    /// render's view is the state's.
    pub pending_resume: Option<PendingResume>,
    /// The render that continues an opened state (its generation), and what it came with.
    pub continued: Option<(u64, Origin)>,
    /// A render state being saved.
    pub saving: Option<PendingSave>,
    /// relMSE over time of the current render.
    pub history: ErrorHistory,
    /// The last error (failed load, render or save), shown until the next success.
    pub error: Option<String>,
    /// The last thing saved, shown as a note.
    pub note: Option<String>,
    /// Where the image was drawn last frame (points), for the screenshot's report.
    pub image_rect: Option<egui::Rect>,
    /// The scripted screenshot, if any.
    pub screenshot: Option<ScreenshotScript>,
    /// The graphics adapter that draws the window, e.g. `llvmpipe (Vulkan)`.
    pub adapter: Option<String>,
}

impl ViewerApp {
    /// The app, with the render worker started and the first scene loading.
    pub fn new(
        creation: &eframe::CreationContext<'_>,
        startup: Startup,
    ) -> std::io::Result<ViewerApp> {
        let ctx = &creation.egui_ctx;
        let adapter = creation.wgpu_render_state.as_ref().map(|state| {
            let info = state.adapter.get_info();
            format!("{} ({:?})", info.name, info.backend)
        });
        let reference_size = startup.reference.as_ref().map(|r| (r.width, r.height));
        let waker = ctx.clone();
        let renderer = Renderer::spawn(startup.reference, move || waker.request_repaint())?;
        let mut app = ViewerApp {
            renderer,
            settings: startup.settings,
            exposure: startup.exposure,
            size_option: (startup.width, startup.height),
            reference_size,
            loading: None,
            scene: None,
            scenes_loaded: 0,
            session: Session::default(),
            shown: None,
            pending_resume: None,
            continued: None,
            saving: None,
            history: ErrorHistory::default(),
            error: None,
            note: None,
            image_rect: None,
            screenshot: startup.screenshot,
            adapter,
        };
        match startup.resume {
            Some(Opened { path, state }) => app.open_state(ctx, &path, Some(state), startup.scene),
            None => {
                let scene = startup.scene.unwrap_or_else(|| DEFAULT_SCENE.into());
                app.open(ctx, &scene, startup.camera);
            }
        }
        Ok(app)
    }

    /// Starts loading `path`, seen from its camera `camera` (`None`: the file's first); the
    /// current scene keeps rendering until it has loaded.
    pub fn open(&mut self, ctx: &egui::Context, path: &Path, camera: Option<String>) {
        let waker = ctx.clone();
        self.loading = Some(SceneLoad::start(path, camera, move || {
            waker.request_repaint()
        }));
    }

    /// Starts opening the render state `file` (read already when `state` holds it) to
    /// continue it: with the scene `scene` if given, else the current scene if it has the
    /// state's content, else the scene the state names. The current scene keeps rendering
    /// until it is ready.
    pub fn open_state(
        &mut self,
        ctx: &egui::Context,
        file: &Path,
        state: Option<RenderState>,
        scene: Option<PathBuf>,
    ) {
        let current = self
            .scene
            .as_ref()
            .map(|loaded| (Arc::clone(&loaded.scene), loaded.hash));
        let waker = ctx.clone();
        self.loading = Some(SceneLoad::open_state(
            file,
            state,
            scene,
            current,
            move || waker.request_repaint(),
        ));
    }

    /// Starts saving the current render as a render state to `path`; the panel shows why
    /// when it cannot be saved.
    pub fn save_state(&mut self, ctx: &egui::Context, path: PathBuf) {
        let generation = self.session.generation();
        let state = match (&self.scene, self.session.view()) {
            (Some(loaded), Some(view)) => {
                let origin = self
                    .continued
                    .as_ref()
                    .filter(|(continued, _)| *continued == generation)
                    .map(|(_, origin)| origin);
                let rendering = self
                    .shown
                    .as_ref()
                    .filter(|shown| shown.snapshot.generation == generation)
                    .map(|shown| shown.snapshot.algorithm);
                crate::render_state::state_to_save(loaded, (view, rendering), origin)
            }
            _ => Err("cannot save the render state: nothing is rendering".into()),
        };
        match state {
            Ok(state) => {
                let waker = ctx.clone();
                self.saving = Some(PendingSave::start(
                    &self.renderer,
                    generation,
                    state,
                    path,
                    move || waker.request_repaint(),
                ));
            }
            Err(message) => self.error = Some(message),
        }
    }

    /// Takes the outcome of a save, once there is one.
    fn poll_save(&mut self) {
        let Some(outcome) = self.saving.as_mut().and_then(PendingSave::poll) else {
            return;
        };
        self.saving = None;
        match outcome {
            Ok(note) => self.note = Some(note),
            Err(message) => self.error = Some(message),
        }
    }

    /// Takes a finished load: a new scene replaces the current one (with an opened state's
    /// settings, camera and size, ready to continue it), an error is shown.
    fn poll_load(&mut self) {
        let Some(result) = self.loading.as_ref().and_then(SceneLoad::poll) else {
            return;
        };
        self.loading = None;
        match result {
            Ok(Loaded {
                scene,
                hash,
                camera,
                choice,
                state,
            }) => {
                let full = match &state {
                    Some(opened) => (opened.state.settings.width, opened.state.settings.height),
                    None => image_size(&scene, self.size_option.0, self.size_option.1),
                };
                self.scenes_loaded += 1;
                let serial = self.scenes_loaded;
                self.scene = Some(LoadedScene {
                    controller: CameraController::new(camera, &scene.features.bounds),
                    home: camera,
                    resolution: ResolutionSwitch::new(full),
                    serial,
                    scene,
                    hash,
                    choice,
                });
                self.pending_resume = state.map(|Opened { path, state }| {
                    self.settings.algorithm = AlgorithmOption::Fixed(state.settings.algorithm);
                    self.settings.integrator = state.settings.options.clone();
                    self.note = Some(format!(
                        "continuing {} (samples {})",
                        path.display(),
                        state.samples
                    ));
                    PendingResume {
                        view: View {
                            scene: serial,
                            settings: self.settings.clone(),
                            camera,
                            size: full,
                        },
                        resume: Resume {
                            film: state.film,
                            samples: state.samples,
                        },
                        origin: Origin {
                            output: state.output,
                            target_spp: state.target_spp,
                        },
                    }
                });
                self.error = None;
            }
            Err(message) => {
                if let Some(script) = &mut self.screenshot {
                    script.fail(message.clone());
                }
                self.error = Some(message);
            }
        }
    }

    /// Takes the worker's latest update.
    fn poll_renderer(&mut self, ctx: &egui::Context) {
        match self.renderer.take_update() {
            Some(Update::Frames(snapshot)) => {
                self.history.record(&snapshot);
                self.show(ctx, *snapshot);
            }
            Some(Update::Failed {
                generation,
                message,
            }) if generation == self.session.generation() => {
                if let Some(script) = &mut self.screenshot {
                    script.fail(message.clone());
                }
                self.error = Some(message);
            }
            Some(Update::Failed { .. }) | None => {}
        }
    }

    /// Puts `snapshot` on screen.
    fn show(&mut self, ctx: &egui::Context, snapshot: Snapshot) {
        let image = tone_map(snapshot.size, &snapshot.mean, self.exposure);
        let options = egui::TextureOptions::LINEAR;
        match &mut self.shown {
            Some(shown) => {
                shown.texture.set(image, options);
                shown.snapshot = snapshot;
                shown.exposure = self.exposure;
            }
            None => {
                self.shown = Some(Shown {
                    texture: ctx.load_texture("render", image, options),
                    snapshot,
                    exposure: self.exposure,
                });
            }
        }
    }

    /// Tone maps the shown image again when the exposure changed.
    fn refresh_exposure(&mut self) {
        if let Some(shown) = &mut self.shown
            && shown.exposure != self.exposure
        {
            let snapshot = &shown.snapshot;
            let image = tone_map(snapshot.size, &snapshot.mean, self.exposure);
            shown.texture.set(image, egui::TextureOptions::LINEAR);
            shown.exposure = self.exposure;
        }
    }

    /// Starts a new render when settings, camera or resolution changed.
    fn submit_view(&mut self, now: Instant) {
        let Some(loaded) = &self.scene else { return };
        let view = View {
            scene: loaded.serial,
            settings: self.settings.clone(),
            camera: loaded.controller.camera(),
            size: loaded.resolution.size(now),
        };
        if let Some(generation) = self.session.restart_if_changed(&view) {
            self.error = None;
            // An opened state continues in the first render of its view; any other render
            // starts afresh, and the state's film is dropped.
            let resume = self.pending_resume.take().filter(|r| r.view == view);
            self.continued = resume.as_ref().map(|r| (generation, r.origin.clone()));
            self.renderer.submit(Job {
                generation,
                scene: Arc::clone(&loaded.scene),
                view,
                frame_limit: self.screenshot.as_ref().map(ScreenshotScript::frames),
                resume: resume.map(|r| Box::new(r.resume)),
            });
        }
    }

    /// Whether the shown image is the current render at full resolution.
    pub fn shows_current_full_render(&self) -> Option<&Snapshot> {
        let shown = self.shown.as_ref()?;
        let loaded = self.scene.as_ref()?;
        let current = shown.snapshot.generation == self.session.generation()
            && shown.snapshot.size == loaded.resolution.full();
        current.then_some(&shown.snapshot)
    }

    /// Opens the first file dropped on the window: a render state (`.state`) to continue,
    /// else a scene.
    fn take_dropped_file(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.first().map(|f| f.path().to_path_buf()));
        match dropped {
            Some(path) if path.extension().is_some_and(|e| e == STATE_EXTENSION) => {
                self.open_state(ctx, &path, None, None);
            }
            Some(path) => self.open(ctx, &path, None),
            None => {}
        }
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let now = Instant::now();
        self.poll_load();
        self.poll_renderer(&ctx);
        self.poll_save();
        self.take_dropped_file(&ctx);
        crate::panels::controls(self, ui);
        crate::viewport::show(self, ui, now);
        self.refresh_exposure();
        self.submit_view(now);
        if let Some(wait) = self
            .scene
            .as_ref()
            .and_then(|s| s.resolution.settles_in(now))
        {
            ctx.request_repaint_after(wait);
        }
        crate::screenshot::step(self, &ctx);
    }
}
