//! The path tracer's settings checks and statistics.

use std::sync::Arc;

use glam::Vec3;
use vcm::{Film, Integrator, PathTracer, PtSettings, RenderError};
use vcm_traversal::{CpuBvh, CpuBvhOptions, Traversal};

use crate::common;

/// A diffuse square at z = 0 filling the view, under a point light.
fn lit_plane() -> vcm_scene::Scene {
    common::lit_floor(5.0, common::camera(Vec3::new(0.0, 0.0, 2.0), 0.5))
}

fn settings(width: u32, height: u32) -> PtSettings {
    PtSettings {
        seed: 1,
        ..PtSettings::new(width, height)
    }
}

#[test]
fn images_without_pixels_or_with_too_many_are_rejected() {
    let scene = Arc::new(lit_plane());
    let bvh = CpuBvh::new(&scene.triangle_corners(), CpuBvhOptions::default()).unwrap();
    let traversal: Arc<dyn Traversal> = Arc::new(bvh);
    let make = |width, height| {
        PathTracer::new(scene.clone(), traversal.clone(), settings(width, height)).err()
    };
    assert_eq!(
        make(0, 4),
        Some(RenderError::EmptyImage {
            width: 0,
            height: 4
        })
    );
    assert_eq!(
        make(1 << 16, 1 << 16),
        Some(RenderError::ImageTooLarge {
            width: 1 << 16,
            height: 1 << 16
        })
    );
    assert_eq!(make(3, 2), None);
}

#[test]
fn frame_stats_count_rays_by_kind() {
    // Every camera ray hits the plane, sends one unoccluded shadow ray to the point light and
    // one continuation ray upward, which escapes.
    let mut tracer = common::path_tracer(lit_plane(), settings(8, 4));
    let mut film = Film::new(8, 4);
    let stats = tracer.render_frame(&mut film, 0);
    assert_eq!(
        (
            stats.camera_rays,
            stats.shadow_rays,
            stats.continuation_rays
        ),
        (32, 32, 32)
    );
    assert!((0..32).all(|p| film.samples(p) == 1));
}

#[test]
#[should_panic(expected = "film size differs")]
fn a_film_of_another_size_is_refused() {
    let mut tracer = common::path_tracer(lit_plane(), settings(8, 4));
    tracer.render_frame(&mut Film::new(4, 8), 0);
}
