//! The image area: the render drawn at its full-resolution size (one image pixel per screen
//! pixel when it fits, scaled down when not; a preview is stretched over the same area), and
//! the camera driven from it: drag to orbit, right- or middle-drag (or shift-drag) to pan,
//! scroll to zoom, W A S D Q E to fly.

use std::time::Instant;

use eframe::egui;
use glam::{Vec2, Vec3};

use crate::app::ViewerApp;
use crate::camera_controller::CameraController;

/// Orbit angle per point of pointer motion (radians).
const ORBIT_PER_POINT: f32 = 0.005;

/// Scroll distance (points) of one zoom step: about one notch of a mouse wheel.
const POINTS_PER_ZOOM_STEP: f32 = 50.0;

/// Longest time step a flying frame may take (seconds), so a stalled frame does not jump.
const MAX_FLY_STEP: f32 = 0.1;

/// Draws the image and applies the camera input to the loaded scene's controller.
pub fn show(app: &mut ViewerApp, ui: &mut egui::Ui, now: Instant) {
    egui::CentralPanel::default().show(ui, |ui| {
        let hovering_files = ui.input(|i| !i.raw.hovered_files.is_empty());
        let Some(loaded) = &mut app.scene else {
            app.image_rect = None;
            ui.centered_and_justified(|ui| {
                ui.label("no scene: open one or drop a .gltf, .glb or .obj file here");
            });
            return;
        };
        let rect = image_rect(ui, loaded.resolution.full());
        app.image_rect = Some(rect);
        let response = ui.interact(
            rect,
            egui::Id::unique("render image"),
            egui::Sense::click_and_drag(),
        );
        if let Some(shown) = &app.shown {
            egui::Image::new((shown.texture.id(), rect.size())).paint_at(ui, rect);
        }
        if hovering_files {
            ui.painter()
                .rect_filled(rect, 0.0, egui::Color32::from_black_alpha(160));
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "drop to open",
                egui::FontId::proportional(24.0),
                egui::Color32::WHITE,
            );
        }
        if camera_input(ui, &response, rect, &mut loaded.controller) {
            loaded.resolution.camera_moved(now);
        }
    });
}

/// The area the full-resolution image takes: centred, whole screen pixels, never enlarged.
fn image_rect(ui: &egui::Ui, (width, height): (u32, u32)) -> egui::Rect {
    let pixels_per_point = ui.ctx().pixels_per_point();
    let full = egui::vec2(width as f32, height as f32) / pixels_per_point;
    let available = ui.available_rect_before_wrap();
    let scale = (available.width() / full.x)
        .min(available.height() / full.y)
        .min(1.0);
    let size = full * scale;
    let min = available.center() - size / 2.0;
    let min = (min * pixels_per_point).round() / pixels_per_point;
    egui::Rect::from_min_size(min, size)
}

/// Applies pointer and keyboard input to `controller`; returns whether the camera moved.
fn camera_input(
    ui: &egui::Ui,
    response: &egui::Response,
    rect: egui::Rect,
    controller: &mut CameraController,
) -> bool {
    let before = controller.camera();
    let delta = response.drag_delta();
    let shift = ui.input(|i| i.modifiers.shift);
    let panning = response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
        || (shift && response.dragged_by(egui::PointerButton::Primary));
    if panning {
        controller.pan(Vec2::new(delta.x, delta.y) / rect.height());
    } else if response.dragged_by(egui::PointerButton::Primary) {
        // Dragging turns the scene with the pointer: right turns the eye to the left
        // around the focus, down raises it.
        controller.orbit(-delta.x * ORBIT_PER_POINT, -delta.y * ORBIT_PER_POINT);
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            controller.zoom(scroll / POINTS_PER_ZOOM_STEP);
        }
    }
    if !ui.ctx().egui_wants_keyboard_input() {
        let direction = ui.input(|i| {
            let axis = |plus, minus| {
                f32::from(u8::from(i.key_down(plus))) - f32::from(u8::from(i.key_down(minus)))
            };
            Vec3::new(
                axis(egui::Key::D, egui::Key::A),
                axis(egui::Key::E, egui::Key::Q),
                axis(egui::Key::W, egui::Key::S),
            )
        });
        if direction != Vec3::ZERO {
            let seconds = ui.input(|i| i.stable_dt).min(MAX_FLY_STEP);
            controller.fly(direction, seconds);
            ui.ctx().request_repaint();
        }
    }
    controller.camera() != before
}
