//! [`GpuFrames`]: what every GPU integrator does with a frame — dispatches of consecutive
//! invocations of its kernel, which add their samples and splats to the film on the device
//! (`film.wgsl`: exact sums, the same whatever the order), and the film read back and merged
//! into the render's once the frame is whole — and the state that goes with it.

use std::cell::Cell;
use std::sync::Arc;
use std::time::Duration;

use bytemuck::{Pod, Zeroable};
use vcm::exact_sum::{ExactSum, WORDS};
use vcm::hash_grid::HashGrid;
use vcm::{
    Algorithm, BidirPlan, Film, FrameStats, PixelSum, RenderError, Schedule, StopFlag, merge_radius,
};
use vcm_scene::Scene;
use vcm_traversal_wgpu::{GpuBvh, PassTimer};

use crate::error::GpuRenderError;
use crate::grid::{GridBuffers, GridBuilder};
use crate::index::IndexBuilder;
use crate::kernel::{
    INDIRECT_BYTES, LightPass, Params, Sampling, SceneKernel, check_host_estimate, film_estimate,
};
use crate::shader::{Kernel, WORKGROUP_SIZE};

/// u32 limbs of one exact sum on the device (`SUM_LIMBS` of `film.wgsl`).
const SUM_LIMBS: usize = 2 * WORDS;
/// Bytes of one pixel's sum of one channel on the device.
const CHANNEL_BYTES_PER_PIXEL: u64 = 4 * SUM_LIMBS as u64;
/// Bytes of the ray counts (up to three kinds).
const RAY_COUNT_BYTES: u64 = 12;
/// Invocations per dispatch on a hardware GPU: enough to fill one, few enough that a frame
/// can stop between dispatches.
const PATHS_PER_DISPATCH: u64 = 1 << 20;
/// Invocations per dispatch on a CPU implementation (lavapipe), which runs them on a few
/// cores.
const PATHS_PER_SOFTWARE_DISPATCH: u64 = 1 << 15;
/// Bytes of one path's state in the path tracer's wavefront (`PathState` of
/// `path_tracer.wgsl`).
const PATH_STATE_BYTES: u64 = 176;
/// Bytes of the wavefront's queue counts (`Wave` of `path_tracer.wgsl`).
const WAVE_BYTES: u64 = 32;
/// Cacheable vertices of each light path that the light pass's first run keeps, so that
/// only the paths with more are traced again to store the rest (fewer where the frame's
/// would not fit one binding): most light paths end within a few vertices.
const KEPT_VERTICES: u64 = 4;
/// Passes a submission may time: a wavefront submission has one per round and its start.
const TIMED_PASSES: u32 = 64;
/// Rounds of the wavefront recorded between two looks at how many paths are left.
const ROUNDS_PER_SUBMIT: u32 = 4;
/// Once at most 1 / TAIL_FRACTION of a dispatch's paths are left, each is taken to its end in
/// one invocation: rounds would be mostly empty by then, and a few paths (behind glass,
/// between mirrors) run for hundreds of segments.
const TAIL_FRACTION: u32 = 16;

/// How a frame runs its kernels.
#[derive(Clone, Copy, Debug)]
pub(crate) enum FramePlan {
    /// The path tracer: its wavefront, started over each dispatch's paths.
    PathTracing,
    /// A bidirectional algorithm: light tracing in one pass of the light kernel; the others
    /// trace their light paths (counting their vertices, keeping the first few), store the
    /// vertices in the cache (tracing the longer paths again), build the iterations' hash
    /// grids where they merge, then run the camera pass.
    Bidirectional(BidirFrames),
}

/// What a bidirectional algorithm's frames need besides their settings.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BidirFrames {
    pub algorithm: Algorithm,
    /// The parts that run on this scene.
    pub plan: BidirPlan,
    /// r₀, the first iteration's merge radius (0 where nothing merges), and α, how it shrinks.
    pub first_radius: f32,
    pub alpha: f32,
    /// N_p, the light paths each iteration traces.
    pub light_paths: u32,
}

/// A GPU integrator's kernels, its frames' film on the device, and the state of its frames.
pub(crate) struct GpuFrames {
    /// The kernels: the one pass's, or the light pass's and the camera pass's.
    pub kernels: Vec<SceneKernel>,
    plan: FramePlan,
    /// The image size.
    pub size: (u32, u32),
    paths_per_dispatch: u64,
    /// The most vertices of each light path the light pass's first run keeps.
    kept_vertices: u64,
    buffers: FrameBuffers,
    /// The kernels that build the light vertex index, once a frame caches.
    index: Option<IndexBuilder>,
    /// The kernels that build the hash grids, once a frame merges.
    grids: Option<GridBuilder>,
    /// Times the scene kernels' passes, where the device writes timestamps.
    timer: Option<PassTimer>,
    /// The time of the frame's passes timed so far.
    device_time: Cell<Duration>,
    samples_per_frame: u32,
    stop: StopFlag,
    /// What failed on the GPU, once something has: no frame renders after it.
    failure: Option<String>,
}

/// A frame rendered on the device.
struct RenderedFrame {
    film: Film,
    /// The rays traced, by the kernels' kinds.
    rays: [u64; 3],
    /// The invocations of a pass.
    invocations: u64,
    /// The light vertices cached.
    light_vertices: u64,
}

/// The buffers of bind group 0 in binding order — the dispatches' parameters, the film's
/// sums per channel, the dropped samples, the ray counts, the light vertex cache's index,
/// the cache, the iterations, the hash grids' bucket starts and entries, the wavefront's
/// path states, queues and queue counts, the light paths' kept vertices — the film's and
/// the queue counts' read-back copies, the wavefront's dispatch arguments, and each
/// kernel's bind group.
struct FrameBuffers {
    bindings: [wgpu::Buffer; 15],
    readback: wgpu::Buffer,
    wave_readback: wgpu::Buffer,
    /// The workgroups of the wavefront's next round (indirect dispatch arguments).
    indirect: wgpu::Buffer,
    /// Bind group 0 of each kernel.
    groups: Vec<wgpu::BindGroup>,
}

/// Where each buffer is bound in group 0 (`bindings` of [`FrameBuffers`]).
const PARAMS: usize = 0;
const FILM: std::ops::Range<usize> = 1..6;
const INDEX: usize = 6;
const CACHE: usize = 7;
const ITERATIONS: usize = 8;
const GRID_STARTS: usize = 9;
const GRID_ENTRIES: usize = 10;
const PATH_STATES: usize = 11;
const QUEUES: usize = 12;
const WAVE: usize = 13;
const SCRATCH: usize = 14;

impl GpuFrames {
    /// The kernels of `plan` compiled for `scene` on the hierarchy `bvh`, and their frames at
    /// `size`. Fails where a channel's sums (40 bytes a pixel) exceed the device's largest
    /// binding, or the films the host's memory.
    pub fn new(
        plan: FramePlan,
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        size: (u32, u32),
    ) -> Result<GpuFrames, GpuRenderError> {
        vcm::check_image_size(size.0, size.1)?;
        let pixels = u64::from(size.0) * u64::from(size.1);
        let channel_bytes = pixels * CHANNEL_BYTES_PER_PIXEL;
        // The read-back copy of the device's film is mapped into the host's memory.
        check_host_estimate(film_estimate(size).with("film read-back", 3 * channel_bytes))?;
        let gpu = bvh.device();
        if channel_bytes > gpu.max_binding_bytes() {
            return Err(GpuRenderError::Unsupported(format!(
                "an image of {pixels} pixels, whose film on the device takes {channel_bytes} \
                 bytes a channel, more than {} can bind ({} bytes): render a smaller image \
                 or shade on the CPU",
                gpu.describe(),
                gpu.max_binding_bytes()
            )));
        }
        let paths_per_dispatch = if gpu.is_software() {
            PATHS_PER_SOFTWARE_DISPATCH
        } else {
            PATHS_PER_DISPATCH
        };
        let kernels = match plan {
            FramePlan::PathTracing => vec![SceneKernel::new(Kernel::PathTracer, scene, bvh)?],
            FramePlan::Bidirectional(bidir) => {
                let light = SceneKernel::new(Kernel::LightTracer, scene, bvh)?;
                if bidir.algorithm == Algorithm::LightTracing {
                    vec![light]
                } else {
                    let camera = light.sibling(Kernel::BidirCamera);
                    vec![light, camera]
                }
            }
        };
        let buffers = FrameBuffers::new(&kernels, channel_bytes);
        let timer = PassTimer::new(gpu, TIMED_PASSES);
        let mut frames = GpuFrames {
            kernels,
            plan,
            size,
            paths_per_dispatch,
            kept_vertices: KEPT_VERTICES,
            buffers,
            index: None,
            grids: None,
            timer,
            device_time: Cell::new(Duration::ZERO),
            samples_per_frame: 1,
            stop: StopFlag::new(),
            failure: None,
        };
        frames.fit_wavefront();
        Ok(frames)
    }

    /// Makes room for the path tracer's wavefront over a dispatch's paths — their states,
    /// the two round queues and the shadow queue — with fewer paths a dispatch where their
    /// states would not fit one binding.
    fn fit_wavefront(&mut self) {
        if let FramePlan::PathTracing = self.plan {
            let fitting = self.kernels[0].gpu.max_binding_bytes() / PATH_STATE_BYTES;
            let workgroup = u64::from(WORKGROUP_SIZE);
            let paths = self.paths_per_dispatch.min(fitting / workgroup * workgroup);
            self.paths_per_dispatch = paths;
            let b = &mut self.buffers;
            b.fit(&self.kernels, PATH_STATES, paths * PATH_STATE_BYTES);
            b.fit(&self.kernels, QUEUES, 3 * 4 * paths);
        }
    }

    /// Renders the frame starting at sample `first_sample` with `sampling`: each pass an
    /// invocation per pixel and sample, in dispatches of consecutive invocations that add to
    /// the film on the device, and adds that film to `film`. Returns the statistics `stats`
    /// makes of the rays traced (by the kernels' kinds) and the invocations of a pass, with
    /// the time it took, or [`FrameStats::INTERRUPTED`] where the frame was stopped or failed
    /// (`algorithm` names it in the failure), leaving `film` as it was.
    pub fn render(
        &mut self,
        film: &mut Film,
        first_sample: u32,
        (algorithm, sampling): (&str, &Sampling),
        stats: impl FnOnce([u64; 3], u64) -> FrameStats,
    ) -> FrameStats {
        assert_eq!(
            (film.width(), film.height()),
            self.size,
            "film size differs from the settings"
        );
        let start = std::time::Instant::now();
        let rendered = self.render_frame(first_sample, sampling);
        let device_time = self.device_time.take();
        match rendered {
            Ok(Some(frame)) => {
                // Exact sums: the same film as adding each sample and splat to `film`.
                film.merge(&frame.film);
                FrameStats {
                    shading_time: start.elapsed(),
                    device_time,
                    light_vertices: frame.light_vertices,
                    ..stats(frame.rays, frame.invocations)
                }
            }
            Ok(None) => FrameStats::INTERRUPTED,
            Err(error) => {
                self.failure = Some(format!("{algorithm} on the GPU: {error}"));
                FrameStats::INTERRUPTED
            }
        }
    }

    /// The frame; `None` where it was stopped.
    fn render_frame(
        &mut self,
        first_sample: u32,
        sampling: &Sampling,
    ) -> Result<Option<RenderedFrame>, String> {
        let (width, height) = self.size;
        let samples = self.samples_per_frame;
        let invocations = u64::from(width) * u64::from(height) * u64::from(samples);
        let frame = (first_sample, samples);
        let pass = |light_pass| (sampling, light_pass);
        let mut cached = 0;
        let done = match self.plan {
            FramePlan::PathTracing => {
                self.run_pass(0, pass(LightPass::LightTracing), frame, true)?
            }
            FramePlan::Bidirectional(bidir) => {
                let mut iterations = self.iterations(&bidir, frame);
                if bidir.algorithm == Algorithm::LightTracing {
                    self.write_iterations(&iterations);
                    self.run_pass(0, pass(LightPass::LightTracing), frame, true)?
                } else {
                    let light_paths = u64::from(bidir.light_paths) * u64::from(samples);
                    self.prepare_index(light_paths, samples)?;
                    let kept = self.prepare_kept_vertices(light_paths);
                    self.write_iterations(&iterations);
                    let later = LightPass::LaterVertices { kept };
                    let done =
                        self.run_pass(0, pass(LightPass::FirstVertices { kept }), frame, true)?
                            && self.index_vertices(&mut iterations, bidir.light_paths)?
                            && self.run_pass(0, pass(later), frame, false)?
                            && (!bidir.plan.merges
                                || self
                                    .build_grids(&mut iterations, bidir.plan.shortest_merged())?)
                            && self.run_pass(1, pass(LightPass::LightTracing), frame, false)?;
                    cached = iterations.iter().map(|it| u64::from(it.cache_count)).sum();
                    done
                }
            }
        };
        if !done {
            return Ok(None);
        }
        let (film, rays) = self.read_film(samples)?;
        Ok(Some(RenderedFrame {
            film,
            rays,
            invocations,
            light_vertices: cached,
        }))
    }

    /// Runs kernel `kernel` with `sampling` and `light_pass` over every invocation of
    /// `frame` (kernel 0, the light pass's or the path tracer's, one per pixel or light path,
    /// whichever are more; the camera pass's one per pixel), clearing the film and the ray
    /// counts first where `clear`; `false` where a stop request cut it short.
    fn run_pass(
        &self,
        kernel: usize,
        (sampling, light_pass): (&Sampling, LightPass),
        frame: (u32, u32),
        clear: bool,
    ) -> Result<bool, String> {
        let light_paths = self.light_paths();
        let b = &self.buffers;
        let per_sample = match kernel {
            0 => self.first_kernel_invocations(),
            _ => self.pixels(),
        };
        let invocations = per_sample * u64::from(frame.1);
        let mut cleared: Vec<&wgpu::Buffer> = if clear {
            b.bindings[FILM].iter().collect()
        } else {
            Vec::new()
        };
        let scene_kernel = &self.kernels[kernel];
        for first in (0..invocations).step_by(self.paths_per_dispatch as usize) {
            if self.stop.is_raised() || self.failure.is_some() {
                return Ok(false);
            }
            let range = (first, self.paths_per_dispatch.min(invocations - first));
            let timer = self.timer.as_ref();
            let dispatch = (&b.bindings[PARAMS], &b.groups[kernel], timer);
            let pass = (sampling, light_pass, light_paths);
            let encoder = scene_kernel.encode(dispatch, pass, frame, range, &cleared);
            // The first dispatch clears the outputs; the others add to them.
            cleared.clear();
            if let FramePlan::PathTracing = self.plan {
                self.run_wavefront(encoder, range.1)?;
            } else {
                self.submit(encoder)?;
            }
        }
        Ok(true)
    }

    /// Submits `encoder`, with its passes' timestamps, and waits until the device is done
    /// with it.
    fn submit(&self, mut encoder: wgpu::CommandEncoder) -> Result<(), String> {
        let gpu = &self.kernels[0].gpu;
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        gpu.wait(gpu.queue.submit([encoder.finish()]))?;
        self.collect_times()
    }

    /// Adds the times of the passes submitted to the frame's.
    fn collect_times(&self) -> Result<(), String> {
        if let Some(timer) = &self.timer {
            let times = timer.collect(&self.kernels[0].gpu)?;
            self.device_time
                .set(self.device_time.get() + times.iter().sum::<Duration>());
        }
        Ok(())
    }

    /// Runs the path tracer's wavefront over `paths` paths that `encoder` starts: rounds of
    /// extending the queued paths and tracing their shadow rays, [`ROUNDS_PER_SUBMIT`] at a
    /// time, each time reading back how many paths go on, until few enough are left to take
    /// each to its end in one invocation ([`TAIL_FRACTION`]).
    fn run_wavefront(&self, mut encoder: wgpu::CommandEncoder, paths: u64) -> Result<(), String> {
        let b = &self.buffers;
        let kernel = &self.kernels[0];
        let gpu = &kernel.gpu;
        let wave = &b.bindings[WAVE];
        // Every path is queued for the first round (`Wave` of path_tracer.wgsl).
        let paths = paths as u32;
        let start = [paths.div_ceil(WORKGROUP_SIZE), 1, 1, paths, 0, 0, 0, 0];
        gpu.queue
            .write_buffer(wave, 0, bytemuck::cast_slice(&start));
        gpu.queue
            .write_buffer(&b.indirect, 0, bytemuck::cast_slice(&start[..3]));
        let dispatch = (&b.groups[0], self.timer.as_ref());
        loop {
            kernel.record_rounds(
                &mut encoder,
                dispatch,
                (wave, &b.indirect),
                ROUNDS_PER_SUBMIT,
            );
            encoder.copy_buffer_to_buffer(wave, 0, &b.wave_readback, 0, WAVE_BYTES);
            if let Some(timer) = &self.timer {
                timer.resolve(&mut encoder);
            }
            let read = |bytes: &[u8]| bytemuck::pod_read_unaligned::<[u32; 8]>(bytes)[3];
            let left = gpu.read_back(encoder, (&b.wave_readback, WAVE_BYTES), read)?;
            self.collect_times()?;
            if left == 0 {
                return Ok(());
            }
            encoder = gpu.device.create_command_encoder(&Default::default());
            if left * TAIL_FRACTION <= paths {
                kernel.record_tail(&mut encoder, dispatch, &b.indirect);
                return self.submit(encoder);
            }
        }
    }

    /// The frame's iterations as `bidir` renders them: their merge radii and MIS factors.
    fn iterations(
        &self,
        bidir: &BidirFrames,
        (first, samples): (u32, u32),
    ) -> Vec<IterationRecord> {
        let light_paths = bidir.light_paths as f32;
        (0..samples)
            .map(|sample| {
                let iteration = u64::from(first) + u64::from(sample);
                let radius = merge_radius(bidir.first_radius, bidir.alpha, iteration);
                IterationRecord {
                    factors: bidir.plan.mis_factors(radius, light_paths),
                    radius,
                    ..IterationRecord::zeroed()
                }
            })
            .collect()
    }

    /// Writes `iterations` to the device, making room for them.
    fn write_iterations(&mut self, iterations: &[IterationRecord]) {
        let bytes: &[u8] = bytemuck::cast_slice(iterations);
        self.buffers
            .fit(&self.kernels, ITERATIONS, bytes.len() as u64);
        let gpu = &self.kernels[0].gpu;
        gpu.queue
            .write_buffer(&self.buffers.bindings[ITERATIONS], 0, bytes);
    }

    /// Makes room in the index for the frame's `paths` light paths and its `samples`.
    fn prepare_index(&mut self, paths: u64, samples: u32) -> Result<(), String> {
        let bytes = 4 * paths;
        if bytes > self.kernels[0].gpu.max_binding_bytes() {
            return Err(format!(
                "{paths} light paths a frame need an index of {bytes} bytes, more than the \
                 device can bind: render fewer samples per frame ({samples} now)"
            ));
        }
        self.buffers.fit(&self.kernels, INDEX, bytes);
        Ok(())
    }

    /// Makes room for the first vertices of the frame's `paths` light paths that the light
    /// pass's first run keeps, and returns how many a path: [`KEPT_VERTICES`], or fewer where
    /// they would not fit one binding (none at worst: every path is traced again).
    fn prepare_kept_vertices(&mut self, paths: u64) -> u32 {
        let vertex = size_of::<LightVertex>() as u64;
        let fitting = self.kernels[0].gpu.max_binding_bytes() / (paths * vertex).max(1);
        let kept = self.kept_vertices.min(fitting);
        self.buffers
            .fit(&self.kernels, SCRATCH, (paths * kept * vertex).max(vertex));
        kept as u32
    }

    /// Turns the light vertices each of `light_paths` light paths per iteration counted into
    /// where they go in the cache, on the device (`index.wgsl`): iteration by iteration, each
    /// iteration's in the order of its paths, as the CPU's cache keeps them. Reads back each
    /// iteration's part into `iterations` and makes room for them (always `true`, to chain
    /// with the passes).
    fn index_vertices(
        &mut self,
        iterations: &mut [IterationRecord],
        light_paths: u32,
    ) -> Result<bool, String> {
        let gpu = Arc::clone(&self.kernels[0].gpu);
        let samples = iterations.len() as u32;
        let index = self.index.get_or_insert_with(|| IndexBuilder::new(&gpu));
        let b = &self.buffers;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let buffers = (&b.bindings[INDEX], &b.bindings[ITERATIONS]);
        index.record(&gpu, &mut encoder, buffers, (light_paths, samples));
        let bytes = size_of_val(iterations) as u64;
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("iterations read-back"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_buffer_to_buffer(&b.bindings[ITERATIONS], 0, &readback, 0, bytes);
        let records: Vec<IterationRecord> =
            gpu.read_back(encoder, (&readback, bytes), bytemuck::pod_collect_to_vec)?;
        for (iteration, record) in iterations.iter_mut().zip(&records) {
            iteration.cache_start = record.cache_start;
            iteration.cache_count = record.cache_count;
        }
        let total: u64 = iterations.iter().map(|it| u64::from(it.cache_count)).sum();
        let cache_bytes = total * size_of::<LightVertex>() as u64;
        if cache_bytes > gpu.max_binding_bytes() {
            return Err(format!(
                "the frame's {total} light vertices take {cache_bytes} bytes, more than the \
                 device can bind ({} bytes): render fewer samples per frame or a smaller image",
                gpu.max_binding_bytes()
            ));
        }
        self.buffers.fit(&self.kernels, CACHE, cache_bytes);
        Ok(true)
    }

    /// Builds each iteration's hash grid over its light vertices that merge (`shortest` or
    /// more segments from their light) within its radius on the device (`grid.wgsl`: the
    /// CPU's `HashGrid::build_over`), recording each grid's layout in `iterations` (the
    /// device counts its buckets and entries; always `true`, to chain with the passes).
    fn build_grids(
        &mut self,
        iterations: &mut [IterationRecord],
        shortest: u32,
    ) -> Result<bool, String> {
        let gpu = Arc::clone(&self.kernels[0].gpu);
        let mut starts = 0u64;
        for it in iterations.iter_mut() {
            // Room for as many buckets as vertices, a power of two, and the total after them.
            let buckets = it.cache_count.max(1).next_power_of_two();
            it.grid_starts = starts as u32;
            starts += u64::from(buckets) + 1;
            it.grid_entries = it.cache_start;
            it.inv_cell_size = HashGrid::inv_cell_size(it.radius);
            it.radius_sq = it.radius * it.radius;
        }
        let vertices: u64 = iterations.iter().map(|it| u64::from(it.cache_count)).sum();
        let entry_bytes = vertices * size_of::<GridEntry>() as u64;
        if 4 * starts > gpu.max_binding_bytes() || entry_bytes > gpu.max_binding_bytes() {
            return Err(format!(
                "the frame's hash grids take {} bytes, more than the device can bind",
                4 * starts + entry_bytes
            ));
        }
        self.buffers.fit(&self.kernels, GRID_STARTS, 4 * starts);
        self.buffers.fit(&self.kernels, GRID_ENTRIES, entry_bytes);
        self.write_iterations(iterations);
        let b = &self.buffers.bindings;
        let buffers = GridBuffers {
            cache: &b[CACHE],
            iterations: &b[ITERATIONS],
            starts: &b[GRID_STARTS],
            entries: &b[GRID_ENTRIES],
        };
        let grids = self.grids.get_or_insert_with(|| GridBuilder::new(&gpu));
        let counts = (vertices as u32, iterations.len() as u32, starts as u32);
        grids.build(&gpu, &buffers, counts, shortest)?;
        Ok(true)
    }

    /// The frame's film of `samples` per pixel and the rays traced, read back.
    fn read_film(&self, samples: u32) -> Result<(Film, [u64; 3]), String> {
        let (width, height) = self.size;
        let b = &self.buffers;
        let gpu = &self.kernels[0].gpu;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let mut at = 0;
        for buffer in &b.bindings[FILM] {
            encoder.copy_buffer_to_buffer(buffer, 0, &b.readback, at, buffer.size());
            at += buffer.size();
        }
        let pixels = width as usize * height as usize;
        let read = |bytes: &[u8]| {
            let limbs: Vec<u32> = bytemuck::pod_collect_to_vec(bytes);
            let (sums, counts) = limbs.split_at(3 * pixels * SUM_LIMBS);
            let (dropped, rays) = (counts[0], &counts[1..]);
            let channel = |c: usize, pixel: usize| {
                let at = (c * pixels + pixel) * SUM_LIMBS;
                exact_sum(&sums[at..at + SUM_LIMBS])
            };
            let sums: Vec<PixelSum> = (0..pixels)
                .map(|pixel| [0, 1, 2].map(|c| channel(c, pixel)))
                .collect();
            let counts = vec![u64::from(samples); pixels];
            let film = Film::from_parts(self.size, sums, counts, u64::from(dropped));
            let rays = [rays[0], rays[1], rays[2]].map(u64::from);
            (film.expect("a sum per pixel"), rays)
        };
        gpu.read_back(encoder, (&b.readback, at), read)
    }

    /// The pixels of the image.
    fn pixels(&self) -> u64 {
        u64::from(self.size.0) * u64::from(self.size.1)
    }

    /// N_p, the light paths per iteration: a bidirectional algorithm's own, else one per
    /// pixel.
    fn light_paths(&self) -> u32 {
        match &self.plan {
            // Fits 32 bits (`vcm::check_image_size`).
            FramePlan::PathTracing => self.pixels() as u32,
            FramePlan::Bidirectional(bidir) => bidir.light_paths,
        }
    }

    /// The invocations of the first kernel (the path tracer's, or the light pass's) per
    /// sample per pixel: one per pixel, or per light path where there are more.
    fn first_kernel_invocations(&self) -> u64 {
        self.pixels().max(u64::from(self.light_paths()))
    }

    /// Takes the samples per pixel per frame of `schedule` (its scheduler, a CPU matter,
    /// does not apply), which must number a frame's invocations (`what`) in 32 bits.
    pub fn set_schedule(&mut self, schedule: Schedule, what: &str) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        let count = self.first_kernel_invocations() * u64::from(schedule.samples_per_frame);
        if count > u64::from(u32::MAX) {
            return Err(RenderError::InvalidSetting(format!(
                "{} samples per pixel per frame make {count} {what}, more than a GPU kernel \
                 numbers in one frame (2³² − 1)",
                schedule.samples_per_frame
            )));
        }
        self.samples_per_frame = schedule.samples_per_frame;
        Ok(())
    }

    /// The samples per pixel per frame.
    pub fn samples_per_frame(&self) -> u32 {
        self.samples_per_frame
    }

    /// Sets the flag that stops a frame between dispatches.
    pub fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    /// What failed on the GPU, if anything has.
    pub fn failure(&self) -> Option<String> {
        self.failure.clone()
    }

    /// Dispatches of at most `paths` invocations from now on.
    #[cfg(test)]
    pub fn set_paths_per_dispatch(&mut self, paths: u64) {
        self.paths_per_dispatch = paths;
        self.fit_wavefront();
    }

    /// At most `kept` vertices of each light path kept by the light pass's first run.
    #[cfg(test)]
    pub fn set_kept_vertices(&mut self, kept: u64) {
        self.kept_vertices = kept;
    }
}

/// The exact sum held by ten u32 limbs, least significant first.
fn exact_sum(limbs: &[u32]) -> ExactSum {
    let mut words = [0u64; WORDS];
    for (word, pair) in words.iter_mut().zip(limbs.chunks_exact(2)) {
        *word = u64::from(pair[0]) | u64::from(pair[1]) << 32;
    }
    ExactSum::from_words(words)
}

/// `LightVertex` of bidir.wgsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct LightVertex {
    pub(crate) position: [f32; 3],
    pub(crate) path_length: u32,
    pub(crate) wo: [f32; 3],
    pub(crate) triangle: u32,
    pub(crate) throughput: [f32; 3],
    pub(crate) u: f32,
    pub(crate) mis: [f32; 3],
    pub(crate) v: f32,
}

/// `Iteration` of bidir.wgsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct IterationRecord {
    pub(crate) cache_start: u32,
    pub(crate) cache_count: u32,
    pub(crate) grid_starts: u32,
    pub(crate) grid_entries: u32,
    pub(crate) factors: [f32; 4],
    pub(crate) grid_min: [f32; 3],
    pub(crate) inv_cell_size: f32,
    pub(crate) grid_max: [f32; 3],
    pub(crate) bucket_mask: u32,
    pub(crate) radius: f32,
    pub(crate) radius_sq: f32,
    pub(crate) entry_count: u32,
    pub(crate) unused: u32,
}

/// `GridEntry` of bidir.wgsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GridEntry {
    pub(crate) position: [f32; 3],
    pub(crate) index: u32,
}

impl FrameBuffers {
    /// Buffers for the frames of `kernels` with `channel_bytes` of sums per channel; the
    /// cache, its index, the iterations, the grids, the kept light vertices and the path
    /// tracer's paths and queues hold nothing yet.
    fn new(kernels: &[SceneKernel], channel_bytes: u64) -> FrameBuffers {
        use wgpu::BufferUsages as U;
        let kernel = &kernels[0];
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        let film = |label| (label, channel_bytes, output);
        // In binding order.
        let bindings = [
            (
                "frame parameters",
                size_of::<Params>() as u64,
                U::UNIFORM | U::COPY_DST,
            ),
            film("film red"),
            film("film green"),
            film("film blue"),
            ("dropped samples", 4, output),
            ("ray counts", RAY_COUNT_BYTES, output),
            ("light vertex index", 16, output),
            (
                "light vertex cache",
                size_of::<LightVertex>() as u64,
                output,
            ),
            ("iterations", size_of::<IterationRecord>() as u64, output),
            ("grid bucket starts", 16, output),
            ("grid entries", size_of::<GridEntry>() as u64, output),
            ("path states", PATH_STATE_BYTES, output),
            ("path queues", 16, output),
            ("queue counts", WAVE_BYTES, output),
            (
                "kept light vertices",
                size_of::<LightVertex>() as u64,
                output,
            ),
        ]
        .map(|(label, bytes, usage)| kernel.buffer(label, bytes, usage));
        let [readback, wave_readback] = [
            ("film read-back", 3 * channel_bytes + 4 + RAY_COUNT_BYTES),
            ("queue counts read-back", WAVE_BYTES),
        ]
        .map(|(label, bytes)| kernel.buffer(label, bytes, U::MAP_READ | U::COPY_DST));
        let indirect = kernel.buffer(
            "round workgroups",
            INDIRECT_BYTES.next_multiple_of(16),
            U::INDIRECT | U::COPY_DST,
        );
        let mut buffers = FrameBuffers {
            bindings,
            readback,
            wave_readback,
            indirect,
            groups: Vec::new(),
        };
        buffers.bind(kernels);
        buffers
    }

    /// (Re)makes each kernel's bind group 0 of the buffers it reads.
    fn bind(&mut self, kernels: &[SceneKernel]) {
        self.groups = kernels
            .iter()
            .map(|kernel| {
                let used = kernel.kind.dispatch_bindings();
                let buffers = used.iter().map(|&b| (b, &self.bindings[b as usize]));
                kernel.bind_at(0, buffers)
            })
            .collect();
    }

    /// Makes binding `binding` at least `bytes` long (growing it by half again where the
    /// device can bind that, a new buffer), rebinding `kernels`.
    fn fit(&mut self, kernels: &[SceneKernel], binding: usize, bytes: u64) {
        if bytes <= self.bindings[binding].size() {
            return;
        }
        use wgpu::BufferUsages as U;
        let kernel = &kernels[0];
        let size = (bytes + bytes / 2).min(kernel.gpu.max_binding_bytes().max(bytes));
        let size = size.next_multiple_of(16);
        let label = "grown frame buffer";
        self.bindings[binding] = kernel.buffer(label, size, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        self.bind(kernels);
    }
}

/// The [`Integrator`](vcm::Integrator) methods that a GPU integrator leaves to its
/// [`GpuFrames`] (field `frames`), whose frames number `$what` (one per pixel and sample).
macro_rules! integrator_methods_of_frames {
    ($what:literal) => {
        fn image_size(&self) -> (u32, u32) {
            self.frames.size
        }

        fn set_schedule(&mut self, schedule: vcm::Schedule) -> Result<(), vcm::RenderError> {
            self.frames.set_schedule(schedule, $what)
        }

        fn set_stop(&mut self, stop: vcm::StopFlag) {
            self.frames.set_stop(stop);
        }

        fn samples_per_frame(&self) -> u32 {
            self.frames.samples_per_frame()
        }

        fn failure(&self) -> Option<String> {
            self.frames.failure()
        }
    };
}
pub(crate) use integrator_methods_of_frames;

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use vcm::{Algorithm, PtSettings, VcmSettings};
    use vcm_scene::sampling::Rng;
    use vcm_traversal_wgpu::{GpuBvhOptions, GpuDevice, device_or_skip};
    use wgpu::util::DeviceExt;

    use super::*;
    use crate::shader::{BSDF_WGSL, FILM_WGSL, host_constants};

    /// Adds `values` on the GPU, value i to channel i mod 3 of pixel (i / 3) mod `pixels`,
    /// all at once, and returns the sums.
    fn add_on_gpu(gpu: &GpuDevice, values: &[f32], pixels: usize) -> Vec<ExactSum> {
        let probe = format!(
            // bsdf.wgsl (for `all_finite`) reads lookup tables, declared and never bound.
            "{}{BSDF_WGSL}\n{FILM_WGSL}\n\
             @group(1) @binding(0) var<storage, read> tables: array<f32>;\n\
             @group(0) @binding(0) var<storage, read> values: array<f32>;\n\
             @compute @workgroup_size(64)\n\
             fn probe_film(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
                 if id.x >= arrayLength(&values) {{ return; }}\n\
                 exact_add(id.x % 3u, (id.x / 3u) % {pixels}u, values[id.x]);\n\
             }}\n",
            host_constants()
        );
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("film probe"),
            source: wgpu::ShaderSource::Wgsl(probe.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("film probe"),
            layout: None,
            module: &module,
            entry_point: Some("probe_film"),
            compilation_options: Default::default(),
            cache: None,
        });
        use wgpu::BufferUsages as U;
        let values_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("values"),
            contents: bytemuck::cast_slice(values),
            usage: U::STORAGE,
        });
        let bytes = (pixels * SUM_LIMBS * 4) as u64;
        let buffer = |size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        let channels = [0; 3].map(|_| buffer(bytes, output));
        let readback = buffer(3 * bytes, U::MAP_READ | U::COPY_DST);
        let entries: Vec<_> = (0u32..)
            .zip([&values_buffer].into_iter().chain(&channels))
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        for channel in &channels {
            encoder.clear_buffer(channel, 0, None);
        }
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((values.len() as u32).div_ceil(64), 1, 1);
        }
        for (c, channel) in channels.iter().enumerate() {
            encoder.copy_buffer_to_buffer(channel, 0, &readback, c as u64 * bytes, bytes);
        }
        let limbs: Vec<u32> = gpu
            .read_back(
                encoder,
                (&readback, 3 * bytes),
                bytemuck::pod_collect_to_vec,
            )
            .unwrap_or_else(|e| panic!("{e}: {:?}", gpu.failure()));
        limbs.chunks_exact(SUM_LIMBS).map(exact_sum).collect()
    }

    /// The device's exact sums are the CPU's `ExactSum`s bit for bit, however the
    /// invocations interleave their atomic additions: values of every sign and magnitude
    /// (zeros, subnormals, the largest floats, cancelling pairs) added at once to a few sums.
    #[test]
    fn device_sums_are_the_cpus_exact_sums() {
        let Some(gpu) = device_or_skip() else { return };
        let mut rng = Rng::new(7, 0);
        let mut values: Vec<f32> = (0..30_000)
            .map(|_| {
                let bits = rng.next_u32();
                // Any finite float: a non-finite one becomes its largest neighbour.
                let value = f32::from_bits(bits);
                if value.is_finite() {
                    value
                } else {
                    f32::MAX.copysign(value)
                }
            })
            .collect();
        values.extend([
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            1.0,
            -1.0,
            3.0e38,
        ]);
        let pixels = 4;
        let on_gpu = add_on_gpu(&gpu, &values, pixels);
        let mut on_cpu = vec![ExactSum::ZERO; 3 * pixels];
        for (i, &value) in values.iter().enumerate() {
            on_cpu[(i % 3) * pixels + (i / 3) % pixels].add_f32(value);
        }
        assert_eq!(on_gpu, on_cpu);
    }

    /// A scene of `scenes/` on `gpu`'s hierarchy.
    fn scene_on(gpu: &Arc<GpuDevice>, name: &str) -> (Arc<Scene>, GpuBvh) {
        let path =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenes/{name}.gltf"));
        let scene = Arc::new(Scene::load(&path).unwrap());
        let corners = scene.triangle_corners();
        let bvh = GpuBvh::new(Arc::clone(gpu), &corners, GpuBvhOptions::default()).unwrap();
        (scene, bvh)
    }

    /// The film of two frames of 3 samples per pixel of `algorithm` on `scene` at 24 × 18,
    /// rendered in dispatches of at most `paths` invocations, keeping at most `kept`
    /// vertices of each light path in the light pass's first run.
    fn film_of(
        algorithm: Algorithm,
        (scene, bvh): &(Arc<Scene>, GpuBvh),
        (paths, kept): (u64, u64),
    ) -> Film {
        let size = (24, 18);
        let (plan, sampling) = match algorithm {
            Algorithm::Pt => (
                FramePlan::PathTracing,
                Sampling::from(&PtSettings::new(size.0, size.1)),
            ),
            bidirectional => {
                let settings = VcmSettings::new(bidirectional, size.0, size.1);
                let plan = BidirPlan::new(bidirectional, &scene.features, false);
                let bidir = BidirFrames {
                    algorithm: bidirectional,
                    plan,
                    first_radius: 0.01,
                    alpha: settings.alpha,
                    light_paths: settings.light_paths() as u32,
                };
                let sampling = Sampling::of_bidir(&settings, &plan);
                (FramePlan::Bidirectional(bidir), sampling)
            }
        };
        let mut frames = GpuFrames::new(plan, Arc::clone(scene), bvh, size).unwrap();
        frames.set_paths_per_dispatch(paths);
        frames.set_kept_vertices(kept);
        let schedule = Schedule {
            samples_per_frame: 3,
            ..Schedule::ONE_BATCH
        };
        frames.set_schedule(schedule, "paths").unwrap();
        let mut film = Film::new(size.0, size.1);
        for frame in 0..2 {
            let stats = frames.render(&mut film, 3 * frame, ("test", &sampling), |_, _| {
                FrameStats::default()
            });
            assert!(!stats.interrupted, "{:?}", frames.failure());
            // The kernels' time, where the device has timestamps, is part of the frame's.
            let timed = frames.kernels[0].gpu.has_timestamps();
            assert_eq!(stats.device_time.is_zero(), !timed, "{stats:?}");
            assert!(stats.device_time <= stats.shading_time, "{stats:?}");
        }
        film
    }

    /// Each algorithm's film is the same bit for bit whether a frame's passes are one
    /// dispatch each or many (the device's sums are exact), and whether the light pass keeps
    /// a light path's first vertices or traces it again for all of them; and not black.
    #[test]
    fn the_film_does_not_depend_on_the_dispatches() {
        let Some(gpu) = device_or_skip().map(Arc::new) else {
            return;
        };
        let scene = scene_on(&gpu, "cornell-box");
        for algorithm in Algorithm::ALL {
            let whole = film_of(algorithm, &scene, (1 << 20, KEPT_VERTICES));
            for (paths, kept) in [(97, KEPT_VERTICES), (1 << 20, 0), (1 << 20, 1)] {
                let film = film_of(algorithm, &scene, (paths, kept));
                assert_eq!(film, whole, "{algorithm:?}, {paths} paths, {kept} kept");
            }
            assert!(whole.mean().iter().any(|p| p.max_element() > 0.0));
        }
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::PATH_TRACER_WGSL;
    use vcm_traversal_wgpu::NodeLayout;
    use vcm_traversal_wgpu::shader::{struct_size, traversal_functions};

    #[test]
    fn the_wavefronts_sizes_are_the_shaders() {
        // The structs' members come from the shared sources before the path tracer's.
        let traversal = traversal_functions(NodeLayout::Wide, 32, false);
        let module = crate::shader::kernel_module(Kernel::PathTracer, &traversal, false);
        assert!(module.contains(PATH_TRACER_WGSL));
        let size = |name| struct_size(&module, name).map(u64::from);
        assert_eq!(size("PathState"), Some(PATH_STATE_BYTES));
        assert_eq!(size("Wave"), Some(WAVE_BYTES));
    }
}
