//! A device that fails mid-render: the frame that meets the failure is dropped whole and the
//! integrator says why, instead of panicking.

use std::sync::Arc;

use vcm::{Algorithm, Film, Integrator, PathTracer, PtSettings, Vcm, VcmSettings};
use vcm_gpu::{GpuBidirectional, GpuPathTracer};
use vcm_traversal::Traversal;
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions, GpuDevice};

use crate::common::{gpu, scene};

/// Renders a frame with each of `integrators`, destroys the device under them, and checks
/// that each then drops its next frame whole, keeps a failure that starts with its entry of
/// `prefixes`, and renders no frame after it.
fn assert_a_lost_device_drops_frames(
    gpu: &GpuDevice,
    integrators: &mut [Box<dyn Integrator + '_>],
    prefixes: &[&str],
) {
    let mut films = vec![Film::new(8, 8); integrators.len()];
    for (integrator, film) in integrators.iter_mut().zip(&mut films) {
        assert!(!integrator.render_frame(film, 0).interrupted);
        assert_eq!(integrator.failure(), None);
    }
    let before = films.clone();
    gpu.device.destroy();
    for (k, (integrator, film)) in integrators.iter_mut().zip(&mut films).enumerate() {
        assert!(
            integrator.render_frame(film, 1).interrupted,
            "integrator {k}"
        );
        let failure = integrator.failure().expect("the failure is kept");
        assert!(failure.starts_with(prefixes[k]), "{failure}");
        assert_eq!(*film, before[k], "the failed frame added nothing");
        // No frame renders after it.
        assert!(integrator.render_frame(film, 2).interrupted);
    }
}

/// The GPU's path tracer, light tracer and BPT, whose kernels fail.
#[test]
fn a_lost_device_drops_the_frame_and_names_the_failure() {
    let Some(gpu) = gpu() else { return };
    let scene = scene("cornell-box");
    let options = GpuBvhOptions::default();
    let bvh = GpuBvh::new(Arc::clone(&gpu), &scene.triangle_corners(), options).unwrap();
    let path_tracer = GpuPathTracer::new(Arc::clone(&scene), &bvh, PtSettings::new(8, 8));
    let bidirectional = |algorithm| {
        let settings = VcmSettings::new(algorithm, 8, 8);
        GpuBidirectional::new(Arc::clone(&scene), &bvh, settings).unwrap()
    };
    let mut integrators: [Box<dyn Integrator + '_>; 3] = [
        Box::new(path_tracer.unwrap()),
        Box::new(bidirectional(Algorithm::LightTracing)),
        Box::new(bidirectional(Algorithm::Bpt)),
    ];
    let prefixes = [
        "path tracing on the GPU: ",
        "light tracing on the GPU: ",
        "bidirectional path tracing on the GPU: ",
    ];
    assert_a_lost_device_drops_frames(&gpu, &mut integrators, &prefixes);
}

/// Shading on the CPU over the GPU's traversal: the traversal's failure drops the frame that
/// met it whole and ends the render, for the path tracer and for VCM alike.
#[test]
fn a_lost_device_under_cpu_shading_drops_the_frame_and_names_the_failure() {
    let Some(gpu) = gpu() else { return };
    let scene = scene("cornell-specular");
    let options = GpuBvhOptions::default();
    let bvh = GpuBvh::new(Arc::clone(&gpu), &scene.triangle_corners(), options).unwrap();
    let traversal: Arc<dyn Traversal> = Arc::new(bvh);
    let path_tracer = PathTracer::new(
        Arc::clone(&scene),
        Arc::clone(&traversal),
        PtSettings::new(8, 8),
    );
    let vcm = Vcm::new(
        Arc::clone(&scene),
        Arc::clone(&traversal),
        VcmSettings::new(Algorithm::Vcm, 8, 8),
    );
    let mut integrators: [Box<dyn Integrator>; 2] =
        [Box::new(path_tracer.unwrap()), Box::new(vcm.unwrap())];
    let prefix = "ray traversal failed: ";
    assert_a_lost_device_drops_frames(&gpu, &mut integrators, &[prefix; 2]);
}
