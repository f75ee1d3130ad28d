//! `vcm-viewer`: the progressive viewer of vcm-rs. It renders a scene on a worker thread and
//! shows the running mean, tone mapped, while the camera and the settings change.

mod app;
mod camera_controller;
mod image_out;
mod loader;
mod options;
mod panels;
mod render_state;
mod renderer;
mod resolution;
mod screenshot;
mod session;
mod settings;
mod stats;
mod viewport;

use std::io::Write;
use std::process::ExitCode;
use std::sync::PoisonError;

use anyhow::{Context, anyhow};
use clap::Parser;
use eframe::egui;
use vcm::image_io::RgbImage;

use crate::app::{Startup, ViewerApp};
use crate::options::Options;
use crate::render_state::Opened;
use crate::screenshot::ScreenshotScript;

/// Exit status when no window could be opened: no display, or no graphics adapter.
const NO_WINDOW: u8 = 3;

/// Why the viewer stopped with an error.
enum Failure {
    /// The window could not be opened (no display or adapter).
    NoWindow(anyhow::Error),
    /// Anything else: bad input, a failed scripted screenshot.
    Other(anyhow::Error),
}

fn main() -> ExitCode {
    let options = Options::parse();
    let (error, code) = match run(options) {
        Ok(()) => return ExitCode::SUCCESS,
        Err(Failure::NoWindow(error)) => (error, ExitCode::from(NO_WINDOW)),
        Err(Failure::Other(error)) => (error, ExitCode::FAILURE),
    };
    // Not `eprintln!`, which panics when stderr is a closed pipe: the exit status must stay.
    let _ = writeln!(std::io::stderr(), "error: {error:#}");
    code
}

fn run(options: Options) -> Result<(), Failure> {
    let reference = match &options.reference {
        Some(path) => Some(RgbImage::read_exr(path).map_err(|e| Failure::Other(e.into()))?),
        None => None,
    };
    // The state is read (and checked) before the window opens; its scene loads in the window.
    let resume = match &options.resume {
        Some(path) => Some(Opened {
            state: crate::render_state::read(path).map_err(|e| Failure::Other(anyhow!(e)))?,
            path: path.clone(),
        }),
        None => None,
    };
    let (script, outcome) = match options.screenshot() {
        Some((frames, path)) => {
            let (script, outcome) = ScreenshotScript::new(frames, path);
            (Some(script), Some(outcome))
        }
        None => (None, None),
    };
    let startup = Startup {
        scene: options.scene.clone(),
        resume,
        camera: options.camera.clone(),
        settings: options.settings(),
        width: options.width,
        height: options.height,
        exposure: options.exposure,
        reference,
        screenshot: script,
    };
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("vcm-viewer")
            .with_inner_size([1100.0, 800.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..eframe::NativeOptions::default()
    };
    let mut created = false;
    let result = eframe::run_native(
        "vcm-viewer",
        native,
        Box::new(|creation| {
            created = true;
            let app = ViewerApp::new(creation, startup)?;
            Ok(Box::new(app))
        }),
    );
    match result {
        Err(error) if !created => {
            return Err(Failure::NoWindow(
                anyhow!("{error}").context("cannot open the viewer window"),
            ));
        }
        Err(error) => return Err(Failure::Other(anyhow!("{error}"))),
        Ok(()) => {}
    }
    let Some(outcome) = outcome else {
        return Ok(());
    };
    let outcome = outcome
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .take();
    match outcome.context("the window closed before the screenshot was taken") {
        Ok(Ok(summary)) => {
            // A reader that has gone away is no reason to fail the screenshot, already saved.
            let _ = writeln!(std::io::stdout(), "{summary}");
            Ok(())
        }
        Ok(Err(message)) => Err(Failure::Other(anyhow!(message))),
        Err(error) => Err(Failure::Other(error)),
    }
}
