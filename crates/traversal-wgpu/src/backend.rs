//! [`GpuBvh`]: the `Traversal` trait on the GPU kernels.

use std::fmt;
use std::ops::Range;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;
use vcm_traversal::build::build_bvh2;
use vcm_traversal::{
    BuildPreset, HitBatch, NO_HIT, PendingTraversal, RayBatch, Traversal, TraversalJob,
};

use crate::PassTimer;
use crate::alpha::AlphaMasks;
use crate::device::{GpuDevice, read_mapped};
use crate::error::GpuError;
use crate::layout::{NodeLayout, SceneLayout};
use crate::shader::{ANY_HIT_ENTRY, CLOSEST_HIT_ENTRY, traversal_functions, traversal_module};
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
    layout: NodeLayout,
    alpha_masks: bool,
}

struct Inner {
    gpu: Arc<GpuDevice>,
    pipelines: [wgpu::ComputePipeline; 2],
    /// Bind groups 1 (nodes, vertices, ids) and, with alpha masks, 2 (the masks), each per
    /// pipeline; `None` for a scene without triangles, where every ray misses without a
    /// dispatch.
    scene_groups: Option<Vec<[wgpu::BindGroup; 2]>>,
    /// The buffers of bind group 1: nodes, triangles in leaf order, triangle ids.
    hierarchy: Option<[wgpu::Buffer; 3]>,
    /// The buffers of bind group 2 where some triangles are alpha-masked.
    mask_buffers: Option<[wgpu::Buffer; 4]>,
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
        let leaf_size = options.preset.params(triangles.len()).max_prims_per_leaf;
        let layout = SceneLayout::new(&bvh, triangles, options.layout, leaf_size);
        let masked = masks.any();
        let device = &gpu.device;
        let source = traversal_module(layout.layout, layout.stack_size, masked);
        let descriptor = wgpu::ShaderModuleDescriptor {
            label: Some("traversal"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        // Without alpha masks every index a kernel computes comes from the rays' own count
        // or from the node layout, checked here; the loops end because each iteration
        // clears a hit bit or pops the stack. Dropping naga's bounds checks and loop guards
        // then traces 15-33% more rays/s on an H100 (README). Masked scenes keep them, as the
        // mask lookups index by texture coordinates.
        let trusted = !masked && layout.indices_in_bounds();
        debug_assert!(
            masked || trusted,
            "the GPU node layout indexes out of bounds"
        );
        let module = if trusted {
            // SAFETY: the kernels stay in bounds and terminate, as checked and argued above.
            unsafe {
                device.create_shader_module_trusted(
                    descriptor,
                    wgpu::ShaderRuntimeChecks::unchecked(),
                )
            }
        } else {
            device.create_shader_module(descriptor)
        };
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
        let mut mask_buffers = None;
        let (scene_groups, hierarchy) = if layout.nodes.is_empty() {
            (None, None)
        } else {
            let hierarchy = [
                gpu.storage_buffer("nodes", bytemuck::cast_slice(&layout.nodes))?,
                gpu.storage_buffer("triangles", bytemuck::cast_slice(&layout.vertices))?,
                gpu.storage_buffer("triangle ids", bytemuck::cast_slice(&layout.ids))?,
            ];
            let mut groups = vec![bind_buffers(&gpu, &pipelines, 1, &hierarchy)];
            if masked {
                let packed = masks.pack(&layout.ids);
                let buffers = [
                    gpu.storage_buffer("leaf masks", bytemuck::cast_slice(&packed.leaf_masks))?,
                    gpu.storage_buffer("masks", bytemuck::cast_slice(&packed.masks))?,
                    gpu.storage_buffer("mask textures", bytemuck::cast_slice(&packed.textures))?,
                    gpu.storage_buffer("mask texels", bytemuck::cast_slice(&packed.texels))?,
                ];
                scene_bytes += buffers.iter().map(|b| b.size() as usize).sum::<usize>();
                groups.push(bind_buffers(&gpu, &pipelines, 2, &buffers));
                mask_buffers = Some(buffers);
            }
            (Some(groups), Some(hierarchy))
        };
        let max_rays_per_slot = gpu.max_binding_bytes() / RAY_BYTES.max(HIT_BYTES);
        Ok(Self {
            build_time: start.elapsed(),
            scene_bytes,
            stack_size: layout.stack_size,
            layout: layout.layout,
            alpha_masks: masked,
            inner: Arc::new(Inner {
                gpu,
                pipelines,
                scene_groups,
                hierarchy,
                mask_buffers,
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

    /// GPU time of the closest-hit (`occlusion` false) or any-hit kernel alone on `rays`:
    /// the median of `repeats` dispatches timed by GPU timestamps, without the upload,
    /// read-back and synchronisation that [`Traversal`] calls also pay. For benchmarks.
    /// `None` when the adapter has no timestamp queries, the scene has no triangles, or the
    /// batch is empty or larger than one dispatch.
    pub fn kernel_time(&self, rays: &RayBatch, occlusion: bool, repeats: u32) -> Option<Duration> {
        let query = if occlusion {
            Query::Any
        } else {
            Query::Closest
        };
        self.inner.kernel_time(rays, query, repeats)
    }

    /// Entries of each invocation's traversal stack (the hierarchy's depth).
    pub fn stack_size(&self) -> u32 {
        self.stack_size
    }

    /// Whether some triangles are alpha-masked (their masks are bind group 2 of the
    /// traversal functions).
    pub fn has_alpha_masks(&self) -> bool {
        self.alpha_masks
    }

    /// The hierarchy's buffers as [`traversal_functions`](Self::traversal_functions) read
    /// them, bindings 0, 1, 2 of bind group 1: nodes, triangles in leaf order, triangle ids;
    /// for kernels that trace rays of their own. `None` for a scene without triangles.
    pub fn hierarchy_buffers(&self) -> Option<&[wgpu::Buffer; 3]> {
        self.inner.hierarchy.as_ref()
    }

    /// The alpha masks' buffers as the traversal functions read them, bindings 0 to 3 of
    /// bind group 2 (leaf masks, masks, mask textures, their texels); `None` without masks.
    pub fn alpha_mask_buffers(&self) -> Option<&[wgpu::Buffer; 4]> {
        self.inner.mask_buffers.as_ref()
    }

    /// The WGSL of `trace(ray, any_hit) -> Hit` over this hierarchy (no entry points, see
    /// [`crate::shader::traversal_functions`]).
    pub fn traversal_functions(&self) -> String {
        traversal_functions(self.layout, self.stack_size, self.alpha_masks)
    }
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
        // A failed device traces nothing more: every ray misses.
        let failed = self.gpu.failure().is_some();
        let Some(scene_groups) = self.scene_groups.as_ref().filter(|_| !failed) else {
            return launch;
        };
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        let step = self.max_rays_per_slot.max(1) as usize;
        let mut recorded = Vec::new();
        for first in (0..rays.len()).step_by(step) {
            let count = step.min(rays.len() - first);
            let slot = self.take_slot(count as u64);
            let workgroups = self.upload_batch(&slot, rays, first..first + count);
            self.record_dispatch(&mut encoder, &slot, query, scene_groups, workgroups, None);
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

    /// Writes `rays[range]` and the kernel parameters into `slot`; returns the workgroups
    /// to dispatch in x and y.
    fn upload_batch(&self, slot: &Slot, rays: &RayBatch, range: Range<usize>) -> (u32, u32) {
        let packed = pack_rays(rays, range.clone());
        let queue = &self.gpu.queue;
        queue.write_buffer(&slot.rays, 0, bytemuck::cast_slice(&packed));
        let max_dim = self
            .gpu
            .device
            .limits()
            .max_compute_workgroups_per_dimension;
        let (x, y, row_threads) = dispatch_shape(range.len() as u64, max_dim);
        let params = Params {
            ray_count: range.len() as u32,
            row_threads,
        };
        queue.write_buffer(&slot.params, 0, bytemuck::bytes_of(&params));
        (x, y)
    }

    /// Records one compute pass running `query`'s kernel over the rays in `slot`.
    fn record_dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: &Slot,
        query: Query,
        scene_groups: &[[wgpu::BindGroup; 2]],
        (x, y): (u32, u32),
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let which = query as usize;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("traversal"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipelines[which]);
        pass.set_bind_group(0, &slot.groups[which], &[]);
        for (group, groups) in (1..).zip(scene_groups) {
            pass.set_bind_group(group, &groups[which], &[]);
        }
        pass.dispatch_workgroups(x, y, 1);
    }

    /// The median GPU time of `repeats` dispatches of `query`'s kernel over `rays`, from
    /// timestamp queries around each pass (see [`GpuBvh::kernel_time`]).
    fn kernel_time(&self, rays: &RayBatch, query: Query, repeats: u32) -> Option<Duration> {
        let scene_groups = self.scene_groups.as_deref()?;
        let fits = (rays.len() as u64) <= self.max_rays_per_slot;
        let repeats = repeats.min(wgpu::QUERY_SET_MAX_QUERIES / 2);
        if rays.is_empty() || !fits {
            return None;
        }
        // None without timestamps or repeats.
        let timer = PassTimer::new(&self.gpu, repeats)?;
        let slot = self.take_slot(rays.len() as u64);
        let workgroups = self.upload_batch(&slot, rays, 0..rays.len());
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        for _ in 0..repeats {
            let writes = timer.writes();
            self.record_dispatch(&mut encoder, &slot, query, scene_groups, workgroups, writes);
        }
        timer.resolve(&mut encoder);
        let submitted = self.gpu.wait(self.gpu.queue.submit([encoder.finish()]));
        let times = submitted.and_then(|()| timer.collect(&self.gpu)).ok()?;
        self.slots.lock().expect("slot pool poisoned").push(slot);
        let mut times: Vec<f64> = times.iter().map(Duration::as_secs_f64).collect();
        times.sort_by(f64::total_cmp);
        Some(Duration::from_secs_f64(times[times.len() / 2]))
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
    /// Fails, saying why, where the device is lost or in error, or a mapping fails: the
    /// device then keeps the failure ([`GpuDevice::fail`]) and traces nothing more.
    fn collect(mut self, mut read: impl FnMut(usize, &[u8])) -> Result<(), ()> {
        let Some(submission) = self.submission.take() else {
            return Ok(());
        };
        let gpu = &self.inner.gpu;
        let failed = |message: String| gpu.fail(format!("traversing on the GPU: {message}"));
        gpu.wait(submission).map_err(failed)?;
        for part in std::mem::take(&mut self.parts) {
            let bytes = part.count as u64 * self.query.output_bytes();
            let slice = part.slot.readback.slice(..bytes);
            read_mapped(slice, &part.mapped, |view| read(part.first, view)).map_err(failed)?;
            part.slot.readback.unmap();
            self.inner
                .slots
                .lock()
                .expect("slot pool poisoned")
                .push(part.slot);
        }
        Ok(())
    }

    /// Waits and writes one hit per ray into `hits`: all misses where the device failed.
    fn into_hits(self, hits: &mut HitBatch) {
        let misses = |hits: &mut HitBatch| {
            hits.t.fill(f32::INFINITY);
            hits.prim.fill(NO_HIT);
            hits.u.fill(0.0);
            hits.v.fill(0.0);
        };
        hits.resize(self.rays);
        misses(hits);
        let collected = self.collect(|first, bytes| {
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
        if collected.is_err() {
            misses(hits);
        }
    }

    /// Waits and writes one flag per ray into `occluded`: none where the device failed.
    fn into_occluded(self, occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.resize(self.rays, false);
        let collected = self.collect(|first, bytes| {
            let flags: &[u32] = bytemuck::cast_slice(bytes);
            for (out, &flag) in occluded[first..].iter_mut().zip(flags) {
                *out = flag != 0;
            }
        });
        if collected.is_err() {
            occluded.fill(false);
        }
    }
}

/// Packs `rays[range]` as `ray.wgsl`'s `Ray`. Rays that cannot hit anything (non-finite or
/// zero direction, non-finite origin, NaN or empty interval) get an empty interval so the
/// kernel skips them; an infinite `tmax` becomes the largest finite value, which the
/// kernel's sentinels rely on. Batches below [`PARALLEL_PACK_RAYS`] are packed on the calling
/// thread: handing them to the rayon pool would cost more than it saves, and a scheduler's
/// submitting thread would wait there behind busy workers.
fn pack_rays(rays: &RayBatch, range: std::ops::Range<usize>) -> Vec<[f32; 8]> {
    const SKIPPED: [f32; 8] = [0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    const CHUNK: usize = 4096;
    let mut packed = vec![SKIPPED; range.len()];
    rays.assert_consistent();
    let pack_chunk = |(chunk, out): (usize, &mut [[f32; 8]])| {
        let start = range.start + chunk * CHUNK;
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
    };
    if range.len() < PARALLEL_PACK_RAYS {
        packed.chunks_mut(CHUNK).enumerate().for_each(pack_chunk);
    } else {
        packed
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(pack_chunk);
    }
    packed
}

/// The smallest batch whose rays [`pack_rays`] packs on the rayon pool.
const PARALLEL_PACK_RAYS: usize = 1 << 16;

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

    fn submits_asynchronously(&self) -> bool {
        true
    }

    fn failure(&self) -> Option<String> {
        self.inner.gpu.failure()
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
