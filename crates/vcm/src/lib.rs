//! # vcm
//!
//! Integrators for vcm-rs. This stage holds the wavefront path tracer and what it is built on:
//!
//! - [`Film`]: per-pixel f64 accumulation of radiance samples (box filter), with non-finite
//!   samples dropped and counted.
//! - [`ray_offset`]: ray origins offset by floating-point error bounds (pbrt-v4), so that
//!   spawned rays neither re-hit their own surface nor depend on the scene's scale.
//! - [`PathTracer`]: unidirectional path tracing with next event estimation and multiple
//!   importance sampling, run in waves: every active path is traced, then shaded in parallel,
//!   then its shadow ray is tested, then the survivors are compacted for the next wave.
//!
//! A render is a pure function of (scene, settings, seed, iteration): every path draws its
//! random numbers from `Rng::from_key(&[seed, iteration, pixel, 0])`, so the image is
//! bit-identical for any number of threads.
//!
//! ```no_run
//! use std::sync::Arc;
//! use vcm::{Film, PathTracer, PtSettings};
//! use vcm_traversal::{CpuBvh, CpuBvhOptions, Traversal};
//!
//! let scene = Arc::new(vcm_scene::Scene::load("scenes/cornell-box.gltf")?);
//! // Scenes with alpha masks need the alpha test: `vcm_rs::cpu_traversal` builds it.
//! let bvh = CpuBvh::new(&scene.triangle_corners(), CpuBvhOptions::default())?;
//! let traversal: Arc<dyn Traversal> = Arc::new(bvh);
//! let settings = PtSettings { width: 256, height: 256, seed: 1, max_depth: None };
//! let mut tracer = PathTracer::new(scene, traversal, settings)?;
//! let mut film = Film::new(settings.width, settings.height);
//! for iteration in 0..16 {
//!     let stats = tracer.render_frame(&mut film, iteration);
//!     eprintln!("frame {iteration}: {} shadow rays", stats.shadow_rays);
//! }
//! let radiance = film.mean(); // W·sr⁻¹·m⁻² per pixel, row by row from the top left
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod atomic_write;
mod error;
mod film;
pub mod image_io;
pub mod metrics;
mod path_state;
mod path_tracer;
pub mod ray_offset;
mod shade;
mod shadow;

pub use error::RenderError;
pub use film::Film;
pub use path_tracer::{FrameStats, PathTracer, PtSettings};
