//! # vcm
//!
//! Integrators for vcm-rs and what they are built on. Every integrator implements
//! [`Integrator`]: frame after frame into a [`Film`].
//!
//! - [`PathTracer`]: unidirectional path tracing with next event estimation and MIS (the
//!   reference), run in waves: every active path is traced, shaded in parallel, its shadow ray
//!   tested, and the survivors compacted for the next wave.
//! - [`Vcm`]: vertex connection and merging, and each of its sub-algorithms ([`Algorithm`]:
//!   light tracing, BPT, PPM, BPM, VCM): a light pass fills the [`light_vertex_cache`], a
//!   [`hash_grid`] is built over it for merging, then a camera pass connects and merges.
//! - [`Film`]: per-pixel exact accumulation ([`exact_sum`], box filter), light tracing
//!   splats, non-finite samples dropped and counted.
//! - [`ray_offset`]: ray origins offset by floating-point error bounds (pbrt-v4), so that
//!   spawned rays neither re-hit their own surface nor depend on the scene's scale.
//!
//! A render is a pure function of (scene, settings, seed, iteration): every path draws its
//! random numbers from a generator keyed by (seed, iteration, path index, stream), and results
//! are gathered in path order, so the image is bit-identical for any number of threads.
//!
//! ```no_run
//! use std::sync::Arc;
//! use vcm::{Algorithm, Film, Integrator, Vcm, VcmSettings};
//! use vcm_traversal::{CpuBvh, CpuBvhOptions, Traversal};
//!
//! let scene = Arc::new(vcm_scene::Scene::load("scenes/cornell-box.gltf")?);
//! // Scenes with alpha masks need the alpha test: `vcm_rs::cpu_traversal` builds it.
//! let bvh = CpuBvh::new(&scene.triangle_corners(), CpuBvhOptions::default())?;
//! let traversal: Arc<dyn Traversal> = Arc::new(bvh);
//! let settings = VcmSettings::new(Algorithm::Vcm, 256, 256);
//! let mut vcm = Vcm::new(scene, traversal, settings)?;
//! let mut film = Film::new(settings.width, settings.height);
//! // One sample per pixel per frame (the default schedule): frame i renders sample i.
//! for sample in 0..16 {
//!     let stats = vcm.render_frame(&mut film, sample);
//!     eprintln!("sample {sample}: {} light vertices", stats.light_vertices);
//! }
//! let radiance = film.mean(); // W·sr⁻¹·m⁻² per pixel, row by row from the top left
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod algorithm;
pub mod atomic_write;
mod bidir;
mod camera_rays;
mod error;
pub mod exact_sum;
mod film;
pub mod hash_grid;
mod huge_pages;
pub mod image_io;
mod integrator;
mod lambert;
mod lanes;
pub mod light_vertex_cache;
mod medium;
pub mod memory;
pub mod metrics;
mod path_state;
mod path_tracer;
mod prefetch;
pub mod ray_offset;
mod roulette;
mod shade;
mod shadow;
mod surface_hit;
mod vertex_numbers;
mod walk;
mod wave;

pub use algorithm::Algorithm;
pub use bidir::mis_paths;
pub use bidir::{
    BidirPlan, DEFAULT_ALPHA, DEFAULT_RADIUS_FRACTION, DEFAULT_RADIUS_PIXELS, MAX_CONNECTIONS,
    MAX_LIGHT_PATHS_PER_PIXEL, MergeRadius, Vcm, VcmSettings, light_paths_per_pixel, merge_radius,
};
pub use error::RenderError;
pub use film::{Film, FilmBand, PixelSum, rounded_sum};
pub use integrator::{FrameStats, Integrator, Schedule, check_image_size};
pub use path_tracer::{PathTracer, PtSettings};
pub use vcm_scheduler::{Scheduler, SchedulerStats, StopFlag};
