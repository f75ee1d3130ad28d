//! Whole frames on the GPU: vcm-rs's path tracer and its bidirectional algorithms (light
//! tracing, BPT, PPM, BPM, VCM) as WGSL compute kernels through wgpu.
//!
//! [`GpuPathTracer`] renders with the hierarchy of a [`GpuBvh`](vcm_traversal_wgpu::GpuBvh)
//! and the scene's shading data uploaded once, as a wavefront: the paths keep their state in
//! storage buffers, and round by round one kernel takes the queued paths one vertex further
//! (closest hit, emission with MIS, one light sample, BSDF sampling, Russian roulette) and
//! another traces their shadow rays; each path adds its radiance to the frame's film on the
//! device once it ends. Only that film comes back, and the host merges it into the render's
//! once the frame is whole (an interrupted frame adds nothing). The kernels draw
//! the same numbers as the CPU for the same path ([`vcm_scene::sampling::SobolSampler`] in
//! `shaders/sampler.wgsl`) and shades with the same operations, so both backends render the
//! same image up to floating-point rounding per path, not only in expectation.
//!
//! [`GpuBidirectional`] does the same for light tracing — each invocation takes one camera
//! sample to its first hit and follows one light path from its light, in importance
//! transport, connecting its vertices to the camera — and for BPT, PPM, BPM and VCM: the
//! light paths store their vertices in a cache on the device (in the CPU's order), the device
//! builds the CPU's hash grids over it where the algorithm merges, and the camera paths
//! sample lights, connect to cached vertices and merge with those nearby, all weighted by MIS
//! as the CPU weighs them. Every kernel adds to a film on the device whose exact sums make the order
//! of the additions irrelevant; only that film comes back.
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

mod bidirectional;
#[cfg(test)]
mod bsdf_probe;
mod compute;
mod error;
mod frames;
mod grid;
mod index;
mod kernel;
#[cfg(test)]
mod mis_probe;
mod path_tracer;
mod plan;
#[cfg(test)]
mod probe;
mod scene_data;
pub mod shader;

pub use bidirectional::GpuBidirectional;
pub use error::GpuRenderError;
pub use path_tracer::GpuPathTracer;
pub use scene_data::check_scene;
