//! Whole frames on the GPU: vcm-rs's path tracer and light tracer as WGSL compute kernels
//! through wgpu.
//!
//! [`GpuPathTracer`] renders with the hierarchy of a [`GpuBvh`](vcm_traversal_wgpu::GpuBvh)
//! and the scene's shading data uploaded once: each kernel invocation follows one camera path
//! to its end (camera ray, closest hits, emission with MIS, one light sample with its shadow
//! ray, BSDF sampling, Russian roulette) and writes its radiance; only those radiances come
//! back, and the host adds them to the film (a frame at a time: an interrupted frame adds
//! nothing; the film's exact sums make the order irrelevant). The kernel draws
//! the same numbers as the CPU for the same path ([`vcm_scene::sampling::SobolSampler`] in
//! `shaders/sampler.wgsl`) and shades with the same operations, so both backends render the
//! same image up to floating-point rounding per path, not only in expectation.
//!
//! [`GpuLightTracer`] does the same for light tracing: each invocation takes one camera
//! sample to its first hit (the lights seen directly) and follows one light path from its
//! light, in importance transport, connecting its vertices to the camera; the splats that
//! reach it come back with the camera samples' radiance.
//!
//! The GPU shades the whole scene model of vcm-scene — every lobe of the glTF
//! metallic-roughness mixture, smooth and GGX, with its textures (base colour,
//! metallic-roughness, specular, transmission, emission, normal maps) and vertex colours —
//! — absorbing volumes and alpha masks (the traversal's own mask test), under every kind of
//! light: emissive triangles, point, spot and directional lights, a constant or image
//! environment. [`check_scene`] refuses only a scene without triangles. The kernels are
//! specialised per scene by override constants: the shader compiler drops the code of what
//! the scene lacks (textures, vertex colours, kinds of light, …), and
//! [`Integrator::decisions`](vcm::Integrator::decisions) says which parts run and why.

#![warn(missing_docs)]

#[cfg(test)]
mod bsdf_probe;
mod error;
mod frames;
mod kernel;
mod light_tracer;
mod path_tracer;
mod plan;
mod scene_data;
pub mod shader;

pub use error::GpuRenderError;
pub use light_tracer::GpuLightTracer;
pub use path_tracer::GpuPathTracer;
pub use scene_data::check_scene;
