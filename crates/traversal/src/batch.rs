//! Structure-of-arrays ray and hit batches, reused across calls to avoid allocation.

use glam::Vec3;

/// Primitive id stored in [`HitBatch::prim`] for rays that hit nothing.
pub const NO_HIT: u32 = u32::MAX;

/// Rays [`RayBatch::refill`] makes room for at a time when it cannot tell how many come.
const REFILL_BLOCK: usize = 256;

/// A batch of rays stored as a structure of arrays.
///
/// Ray `i` is `origin(i) + t · direction(i)` for `t` in the half-open interval
/// `[tmin[i], tmax[i])`. Directions need not be normalised; hit distances are measured in
/// units of the direction's length. Rays with a non-finite origin or direction, a zero
/// direction, or a NaN bound miss everything. The arrays are public so they can be filled
/// or uploaded directly, but must keep equal lengths: traversal panics otherwise.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayBatch {
    /// Origin x coordinates.
    pub origin_x: Vec<f32>,
    /// Origin y coordinates.
    pub origin_y: Vec<f32>,
    /// Origin z coordinates.
    pub origin_z: Vec<f32>,
    /// Direction x components.
    pub dir_x: Vec<f32>,
    /// Direction y components.
    pub dir_y: Vec<f32>,
    /// Direction z components.
    pub dir_z: Vec<f32>,
    /// Inclusive lower bounds of the ray parameter.
    pub tmin: Vec<f32>,
    /// Exclusive upper bounds of the ray parameter (may be `f32::INFINITY`).
    pub tmax: Vec<f32>,
}

impl RayBatch {
    /// Bytes each ray takes in a batch: its eight `f32` fields.
    pub const BYTES_PER_RAY: usize = 8 * size_of::<f32>();

    /// Bytes allocated for the batch's arrays (their capacity, not just their length).
    pub fn memory_bytes(&self) -> usize {
        self.arrays().map(Vec::capacity).iter().sum::<usize>() * size_of::<f32>()
    }

    /// Creates an empty batch with room for `capacity` rays in every array.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            origin_x: Vec::with_capacity(capacity),
            origin_y: Vec::with_capacity(capacity),
            origin_z: Vec::with_capacity(capacity),
            dir_x: Vec::with_capacity(capacity),
            dir_y: Vec::with_capacity(capacity),
            dir_z: Vec::with_capacity(capacity),
            tmin: Vec::with_capacity(capacity),
            tmax: Vec::with_capacity(capacity),
        }
    }

    /// Appends the ray `origin + t · direction`, `t ∈ [tmin, tmax)`.
    #[inline]
    pub fn push(&mut self, origin: Vec3, direction: Vec3, tmin: f32, tmax: f32) {
        self.origin_x.push(origin.x);
        self.origin_y.push(origin.y);
        self.origin_z.push(origin.z);
        self.dir_x.push(direction.x);
        self.dir_y.push(direction.y);
        self.dir_z.push(direction.z);
        self.tmin.push(tmin);
        self.tmax.push(tmax);
    }

    /// Replaces the batch's rays by `rays`, each `(origin, direction, tmin, tmax)` as for
    /// [`push`](Self::push). Faster than clearing and pushing one by one: the arrays grow
    /// together, a block at a time, and each ray is stored without a capacity or bounds
    /// check per array.
    pub fn refill(&mut self, rays: impl IntoIterator<Item = (Vec3, Vec3, f32, f32)>) {
        let mut rays = rays.into_iter();
        let mut len = rays.size_hint().1.unwrap_or(REFILL_BLOCK);
        let mut n = 0;
        loop {
            self.resize(len);
            n += self.write_from(n, &mut rays);
            // Stop once a block is left unfilled or nothing can follow.
            if n < len || rays.size_hint().1 == Some(0) {
                break;
            }
            len = (2 * len).max(REFILL_BLOCK);
        }
        self.resize(n);
    }

    /// Writes rays taken from `rays` from index `from` on, up to the arrays' length, and
    /// returns how many it wrote. Every array is sliced to the same length first, so that the
    /// stores need no bounds checks.
    fn write_from(
        &mut self,
        from: usize,
        rays: &mut impl Iterator<Item = (Vec3, Vec3, f32, f32)>,
    ) -> usize {
        let room = self.len() - from;
        let [ox, oy, oz, dx, dy, dz, t0, t1] = self.arrays_mut().map(|a| &mut a[from..from + room]);
        for i in 0..room {
            let Some((origin, direction, tmin, tmax)) = rays.next() else {
                return i;
            };
            (ox[i], oy[i], oz[i]) = (origin.x, origin.y, origin.z);
            (dx[i], dy[i], dz[i]) = (direction.x, direction.y, direction.z);
            (t0[i], t1[i]) = (tmin, tmax);
        }
        room
    }

    /// Sets every array's length to `len` (new entries are zero).
    fn resize(&mut self, len: usize) {
        for array in self.arrays_mut() {
            array.resize(len, 0.0);
        }
    }

    /// Number of rays in the batch.
    #[inline]
    pub fn len(&self) -> usize {
        self.tmin.len()
    }

    /// Whether the batch holds no rays.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.tmin.is_empty()
    }

    /// Removes all rays, keeping the allocations.
    #[inline]
    pub fn clear(&mut self) {
        for array in self.arrays_mut() {
            array.clear();
        }
    }

    /// Origin of ray `i`. Panics if `i >= len()`.
    #[inline]
    pub fn origin(&self, i: usize) -> Vec3 {
        Vec3::new(self.origin_x[i], self.origin_y[i], self.origin_z[i])
    }

    /// Direction of ray `i`. Panics if `i >= len()`.
    #[inline]
    pub fn direction(&self, i: usize) -> Vec3 {
        Vec3::new(self.dir_x[i], self.dir_y[i], self.dir_z[i])
    }

    /// Panics unless all eight arrays have the same length (backends call it first).
    pub fn assert_consistent(&self) {
        let len = self.len();
        let lengths = self.arrays().map(Vec::len);
        assert!(
            lengths.iter().all(|&l| l == len),
            "RayBatch arrays differ in length: {lengths:?} vs {len} tmin values"
        );
    }

    fn arrays(&self) -> [&Vec<f32>; 8] {
        [
            &self.origin_x,
            &self.origin_y,
            &self.origin_z,
            &self.dir_x,
            &self.dir_y,
            &self.dir_z,
            &self.tmin,
            &self.tmax,
        ]
    }

    fn arrays_mut(&mut self) -> [&mut Vec<f32>; 8] {
        [
            &mut self.origin_x,
            &mut self.origin_y,
            &mut self.origin_z,
            &mut self.dir_x,
            &mut self.dir_y,
            &mut self.dir_z,
            &mut self.tmin,
            &mut self.tmax,
        ]
    }
}

/// Closest-hit results, one entry per ray, stored as a structure of arrays.
///
/// For a hit on triangle `prim` with vertices `p0, p1, p2`, the hit point is
/// `(1 − u − v)·p0 + u·p1 + v·p2` and `origin + t · direction`. For a miss, `prim` is
/// [`NO_HIT`], `t` is `f32::INFINITY` and `u = v = 0`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HitBatch {
    /// Ray parameter of the hit.
    pub t: Vec<f32>,
    /// The caller's triangle index, or [`NO_HIT`].
    pub prim: Vec<u32>,
    /// Barycentric weight of the triangle's second vertex.
    pub u: Vec<f32>,
    /// Barycentric weight of the triangle's third vertex.
    pub v: Vec<f32>,
}

impl HitBatch {
    /// Bytes each hit takes in a batch: `t`, `u` and `v` and the primitive.
    pub const BYTES_PER_HIT: usize = 3 * size_of::<f32>() + size_of::<u32>();

    /// Bytes allocated for the batch's arrays (their capacity, not just their length).
    pub fn memory_bytes(&self) -> usize {
        (self.t.capacity() + self.u.capacity() + self.v.capacity()) * size_of::<f32>()
            + self.prim.capacity() * size_of::<u32>()
    }

    /// Creates an empty batch with room for `capacity` hits in every array.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            t: Vec::with_capacity(capacity),
            prim: Vec::with_capacity(capacity),
            u: Vec::with_capacity(capacity),
            v: Vec::with_capacity(capacity),
        }
    }

    /// Resizes every array to `len` entries. Existing entries are kept, new ones are misses;
    /// traversal overwrites all entries anyway.
    pub fn resize(&mut self, len: usize) {
        self.t.resize(len, f32::INFINITY);
        self.prim.resize(len, NO_HIT);
        self.u.resize(len, 0.0);
        self.v.resize(len, 0.0);
    }

    /// Number of entries.
    #[inline]
    pub fn len(&self) -> usize {
        self.prim.len()
    }

    /// Whether the batch holds no entries.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.prim.is_empty()
    }

    /// Whether ray `i` hit something. Panics if `i >= len()`.
    #[inline]
    pub fn is_hit(&self, i: usize) -> bool {
        self.prim[i] != NO_HIT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `count` distinct rays.
    fn rays(count: usize) -> impl Iterator<Item = (Vec3, Vec3, f32, f32)> {
        (0..count).map(|i| {
            let x = i as f32;
            (Vec3::new(x, -x, 0.5), Vec3::new(1.0, x, 2.0), x, x + 1.0)
        })
    }

    fn pushed(count: usize) -> RayBatch {
        let mut batch = RayBatch::default();
        for (origin, direction, tmin, tmax) in rays(count) {
            batch.push(origin, direction, tmin, tmax);
        }
        batch
    }

    /// Refilling gives the batch pushing would, whether the iterator's length is exact, only
    /// bounded above (a filter), or unknown and longer than a growth block; earlier rays and
    /// a longer previous batch leave nothing behind.
    #[test]
    fn refill_equals_pushing_the_same_rays() {
        let mut batch = pushed(3 * REFILL_BLOCK);
        for count in [0, 1, 5, REFILL_BLOCK, 3 * REFILL_BLOCK + 7] {
            batch.refill(rays(count));
            assert_eq!(batch, pushed(count), "exact length {count}");

            batch.refill(rays(2 * count).filter(|r| r.2 < count as f32));
            assert_eq!(batch, pushed(count), "upper bound {count}");

            let mut unknown = rays(count);
            batch.refill(std::iter::from_fn(|| unknown.next()));
            assert_eq!(batch, pushed(count), "unknown length {count}");
        }
    }
}
