//! A device that fails mid-render: the frame that meets the failure is dropped whole and the
//! path tracer says why, instead of panicking.

use std::sync::Arc;

use vcm::{Film, Integrator, PtSettings};
use vcm_gpu::GpuPathTracer;
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions};

use crate::common::{gpu, scene};

#[test]
fn a_lost_device_drops_the_frame_and_names_the_failure() {
    let Some(gpu) = gpu() else { return };
    let scene = scene("cornell-box");
    let options = GpuBvhOptions::default();
    let bvh = GpuBvh::new(Arc::clone(&gpu), &scene.triangle_corners(), options).unwrap();
    let mut tracer = GpuPathTracer::new(Arc::clone(&scene), &bvh, PtSettings::new(8, 8)).unwrap();
    let mut film = Film::new(8, 8);
    assert!(!tracer.render_frame(&mut film, 0).interrupted);
    assert_eq!(tracer.failure(), None);
    let before = film.clone();
    gpu.device.destroy();
    assert!(tracer.render_frame(&mut film, 1).interrupted);
    let failure = tracer.failure().expect("the failure is kept");
    assert!(
        failure.starts_with("path tracing on the GPU: "),
        "{failure}"
    );
    assert_eq!(film, before, "the failed frame added nothing");
    // No frame renders after it.
    assert!(tracer.render_frame(&mut film, 2).interrupted);
}
