//! Schedulers for wavefront integrators: they decide which paths are traced and shaded
//! together, so that no core idles while a pass runs out of rays.
//!
//! An integrator describes its paths as a [`Wavefront`]: something that starts the paths of
//! a [`Tile`], hands out the rays of its active paths, shades their hits and resolves its
//! shadow rays. A [`Scheduler`] drives wavefronts over a [`Traversal`](vcm_traversal::Traversal)
//! backend:
//! - [`Scheduler::None`]: one wavefront over the whole image, every pass one big batch;
//! - [`Scheduler::Tile`]: the worker threads take tiles from an atomic counter and trace each
//!   to completion; when a worker's active paths drop below a fraction of a tile, it pulls in
//!   the next tile's camera paths (tile merging);
//! - [`Scheduler::Queue`]: a pool of wavefronts ("queues") in explicit states, taking tiles
//!   from the same counter; one thread collects every traversal job
//!   ([`Traversal::submit`](vcm_traversal::Traversal::submit)) while the others shade (and,
//!   on an asynchronous backend, submit), so shading overlaps traversal on a GPU.
//!
//! A [`StopFlag`] ends a pass early: no tile starts once it is raised, and the `none` and
//! `tile` workers stop between passes; what the pass returns then is incomplete, and the
//! caller drops it.
//!
//! Paths' random numbers must not depend on which wavefront traces them (the integrators seed
//! them from the pixel and sample), and results are gathered per path and added in a fixed
//! order, so every scheduler and thread count gives the same image.

#![warn(missing_docs)]

mod drive;
mod queue;
mod stats;
mod stop;
#[cfg(test)]
mod tests;
mod tiles;
mod wavefront;

pub use drive::{Scheduler, run};
pub use stats::SchedulerStats;
pub use stop::StopFlag;
pub use tiles::{Tile, TileGrid};
pub use wavefront::Wavefront;
