//! The light vertex cache: every connectable vertex of a frame's light paths, in one array
//! of fixed capacity (Davidovič et al. 2014, "Progressive Light Transport Simulation on the
//! GPU: Survey and Improvements").

use std::num::NonZeroU32;

use glam::Vec3;
use rayon::prelude::*;

use vcm_scene::mesh::Mesh;

use crate::bidir::mis::SubpathMis;
use crate::huge_pages::advise_huge_pages;

/// Head room of the cache over the preprocess estimate.
const CAPACITY_MARGIN: f64 = 1.1;

/// A non-specular vertex of a light path, as connections and merging need it. Its 64 bytes
/// are aligned to a cache line: connections and merges read vertices from all over the
/// cache, and each read is then one line, not two.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(align(64))]
pub struct LightVertex {
    /// Position on the surface.
    pub position: Vec3,
    /// Unit direction toward the previous vertex of the light path (where light comes from).
    pub wo: Vec3,
    /// The light path's throughput up to and including the segment that reached this vertex
    /// (W in scene units: emitted power over the sampling pdfs).
    pub throughput: Vec3,
    /// The recursive MIS quantities on arrival.
    pub(crate) mis: SubpathMis,
    /// Triangle hit (the BSDF is rebuilt from it for connections).
    pub triangle: u32,
    /// Barycentric weight of the triangle's second corner.
    pub u: f32,
    /// Barycentric weight of the triangle's third corner.
    pub v: f32,
    /// Segments from the light to this vertex (1: the first hit). Never zero, so that an
    /// `Option<LightVertex>` (a light path's latest vertex, carried between waves) takes no
    /// more room than a vertex: with a tag of its own it took two cache lines.
    pub path_length: NonZeroU32,
}

impl LightVertex {
    /// |ωo·n_g| on arrival: the cosine between `wo` and the geometric normal of the triangle
    /// the vertex lies on, which converts the light path's density per solid angle into its
    /// density over that surface's area. `known` is a triangle whose unit geometric normal is
    /// at hand (a camera vertex's); the mesh is read only for another triangle.
    pub fn cos_on_arrival(&self, mesh: &Mesh, known: (u32, Vec3)) -> f32 {
        let (triangle, normal) = known;
        let normal = if self.triangle == triangle {
            normal
        } else {
            mesh.geometric_normal(self.triangle as usize)
        };
        normal.dot(self.wo).abs()
    }
}

/// The light vertices of one frame, path by path, each path's from the light on. Vertices
/// beyond the capacity (those of the last paths) are discarded and counted.
#[derive(Clone, Debug, Default)]
pub struct LightVertexCache {
    vertices: Vec<LightVertex>,
    capacity: usize,
    discarded: u64,
}

impl LightVertexCache {
    /// An empty cache that holds at most `capacity` vertices (allocated up front).
    pub fn with_capacity(capacity: usize) -> LightVertexCache {
        let mut vertices = Vec::with_capacity(capacity);
        advise_huge_pages(&mut vertices);
        LightVertexCache {
            vertices,
            capacity,
            discarded: 0,
        }
    }

    /// The capacity for `light_paths` paths per frame when a preprocess saw
    /// `sampled_vertices` cacheable vertices on `sampled_paths` paths: the mean per path ×
    /// paths × 1.1.
    pub fn estimate_capacity(sampled_vertices: u64, sampled_paths: u64, light_paths: u64) -> usize {
        let per_path = sampled_vertices as f64 / sampled_paths.max(1) as f64;
        (per_path * light_paths as f64 * CAPACITY_MARGIN).ceil() as usize
    }

    /// Empties the cache for the next frame (the capacity stays; the discard count restarts).
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.discarded = 0;
    }

    /// Appends `vertices` in order while there is room, in parallel and straight into the
    /// cache's memory; counts the rest as discarded.
    pub fn extend(&mut self, vertices: impl IndexedParallelIterator<Item = LightVertex>) {
        let room = self.capacity.saturating_sub(self.vertices.len());
        self.discarded += vertices.len().saturating_sub(room) as u64;
        self.vertices.par_extend(vertices.take(room));
    }

    /// The stored vertices.
    pub fn vertices(&self) -> &[LightVertex] {
        &self.vertices
    }

    /// Number of stored vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Whether no vertex is stored.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// The most vertices the cache holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Vertices discarded since the last [`LightVertexCache::clear`] because the cache was full.
    pub fn discarded(&self) -> u64 {
        self.discarded
    }

    /// Bytes of the vertex array (its capacity).
    pub fn memory_bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<LightVertex>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(i: u32) -> LightVertex {
        LightVertex {
            position: Vec3::splat(i as f32),
            wo: Vec3::Z,
            throughput: Vec3::ONE,
            mis: SubpathMis::default(),
            triangle: i,
            u: 0.0,
            v: 0.0,
            path_length: NonZeroU32::MIN,
        }
    }

    #[test]
    fn a_vertex_and_a_vertex_in_flight_take_one_cache_line() {
        assert_eq!(size_of::<LightVertex>(), 64);
        assert_eq!(size_of::<Option<LightVertex>>(), 64);
    }

    #[test]
    fn the_cosine_on_arrival_is_the_vertex_s_own_triangle_s() {
        // A floor (triangle 0, facing +z) meeting a wall (triangle 1, facing +x) at a corner.
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::Y, Vec3::X, Vec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3]],
            ..Mesh::default()
        };
        let (floor, wall) = (mesh.geometric_normal(0), mesh.geometric_normal(1));
        assert_eq!((floor, wall), (Vec3::Z, Vec3::X));
        // Light reaching the wall along the floor's plane: grazing for the floor, head-on
        // for the wall it lies on.
        let on_wall = LightVertex {
            wo: Vec3::X,
            triangle: 1,
            ..vertex(0)
        };
        assert_eq!(on_wall.cos_on_arrival(&mesh, (0, floor)), 1.0);
        // On the known triangle the known normal is taken, whatever the mesh holds.
        let on_floor = LightVertex {
            wo: Vec3::new(0.6, 0.0, 0.8),
            triangle: 0,
            ..vertex(0)
        };
        assert_eq!(on_floor.cos_on_arrival(&mesh, (0, floor)), 0.8);
        assert_eq!(on_floor.cos_on_arrival(&mesh, (0, Vec3::X)), 0.6);
    }

    #[test]
    fn overflow_is_discarded_and_counted() {
        let mut cache = LightVertexCache::with_capacity(3);
        cache.extend((0..5).into_par_iter().map(vertex));
        assert_eq!(cache.len(), 3);
        assert_eq!(cache.discarded(), 2);
        assert_eq!(cache.vertices()[2].triangle, 2);
        cache.clear();
        assert!(cache.is_empty());
        assert_eq!((cache.discarded(), cache.capacity()), (0, 3));
    }

    #[test]
    fn capacity_is_the_mean_times_paths_plus_ten_percent() {
        assert_eq!(
            LightVertexCache::estimate_capacity(25_000, 10_000, 1000),
            2750
        );
        assert_eq!(LightVertexCache::estimate_capacity(0, 0, 1000), 0);
    }
}
