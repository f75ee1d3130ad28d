//! [`GpuFrames`]: what every GPU integrator does with a frame — dispatches of consecutive
//! invocations of its kernel, which add their samples and splats to the film on the device
//! (`film.wgsl`: exact sums, the same whatever the order), and the film read back and merged
//! into the render's once the frame is whole — and the state that goes with it.

use std::sync::Arc;

use vcm::exact_sum::{ExactSum, WORDS};
use vcm::{Film, FrameStats, PixelSum, RenderError, Schedule, StopFlag};
use vcm_scene::Scene;
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::kernel::{LightPass, Params, Sampling, SceneKernel, check_host_estimate, film_estimate};
use crate::shader::Kernel;

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

/// How a frame runs its kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FramePlan {
    /// One kernel, an invocation per pixel and sample (path tracing, light tracing).
    OnePass(Kernel),
    /// The light pass counting its light vertices, then storing them in the cache, then the
    /// camera pass connecting to them (bidirectional path tracing).
    Bidirectional,
}

/// A GPU integrator's kernels, its frames' film on the device, and the state of its frames.
pub(crate) struct GpuFrames {
    /// The kernels: the one pass's, or the light pass's and the camera pass's.
    pub kernels: Vec<SceneKernel>,
    plan: FramePlan,
    /// The image size.
    pub size: (u32, u32),
    paths_per_dispatch: u64,
    buffers: FrameBuffers,
    samples_per_frame: u32,
    stop: StopFlag,
    /// What failed on the GPU, once something has: no frame renders after it.
    failure: Option<String>,
}

/// The dispatches' parameters, the film's sums per channel, the dropped samples and the ray
/// counts, their read-back copy, the light vertex cache and its index, and the bind groups
/// of each kernel.
struct FrameBuffers {
    params: wgpu::Buffer,
    /// The sums of each channel, then the dropped samples, then the ray counts: what a frame
    /// clears and reads back, in the read-back's order.
    outputs: [wgpu::Buffer; 5],
    readback: wgpu::Buffer,
    /// Per light path of the frame its vertices' count or first slot, then per iteration its
    /// first vertex and count (`vertex_index` of bidir.wgsl).
    index: wgpu::Buffer,
    index_readback: wgpu::Buffer,
    /// The light vertices (`cache` of bidir.wgsl).
    cache: wgpu::Buffer,
    /// Bind group 0 of each kernel.
    groups: Vec<wgpu::BindGroup>,
}

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
            FramePlan::OnePass(kernel) => vec![SceneKernel::new(kernel, scene, bvh)?],
            FramePlan::Bidirectional => {
                let light = SceneKernel::new(Kernel::LightTracer, scene, bvh)?;
                let camera = light.sibling(Kernel::BidirCamera);
                vec![light, camera]
            }
        };
        let buffers = FrameBuffers::new(&kernels, channel_bytes);
        Ok(GpuFrames {
            kernels,
            plan,
            size,
            paths_per_dispatch,
            buffers,
            samples_per_frame: 1,
            stop: StopFlag::new(),
            failure: None,
        })
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
        match self.render_frame(first_sample, sampling) {
            Ok(Some((frame, rays, invocations))) => {
                // Exact sums: the same film as adding each sample and splat to `film`.
                film.merge(&frame);
                FrameStats {
                    shading_time: start.elapsed(),
                    ..stats(rays, invocations)
                }
            }
            Ok(None) => FrameStats::INTERRUPTED,
            Err(error) => {
                self.failure = Some(format!("{algorithm} on the GPU: {error}"));
                FrameStats::INTERRUPTED
            }
        }
    }

    /// The frame's film, rays and invocations per pass; `None` where it was stopped.
    fn render_frame(
        &mut self,
        first_sample: u32,
        sampling: &Sampling,
    ) -> Result<Option<(Film, [u64; 3], u64)>, String> {
        let (width, height) = self.size;
        let samples = self.samples_per_frame;
        let invocations = u64::from(width) * u64::from(height) * u64::from(samples);
        let frame = (first_sample, samples);
        let pass = |light_pass| (sampling, light_pass);
        let done = match self.plan {
            FramePlan::OnePass(_) => {
                self.run_pass(0, pass(LightPass::LightTracing), frame, true)?
            }
            FramePlan::Bidirectional => {
                // A count per light path, then a first vertex and a count per iteration.
                let bytes = 4 * (invocations + 2 * u64::from(samples));
                if bytes > self.kernels[0].gpu.max_binding_bytes() {
                    return Err(format!(
                        "{invocations} light paths a frame need an index of {bytes} bytes, \
                         more than the device can bind: render fewer samples per frame"
                    ));
                }
                if bytes > self.buffers.index.size() {
                    self.buffers.grow_index(&self.kernels, bytes);
                }
                self.run_pass(0, pass(LightPass::CountVertices), frame, true)?
                    && self.index_vertices(invocations as usize, samples as usize)?
                    && self.run_pass(0, pass(LightPass::StoreVertices), frame, false)?
                    && self.run_pass(1, pass(LightPass::LightTracing), frame, false)?
            }
        };
        if !done {
            return Ok(None);
        }
        self.read_film(samples)
            .map(|(film, rays)| Some((film, rays, invocations)))
    }

    /// Runs kernel `kernel` with `sampling` and `light_pass` over every invocation of
    /// `frame`, clearing the outputs first where `clear`; `false` where a stop request cut
    /// it short.
    fn run_pass(
        &self,
        kernel: usize,
        (sampling, light_pass): (&Sampling, LightPass),
        frame: (u32, u32),
        clear: bool,
    ) -> Result<bool, String> {
        let b = &self.buffers;
        let (width, height) = self.size;
        let invocations = u64::from(width) * u64::from(height) * u64::from(frame.1);
        let mut cleared: Vec<&wgpu::Buffer> = if clear {
            b.outputs.iter().collect()
        } else {
            Vec::new()
        };
        let scene_kernel = &self.kernels[kernel];
        let gpu = &scene_kernel.gpu;
        for first in (0..invocations).step_by(self.paths_per_dispatch as usize) {
            if self.stop.is_raised() || self.failure.is_some() {
                return Ok(false);
            }
            let range = (first, self.paths_per_dispatch.min(invocations - first));
            let dispatch = (&b.params, &b.groups[kernel]);
            let pass = (sampling, light_pass);
            let encoder = scene_kernel.encode(dispatch, pass, frame, range, &cleared);
            // The first dispatch clears the outputs; the others add to them.
            cleared.clear();
            gpu.wait(gpu.queue.submit([encoder.finish()]))?;
        }
        Ok(true)
    }

    /// Turns the light vertices each of the frame's `paths` light paths counted into where
    /// they go in the cache — iteration by iteration (`samples` of them), each iteration's
    /// in the order of its paths, as the CPU's cache keeps them — and makes room for them
    /// (always `true`, to chain with the passes).
    fn index_vertices(&mut self, paths: usize, samples: usize) -> Result<bool, String> {
        let gpu = Arc::clone(&self.kernels[0].gpu);
        let b = &self.buffers;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let count_bytes = 4 * paths as u64;
        encoder.copy_buffer_to_buffer(&b.index, 0, &b.index_readback, 0, count_bytes);
        let counts: Vec<u32> = gpu.read_back(
            encoder,
            (&b.index_readback, count_bytes),
            bytemuck::pod_collect_to_vec,
        )?;
        let mut index = vec![0u32; paths + 2 * samples];
        let mut total = 0u64;
        for sample in 0..samples {
            let first = total;
            // Path number p = pixel · samples + sample.
            for path in (sample..paths).step_by(samples) {
                index[path] = total as u32;
                total += u64::from(counts[path]);
            }
            index[paths + 2 * sample] = first as u32;
            index[paths + 2 * sample + 1] = (total - first) as u32;
        }
        let cache_bytes = total.max(1) * size_of::<LightVertex>() as u64;
        if cache_bytes > gpu.max_binding_bytes() || total > u64::from(u32::MAX) {
            return Err(format!(
                "the frame's {total} light vertices take {cache_bytes} bytes, more than the \
                 device can bind ({} bytes): render fewer samples per frame or a smaller image",
                gpu.max_binding_bytes()
            ));
        }
        if cache_bytes > self.buffers.cache.size() {
            self.buffers.grow_cache(&self.kernels, cache_bytes);
        }
        gpu.queue
            .write_buffer(&self.buffers.index, 0, bytemuck::cast_slice(&index));
        Ok(true)
    }

    /// The frame's film of `samples` per pixel and the rays traced, read back.
    fn read_film(&self, samples: u32) -> Result<(Film, [u64; 3]), String> {
        let (width, height) = self.size;
        let b = &self.buffers;
        let gpu = &self.kernels[0].gpu;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let mut at = 0;
        for buffer in &b.outputs {
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

    /// Takes the samples per pixel per frame of `schedule` (its scheduler, a CPU matter,
    /// does not apply), which must number a frame's invocations (`what`) in 32 bits.
    pub fn set_schedule(&mut self, schedule: Schedule, what: &str) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        let (width, height) = self.size;
        let count = u64::from(width) * u64::from(height) * u64::from(schedule.samples_per_frame);
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
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct LightVertex {
    position: [f32; 3],
    path_length: u32,
    wo: [f32; 3],
    triangle: u32,
    throughput: [f32; 3],
    u: f32,
    mis: [f32; 3],
    v: f32,
}

impl FrameBuffers {
    /// Buffers for the frames of `kernels` with `channel_bytes` of sums per channel; the
    /// cache and its index hold nothing yet.
    fn new(kernels: &[SceneKernel], channel_bytes: u64) -> FrameBuffers {
        use wgpu::BufferUsages as U;
        let kernel = &kernels[0];
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        let params = kernel.buffer(
            "frame parameters",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let [red, green, blue] = ["film red", "film green", "film blue"]
            .map(|label| kernel.buffer(label, channel_bytes, output));
        let dropped = kernel.buffer("dropped samples", 4, output);
        let rays = kernel.buffer("ray counts", RAY_COUNT_BYTES, output);
        let outputs = [red, green, blue, dropped, rays];
        let readback = kernel.buffer(
            "film read-back",
            outputs.iter().map(wgpu::Buffer::size).sum(),
            U::MAP_READ | U::COPY_DST,
        );
        // Room for nothing yet: the frames make it.
        let index = kernel.buffer("light vertex index", 16, output);
        let index_readback = kernel.buffer("light vertex counts", 16, U::MAP_READ | U::COPY_DST);
        let cache = kernel.buffer(
            "light vertex cache",
            size_of::<LightVertex>() as u64,
            output,
        );
        let mut buffers = FrameBuffers {
            params,
            outputs,
            readback,
            index,
            index_readback,
            cache,
            groups: Vec::new(),
        };
        buffers.bind(kernels);
        buffers
    }

    /// (Re)makes each kernel's bind group 0: 0 the parameters, 1–3 the channels, 4 the
    /// dropped samples, 5 the rays, and where it reads them 6 the index and 7 the cache.
    fn bind(&mut self, kernels: &[SceneKernel]) {
        self.groups = kernels
            .iter()
            .map(|kernel| {
                let film = [&self.params].into_iter().chain(&self.outputs);
                if kernel.kind.uses_cache() {
                    kernel.bind(0, film.chain([&self.index, &self.cache]))
                } else {
                    kernel.bind(0, film)
                }
            })
            .collect();
    }

    /// A cache of `bytes`, bound to `kernels`.
    fn grow_cache(&mut self, kernels: &[SceneKernel], bytes: u64) {
        use wgpu::BufferUsages as U;
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        self.cache = kernels[0].buffer("light vertex cache", bytes, output);
        self.bind(kernels);
    }

    /// An index of `bytes` and its read-back copy, bound to `kernels`.
    fn grow_index(&mut self, kernels: &[SceneKernel], bytes: u64) {
        use wgpu::BufferUsages as U;
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        self.index = kernels[0].buffer("light vertex index", bytes, output);
        self.index_readback =
            kernels[0].buffer("light vertex counts", bytes, U::MAP_READ | U::COPY_DST);
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
    /// rendered in dispatches of at most `paths` invocations.
    fn film_of(algorithm: Algorithm, (scene, bvh): &(Arc<Scene>, GpuBvh), paths: u64) -> Film {
        let size = (24, 18);
        let (plan, sampling) = match algorithm {
            Algorithm::Pt => (
                FramePlan::OnePass(Kernel::PathTracer),
                Sampling::from(&PtSettings::new(size.0, size.1)),
            ),
            bidirectional => (
                match bidirectional {
                    Algorithm::LightTracing => FramePlan::OnePass(Kernel::LightTracer),
                    _ => FramePlan::Bidirectional,
                },
                Sampling::from(&VcmSettings::new(bidirectional, size.0, size.1)),
            ),
        };
        let mut frames = GpuFrames::new(plan, Arc::clone(scene), bvh, size).unwrap();
        frames.set_paths_per_dispatch(paths);
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
        }
        film
    }

    /// Each algorithm's film is the same bit for bit whether a frame's passes are one
    /// dispatch each or many (the device's sums are exact), and not black.
    #[test]
    fn the_film_does_not_depend_on_the_dispatches() {
        let Some(gpu) = device_or_skip().map(Arc::new) else {
            return;
        };
        let scene = scene_on(&gpu, "cornell-box");
        for algorithm in [Algorithm::Pt, Algorithm::LightTracing, Algorithm::Bpt] {
            let whole = film_of(algorithm, &scene, 1 << 20);
            assert_eq!(film_of(algorithm, &scene, 97), whole, "{algorithm:?}");
            assert!(whole.mean().iter().any(|p| p.max_element() > 0.0));
        }
    }
}
