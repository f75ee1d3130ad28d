//! A hashed uniform grid over points for fixed-radius queries (the photon map of vertex
//! merging).
//!
//! Cells are 2r wide, so a sphere of radius r around a query point overlaps at most the
//! 2 × 2 × 2 cells nearest to it: the query's own cell and, per axis, the neighbour on the
//! side of the cell the point lies in. Cells are hashed into as many buckets as there are
//! points (rounded up to a power of two).
//!
//! The build is a parallel counting sort: bucket ids in parallel, counts by atomic
//! increments, an exclusive prefix sum, a scatter by atomic cursors, then each bucket's
//! indices sorted so that the order inside a bucket (and hence any sum over a query) does not
//! depend on thread timing.

use std::sync::atomic::{AtomicU32, Ordering};

use glam::{I64Vec3, Vec3};
use rayon::prelude::*;

/// A hashed grid over a set of points for queries within a fixed radius.
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    radius_sq: f32,
    inv_cell_size: f32,
    /// Lower corner of the points' bounds (cells are counted from here).
    min: Vec3,
    /// Upper corner of the points' bounds.
    max: Vec3,
    /// `bucket_mask + 1` buckets.
    bucket_mask: u64,
    /// Bucket b's point indices are `indices[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    indices: Vec<u32>,
    /// `points[indices[k]]`: the positions in bucket order, read contiguously by queries.
    sorted_points: Vec<Vec3>,
}

impl HashGrid {
    /// Builds the grid over `points` for queries of radius `radius` (> 0).
    ///
    /// Panics if there are 2³² or more points.
    pub fn build(points: &[Vec3], radius: f32) -> HashGrid {
        assert!(
            points.len() < u32::MAX as usize,
            "too many points for a hash grid"
        );
        let (min, max) = points
            .par_iter()
            .fold(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            )
            .reduce(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(a, b), (c, d)| (a.min(c), b.max(d)),
            );
        let buckets = points.len().max(1).next_power_of_two();
        let mut grid = HashGrid {
            radius_sq: radius * radius,
            inv_cell_size: 0.5 / radius,
            min,
            max,
            bucket_mask: buckets as u64 - 1,
            starts: Vec::new(),
            indices: Vec::new(),
            sorted_points: Vec::new(),
        };
        let bucket_of: Vec<u32> = points
            .par_iter()
            .map(|&p| grid.bucket(grid.cell_of(p)))
            .collect();
        let counts: Vec<AtomicU32> = (0..buckets).map(|_| AtomicU32::new(0)).collect();
        bucket_of.par_iter().for_each(|&b| {
            counts[b as usize].fetch_add(1, Ordering::Relaxed);
        });
        let mut starts = Vec::with_capacity(buckets + 1);
        let mut total = 0u32;
        starts.push(0);
        for count in &counts {
            total += count.load(Ordering::Relaxed);
            starts.push(total);
        }
        let cursors: Vec<AtomicU32> = starts[..buckets]
            .iter()
            .map(|&s| AtomicU32::new(s))
            .collect();
        let slots: Vec<AtomicU32> = (0..points.len()).map(|_| AtomicU32::new(0)).collect();
        bucket_of.par_iter().enumerate().for_each(|(i, &b)| {
            let slot = cursors[b as usize].fetch_add(1, Ordering::Relaxed);
            slots[slot as usize].store(i as u32, Ordering::Relaxed);
        });
        let mut indices: Vec<u32> = slots.into_iter().map(AtomicU32::into_inner).collect();
        indices
            .par_chunk_by_mut(|&a, &b| bucket_of[a as usize] == bucket_of[b as usize])
            .for_each(|bucket| bucket.sort_unstable());
        grid.sorted_points = indices.par_iter().map(|&i| points[i as usize]).collect();
        grid.starts = starts;
        grid.indices = indices;
        grid
    }

    /// Calls `visit` with the index of every point within the radius of `query` (distance
    /// ≤ r), each once, in an order that depends only on the points.
    pub fn query(&self, query: Vec3, mut visit: impl FnMut(usize)) {
        let r = self.radius_sq.sqrt();
        if self.indices.is_empty()
            || query.cmplt(self.min - r).any()
            || query.cmpgt(self.max + r).any()
        {
            return;
        }
        let scaled = (query - self.min) * self.inv_cell_size;
        let cell = scaled.floor();
        let side = (scaled - cell).cmpgt(Vec3::splat(0.5));
        let cell = cell.as_i64vec3();
        let step = I64Vec3::select(side, I64Vec3::ONE, I64Vec3::NEG_ONE);
        let mut visited = [u32::MAX; 8];
        for (n, corner) in (0..8).enumerate() {
            let offset = I64Vec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let bucket = self.bucket(cell + offset * step);
            // Two neighbouring cells can share a bucket; visit it once.
            if visited[..n].contains(&bucket) {
                continue;
            }
            visited[n] = bucket;
            let range =
                self.starts[bucket as usize] as usize..self.starts[bucket as usize + 1] as usize;
            for (&i, p) in self.indices[range.clone()]
                .iter()
                .zip(&self.sorted_points[range])
            {
                if p.distance_squared(query) <= self.radius_sq {
                    visit(i as usize);
                }
            }
        }
    }

    /// Bytes of the bucket and index arrays.
    pub fn memory_bytes(&self) -> usize {
        (self.starts.capacity() + self.indices.capacity()) * std::mem::size_of::<u32>()
            + self.sorted_points.capacity() * std::mem::size_of::<Vec3>()
    }

    fn cell_of(&self, p: Vec3) -> I64Vec3 {
        ((p - self.min) * self.inv_cell_size).floor().as_i64vec3()
    }

    /// The bucket of a cell (the spatial hash of Teschner et al. 2003).
    fn bucket(&self, cell: I64Vec3) -> u32 {
        let h = (cell.x.wrapping_mul(73_856_093))
            ^ (cell.y.wrapping_mul(19_349_663))
            ^ (cell.z.wrapping_mul(83_492_791));
        (h as u64 & self.bucket_mask) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_scene::sampling::Rng;

    fn random_points(n: usize, rng: &mut Rng) -> Vec<Vec3> {
        (0..n)
            .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - 1.0)
            .collect()
    }

    #[test]
    fn queries_find_exactly_the_points_within_the_radius() {
        let mut rng = Rng::new(7, 0);
        let points = random_points(5000, &mut rng);
        for radius in [0.01, 0.07, 0.3, 3.0] {
            let grid = HashGrid::build(&points, radius);
            for query in random_points(200, &mut rng) {
                let mut found = Vec::new();
                grid.query(query, |i| found.push(i));
                let mut expected: Vec<usize> = (0..points.len())
                    .filter(|&i| points[i].distance_squared(query) <= radius * radius)
                    .collect();
                found.sort_unstable();
                expected.sort_unstable();
                assert_eq!(found, expected, "radius {radius}, query {query}");
            }
        }
    }

    #[test]
    fn query_order_is_the_same_for_any_thread_count() {
        let mut rng = Rng::new(8, 0);
        let points = random_points(20_000, &mut rng);
        let order = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let grid = pool.install(|| HashGrid::build(&points, 0.05));
            let mut visits = Vec::new();
            for &q in points.iter().step_by(97) {
                grid.query(q, |i| visits.push(i));
            }
            visits
        };
        assert_eq!(order(1), order(4));
    }

    #[test]
    fn empty_and_far_queries_find_nothing() {
        let grid = HashGrid::build(&[], 0.1);
        grid.query(Vec3::ZERO, |_| panic!("no points"));
        let points = [Vec3::ZERO];
        let grid = HashGrid::build(&points, 0.1);
        grid.query(Vec3::splat(5.0), |_| panic!("too far"));
        let mut hits = 0;
        grid.query(Vec3::splat(0.05), |_| hits += 1);
        assert_eq!(hits, 1);
    }
}
