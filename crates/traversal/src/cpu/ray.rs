//! Per-ray constants shared by the node and triangle tests.

use glam::{Vec3, Vec3A};

/// Direction components smaller than this in magnitude are replaced by it (keeping their
/// sign) before taking reciprocals, so slab distances stay finite and never NaN.
const MIN_DIR_COMPONENT: f32 = 1e-18;

/// A ray with everything the traversal derives from it precomputed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PreparedRay {
    /// Ray origin.
    pub origin: Vec3A,
    /// Safe reciprocal of the direction: finite and never zero.
    pub inv_dir: Vec3A,
    /// Per axis, the [`WideNode::planes`](super::wide_node::WideNode::planes) index of the
    /// plane the ray enters a slab through: `2·axis` (the minimum) for a positive direction,
    /// `2·axis + 1` (the maximum) for a negative one. The exit plane is the other, `^ 1`.
    pub near_planes: [usize; 3],
    /// Inclusive lower bound of the ray parameter.
    pub tmin: f32,
    /// Exclusive upper bound of the ray parameter.
    pub tmax: f32,
    /// Axes permuted so that `axes[2]` is the dominant direction axis, with the first two
    /// swapped for negative dominant directions to preserve winding (Woop et al. 2013).
    pub axes: [usize; 3],
    /// `origin` permuted by `axes`.
    pub origin_permuted: [f32; 3],
    /// Shear constants `(Sx, Sy, Sz)` mapping the ray onto the +z axis of the permuted frame.
    pub shear: [f32; 3],
}

impl PreparedRay {
    /// Prepares a ray, or returns `None` for rays that cannot hit anything: a non-finite
    /// origin or direction, a zero direction, a NaN bound or an empty interval.
    #[inline(always)]
    pub fn new(origin: Vec3, direction: Vec3, tmin: f32, tmax: f32) -> Option<Self> {
        // NaN bounds fail `tmin < tmax`.
        let valid =
            origin.is_finite() && direction.is_finite() && direction != Vec3::ZERO && tmin < tmax;
        if !valid {
            return None;
        }
        // Arrays, not `Vec3`: indexing a `Vec3` at a run-time axis is a chain of branches on
        // the axis, which incoherent rays mispredict; an array index is a plain load.
        let (o, d) = (origin.to_array(), direction.to_array());
        let abs = direction.abs();
        let kz = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let safe_dir = Vec3A::from(direction.signum() * abs.max(Vec3::splat(MIN_DIR_COMPONENT)));
        let inv_dir = safe_dir.recip();
        let near_planes = [
            usize::from(inv_dir.x < 0.0),
            2 + usize::from(inv_dir.y < 0.0),
            4 + usize::from(inv_dir.z < 0.0),
        ];
        let sz = 1.0 / d[kz];
        Some(Self {
            origin: origin.into(),
            inv_dir,
            near_planes,
            tmin,
            tmax,
            axes: [kx, ky, kz],
            origin_permuted: [o[kx], o[ky], o[kz]],
            shear: [d[kx] * sz, d[ky] * sz, sz],
        })
    }
}
