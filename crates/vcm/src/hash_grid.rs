//! A hashed uniform grid over points for fixed-radius queries (the photon map of vertex
//! merging).
//!
//! Cells are [`HashGrid::CELL_RADII`] = 3 radii wide, so a sphere of radius r around a
//! query point overlaps at most the 2 × 2 × 2 cells nearest to it: the query's own cell and,
//! per axis, the neighbour on the side of the cell the point lies in, where the point is
//! within r of that face. Cells are hashed into as many buckets as there are points (rounded
//! up to a power of two).
//!
//! The width trades buckets against entries: a query reads each bucket it visits from an
//! unrelated place in memory, then the bucket's entries one after another. With the default
//! radius a query finds about one point; at 2r a query visited 7.2 buckets and 10.4 entries
//! on average, at 3r 4.2 buckets and 12–13 entries (4r: 3.7 and 15–16): VCM ran 1.02× as
//! fast on one thread on cornell-water and cornell-specular, within noise on two threads
//! and with denser points (docs/performance.md, "VCM's light and camera passes").
//!
//! The build is a parallel counting sort: bucket ids in parallel, counts by atomic
//! increments, an exclusive prefix sum, a scatter by atomic cursors, then each bucket's
//! entries sorted so that the order inside a bucket (and hence any sum over a query) does not
//! depend on thread timing.
//!
//! A query's cost is its cache misses: the grid is far larger than the caches, and the
//! cells around a point hash to unrelated places. So each entry keeps the point's position
//! beside its index (one miss per bucket, not two), cells the sphere does not reach are
//! skipped, and a query's cells are found from the point alone ([`HashGrid::cells`]), so
//! that a caller can request where their buckets begin, then their entries, each a while
//! before it reads them ([`HashGrid::prefetch_bucket_starts`],
//! [`HashGrid::prefetch_entries`], then [`HashGrid::query_cells`]).

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
    /// Bucket b's points are `entries[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    /// The points in bucket order, each with its index.
    entries: Vec<Entry>,
}

/// A grid's data as [`HashGrid::layout`] gives it.
pub struct GridLayout<'a> {
    /// The query radius, squared.
    pub radius_sq: f32,
    /// 1 / the cell size ([`HashGrid::CELL_RADII`] radii).
    pub inv_cell_size: f32,
    /// The points' bounds.
    pub min: Vec3,
    /// The points' bounds.
    pub max: Vec3,
    /// Buckets − 1 (a power of two less one).
    pub bucket_mask: u32,
    /// Each bucket's first entry, then the number of entries.
    pub starts: &'a [u32],
    /// (point, its index) in bucket order.
    pub entries: Box<dyn ExactSizeIterator<Item = (Vec3, u32)> + 'a>,
}

/// The buckets a query reads ([`HashGrid::cells`]): at most 8, each once.
#[derive(Clone, Copy, Debug)]
pub struct GridCells([u32; 8]);

impl GridCells {
    /// An unused slot.
    const NONE: u32 = u32::MAX;

    /// The buckets, in cell order.
    fn buckets(&self) -> impl Iterator<Item = usize> + '_ {
        self.0
            .iter()
            .filter(|&&b| b != Self::NONE)
            .map(|&b| b as usize)
    }
}

/// A point of the grid: its position and its index in the caller's list (16 bytes, so an
/// entry never straddles two cache lines).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(16))]
struct Entry {
    position: Vec3,
    index: u32,
}

impl HashGrid {
    /// The most bytes building a grid over `points` points holds at once: the points
    /// themselves, each point's bucket, slot and index, the entries, and three lists over
    /// the buckets (up to twice as many as points).
    pub fn bytes_to_build(points: u64) -> u64 {
        let per_point = size_of::<Vec3>() + 3 * size_of::<u32>() + size_of::<Entry>();
        let per_bucket = 3 * size_of::<u32>();
        points.saturating_mul((per_point + 2 * per_bucket) as u64)
    }

    /// Builds the grid over `points` for queries of radius `radius` (> 0); a query names
    /// each point by its place in `points`.
    ///
    /// Panics if there are 2³² or more points.
    pub fn build(points: &[Vec3], radius: f32) -> HashGrid {
        HashGrid::build_named(points, radius, |i| i)
    }

    /// [`HashGrid::build`], with a query naming `points[i]` by `indices[i]` (increasing, as
    /// many as the points).
    ///
    /// Panics if there are 2³² or more points, or not a name for each.
    pub fn build_over(points: &[Vec3], indices: &[u32], radius: f32) -> HashGrid {
        assert_eq!(points.len(), indices.len(), "a name for every point");
        HashGrid::build_named(points, radius, |i| indices[i as usize])
    }

    /// The grid over `points`, the point at `i` named `name(i)` (in the order of `i`).
    fn build_named(points: &[Vec3], radius: f32, name: impl Fn(u32) -> u32 + Sync) -> HashGrid {
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
            inv_cell_size: HashGrid::inv_cell_size(radius),
            min,
            max,
            bucket_mask: buckets as u64 - 1,
            starts: Vec::new(),
            entries: Vec::new(),
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
        grid.entries = indices
            .par_iter()
            .map(|&i| Entry {
                position: points[i as usize],
                index: name(i),
            })
            .collect();
        grid.starts = starts;
        grid
    }

    /// Calls `visit` with the index of every point within the radius of `query` (distance
    /// ≤ r), each once, in an order that depends only on the points.
    pub fn query(&self, query: Vec3, visit: impl FnMut(usize)) {
        self.query_cells(&self.cells(query), query, visit);
    }

    /// [`query`](Self::query) in the cells [`cells`](Self::cells) found for `query`.
    pub fn query_cells(&self, cells: &GridCells, query: Vec3, mut visit: impl FnMut(usize)) {
        for range in cells.buckets().map(|b| self.bucket_range(b)) {
            for entry in &self.entries[range] {
                if entry.position.distance_squared(query) <= self.radius_sq {
                    visit(entry.index as usize);
                }
            }
        }
    }

    /// Starts loading where the buckets of `cells` begin: the first of two look-ahead steps
    /// before a query.
    pub fn prefetch_bucket_starts(&self, cells: &GridCells) {
        for b in cells.buckets() {
            crate::prefetch::prefetch(&self.starts[b]);
        }
    }

    /// Starts loading the first entries of the buckets of `cells`: the second look-ahead
    /// step, which reads where the buckets begin.
    pub fn prefetch_entries(&self, cells: &GridCells) {
        for range in cells.buckets().map(|b| self.bucket_range(b)) {
            if let Some(first) = self.entries.get(range.start) {
                crate::prefetch::prefetch(first);
            }
        }
    }

    /// The entries of bucket `b`.
    fn bucket_range(&self, b: usize) -> std::ops::Range<usize> {
        self.starts[b] as usize..self.starts[b + 1] as usize
    }

    /// The buckets of the (at most 8) cells that points within the radius of `query` can
    /// lie in, each bucket once. Reads nothing but the grid's bounds.
    pub fn cells(&self, query: Vec3) -> GridCells {
        let mut buckets = [GridCells::NONE; 8];
        let r = self.radius_sq.sqrt();
        if self.entries.is_empty()
            || query.cmplt(self.min - r).any()
            || query.cmpgt(self.max + r).any()
        {
            return GridCells(buckets);
        }
        let scaled = (query - self.min) * self.inv_cell_size;
        let cell = scaled.floor();
        let side = (scaled - cell).cmpgt(Vec3::splat(0.5));
        // Squared distance (in cells) from the query to the face shared with the neighbour on
        // its side, per axis; a neighbour across several faces is at least the sum away. The
        // distance is shortened by a bound of its rounding error (a few ulps of `scaled`), so
        // that a reachable cell is never skipped.
        let to_face = Vec3::select(side, cell + 1.0 - scaled, scaled - cell);
        let rounding = (scaled.abs() + 1.0) * HashGrid::SCALED_ERROR;
        let to_face = (to_face - rounding).max(Vec3::ZERO);
        let to_face_sq = to_face * to_face;
        let reach_sq = HashGrid::REACH_SQ;
        let cell = cell.as_i64vec3();
        let step = I64Vec3::select(side, I64Vec3::ONE, I64Vec3::NEG_ONE);
        for (slot, corner) in (0..8_i64).enumerate() {
            let across = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let distance_sq: f32 = (0..3)
                .filter(|&axis| across[axis] == 1)
                .map(|axis| to_face_sq[axis])
                .sum();
            if distance_sq > reach_sq {
                continue;
            }
            let offset = I64Vec3::from_array(across);
            let bucket = self.bucket(cell + offset * step);
            // Two neighbouring cells can share a bucket; visit it once.
            if !buckets.contains(&bucket) {
                buckets[slot] = bucket;
            }
        }
        GridCells(buckets)
    }

    /// The width of a cell in radii.
    pub const CELL_RADII: f32 = 3.0;

    /// 1 / the width of a cell for merge radius `radius`.
    pub fn inv_cell_size(radius: f32) -> f32 {
        1.0 / (HashGrid::CELL_RADII * radius)
    }

    /// The squared distance (in cells) within which a neighbouring cell is visited,
    /// (r / cell width)², with a margin for its own rounding.
    pub const REACH_SQ: f32 = (1.0 + 1e-4) / (HashGrid::CELL_RADII * HashGrid::CELL_RADII);

    /// Relative error bound of a query's position in cells, `(q − min) / width` (three
    /// roundings, with room to spare): the distance to a face is shortened by this much of
    /// the position's magnitude (plus one cell's worth) before it is compared with the reach.
    pub const SCALED_ERROR: f32 = 8.0 * f32::EPSILON;

    /// What another implementation of [`HashGrid::cells`] and [`HashGrid::query_cells`] (the
    /// GPU's) needs: the radius squared, the inverse cell size, the points' bounds, the
    /// bucket mask of the cells' spatial hash (Teschner et al.), each bucket's first entry
    /// (and the end), and the entries (point, its index) in bucket order.
    pub fn layout(&self) -> GridLayout<'_> {
        GridLayout {
            radius_sq: self.radius_sq,
            inv_cell_size: self.inv_cell_size,
            min: self.min,
            max: self.max,
            bucket_mask: self.bucket_mask as u32,
            starts: &self.starts,
            entries: Box::new(self.entries.iter().map(|e| (e.position, e.index))),
        }
    }

    /// Bytes of the bucket and entry arrays.
    pub fn memory_bytes(&self) -> usize {
        self.starts.capacity() * std::mem::size_of::<u32>()
            + self.entries.capacity() * std::mem::size_of::<Entry>()
    }

    fn cell_of(&self, p: Vec3) -> I64Vec3 {
        ((p - self.min) * self.inv_cell_size).floor().as_i64vec3()
    }

    /// The bucket of a cell (the spatial hash of Teschner et al. 2003; only the low bits,
    /// which 32-bit arithmetic gives alike, survive the mask).
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
    use vcm_scene::sampling::{Rng, Sampler};

    fn random_points(n: usize, rng: &mut Rng) -> Vec<Vec3> {
        (0..n)
            .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - 1.0)
            .collect()
    }

    /// The grid's query at `query` finds exactly the points within `radius`, by brute force.
    /// With the look-ahead steps first too ([`HashGrid::query_cells`]), in the same order.
    fn assert_finds_exactly(grid: &HashGrid, points: &[Vec3], radius: f32, query: Vec3) {
        let mut found = Vec::new();
        grid.query(query, |i| found.push(i));
        let mut found_ahead = Vec::new();
        query_ahead(grid, query, |i| found_ahead.push(i));
        assert_eq!(found_ahead, found);
        found.sort_unstable();
        let expected: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].distance_squared(query) <= radius * radius)
            .collect();
        assert_eq!(found, expected, "radius {radius}, query {query}");
    }

    #[test]
    fn queries_find_exactly_the_points_within_the_radius() {
        let mut rng = Rng::new(7, 0);
        let points = random_points(5000, &mut rng);
        for radius in [0.01, 0.07, 0.3, 3.0] {
            let grid = HashGrid::build(&points, radius);
            for query in random_points(200, &mut rng) {
                assert_finds_exactly(&grid, &points, radius, query);
            }
        }
    }

    #[test]
    fn a_grid_over_some_points_names_them_as_told() {
        let mut rng = Rng::new(8, 0);
        let points = random_points(3000, &mut rng);
        // Every third point, named by its place among all.
        let names: Vec<u32> = (0..points.len() as u32).step_by(3).collect();
        let some: Vec<Vec3> = names.iter().map(|&i| points[i as usize]).collect();
        let radius = 0.07;
        let grid = HashGrid::build_over(&some, &names, radius);
        for query in random_points(200, &mut rng) {
            let mut found = Vec::new();
            grid.query(query, |i| found.push(i));
            found.sort_unstable();
            let expected: Vec<usize> = (names.iter().map(|&i| i as usize))
                .filter(|&i| points[i].distance_squared(query) <= radius * radius)
                .collect();
            assert_eq!(found, expected, "query {query}");
        }
    }

    /// Queries on and beside cell faces, edges, corners and the planes where the sphere
    /// starts to reach a neighbour find points just inside the radius across every face, edge
    /// and corner: skipping cells the sphere cannot reach must never skip a point it does
    /// reach. Also far from the grid's corner (30,000 cells away), where the query's
    /// position in cells is rounded by thousandths of a cell.
    #[test]
    fn queries_near_cell_boundaries_miss_nothing() {
        let radius = 0.05;
        let cell = HashGrid::CELL_RADII * radius;
        let reach = 1.0 / HashGrid::CELL_RADII;
        for base in [Vec3::new(3.0, 4.0, 5.0), Vec3::new(30_000.0, 4.0, 29_000.0)] {
            let mut queries = Vec::new();
            for f in [
                0.0,
                1e-6,
                0.25,
                reach - 1e-6,
                reach,
                reach + 1e-6,
                0.5 - 1e-6,
                0.5,
                0.5 + 1e-6,
                1.0 - reach - 1e-6,
                1.0 - reach,
                1.0 - reach + 1e-6,
                1.0 - 1e-6,
            ] {
                for g in [0.0, 0.3, reach, 0.5, 0.9] {
                    queries.push((base + Vec3::new(f, g, f * g)) * cell);
                    queries.push((base + Vec3::new(g, f, f)) * cell);
                }
            }
            // Around every query: points at 0.999 r along all 26 lattice directions, and just
            // outside the radius.
            let mut points = vec![Vec3::ZERO, (base + 10.0) * cell];
            for q in &queries {
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let d = Vec3::new(dx as f32, dy as f32, dz as f32);
                            if d != Vec3::ZERO {
                                points.push(*q + d.normalize() * radius * 0.999);
                                points.push(*q + d.normalize() * radius * 1.001);
                            }
                        }
                    }
                }
            }
            let grid = HashGrid::build(&points, radius);
            for query in queries {
                assert_finds_exactly(&grid, &points, radius, query);
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

    /// The look-ahead steps of a query, then the query in its cells.
    fn query_ahead(grid: &HashGrid, query: Vec3, visit: impl FnMut(usize)) {
        let cells = grid.cells(query);
        grid.prefetch_bucket_starts(&cells);
        grid.prefetch_entries(&cells);
        grid.query_cells(&cells, query, visit);
    }

    #[test]
    fn empty_and_far_queries_find_nothing() {
        let grid = HashGrid::build(&[], 0.1);
        grid.query(Vec3::ZERO, |_| panic!("no points"));
        query_ahead(&grid, Vec3::ZERO, |_| panic!("no points"));
        let points = [Vec3::ZERO];
        let grid = HashGrid::build(&points, 0.1);
        grid.query(Vec3::splat(5.0), |_| panic!("too far"));
        query_ahead(&grid, Vec3::splat(5.0), |_| panic!("too far"));
        assert_eq!(grid.cells(Vec3::splat(5.0)).buckets().count(), 0);
        let mut hits = 0;
        query_ahead(&grid, Vec3::splat(0.05), |_| hits += 1);
        assert_eq!(hits, 1);
    }
}
