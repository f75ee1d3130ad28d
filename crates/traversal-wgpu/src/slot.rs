//! The per-batch GPU buffers: rays in, hits or flags out, and a mappable copy to read back.
//! A slot grows to the largest batch it has carried and is reused; every batch in flight
//! holds its own slot.

use crate::shader::WORKGROUP_SIZE;

/// Bytes of one packed ray: origin, tmin, direction, tmax.
pub(crate) const RAY_BYTES: u64 = 32;
/// Bytes of one hit record: t, primitive, u, v.
pub(crate) const HIT_BYTES: u64 = 16;

/// Which kernel a batch runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Query {
    /// Closest hit: a hit record per ray (pipeline and bind group index 0).
    Closest = 0,
    /// Any hit: a flag (`u32`) per ray (index 1).
    Any = 1,
}

impl Query {
    /// Output bytes per ray.
    pub fn output_bytes(self) -> u64 {
        match self {
            Self::Closest => HIT_BYTES,
            Self::Any => 4,
        }
    }
}

/// Kernel parameters, the `Params` struct of `ray.wgsl`.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct Params {
    pub ray_count: u32,
    pub row_threads: u32,
}

/// Buffers and bind groups for batches of up to `capacity` rays.
#[derive(Debug)]
pub(crate) struct Slot {
    pub capacity: u64,
    pub rays: wgpu::Buffer,
    pub output: wgpu::Buffer,
    pub readback: wgpu::Buffer,
    pub params: wgpu::Buffer,
    /// Bind group 0 of the closest-hit and the any-hit pipeline.
    pub groups: [wgpu::BindGroup; 2],
}

impl Slot {
    /// Allocates buffers for `capacity` rays; `layouts` are group 0 of the closest-hit and
    /// the any-hit pipeline.
    pub fn new(device: &wgpu::Device, layouts: [&wgpu::BindGroupLayout; 2], capacity: u64) -> Self {
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let capacity = capacity.max(1);
        let rays = buffer("rays", capacity * RAY_BYTES, U::STORAGE | U::COPY_DST);
        let output = buffer("hits", capacity * HIT_BYTES, U::STORAGE | U::COPY_SRC);
        let readback = buffer("readback", capacity * HIT_BYTES, U::MAP_READ | U::COPY_DST);
        let params = buffer(
            "params",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let group = |layout, output_binding| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("batch"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: rays.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: output_binding,
                        resource: output.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: params.as_entire_binding(),
                    },
                ],
            })
        };
        let groups = [group(layouts[0], 1), group(layouts[1], 3)];
        Self {
            capacity,
            rays,
            output,
            readback,
            params,
            groups,
        }
    }

    /// Bytes of GPU memory the slot holds.
    pub fn memory_bytes(&self) -> u64 {
        self.capacity * (RAY_BYTES + 2 * HIT_BYTES)
    }
}

/// Workgroups in x and y for `rays` invocations of [`WORKGROUP_SIZE`] per workgroup, with no
/// dimension above `max_per_dimension`, and the invocations per row.
pub fn dispatch_shape(rays: u64, max_per_dimension: u32) -> (u32, u32, u32) {
    let groups = rays.div_ceil(u64::from(WORKGROUP_SIZE)).max(1);
    let x = groups.min(u64::from(max_per_dimension)) as u32;
    let y = groups.div_ceil(u64::from(x)) as u32;
    (x, y, x * WORKGROUP_SIZE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dispatch_covers_every_ray_within_the_limits() {
        for (rays, max) in [
            (1, 65535),
            (64, 65535),
            (65, 65535),
            (10_000_000, 65535),
            (1000, 3),
        ] {
            let (x, y, row) = dispatch_shape(rays, max);
            assert!(x <= max && x >= 1 && y >= 1);
            assert_eq!(row, x * WORKGROUP_SIZE);
            assert!(u64::from(row) * u64::from(y) >= rays, "{rays} {max}");
            // No row is entirely idle.
            assert!(u64::from(row) * u64::from(y - 1) < rays);
        }
    }
}
