//! `--algo auto`: the algorithm a scene is rendered with, chosen from short pilot renders.
//!
//! Each candidate — path tracing, BPT and, where the scene has specular or near-specular
//! surfaces for merging to serve, VCM — renders [`PILOT_FRAMES`] frames of one sample per
//! pixel of the image scaled down to at most [`PILOT_PIXELS`] pixels. Its *relative variance
//! per sample* is estimated from the spread of its frames per pixel,
//!
//!   v₁ = mean over pixels and channels of s² / (μ² + 0.01),
//!
//! with s² the frames' sample variance at the pixel, 0.01 the ε of relMSE, and μ the most
//! robust candidate's mean (the last: VCM, else BPT) averaged over the pixel's 3 × 3
//! neighbourhood — a denominator that a candidate's own fireflies cannot inflate. The frames
//! are the points of a stratified sequence, so the error of a mean of N of them falls faster
//! than v₁ / N where the integrand is smooth (path tracing's direct light) and not at all
//! faster where it is not (light paths landing in pixels at random). The pilot measures how
//! much: v₄, the same mean of 4 × the variance of the means of its two halves (frames 0–3 and
//! 4–7, each a stratified set), gives γ = ln(v₁ / v₄) / ln 4 (clamped to [0, 1]), and the
//! variance per sample after N samples is taken as v(N) = v₄ · (N / 4)^−γ. Its *cost per
//! sample* is the work its frames counted (rays and light vertices), weighted by
//! [`COST_WEIGHTS`]. After a time T a render's relMSE is about v(N) · cost / T, with N the
//! samples it renders in T; the candidates are compared at the time in which the cheapest
//! renders [`COMPARED_AT_SPP`] samples per pixel, and the one with the least v(N) · cost
//! wins — with v₄ taken two standard errors high, so that a variance resting on a few
//! pixels' rare paths does not win on luck.
//!
//! A candidate whose sample costs more than [`COMPARED_AT_SPP`] samples of the cheapest
//! piloted before it would not render one sample in the time compared at: its pilot stops
//! after its first frame and it is left out ([`Choice::too_costly`]), so that settings that
//! make one candidate hundreds of times dearer (`--connections 1024`) cost one pilot frame.
//!
//! The choice is a pure function of the scene, the options and the seed — counts, not clock
//! times, measure the cost — so shards of one render made on different machines choose the
//! same algorithm. With GPU shading the pilots are shaded on the GPU too ([`Pilots::Gpu`]),
//! by the kernels that render the image, and weighed with the same costs (the GPU's
//! variances are the CPU's up to rounding, which a near tie could tip). An image of fewer
//! than [`MIN_PILOTED_PIXELS`] is not piloted: at 16 samples per pixel its render would be
//! smaller than its pilots, and path tracing, the cheapest per sample, renders it.
//!
//! Where only merging finds all of the scene's light ([`only_merging_finds_all_light`]),
//! path tracing and BPT converge to an image without some of it, which no variance shows.
//! There VCM's pilot also measures what they miss: over blocks of 8 × 8 pixels, the squared
//! mean difference of their frames and VCM's, less the part the frames' noise gives it,
//! relative as v is; its mean over the blocks, b², is a relMSE that no number of samples
//! lowers. A render's relMSE after N samples is then v(N) / N + b², and they are compared
//! as (v(N) + N · b²) · cost (b² as estimated: [`Candidate::inefficiency`]). A small image
//! of such a scene renders VCM.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};
use vcm::metrics::RELMSE_EPSILON;
use vcm::{Film, FrameStats, RenderError, Schedule, StopFlag};
use vcm_gpu::GpuRenderError;
use vcm_scene::Scene;
use vcm_traversal::Traversal;
use vcm_traversal_wgpu::GpuBvh;

use super::{Algorithm, IntegratorOptions, MergeRadius, build, build_on_gpu};
use crate::{BuiltTraversal, Shading};

/// Frames (one sample per pixel each) every candidate renders: two halves of 4, each a
/// stratified set of the sequence's points.
pub const PILOT_FRAMES: u32 = 8;

/// Frames per half of a pilot: the block whose means measure how stratification lowers the
/// variance.
const HALF: usize = PILOT_FRAMES as usize / 2;

/// Samples per pixel the cheapest candidate renders in the time at which the candidates are
/// compared: a short render's worth (on the Cornell box path tracing reaches ~300 in 10 s
/// at 256²); the others render fewer in that time, as many fewer as they cost more.
pub const COMPARED_AT_SPP: f64 = 64.0;
/// Most pixels of a pilot render (128²): the image scaled down to them, or a smaller image
/// at its own size.
pub const PILOT_PIXELS: u32 = 128 * 128;

/// Fewest pixels of an image that is piloted (64²).
pub const MIN_PILOTED_PIXELS: u32 = 64 * 64;

/// What each unit of work a frame counts costs, relative to a closest-hit ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostWeights {
    /// A closest-hit ray (camera, continuation or light path segment) and its shading.
    pub closest_hit_ray: f64,
    /// An occlusion ray and the light sample or connection it tests.
    pub shadow_ray: f64,
    /// A light vertex stored in the cache (and, when merging, in the hash grid).
    pub light_vertex: f64,
    /// A camera vertex merged with the light vertices around it.
    pub merge: f64,
}

/// The cost model's weights: the least-squares fit of the ratios of the time per sample of
/// pt, bpt and vcm within each of the seven scenes in `scenes/` at 512² (each scene's own
/// scale left free: only a scene's candidates are compared; within 10 % of the measured
/// ratios on each; `docs/algorithms.md`).
pub const COST_WEIGHTS: CostWeights = CostWeights {
    closest_hit_ray: 1.0,
    shadow_ray: 0.8,
    light_vertex: 1.25,
    merge: 1.3,
};

/// One candidate's pilot: how much its samples vary and what they cost.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The algorithm piloted.
    pub algorithm: Algorithm,
    /// Relative variance per sample measured on single frames, v₁, and on the means of the
    /// pilot's two halves, v₄ (see the [module](self)).
    pub measured: [Estimate; 2],
    /// γ: how fast the variance per sample falls with the samples, v(N) ∝ N^−γ.
    pub stratification: f64,
    /// Samples per pixel it renders in the time the candidates are compared at.
    pub samples: f64,
    /// Relative variance per sample after [`Candidate::samples`], v(N) (see the
    /// [module](self)).
    pub relative_variance: Estimate,
    /// Cost of one sample per pixel, in closest-hit rays ([`COST_WEIGHTS`]).
    pub cost: f64,
    /// The relMSE its image keeps however long it renders, b², where only merging finds all
    /// of the light and the candidate does not merge (see the [module](self)).
    pub missed_light: Option<Estimate>,
    /// Wall-clock time of the pilot (reported; the choice does not depend on it).
    pub time: Duration,
}

impl Candidate {
    /// (v(N) + N · b²) · cost, with v two standard errors above its estimate: a render's
    /// relMSE after a given time, up to a factor common to every candidate, as high as the
    /// pilot leaves likely. The smaller, the better: a candidate whose low variance rests on
    /// a few pixels of a short pilot is not trusted with the render. b² is taken as
    /// estimated (at least 0): its standard error grows with VCM's own noise, and where
    /// VCM's pilot is noisy (fireflies on glossy models) a bound above it would charge the
    /// other candidates for that noise rather than for light they miss.
    pub fn inefficiency(&self) -> f64 {
        let missed = self.missed_light.map_or(0.0, |b2| b2.value.max(0.0));
        (self.relative_variance.upper() + self.samples * missed) * self.cost
    }
}

/// γ = ln(v₁ / v₄) / ln 4 from the relative variances per sample of single frames and of
/// 4-frame means, clamped to [0, 1] (0 where either is not positive: nothing to compare).
fn stratification(v1: f64, v4: f64) -> f64 {
    if v1 > 0.0 && v4 > 0.0 {
        ((v1 / v4).ln() / 4f64.ln()).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// v(N) = v₄ · (N / 4)^−γ, the value and its standard error alike.
fn variance_after(v4: Estimate, gamma: f64, samples: f64) -> Estimate {
    let factor = (samples / HALF as f64).powf(-gamma);
    Estimate {
        value: v4.value * factor,
        standard_error: v4.standard_error * factor,
    }
}

/// A quantity estimated from the pilot's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The mean over pixels.
    pub value: f64,
    /// Its standard error: the pixels' spread over √pixels.
    pub standard_error: f64,
}

impl Estimate {
    /// The value plus two standard errors.
    pub fn upper(&self) -> f64 {
        self.value + 2.0 * self.standard_error
    }
}

/// The algorithm chosen for a scene and the pilots it was chosen from.
#[derive(Clone, Debug)]
pub struct Choice {
    /// The candidate with the least [`Candidate::inefficiency`], or the algorithm chosen
    /// without pilots ([`Choice::unpiloted`]).
    pub algorithm: Algorithm,
    /// Every candidate piloted, in the order they ran (none where nothing was piloted).
    pub candidates: Vec<Candidate>,
    /// Candidates whose pilot stopped after its first frame, as a sample of theirs cost more
    /// than [`COMPARED_AT_SPP`] samples of the cheapest piloted before them (so that in the
    /// time the candidates are compared at they would not render one).
    pub too_costly: Vec<TooCostly>,
    /// (width, height) of the pilot renders.
    pub pilot_size: (u32, u32),
    /// Why the pilots did not choose, where they did not (a stop before the first pilot
    /// aside).
    pub unpiloted: Option<Unpiloted>,
}

/// A candidate left out after its pilot's first frame ([`Choice::too_costly`]).
#[derive(Clone, Debug)]
pub struct TooCostly {
    /// The algorithm.
    pub algorithm: Algorithm,
    /// Cost of one of its samples, in closest-hit rays ([`COST_WEIGHTS`]).
    pub cost: f64,
    /// Wall-clock time of its pilot.
    pub time: Duration,
}

/// Why an algorithm is chosen without pilots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unpiloted {
    /// The image has fewer than [`MIN_PILOTED_PIXELS`]: its pilots would take longer than
    /// its render. Path tracing renders it, the cheapest per sample.
    SmallImage,
    /// Only merging finds all of the scene's light ([`only_merging_finds_all_light`]) and
    /// the image is too small for pilots, or VCM's pilot did not finish (so nothing measures
    /// what the others miss): VCM renders it, the one candidate that converges to the whole
    /// image.
    OnlyMergingFindsAllLight,
}

impl Choice {
    /// Wall-clock time of all pilots, those left out included.
    pub fn time(&self) -> Duration {
        let left_out = self.too_costly.iter().map(|c| c.time);
        self.candidates.iter().map(|c| c.time).chain(left_out).sum()
    }
}

/// Whether only merging finds all of `scene`'s light: where a point, spot or directional
/// light shines through delta lobes (mirrors, smooth glass, smooth coats). A camera path
/// finds such light neither by a light sample (no light sample passes a delta lobe) nor by
/// a BSDF sample (which never hits a delta light), so path tracing misses every caustic of
/// it; BPT's light paths find the caustics seen directly, but not those seen through a delta
/// lobe in turn (a connection needs a non-delta vertex on each side). Both converge to an
/// image without that light, however long they render, and their pilots' variance says
/// nothing of it; VCM's merging finds it, and its pilot measures how much they miss.
pub fn only_merging_finds_all_light(scene: &Scene) -> bool {
    let lights = &scene.features.lights;
    let delta_lights = lights.point + lights.spot + lights.directional;
    delta_lights > 0 && scene.features.materials.specular
}

/// Where the pilots' paths are shaded: where the render's are.
#[derive(Clone, Copy)]
pub enum Pilots<'a> {
    /// On the CPU, tracing rays with this backend.
    Cpu(&'a Arc<dyn Traversal>),
    /// In the GPU kernels ([`build_on_gpu`]), on the GPU backend's hierarchy.
    Gpu(&'a GpuBvh),
}

impl<'a> Pilots<'a> {
    /// The pilots of a render shaded as `shading` says on `built`: GPU shading needs the GPU
    /// backend's hierarchy.
    pub fn of(built: &'a BuiltTraversal, shading: Shading) -> Result<Pilots<'a>, RenderError> {
        match (shading, &built.gpu) {
            (Shading::Cpu, _) => Ok(Pilots::Cpu(&built.traversal)),
            (Shading::Gpu, Some(bvh)) => Ok(Pilots::Gpu(bvh)),
            (Shading::Gpu, None) => Err(RenderError::InvalidSetting(
                "shading on the GPU needs the gpu backend, whose hierarchy it traces".into(),
            )),
        }
    }

    /// An integrator of `algorithm` for `scene` at `size` with `options`, shaded here.
    fn build(
        self,
        algorithm: Algorithm,
        scene: &Arc<Scene>,
        size: (u32, u32),
        options: &IntegratorOptions,
    ) -> Result<Box<dyn vcm::Integrator>, RenderError> {
        match self {
            Pilots::Cpu(traversal) => build(algorithm, scene, Arc::clone(traversal), size, options),
            Pilots::Gpu(bvh) => {
                build_on_gpu(algorithm, scene, bvh, size, options).map_err(|error| match error {
                    GpuRenderError::Render(error) => error,
                    other => RenderError::DeviceFailed(other.to_string()),
                })
            }
        }
    }
}

/// Chooses the algorithm to render `scene` with at `size` with `options` by piloting the
/// candidates, shaded where `shading` says (see the [module](self)). An image of fewer than
/// [`MIN_PILOTED_PIXELS`] is not piloted: path tracing renders it, or VCM where only merging
/// finds all of the scene's light ([`only_merging_finds_all_light`], [`Unpiloted`]).
/// Once `stop` is raised the pilot in progress is dropped, and those finished before it
/// choose.
pub fn choose(
    scene: &Arc<Scene>,
    shading: Pilots,
    size: (u32, u32),
    options: &IntegratorOptions,
    stop: &StopFlag,
) -> Result<Choice, RenderError> {
    let pilot_size = pilot_size(size);
    let unpiloted = |why: Option<Unpiloted>| Choice {
        algorithm: match why {
            Some(Unpiloted::OnlyMergingFindsAllLight) => Algorithm::Vcm,
            _ => Algorithm::Pt,
        },
        candidates: Vec::new(),
        too_costly: Vec::new(),
        pilot_size,
        unpiloted: why,
    };
    let merging_needed = only_merging_finds_all_light(scene);
    if u64::from(size.0) * u64::from(size.1) < u64::from(MIN_PILOTED_PIXELS) {
        return Ok(unpiloted(Some(match merging_needed {
            true => Unpiloted::OnlyMergingFindsAllLight,
            false => Unpiloted::SmallImage,
        })));
    }
    let options = pilot_options(options, size.0, pilot_size.0);
    let mut algorithms = vec![Algorithm::Pt, Algorithm::Bpt];
    if options.no_prune || scene.features.materials.specular_or_near() {
        algorithms.push(Algorithm::Vcm);
    }
    let mut pilots: Vec<Pilot> = Vec::new();
    let mut too_costly = Vec::new();
    let mut cheapest = f64::INFINITY;
    for &algorithm in &algorithms {
        // A sample may cost at most COMPARED_AT_SPP samples of the cheapest so far.
        let run = (algorithm, pilot_size, &options);
        match pilot(run, (scene, shading), cheapest * COMPARED_AT_SPP, stop)? {
            Outcome::Done(pilot) => {
                cheapest = cheapest.min(pilot.cost);
                pilots.push(pilot);
            }
            Outcome::TooCostly(left_out) => too_costly.push(left_out),
            Outcome::Stopped => break,
        }
    }
    let Some(robust) = pilots.last() else {
        return Ok(Choice {
            too_costly,
            ..unpiloted(None)
        });
    };
    if merging_needed && !robust.algorithm.merges() {
        return Ok(Choice {
            too_costly,
            ..unpiloted(Some(Unpiloted::OnlyMergingFindsAllLight))
        });
    }
    let mean = smoothed(&robust.mean, pilot_size);
    let candidates: Vec<_> = pilots
        .iter()
        .map(|pilot| {
            let measured = pilot
                .variance
                .each_ref()
                .map(|v| relative_variance(v, &mean));
            let gamma = stratification(measured[0].value, measured[1].value);
            let samples = COMPARED_AT_SPP * cheapest / pilot.cost;
            let missed_light = (merging_needed && !pilot.algorithm.merges())
                .then(|| missed_light(pilot, robust, &mean, pilot_size));
            Candidate {
                algorithm: pilot.algorithm,
                measured,
                stratification: gamma,
                samples,
                relative_variance: variance_after(measured[1], gamma, samples),
                cost: pilot.cost,
                missed_light,
                time: pilot.time,
            }
        })
        .collect();
    let best = candidates
        .iter()
        .min_by(|a, b| a.inefficiency().total_cmp(&b.inefficiency()))
        .expect("at least one pilot finished");
    Ok(Choice {
        algorithm: best.algorithm,
        pilot_size,
        candidates,
        too_costly,
        unpiloted: None,
    })
}

/// The pilots' image size for an image of `width` × `height`: the image scaled down to at
/// most [`PILOT_PIXELS`] pixels, with about its aspect ratio.
fn pilot_size((width, height): (u32, u32)) -> (u32, u32) {
    let pixels = f64::from(width) * f64::from(height);
    if pixels <= f64::from(PILOT_PIXELS) {
        return (width, height);
    }
    // Each side × √(PILOT_PIXELS / pixels), rounded down, at least 1 (and the other side
    // shortened to stay within PILOT_PIXELS where that made one side 1).
    let scale = (f64::from(PILOT_PIXELS) / pixels).sqrt();
    let side = |n: u32| ((f64::from(n) * scale) as u32).max(1);
    let pilot_width = side(width).min(PILOT_PIXELS);
    (pilot_width, side(height).min(PILOT_PIXELS / pilot_width))
}

/// The options of the pilots: the render's, with a merge radius of as many pilot pixels as
/// the render's is of its own, so that a merge finds about as many light vertices (a frame
/// traces one light path per pixel) as in the render.
fn pilot_options(options: &IntegratorOptions, width: u32, pilot_width: u32) -> IntegratorOptions {
    let radius = match options.radius {
        MergeRadius::SceneFraction(fraction) => {
            MergeRadius::SceneFraction(fraction * width as f32 / pilot_width as f32)
        }
        pixels @ MergeRadius::Pixels(_) => pixels,
    };
    IntegratorOptions {
        radius,
        ..options.clone()
    }
}

/// How a pilot ended.
enum Outcome {
    /// It rendered all its frames.
    Done(Pilot),
    /// Its samples cost more each than the limit it was given.
    TooCostly(TooCostly),
    /// A stop request cut a frame short.
    Stopped,
}

/// A candidate's pilot, reduced per pixel.
struct Pilot {
    /// The algorithm piloted.
    algorithm: Algorithm,
    /// Each frame's image.
    frames: Vec<Vec<Vec3>>,
    /// The mean of the frames.
    mean: Vec<DVec3>,
    /// The variance per sample from single frames, s² = Σ (x − x̄)² / (n − 1), the unbiased
    /// sample variance of one frame's value; and from the means of the two halves,
    /// 4 · (m₁ − m₂)² / 2, four times the unbiased sample variance of a half's mean.
    variance: [Vec<DVec3>; 2],
    /// Cost per sample ([`cost`]).
    cost: f64,
    time: Duration,
}

/// Renders `PILOT_FRAMES` frames of `algorithm` at `(width, height)`, each into a film of its
/// own; stops as soon as its samples so far cost more than `limit` each ([`cost`]), or when
/// `stop` cuts a frame short; an error if the device it traces or shades on failed.
fn pilot(
    (algorithm, (width, height), options): (Algorithm, (u32, u32), &IntegratorOptions),
    (scene, pilots): (&Arc<Scene>, Pilots),
    limit: f64,
    stop: &StopFlag,
) -> Result<Outcome, RenderError> {
    let start = Instant::now();
    let mut integrator = pilots.build(algorithm, scene, (width, height), options)?;
    integrator.set_schedule(Schedule::default())?;
    integrator.set_stop(stop.clone());
    let mut stats = FrameStats::default();
    let mut frames: Vec<Vec<Vec3>> = Vec::new();
    let mut cost_per_sample = 0.0;
    for sample in 0..PILOT_FRAMES {
        let mut film = Film::new(width, height);
        let frame = integrator.render_frame(&mut film, sample);
        if let Some(failure) = integrator.failure() {
            return Err(RenderError::DeviceFailed(failure));
        }
        if frame.interrupted {
            return Ok(Outcome::Stopped);
        }
        stats.accumulate(&frame);
        frames.push(film.mean());
        cost_per_sample =
            cost(&stats, algorithm) / (f64::from(width * height) * frames.len() as f64);
        if cost_per_sample > limit {
            return Ok(Outcome::TooCostly(TooCostly {
                algorithm,
                cost: cost_per_sample,
                time: start.elapsed(),
            }));
        }
    }
    let mut mean = Vec::new();
    let mut variance = [Vec::new(), Vec::new()];
    let pixel = |p: usize| -> [DVec3; PILOT_FRAMES as usize] {
        std::array::from_fn(|k| frames[k][p].as_dvec3())
    };
    for values in (0..frames[0].len()).map(pixel) {
        let (m, s2) = mean_and_variance(&values);
        let (first, second) = half_means(&values);
        let difference = first - second;
        mean.push(m);
        variance[0].push(s2);
        variance[1].push(HALF as f64 * difference * difference / 2.0);
    }
    Ok(Outcome::Done(Pilot {
        algorithm,
        frames,
        mean,
        variance,
        cost: cost_per_sample,
        time: start.elapsed(),
    }))
}

/// `image` (`width` × `height`) averaged over each pixel's 3 × 3 neighbourhood (within the
/// image).
fn smoothed(image: &[DVec3], (width, height): (u32, u32)) -> Vec<DVec3> {
    let (width, height) = (width as usize, height as usize);
    (0..width * height)
        .map(|pixel| {
            let (x, y) = (pixel % width, pixel / width);
            let xs = x.saturating_sub(1)..(x + 2).min(width);
            let ys = y.saturating_sub(1)..(y + 2).min(height);
            let count = xs.len() * ys.len();
            let sum: DVec3 = ys
                .flat_map(|y| xs.clone().map(move |x| image[y * width + x]))
                .sum();
            sum / count as f64
        })
        .collect()
}

/// v = mean over pixels and channels of s² / (μ² + ε), with its standard error.
fn relative_variance(variance: &[DVec3], mean: &[DVec3]) -> Estimate {
    let terms = variance.iter().zip(mean).map(|(&s2, &mu)| relative(s2, mu));
    mean_of(terms.collect())
}

/// Side in pixels of the blocks over which [`missed_light`] averages the differences.
const MISSED_LIGHT_BLOCK: usize = 8;

/// b² = mean over blocks of [`MISSED_LIGHT_BLOCK`]² pixels and channels of (d̄² − σ²) /
/// (μ² + ε): d̄ the mean over the block's pixels and the n frames of the difference of
/// `pilot`'s value and the `robust` pilot's, σ² the variance of that mean as the two halves
/// of the frames give it (Σ over the block's pixels of (h₀ − h₁)² / 4, h the halves' mean
/// differences, over the pixels squared), μ the block's mean of the smoothed robust mean;
/// relative as v is (see the [module](self)). Averaging over a block before squaring leaves
/// the missed light (which spreads over regions: caustics, their reflections) and divides
/// the noise by the block's pixels. The halves, each a stratified set as v₄'s are, see what
/// stratification takes off the noise; the frames' spread s²_d / n does not, and where the
/// two pilots share their smooth techniques (VCM's light samples and emission hits are path
/// tracing's) it overstated σ² enough to read b² = −4.1·10⁻⁵ ± 7.3·10⁻⁶ on the Khronos
/// Avocado.
fn missed_light(
    pilot: &Pilot,
    robust: &Pilot,
    mean: &[DVec3],
    (width, height): (u32, u32),
) -> Estimate {
    let (width, height) = (width as usize, height as usize);
    // Per pixel: the mean difference and the variance of that mean, from its halves.
    let pixel = |p: usize| {
        let d: [DVec3; PILOT_FRAMES as usize] =
            std::array::from_fn(|k| (pilot.frames[k][p] - robust.frames[k][p]).as_dvec3());
        let (first, second) = half_means(&d);
        // Var((h₀ + h₁) / 2) = Var(h) / 2, and E[(h₀ − h₁)²] = 2 Var(h).
        (
            (first + second) / 2.0,
            (first - second) * (first - second) / 4.0,
        )
    };
    let block = MISSED_LIGHT_BLOCK;
    let mut terms = Vec::new();
    for y0 in (0..height).step_by(block) {
        for x0 in (0..width).step_by(block) {
            let pixels: Vec<usize> = (y0..(y0 + block).min(height))
                .flat_map(|y| (x0..(x0 + block).min(width)).map(move |x| y * width + x))
                .collect();
            let count = pixels.len() as f64;
            let (mut d, mut variance, mut mu) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
            for &p in &pixels {
                let (d_p, variance_p) = pixel(p);
                d += d_p / count;
                variance += variance_p / (count * count);
                mu += mean[p] / count;
            }
            terms.push(relative(d * d - variance, mu));
        }
    }
    mean_of(terms)
}

/// The means of the first and the second half of a pixel's frame values.
fn half_means(values: &[DVec3]) -> (DVec3, DVec3) {
    let (first, second) = values.split_at(HALF);
    let mean = |half: &[DVec3]| half.iter().sum::<DVec3>() / half.len() as f64;
    (mean(first), mean(second))
}

/// The mean of a pixel's frame values and their unbiased sample variance,
/// s² = Σ (x − x̄)² / (n − 1).
fn mean_and_variance(values: &[DVec3]) -> (DVec3, DVec3) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<DVec3>() / n;
    let squares = values
        .iter()
        .map(|&x| (x - mean) * (x - mean))
        .sum::<DVec3>();
    (mean, squares / (n - 1.0))
}

/// x / (μ² + ε), averaged over the channels.
fn relative(x: DVec3, mu: DVec3) -> f64 {
    (x / (mu * mu + RELMSE_EPSILON)).element_sum() / 3.0
}

/// The mean of `terms`, with its standard error.
fn mean_of(terms: Vec<f64>) -> Estimate {
    let n = terms.len() as f64;
    let value = terms.iter().sum::<f64>() / n;
    // The terms' sample variance Σ (t − v)² / (n − 1), over n for the mean's.
    let spread = terms.iter().map(|t| (t - value) * (t - value)).sum::<f64>() / (n - 1.0).max(1.0);
    Estimate {
        value,
        standard_error: (spread / n).sqrt(),
    }
}

/// The cost of the work in `stats` ([`COST_WEIGHTS`]): every closest-hit and occlusion ray,
/// every cached light vertex and, for algorithms that merge, every camera-path vertex.
fn cost(stats: &FrameStats, algorithm: Algorithm) -> f64 {
    let w = &COST_WEIGHTS;
    let camera_vertices = stats.camera_rays + stats.continuation_rays;
    let closest_hits = camera_vertices + stats.light_rays;
    let merges = if algorithm.merges() {
        camera_vertices
    } else {
        0
    };
    w.closest_hit_ray * closest_hits as f64
        + w.shadow_ray * stats.shadow_rays as f64
        + w.light_vertex * stats.light_vertices as f64
        + w.merge * merges as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pilots_have_at_most_pilot_pixels_with_the_image_aspect() {
        assert_eq!(pilot_size((512, 512)), (128, 128));
        assert_eq!(pilot_size((100, 50)), (100, 50));
        let (w, h) = pilot_size((1024, 768));
        assert!((w, h) == (147, 110) && w * h <= PILOT_PIXELS, "{w}×{h}");
        assert_eq!(pilot_size((1, 1 << 20)), (1, 16384));
    }

    #[test]
    fn a_scene_fraction_radius_spans_as_many_pixels_in_the_pilot() {
        let options = IntegratorOptions {
            radius: MergeRadius::SceneFraction(0.003),
            ..IntegratorOptions::default()
        };
        let pilot = pilot_options(&options, 512, 128);
        assert_eq!(pilot.radius, MergeRadius::SceneFraction(0.012));
        let pixels = IntegratorOptions::default();
        assert_eq!(pilot_options(&pixels, 512, 128).radius, pixels.radius);
    }

    #[test]
    fn relative_variance_weighs_each_pixel_by_its_mean() {
        // Pixel 0: s² 1 over μ² + ε = 1.01; pixel 1: s² 0.01 over μ 0 → 0.01 / 0.01 = 1.
        let variance = [DVec3::splat(1.0), DVec3::splat(0.01)];
        let mean = [DVec3::splat(1.0), DVec3::ZERO];
        let v = relative_variance(&variance, &mean);
        let terms = [1.0 / 1.01, 1.0];
        assert!((v.value - (terms[0] + terms[1]) / 2.0).abs() < 1e-12);
        // Two terms: standard error |t₀ − t₁| / 2.
        assert!((v.standard_error - (terms[1] - terms[0]) / 2.0).abs() < 1e-12);
        assert_eq!(v.upper(), v.value + 2.0 * v.standard_error);
    }

    /// A pilot of `algorithm` rendering `frames`, its means and variances left empty.
    fn pilot_of(algorithm: Algorithm, frames: Vec<Vec<Vec3>>) -> Pilot {
        Pilot {
            algorithm,
            frames,
            mean: Vec::new(),
            variance: [Vec::new(), Vec::new()],
            cost: 1.0,
            time: Duration::ZERO,
        }
    }

    #[test]
    fn missed_light_is_the_squared_relative_difference_of_the_means_less_their_noise() {
        let side = 128;
        // Independent uniform noise in [−0.5, 0.5) per frame and pixel (an LCG).
        let mut state = 12345u64;
        let mut noise = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let mut frames = |offset: &dyn Fn(usize) -> f32, noisy: bool| -> Vec<Vec<Vec3>> {
            (0..PILOT_FRAMES)
                .map(|_| {
                    (0..side * side)
                        .map(|p| Vec3::splat(1.0 + offset(p) + if noisy { noise() } else { 0.0 }))
                        .collect()
                })
                .collect()
        };
        let robust = pilot_of(Algorithm::Vcm, frames(&|_| 0.0, true));
        let mean = vec![DVec3::ONE; side * side];
        // The robust frames less 0.5 on the left half: b² = ½ · 0.5² / (1 + ε) exactly.
        let left = |p: usize| if p % side < side / 2 { -0.5 } else { 0.0 };
        let shifted: Vec<Vec<Vec3>> = robust
            .frames
            .iter()
            .map(|frame| {
                frame
                    .iter()
                    .enumerate()
                    .map(|(p, &x)| x + left(p))
                    .collect()
            })
            .collect();
        let missing = pilot_of(Algorithm::Pt, shifted);
        let b2 = missed_light(&missing, &robust, &mean, (side as u32, side as u32));
        let expected = 0.5 * 0.25 / (1.0 + RELMSE_EPSILON);
        assert!((b2.value - expected).abs() < 1e-6, "{b2:?}");
        // The same light with noise of its own: nothing missed, within the noise (4
        // standard errors: the blocks' terms are skewed, as squares of normal variables
        // less their mean). Without the noise term each block would add Var(d̄) = (1/6) / 8
        // / 64 ≈ 3.3·10⁻⁴.
        let unbiased = pilot_of(Algorithm::Pt, frames(&|_| 0.0, true));
        let b2 = missed_light(&unbiased, &robust, &mean, (side as u32, side as u32));
        assert!(b2.value.abs() < 4.0 * b2.standard_error, "{b2:?}");
        assert!(b2.value.abs() < 3.3e-5, "{b2:?}");
    }

    #[test]
    fn stratification_is_the_fall_of_the_variance_per_sample_from_one_frame_to_four() {
        // v₄ = v₁ / 2: γ = ln 2 / ln 4 = 1/2, and v(16) = v₄ · 4^−½ = v₄ / 2.
        let gamma = stratification(0.4, 0.2);
        assert!((gamma - 0.5).abs() < 1e-12);
        let v4 = Estimate {
            value: 0.2,
            standard_error: 0.02,
        };
        let v16 = variance_after(v4, gamma, 16.0);
        assert!((v16.value - 0.1).abs() < 1e-12 && (v16.standard_error - 0.01).abs() < 1e-12);
        // At 4 samples, v₄ itself; below, more (towards v₁ at 1).
        assert_eq!(variance_after(v4, gamma, 4.0), v4);
        assert!((variance_after(v4, gamma, 1.0).value - 0.4).abs() < 1e-12);
        // Halves noisier than single frames (no stratification) give γ 0, never a negative
        // one; nor does a zero variance; and γ stays at most 1.
        assert_eq!(stratification(0.2, 0.3), 0.0);
        assert_eq!(stratification(0.0, 0.3), 0.0);
        assert_eq!(stratification(0.3, 0.0), 0.0);
        assert_eq!(stratification(1.0, 1e-6), 1.0);
    }

    #[test]
    fn smoothing_averages_the_neighbours_within_the_image() {
        let image: Vec<_> = (0..6).map(|i| DVec3::splat(f64::from(i))).collect();
        // 3 × 2: the corner (0, 0) averages pixels 0, 1, 3, 4; the middle of the top row all 6.
        let smooth = smoothed(&image, (3, 2));
        assert_eq!(smooth[0], DVec3::splat(2.0));
        assert_eq!(smooth[1], DVec3::splat(2.5));
    }

    #[test]
    fn merging_costs_each_camera_vertex_and_every_kind_of_work_has_its_weight() {
        let stats = FrameStats {
            camera_rays: 10,
            continuation_rays: 20,
            light_rays: 30,
            shadow_rays: 40,
            light_vertices: 50,
            ..FrameStats::default()
        };
        let bpt = 60.0 + 0.8 * 40.0 + 1.25 * 50.0;
        assert_eq!(cost(&stats, Algorithm::Bpt), bpt);
        assert_eq!(cost(&stats, Algorithm::Vcm), bpt + 1.3 * 30.0);
    }
}
