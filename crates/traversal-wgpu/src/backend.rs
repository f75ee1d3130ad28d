//! [`GpuBvh`]: the `Traversal` trait on the GPU kernels.

use std::fmt;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;
use vcm_traversal::build::build_bvh2;
use vcm_traversal::{
    BuildPreset, HitBatch, NO_HIT, PendingTraversal, RayBatch, Traversal, TraversalJob,
};
use wgpu::util::DeviceExt;

use crate::alpha::AlphaMasks;
use crate::device::GpuDevice;
use crate::error::GpuError;
use crate::layout::{NodeLayout, SceneLayout};
use crate::shader::{ANY_HIT_ENTRY, CLOSEST_HIT_ENTRY, traversal_module};
use crate::slot::{HIT_BYTES, Params, Query, RAY_BYTES, Slot, dispatch_shape};

/// How to build a [`GpuBvh`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuBvhOptions {
    /// Hierarchy build quality (the same presets as the CPU backend).
    pub preset: BuildPreset,
    /// The node format the kernels traverse.
    pub layout: NodeLayout,
}

/// GPU ray traversal: a BVH built on the CPU, laid out in one of the [`NodeLayout`]s,
/// uploaded once and traversed by WGSL compute kernels, one invocation per ray.
///
/// Ray and output buffers live in slots that grow to the largest batch submitted and are
/// reused; batches in flight at the same time (from [`Traversal::submit`] or from several
/// threads) each hold their own slot, so the CPU can shade one batch while the GPU traverses
/// another.
pub struct GpuBvh {
    inner: Arc<Inner>,
    build_time: Duration,
    scene_bytes: usize,
    stack_size: u32,
}

struct Inner {
    gpu: Arc<GpuDevice>,
    pipelines: [wgpu::ComputePipeline; 2],
    /// Bind groups 1 (nodes, vertices, ids) and, with alpha masks, 2 (the masks), each per
    /// pipeline; `None` for a scene without triangles, where every ray misses without a
    /// dispatch.
    scene_groups: Option<Vec<[wgpu::BindGroup; 2]>>,
    slots: Mutex<Vec<Slot>>,
    max_rays_per_slot: u64,
}

impl GpuBvh {
    /// Opens the preferred adapter ([`GpuDevice::open`]) and builds the backend on it.
    pub fn open(triangles: &[[Vec3; 3]], options: GpuBvhOptions) -> Result<Self, GpuError> {
        Self::new(Arc::new(GpuDevice::open()?), triangles, options)
    }

    /// Builds the hierarchy over `triangles` (triangle `i` is reported as primitive `i`),
    /// uploads it to `gpu` (which several backends may share) and compiles the kernels.
    pub fn new(
        gpu: Arc<GpuDevice>,
        triangles: &[[Vec3; 3]],
        options: GpuBvhOptions,
    ) -> Result<Self, GpuError> {
        Self::with_alpha_masks(gpu, triangles, options, &AlphaMasks::default())
    }

    /// Like [`new`](Self::new), with masked triangles transparent where their mask says so,
    /// for both queries. Without any masked triangle the kernels are built without mask code.
    pub fn with_alpha_masks(
        gpu: Arc<GpuDevice>,
        triangles: &[[Vec3; 3]],
        options: GpuBvhOptions,
        masks: &AlphaMasks,
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        let bvh = build_bvh2(triangles, options.preset)?;
        let leaf_size = options.preset.params().max_prims_per_leaf;
        let layout = SceneLayout::new(&bvh, triangles, options.layout, leaf_size);
        let masked = masks.any();
        let device = &gpu.device;
        let source = traversal_module(layout.layout, layout.stack_size, masked);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("traversal"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = |entry| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            })
        };
        let pipelines = [pipeline(CLOSEST_HIT_ENTRY), pipeline(ANY_HIT_ENTRY)];
        let mut scene_bytes = layout.memory_bytes();
        let scene_groups = if layout.nodes.is_empty() {
            None
        } else {
            let mut buffers = vec![
                upload(&gpu, "nodes", bytemuck::cast_slice(&layout.nodes))?,
                upload(&gpu, "triangles", bytemuck::cast_slice(&layout.vertices))?,
                upload(&gpu, "triangle ids", bytemuck::cast_slice(&layout.ids))?,
            ];
            let mut groups = vec![bind_buffers(&gpu, &pipelines, 1, &buffers)];
            if masked {
                let packed = masks.pack(&layout.ids);
                buffers = vec![
                    upload(&gpu, "leaf masks", bytemuck::cast_slice(&packed.leaf_masks))?,
                    upload(&gpu, "masks", bytemuck::cast_slice(&packed.masks))?,
                    upload(
                        &gpu,
                        "mask textures",
                        bytemuck::cast_slice(&packed.textures),
                    )?,
                    upload(&gpu, "mask texels", bytemuck::cast_slice(&packed.texels))?,
                ];
                scene_bytes += buffers.iter().map(|b| b.size() as usize).sum::<usize>();
                groups.push(bind_buffers(&gpu, &pipelines, 2, &buffers));
            }
            Some(groups)
        };
        let max_rays_per_slot = gpu.max_binding_bytes() / RAY_BYTES.max(HIT_BYTES);
        Ok(Self {
            build_time: start.elapsed(),
            scene_bytes,
            stack_size: layout.stack_size,
            inner: Arc::new(Inner {
                gpu,
                pipelines,
                scene_groups,
                slots: Mutex::new(Vec::new()),
                max_rays_per_slot,
            }),
        })
    }

    /// The adapter the kernels run on.
    pub fn device(&self) -> &Arc<GpuDevice> {
        &self.inner.gpu
    }

    /// Wall-clock time of [`new`](Self::new): hierarchy build, layout, upload and pipelines.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Bytes of scene data on the GPU (nodes, triangles, ids) plus the idle batch buffers.
    pub fn memory_bytes(&self) -> usize {
        let slots = self.inner.slots.lock().expect("slot pool poisoned");
        self.scene_bytes
            + slots
                .iter()
                .map(|s| s.memory_bytes() as usize)
                .sum::<usize>()
    }

    /// Entries of each invocation's traversal stack (the hierarchy's depth).
    pub fn stack_size(&self) -> u32 {
        self.stack_size
    }
}

/// Uploads `bytes` as a read-only storage buffer (at least 4 bytes: empty bindings are
/// invalid), checking the device's binding limit.
fn upload(gpu: &GpuDevice, label: &'static str, bytes: &[u8]) -> Result<wgpu::Buffer, GpuError> {
    let limit = gpu.max_binding_bytes();
    if bytes.len() as u64 > limit {
        return Err(GpuError::SceneTooLarge {
            buffer: label,
            bytes: bytes.len() as u64,
            limit,
            adapter: gpu.info.name.clone(),
        });
    }
    let contents = if bytes.is_empty() { &[0; 4][..] } else { bytes };
    Ok(gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        }))
}

/// Binds `buffers` to bindings 0, 1, … of bind group `group`, for each pipeline.
fn bind_buffers(
    gpu: &GpuDevice,
    pipelines: &[wgpu::ComputePipeline; 2],
    group: u32,
    buffers: &[wgpu::Buffer],
) -> [wgpu::BindGroup; 2] {
    pipelines.each_ref().map(|pipeline| {
        let entries: Vec<_> = (0u32..)
            .zip(buffers)
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &pipeline.get_bind_group_layout(group),
            entries: &entries,
        })
    })
}

/// One dispatch in flight: its slot, the range of rays it covers and the mapping signal.
struct Part {
    slot: Slot,
    first: usize,
    count: usize,
    mapped: mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
}

/// A batch in flight: one part per slot-sized piece of the batch.
struct Launch {
    inner: Arc<Inner>,
    query: Query,
    rays: usize,
    parts: Vec<Part>,
    submission: Option<wgpu::SubmissionIndex>,
}

impl Inner {
    /// Uploads `rays`, records the kernels and submits them; returns without waiting.
    fn launch(self: &Arc<Self>, rays: &RayBatch, query: Query) -> Launch {
        let mut launch = Launch {
            inner: Arc::clone(self),
            query,
            rays: rays.len(),
            parts: Vec::new(),
            submission: None,
        };
        let Some(scene_groups) = &self.scene_groups else {
            return launch;
        };
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        let step = self.max_rays_per_slot.max(1) as usize;
        let mut recorded = Vec::new();
        for first in (0..rays.len()).step_by(step) {
            let count = step.min(rays.len() - first);
            let slot = self.take_slot(count as u64);
            let packed = pack_rays(rays, first..first + count);
            self.gpu
                .queue
                .write_buffer(&slot.rays, 0, bytemuck::cast_slice(&packed));
            let max_dim = device.limits().max_compute_workgroups_per_dimension;
            let (x, y, row_threads) = dispatch_shape(count as u64, max_dim);
            let params = Params {
                ray_count: count as u32,
                row_threads,
            };
            self.gpu
                .queue
                .write_buffer(&slot.params, 0, bytemuck::bytes_of(&params));
            let which = query as usize;
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipelines[which]);
                pass.set_bind_group(0, &slot.groups[which], &[]);
                for (group, groups) in (1..).zip(scene_groups) {
                    pass.set_bind_group(group, &groups[which], &[]);
                }
                pass.dispatch_workgroups(x, y, 1);
            }
            let bytes = count as u64 * query.output_bytes();
            encoder.copy_buffer_to_buffer(&slot.output, 0, &slot.readback, 0, bytes);
            recorded.push((slot, first, count));
        }
        launch.submission = Some(self.gpu.queue.submit([encoder.finish()]));
        launch.parts = recorded
            .into_iter()
            .map(|(slot, first, count)| {
                let (sender, mapped) = mpsc::channel();
                let bytes = count as u64 * query.output_bytes();
                slot.readback
                    .slice(..bytes)
                    .map_async(wgpu::MapMode::Read, move |result| {
                        // The receiver only goes away if the launch was dropped uncollected.
                        let _ = sender.send(result);
                    });
                Part {
                    slot,
                    first,
                    count,
                    mapped,
                }
            })
            .collect();
        launch
    }

    /// A slot with room for `rays`, from the pool if one is big enough.
    fn take_slot(&self, rays: u64) -> Slot {
        let mut pool = self.slots.lock().expect("slot pool poisoned");
        if let Some(i) = pool.iter().position(|slot| slot.capacity >= rays) {
            return pool.swap_remove(i);
        }
        // Replace the largest idle slot rather than keeping a too-small one around.
        if let Some(i) = (0..pool.len()).max_by_key(|&i| pool[i].capacity) {
            pool.swap_remove(i);
        }
        drop(pool);
        let layouts = self
            .pipelines
            .each_ref()
            .map(|p| p.get_bind_group_layout(0));
        Slot::new(&self.gpu.device, [&layouts[0], &layouts[1]], rays)
    }
}

impl Launch {
    /// Waits for the GPU and hands each part's output bytes to `read` with its first ray.
    fn collect(mut self, mut read: impl FnMut(usize, &[u8])) {
        let Some(submission) = self.submission.take() else {
            return;
        };
        let poll = wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        };
        self.inner
            .gpu
            .device
            .poll(poll)
            .expect("GPU device lost while traversing");
        for part in std::mem::take(&mut self.parts) {
            part.mapped
                .recv()
                .expect("wgpu dropped a buffer mapping callback")
                .expect("mapping the traversal results failed");
            let bytes = part.count as u64 * self.query.output_bytes();
            {
                let view = part
                    .slot
                    .readback
                    .slice(..bytes)
                    .get_mapped_range()
                    .expect("the readback buffer was just mapped");
                read(part.first, &view);
            }
            part.slot.readback.unmap();
            self.inner
                .slots
                .lock()
                .expect("slot pool poisoned")
                .push(part.slot);
        }
    }

    /// Waits and writes one hit per ray into `hits`.
    fn into_hits(self, hits: &mut HitBatch) {
        hits.resize(self.rays);
        hits.t.fill(f32::INFINITY);
        hits.prim.fill(NO_HIT);
        hits.u.fill(0.0);
        hits.v.fill(0.0);
        self.collect(|first, bytes| {
            let records: &[[u32; 4]] = bytemuck::cast_slice(bytes);
            for (i, &[t, prim, u, v]) in records.iter().enumerate() {
                if prim != NO_HIT {
                    let i = first + i;
                    hits.t[i] = f32::from_bits(t);
                    hits.prim[i] = prim;
                    hits.u[i] = f32::from_bits(u);
                    hits.v[i] = f32::from_bits(v);
                }
            }
        });
    }

    /// Waits and writes one flag per ray into `occluded`.
    fn into_occluded(self, occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.resize(self.rays, false);
        self.collect(|first, bytes| {
            let flags: &[u32] = bytemuck::cast_slice(bytes);
            for (out, &flag) in occluded[first..].iter_mut().zip(flags) {
                *out = flag != 0;
            }
        });
    }
}

/// Packs `rays[range]` as `ray.wgsl`'s `Ray`. Rays that cannot hit anything (non-finite or
/// zero direction, non-finite origin, NaN or empty interval) get an empty interval so the
/// kernel skips them; an infinite `tmax` becomes the largest finite value, which the
/// kernel's sentinels rely on.
fn pack_rays(rays: &RayBatch, range: std::ops::Range<usize>) -> Vec<[f32; 8]> {
    const SKIPPED: [f32; 8] = [0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let mut packed = vec![SKIPPED; range.len()];
    rays.assert_consistent();
    packed
        .par_chunks_mut(4096)
        .enumerate()
        .for_each(|(chunk, out)| {
            let start = range.start + chunk * 4096;
            for (k, ray) in out.iter_mut().enumerate() {
                let i = start + k;
                let (origin, direction) = (rays.origin(i), rays.direction(i));
                let (tmin, tmax) = (rays.tmin[i], rays.tmax[i]);
                let valid = origin.is_finite()
                    && direction.is_finite()
                    && direction != Vec3::ZERO
                    && tmin < tmax;
                if valid {
                    let tmax = tmax.min(f32::MAX);
                    *ray = [
                        origin.x,
                        origin.y,
                        origin.z,
                        tmin,
                        direction.x,
                        direction.y,
                        direction.z,
                        tmax,
                    ];
                }
            }
        });
    packed
}

impl Traversal for GpuBvh {
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        self.inner.launch(rays, Query::Closest).into_hits(hits);
    }

    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        self.inner.launch(rays, Query::Any).into_occluded(occluded);
    }

    fn submit(&self, job: TraversalJob) -> Box<dyn PendingTraversal + '_> {
        let query = match job {
            TraversalJob::Intersect { .. } => Query::Closest,
            TraversalJob::Occluded { .. } => Query::Any,
        };
        let launch = self.inner.launch(job.rays(), query);
        Box::new(PendingGpu { launch, job })
    }
}

/// A batch submitted with [`Traversal::submit`], collected by [`PendingTraversal::wait`].
struct PendingGpu {
    launch: Launch,
    job: TraversalJob,
}

impl PendingTraversal for PendingGpu {
    fn wait(self: Box<Self>) -> TraversalJob {
        let Self { launch, mut job } = *self;
        match &mut job {
            TraversalJob::Intersect { hits, .. } => launch.into_hits(hits),
            TraversalJob::Occluded { occluded, .. } => launch.into_occluded(occluded),
        }
        job
    }
}

impl fmt::Debug for GpuBvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuBvh")
            .field("adapter", &self.inner.gpu.info.name)
            .field("scene_bytes", &self.scene_bytes)
            .field("stack_size", &self.stack_size)
            .field("build_time", &self.build_time)
            .finish()
    }
}
