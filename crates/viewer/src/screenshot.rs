//! The scripted screenshot of `--frames N --screenshot FILE`: once the current render has N
//! samples per pixel at full resolution and is on screen, capture the window, save it as a
//! PNG, report where the image lies in it, and close the window.

use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex, PoisonError};

use eframe::egui;
use vcm::image_io::write_rgb8_png;

use crate::app::ViewerApp;

/// How the script ended: `None` while it runs (or when the window was closed before it
/// finished); read by `main` after the window has closed.
pub type ScriptOutcome = Arc<Mutex<Option<Result<String, String>>>>;

/// The screenshot to take and how far it got.
pub struct ScreenshotScript {
    frames: u32,
    path: PathBuf,
    state: State,
    outcome: ScriptOutcome,
}

enum State {
    /// Waiting for the render to reach the frame count.
    Rendering,
    /// The capture was requested; the window's pixels arrive here.
    Requested(Receiver<Arc<egui::ColorImage>>),
    /// Saved or failed: the window closes.
    Done,
}

impl ScreenshotScript {
    /// A script that saves the window to `path` after `frames` frames, and the outcome it
    /// will report (a summary line, or the error).
    pub fn new(frames: u32, path: PathBuf) -> (ScreenshotScript, ScriptOutcome) {
        let outcome = ScriptOutcome::default();
        let script = ScreenshotScript {
            frames,
            path,
            state: State::Rendering,
            outcome: Arc::clone(&outcome),
        };
        (script, outcome)
    }

    /// Frames (samples per pixel) to render before the screenshot.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Ends the script with an error (a scene or render failure); the window closes.
    pub fn fail(&mut self, message: String) {
        self.finish(Err(message));
    }

    fn finish(&mut self, result: Result<String, String>) {
        *self.outcome.lock().unwrap_or_else(PoisonError::into_inner) = Some(result);
        self.state = State::Done;
    }
}

/// Advances the script by one UI frame.
pub fn step(app: &mut ViewerApp, ctx: &egui::Context) {
    let spp = app.shows_current_full_render().map(|s| s.spp);
    let image_rect = app.image_rect;
    let Some(script) = &mut app.screenshot else {
        return;
    };
    match &script.state {
        State::Rendering => {
            if spp.is_some_and(|spp| spp >= script.frames) && image_rect.is_some() {
                let (sender, receiver) = std::sync::mpsc::channel();
                let waker = ctx.clone();
                ctx.request_screenshot(move |image| {
                    let _ = sender.send(image);
                    waker.request_repaint();
                });
                script.state = State::Requested(receiver);
            }
        }
        State::Requested(receiver) => {
            if let (Ok(image), Some(rect)) = (receiver.try_recv(), image_rect) {
                let pixels = rect * ctx.pixels_per_point();
                let result = save_png(&script.path, &image).map(|()| {
                    format!(
                        "screenshot {}: window {}x{}, image at {},{} size {}x{}",
                        script.path.display(),
                        image.size[0],
                        image.size[1],
                        pixels.min.x.round(),
                        pixels.min.y.round(),
                        pixels.width().round(),
                        pixels.height().round()
                    )
                });
                script.finish(result);
            }
        }
        State::Done => {}
    }
    if matches!(script.state, State::Done) {
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

/// Writes the window's pixels as an 8-bit RGB PNG (through a temporary file).
fn save_png(path: &Path, image: &egui::ColorImage) -> Result<(), String> {
    let bytes = image
        .pixels
        .iter()
        .flat_map(|c| [c.r(), c.g(), c.b()])
        .collect();
    let [width, height] = image.size;
    write_rgb8_png(path, width, height, bytes).map_err(|e| e.to_string())
}
