//! The stiff-scene suite (issue 8, part 1): scenes generated in code at the edges of floating
//! point and of the estimators, each rendered with every algorithm where it can sample the
//! scene. Every render must be finite with no dropped sample, gain no energy in a furnace, and
//! agree with its analytic value, with the same scene at scale 1, or with the path tracer.
//!
//! * `scale`: one scene at scales 10⁻⁴ … 10⁵ and far from the origin;
//! * `lights`: a tiny light 10⁶ times brighter than a large dim one; a point light almost
//!   touching a wall, its light grazing the floor;
//! * `furnaces`: near-specular and glossy metals, glass of IOR 1.0001 and 3, a grazing camera,
//!   coincident, degenerate and sliver triangles, 100-bounce mirror chains and photon mapping
//!   after a billion iterations, all inside a white furnace whose value is known.

mod furnaces;
mod harness;
mod lights;
mod scale;
mod scenes;
