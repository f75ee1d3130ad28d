//! [`GridBuilder`]: the iterations' hash grids built on the device (`grid.wgsl`), the CPU's
//! `HashGrid::build` over each iteration's light vertices, without the cache leaving the
//! device.

use bytemuck::{Pod, Zeroable};
use vcm_traversal_wgpu::{GpuDevice, dispatch_shape};

use crate::compute::{Kernels, record};
use crate::shader::{CACHE_WGSL, GRID_WGSL};

/// `GridParams` of `grid.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct GridParams {
    vertices: u32,
    iterations: u32,
    starts: u32,
    shortest: u32,
}

/// The kernels in the order they run (`grid.wgsl`), and whether each runs per vertex, per
/// iteration (a workgroup each for the scan) or per bucket start.
const KERNELS: [(&str, Over); 6] = [
    ("grid_bounds", Over::Vertices),
    ("grid_layout", Over::Iterations),
    ("grid_count", Over::Vertices),
    ("grid_scan", Over::Workgroups),
    ("grid_scatter", Over::Vertices),
    ("grid_sort", Over::Starts),
];

/// `BOUNDS_SLOTS` of `grid.wgsl`: an iteration's bounds (6) and its vertices that merge.
const BOUNDS_SLOTS: usize = 7;

/// What a kernel's invocations run over.
#[derive(Clone, Copy)]
enum Over {
    Vertices,
    Iterations,
    Workgroups,
    Starts,
}

/// Workgroups (x, y) for `count` invocations in rows of at most `max_groups` workgroups of
/// `GRID_WORKGROUP` (`grid.wgsl`, the traversal kernels' workgroup size: tested below).
fn spread(count: u32, max_groups: u32) -> (u32, u32) {
    let (x, y, _) = dispatch_shape(u64::from(count), max_groups);
    (x, y)
}

/// The grid-building kernels and their scratch buffers.
pub(crate) struct GridBuilder {
    kernels: Kernels,
    params: wgpu::Buffer,
    /// Each vertex's bucket, each bucket's cursor, each iteration's bounds.
    scratch: [wgpu::Buffer; 3],
}

/// The frame's buffers the grids are built from and into: the cache, the iterations (their
/// grid layouts written), the bucket starts and the entries.
pub(crate) struct GridBuffers<'a> {
    pub cache: &'a wgpu::Buffer,
    pub iterations: &'a wgpu::Buffer,
    pub starts: &'a wgpu::Buffer,
    pub entries: &'a wgpu::Buffer,
}

impl GridBuilder {
    /// The kernels compiled on `gpu`.
    pub fn new(gpu: &GpuDevice) -> GridBuilder {
        let entries: Vec<&str> = KERNELS.iter().map(|(entry, _)| *entry).collect();
        let source = format!("{CACHE_WGSL}\n{GRID_WGSL}");
        let kernels = Kernels::new(gpu, "grid build", source, &entries);
        let buffer = |label, size, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let params = buffer(
            "grid parameters",
            size_of::<GridParams>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let scratch = ["bucket of", "cursors", "bounds"]
            .map(|label| buffer(label, 16, U::STORAGE | U::COPY_DST | U::COPY_SRC));
        GridBuilder {
            kernels,
            params,
            scratch,
        }
    }

    /// Builds the grids of `iterations` iterations over those of the frame's `vertices` light
    /// vertices that lie `shortest` or more segments from their light (the ones that merge)
    /// into `buffers`, whose bucket starts number `starts` in all (room for as many buckets
    /// as each iteration's cache has vertices); writes each grid's bucket count and entry
    /// count into the iterations; waits for the device.
    pub fn build(
        &mut self,
        gpu: &GpuDevice,
        buffers: &GridBuffers,
        (vertices, iterations, starts): (u32, u32, u32),
        shortest: u32,
    ) -> Result<(), String> {
        let device = &gpu.device;
        let sizes = [
            4 * u64::from(vertices),
            4 * u64::from(starts),
            4 * BOUNDS_SLOTS as u64 * u64::from(iterations),
        ];
        for (buffer, bytes) in self.scratch.iter_mut().zip(sizes) {
            if bytes > buffer.size() {
                use wgpu::BufferUsages as U;
                *buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("grid scratch"),
                    size: bytes.next_multiple_of(16),
                    usage: U::STORAGE | U::COPY_DST | U::COPY_SRC,
                    mapped_at_creation: false,
                });
            }
        }
        let params = GridParams {
            vertices,
            iterations,
            starts,
            shortest,
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        // The bounds start empty: the largest order for the minima, the smallest for the
        // maxima; and no vertex counted.
        let empty: Vec<u32> = (0..iterations)
            .flat_map(|_| [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0, 0])
            .collect();
        gpu.queue
            .write_buffer(&self.scratch[2], 0, bytemuck::cast_slice(&empty));
        let [bucket_of, cursors, bounds] = &self.scratch;
        let bound = [
            buffers.cache,
            buffers.iterations,
            buffers.starts,
            buffers.entries,
            bucket_of,
            cursors,
            bounds,
            &self.params,
        ];
        let group = self.kernels.group(gpu, &bound);
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(buffers.starts, 0, Some(4 * u64::from(starts)));
        let max_groups = device.limits().max_compute_workgroups_per_dimension;
        for ((entry, over), pipeline) in KERNELS.iter().zip(&self.kernels.pipelines) {
            if *entry == "grid_scatter" {
                // The cursors start where the buckets do.
                let bytes = 4 * u64::from(starts);
                encoder.copy_buffer_to_buffer(buffers.starts, 0, cursors, 0, bytes);
            }
            let workgroups = match over {
                Over::Workgroups => (iterations, 1),
                Over::Vertices => spread(vertices, max_groups),
                Over::Iterations => spread(iterations, max_groups),
                Over::Starts => spread(starts, max_groups),
            };
            record(&mut encoder, (pipeline, &group), workgroups);
        }
        gpu.wait(gpu.queue.submit([encoder.finish()]))
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use vcm::hash_grid::HashGrid;
    use vcm_scene::sampling::{Rng, Sampler};
    use vcm_traversal_wgpu::device_or_skip;
    use wgpu::util::DeviceExt;

    use super::*;
    use crate::frames::{GridEntry, IterationRecord, LightVertex};

    /// The fewest segments from its light of a vertex the test's grids hold.
    const SHORTEST: u32 = 2;

    /// The test's `i`-th vertex of an iteration lies this many segments from its light (1
    /// for the first, which alone its iteration of one vertex holds).
    fn path_length(i: usize) -> u32 {
        1 + (i as u32 * 7) % 3
    }

    #[test]
    fn the_grid_kernels_workgroups_are_the_ones_dispatch_shape_counts() {
        let size = vcm_traversal_wgpu::shader::WORKGROUP_SIZE;
        assert!(GRID_WGSL.contains(&format!("const GRID_WORKGROUP: u32 = {size}u;")));
    }

    /// The device builds the CPU's grids bit for bit: bounds, bucket starts and entries in
    /// the same order, for iterations of several sizes (one empty, one whose only vertex
    /// does not merge) in one frame's cache, over the vertices two or more segments from
    /// their light.
    #[test]
    fn device_grids_are_the_cpus() {
        let Some(gpu) = device_or_skip() else { return };
        let mut rng = Rng::new(3, 0);
        let sizes = [700usize, 0, 1, 33];
        let radii = [0.05f32, 0.1, 0.2, 0.03];
        let points: Vec<Vec<Vec3>> = sizes
            .iter()
            .map(|&n| {
                (0..n)
                    .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - 1.0)
                    .collect()
            })
            .collect();
        let mut cache = Vec::new();
        let mut iterations = Vec::new();
        let mut starts = 0u32;
        for (points, &radius) in points.iter().zip(&radii) {
            let buckets = (points.len() as u32).max(1).next_power_of_two();
            iterations.push(IterationRecord {
                cache_start: cache.len() as u32,
                cache_count: points.len() as u32,
                grid_starts: starts,
                grid_entries: cache.len() as u32,
                inv_cell_size: HashGrid::inv_cell_size(radius),
                radius,
                radius_sq: radius * radius,
                ..IterationRecord::zeroed()
            });
            starts += buckets + 1;
            cache.extend(points.iter().enumerate().map(|(i, p)| LightVertex {
                position: p.to_array(),
                path_length: path_length(i),
                ..LightVertex::zeroed()
            }));
        }
        let device = &gpu.device;
        use wgpu::BufferUsages as U;
        let init = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: U::STORAGE | U::COPY_SRC | U::COPY_DST,
            })
        };
        let cache_buffer = init("cache", bytemuck::cast_slice(&cache));
        let iterations_buffer = init("iterations", bytemuck::cast_slice(&iterations));
        let starts_buffer = init("starts", &vec![0u8; 4 * starts as usize]);
        let entries_buffer = init("entries", &vec![0u8; 16 * cache.len()]);
        let buffers = GridBuffers {
            cache: &cache_buffer,
            iterations: &iterations_buffer,
            starts: &starts_buffer,
            entries: &entries_buffer,
        };
        let counts = (cache.len() as u32, iterations.len() as u32, starts);
        GridBuilder::new(&gpu)
            .build(&gpu, &buffers, counts, SHORTEST)
            .unwrap();
        let read = |buffer: &wgpu::Buffer| -> Vec<u8> {
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: buffer.size(),
                usage: U::MAP_READ | U::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(buffer, 0, &readback, 0, buffer.size());
            gpu.read_back(encoder, (&readback, buffer.size()), |b| b.to_vec())
                .unwrap()
        };
        let device_starts: Vec<u32> = bytemuck::pod_collect_to_vec(&read(&starts_buffer));
        let device_entries: Vec<GridEntry> = bytemuck::pod_collect_to_vec(&read(&entries_buffer));
        let records: Vec<IterationRecord> = bytemuck::pod_collect_to_vec(&read(&iterations_buffer));
        for (s, (points, &radius)) in points.iter().zip(&radii).enumerate() {
            let (points, indices): (Vec<Vec3>, Vec<u32>) = (points.iter().zip(0u32..))
                .filter(|&(_, i)| path_length(i as usize) >= SHORTEST)
                .unzip();
            let grid = HashGrid::build_over(&points, &indices, radius);
            let layout = grid.layout();
            let it = &records[s];
            assert_eq!(it.entry_count as usize, points.len(), "{s}");
            let first = it.grid_starts as usize;
            let buckets = it.bucket_mask as usize + 1;
            assert_eq!(
                &device_starts[first..first + buckets + 1],
                layout.starts,
                "{s}"
            );
            let entries = &device_entries[it.grid_entries as usize..][..points.len()];
            let expected: Vec<(Vec3, u32)> = layout.entries.collect();
            let found: Vec<(Vec3, u32)> = entries
                .iter()
                .map(|e| (Vec3::from(e.position), e.index))
                .collect();
            assert_eq!(found, expected, "{s}");
            if !points.is_empty() {
                assert_eq!(
                    (Vec3::from(it.grid_min), Vec3::from(it.grid_max)),
                    (layout.min, layout.max)
                );
            }
        }
    }
}
