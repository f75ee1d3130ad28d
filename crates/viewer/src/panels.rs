//! The control panel: scene, render settings, exposure, saving, live statistics and the
//! relMSE plot. Widgets edit [`ViewerApp::settings`] directly; the session notices the change
//! and restarts the accumulation.

use std::sync::Arc;

use clap::ValueEnum;
use eframe::egui;
use egui_plot::{Line, Plot, PlotPoints};
use vcm::{DEFAULT_RADIUS_FRACTION, DEFAULT_RADIUS_PIXELS, MergeRadius, Scheduler};
use vcm_rs::integrators::{Algorithm, AlgorithmOption};
use vcm_rs::render_loop::{Frames, ScheduleOptions, SchedulerKind};
use vcm_rs::{Backend, Shading};

use crate::app::{LoadedScene, STATE_EXTENSION, ViewerApp};
use crate::camera_controller::CameraController;
use crate::settings::RenderSettings;
use crate::stats::LiveStats;

/// Longest path offered by the max depth control (segments).
const MAX_DEPTH_LIMIT: u32 = 64;

/// Draws the control panel on the left of the window.
pub fn controls(app: &mut ViewerApp, ui: &mut egui::Ui) {
    egui::Panel::left("controls")
        .resizable(false)
        .default_size(290.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                scene_section(app, ui);
                ui.separator();
                render_section(&mut app.settings, ui);
                ui.separator();
                image_section(app, ui);
                ui.separator();
                state_section(app, ui);
                ui.separator();
                stats_section(app, ui);
                if app.reference_size.is_some() {
                    ui.separator();
                    error_plot(app, ui);
                }
                messages(app, ui);
            });
        });
}

fn scene_section(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.heading("Scene");
    if let Some(loading) = &app.loading {
        ui.label(format!("loading {} …", loading.path().display()));
    } else if let Some(loaded) = &app.scene {
        ui.label(loaded.scene.path.display().to_string());
    }
    ui.horizontal(|ui| {
        if ui.button("Open…").clicked() {
            let picked = rfd::FileDialog::new()
                .add_filter("scenes", &["gltf", "glb", "obj"])
                .pick_file();
            if let Some(path) = picked {
                app.open(ui.ctx(), &path, None);
            }
        }
        if let Some(loaded) = &mut app.scene
            && ui.button("Reset camera").clicked()
        {
            let bounds = &loaded.scene.features.bounds;
            loaded.controller = CameraController::new(loaded.home, bounds);
        }
    });
    if let Some(loaded) = &mut app.scene
        && loaded.scene.cameras.len() > 1
    {
        camera_choice(loaded, ui);
    }
    ui.small("or drop a .gltf, .glb or .obj file on the window");
    if let Some(loaded) = &app.scene
        && !loaded.scene.warnings.is_empty()
    {
        ui.collapsing(format!("{} warnings", loaded.scene.warnings.len()), |ui| {
            for warning in &loaded.scene.warnings {
                ui.small(warning);
            }
        });
    }
}

/// The file's cameras, when it has several: choosing one moves the view there, and *Reset
/// camera* then returns to it.
fn camera_choice(loaded: &mut LoadedScene, ui: &mut egui::Ui) {
    let scene = Arc::clone(&loaded.scene);
    let current = scene.cameras.iter().position(|c| c.camera == loaded.home);
    let text = current.map_or_else(|| "moved".to_string(), |i| scene.cameras[i].to_string());
    egui::ComboBox::from_label("Camera")
        .selected_text(text)
        .show_ui(ui, |ui| {
            for (i, file_camera) in scene.cameras.iter().enumerate() {
                let label = file_camera.to_string();
                if ui.selectable_label(current == Some(i), label).clicked() {
                    loaded.home = file_camera.camera;
                    let bounds = &scene.features.bounds;
                    loaded.controller = CameraController::new(file_camera.camera, bounds);
                }
            }
        });
}

fn render_section(settings: &mut RenderSettings, ui: &mut egui::Ui) {
    ui.heading("Render");
    egui::Grid::new("render settings")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("Algorithm");
            egui::ComboBox::from_id_salt("algorithm")
                .selected_text(settings.algorithm.name())
                .show_ui(ui, |ui| {
                    for algorithm in AlgorithmOption::ALL {
                        ui.selectable_value(&mut settings.algorithm, algorithm, algorithm.name());
                    }
                });
            ui.end_row();

            ui.label("Backend");
            egui::ComboBox::from_id_salt("backend")
                .selected_text(settings.backend.name())
                .show_ui(ui, |ui| {
                    for &backend in Backend::ALL {
                        ui.selectable_value(&mut settings.backend, backend, backend.name());
                    }
                });
            ui.end_row();

            shading_row(settings, ui);

            ui.label("Max depth");
            ui.horizontal(|ui| {
                let options = &mut settings.integrator;
                let mut limited = options.max_depth.is_some();
                ui.checkbox(&mut limited, "limit");
                let mut depth = options.max_depth.unwrap_or(8);
                ui.add_enabled(
                    limited,
                    egui::DragValue::new(&mut depth).range(1..=MAX_DEPTH_LIMIT),
                );
                options.max_depth = limited.then_some(depth);
            });
            ui.end_row();

            ui.label("Merge radius");
            // `auto` may choose VCM.
            let merges = settings.algorithm.fixed().is_none_or(|algorithm| {
                matches!(algorithm, Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm)
            });
            ui.add_enabled_ui(merges, |ui| {
                radius_row(&mut settings.integrator.radius, ui);
            });
            ui.end_row();

            schedule_rows(&mut settings.schedule, settings.backend, ui);
        });
}

/// The merge radius's unit (a fraction of the scene's radius or pixel footprints) and its
/// number.
fn radius_row(radius: &mut MergeRadius, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        let pixels = matches!(radius, MergeRadius::Pixels(_));
        if ui.radio(!pixels, "× scene radius").clicked() && pixels {
            *radius = MergeRadius::SceneFraction(DEFAULT_RADIUS_FRACTION);
        }
        if ui.radio(pixels, "pixels").clicked() && !pixels {
            *radius = MergeRadius::Pixels(DEFAULT_RADIUS_PIXELS);
        }
        match radius {
            MergeRadius::SceneFraction(fraction) => {
                ui.add(egui::Slider::new(fraction, 1e-4..=0.1).logarithmic(true))
            }
            MergeRadius::Pixels(pixels) => {
                ui.add(egui::Slider::new(pixels, 0.25..=32.0).logarithmic(true))
            }
        };
    });
}

/// Where paths are shaded: on the GPU only on the GPU backend (else back to the CPU; `auto`
/// pilots there on the GPU, as `vcm render` does).
fn shading_row(settings: &mut RenderSettings, ui: &mut egui::Ui) {
    let possible = settings.backend == Backend::Gpu;
    if !possible {
        settings.shading = Shading::Cpu;
    }
    ui.label("Shading");
    ui.add_enabled_ui(possible, |ui| {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut settings.shading, Shading::Cpu, "cpu");
            ui.selectable_value(&mut settings.shading, Shading::Gpu, "gpu");
        })
        .response
        .on_disabled_hover_text("whole paths on the GPU: with the gpu backend");
    });
    ui.end_row();
}

/// The scheduler (its backend's choice unless picked), the tile size where tiles are used,
/// and the samples per pixel per frame.
fn schedule_rows(schedule: &mut ScheduleOptions, backend: Backend, ui: &mut egui::Ui) {
    let name = |kind: SchedulerKind| {
        kind.to_possible_value()
            .map_or_else(String::new, |value| value.get_name().to_owned())
    };
    ui.label("Scheduler");
    let automatic = format!("auto ({})", backend.name());
    egui::ComboBox::from_id_salt("scheduler")
        .selected_text(schedule.scheduler.map_or(automatic.clone(), name))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut schedule.scheduler, None, automatic);
            for &kind in SchedulerKind::value_variants() {
                ui.selectable_value(&mut schedule.scheduler, Some(kind), name(kind));
            }
        });
    ui.end_row();

    ui.label("Tile size");
    // Whether some frame size runs tiles (the GPU's own choice does from a few samples on).
    let tiled = !matches!(
        schedule.schedule_on(backend, Frames::MOST_PACED).scheduler,
        Scheduler::None
    );
    let mut size = schedule.tile_size.unwrap_or(Scheduler::DEFAULT_TILE_SIZE);
    let edited = ui.add_enabled(
        tiled,
        egui::DragValue::new(&mut size)
            .range(1..=1024)
            .suffix(" px"),
    );
    if edited.changed() {
        schedule.tile_size = Some(size);
    }
    ui.end_row();

    ui.label("Samples/frame");
    ui.horizontal(|ui| {
        // Automatic: the backend's choice (one on the CPU, paced frames on the GPU).
        let mut automatic = schedule.spp_per_frame.is_none();
        if ui.checkbox(&mut automatic, "auto").changed() {
            schedule.spp_per_frame = (!automatic).then_some(1);
        }
        let mut samples = schedule.spp_per_frame.unwrap_or(1);
        let slider = egui::Slider::new(&mut samples, 1..=64);
        if ui.add_enabled(!automatic, slider).changed() {
            schedule.spp_per_frame = Some(samples);
        }
    });
    ui.end_row();
}

fn image_section(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.heading("Image");
    ui.add(egui::Slider::new(&mut app.exposure, -10.0..=10.0).text("exposure (stops)"));
    let save = ui.add_enabled(app.shown.is_some(), egui::Button::new("Save EXR + PNG…"));
    if save.clicked() {
        let picked = rfd::FileDialog::new()
            .add_filter("OpenEXR", &["exr"])
            .set_file_name("render.exr")
            .save_file();
        if let (Some(path), Some(shown)) = (picked, &app.shown) {
            let snapshot = &shown.snapshot;
            match crate::image_out::save(&path, snapshot.size, &snapshot.mean, app.exposure) {
                Ok([exr, png]) => {
                    app.note = Some(format!("saved {} and {}", exr.display(), png.display()));
                }
                Err(e) => app.error = Some(e.to_string()),
            }
        }
    }
}

/// Saving the render as a render state, and opening one (of `vcm render --state`, or saved
/// here) to continue it.
fn state_section(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.heading("Render state");
    ui.horizontal(|ui| {
        if ui.button("Open state…").clicked()
            && let Some(path) = rfd::FileDialog::new().pick_file()
        {
            app.open_state(ui.ctx(), &path, None, None);
        }
        let can_save = app.shown.is_some() && app.saving.is_none();
        if ui
            .add_enabled(can_save, egui::Button::new("Save state…"))
            .clicked()
            && let Some(path) = rfd::FileDialog::new()
                .add_filter("render state", &[STATE_EXTENSION])
                .set_file_name(format!("render.{STATE_EXTENSION}"))
                .save_file()
        {
            app.save_state(ui.ctx(), path);
        }
    });
    if let Some(saving) = &app.saving {
        ui.label(format!("saving {} …", saving.path().display()));
    }
    ui.small("continue a render of vcm render --state, or save this one for --resume");
}

fn stats_section(app: &ViewerApp, ui: &mut egui::Ui) {
    ui.heading("Statistics");
    if let Some(adapter) = &app.adapter {
        ui.small(format!("window drawn by {adapter}"));
    }
    let Some(shown) = &app.shown else {
        ui.label(if app.scene.is_some() || app.loading.is_some() {
            "waiting for the first frame …"
        } else {
            "no render"
        });
        return;
    };
    let snapshot = &shown.snapshot;
    let stats = LiveStats::of(snapshot);
    egui::Grid::new("statistics").num_columns(2).show(ui, |ui| {
        let mut row = |name: &str, value: String| {
            ui.label(name);
            ui.label(value);
            ui.end_row();
        };
        row("algorithm", snapshot.algorithm.name().to_string());
        if let Some(chosen) = &snapshot.chosen {
            row("chosen by", chosen.clone());
        }
        row(
            "resolution",
            format!("{} × {}", snapshot.size.0, snapshot.size.1),
        );
        row("samples/pixel", stats.spp.to_string());
        row("frames/s", format!("{:.2}", stats.frames_per_second));
        row("rays/s", format!("{:.2} M", stats.rays_per_second / 1e6));
        row("elapsed", format!("{:.1} s", stats.elapsed.as_secs_f64()));
        row("dropped samples", stats.dropped.to_string());
        if let Some(relmse) = snapshot.relmse {
            row("relMSE", format!("{relmse:.3e}"));
        }
    });
}

/// relMSE against render time on log-log axes (egui_plot has linear axes: the plot shows
/// log₁₀ of both and labels each tick with the value it stands for).
fn error_plot(app: &ViewerApp, ui: &mut egui::Ui) {
    ui.heading("relMSE over time");
    if let (Some((w, h)), Some(loaded)) = (app.reference_size, &app.scene) {
        let (width, height) = loaded.resolution.full();
        if (w, h) != (width as usize, height as usize) {
            ui.colored_label(
                ui.visuals().warn_fg_color,
                format!("the reference is {w} × {h}, the render {width} × {height}: no relMSE"),
            );
            return;
        }
    }
    let points: PlotPoints = app
        .history
        .points()
        .iter()
        .filter(|(seconds, relmse)| *seconds > 0.0 && *relmse > 0.0)
        .map(|&(seconds, relmse)| [seconds.log10(), relmse.log10()])
        .collect();
    let power_of_ten = |mark: egui_plot::GridMark, _: &std::ops::RangeInclusive<f64>| {
        format!("{:.0e}", 10f64.powf(mark.value))
    };
    Plot::new("relmse")
        .height(200.0)
        .x_axis_label("seconds")
        .y_axis_label("relMSE")
        .x_axis_formatter(power_of_ten)
        .y_axis_formatter(power_of_ten)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .show(ui, |plot| plot.line(Line::new("relMSE", points)));
}

fn messages(app: &ViewerApp, ui: &mut egui::Ui) {
    if let Some(error) = &app.error {
        ui.separator();
        ui.colored_label(ui.visuals().error_fg_color, error);
    }
    if let Some(note) = &app.note {
        ui.separator();
        ui.label(note);
    }
}
