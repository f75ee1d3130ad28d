//! `--algo auto`: the algorithm a scene is rendered with, chosen from short pilot renders.
//!
//! Each candidate — path tracing, BPT and, where the scene has specular or near-specular
//! surfaces for merging to serve, VCM — renders [`PILOT_FRAMES`] frames of one sample per
//! pixel of the image scaled down to at most [`PILOT_PIXELS`] pixels. Its *relative variance per sample* is
//! estimated from the spread of its frames per pixel,
//!
//!   v = mean over pixels and channels of s² / (μ² + 0.01),
//!
//! with s² the frames' sample variance at the pixel, 0.01 the ε of relMSE, and μ the most
//! robust candidate's mean (the last: VCM, else BPT) averaged over the pixel's 3 × 3
//! neighbourhood — a denominator that a candidate's own fireflies cannot inflate. Its *cost
//! per sample* is the work its frames counted (rays and light vertices), weighted by
//! [`COST_WEIGHTS`]. After a time T a render's relMSE is about v · cost / T, so the
//! candidate with the least v · cost wins — with v taken two standard errors high, so that
//! a variance resting on a few pixels' rare paths does not win on luck.
//!
//! The choice is a pure function of the scene, the options and the seed — counts, not clock
//! times, measure the cost — so shards of one render made on different machines choose the
//! same algorithm. An image of fewer than [`MIN_PILOTED_PIXELS`] is not piloted: at 16
//! samples per pixel its render would be smaller than its pilots, and path tracing, the
//! cheapest per sample, renders it. Where only merging finds all of the scene's light
//! ([`only_merging_finds_all_light`]), VCM renders without pilots.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};
use vcm::metrics::RELMSE_EPSILON;
use vcm::{Film, FrameStats, RenderError, Schedule, StopFlag};
use vcm_scene::Scene;
use vcm_traversal::Traversal;

use super::{Algorithm, IntegratorOptions, MergeRadius, build};

/// Frames (one sample per pixel each) every candidate renders.
pub const PILOT_FRAMES: u32 = 8;
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

/// The cost model's weights: the least-squares fit of the time per sample of pt, bpt and vcm
/// on the six scenes in `scenes/` at 512² (to within 12 % on each; `docs/algorithms.md`).
pub const COST_WEIGHTS: CostWeights = CostWeights {
    closest_hit_ray: 1.0,
    shadow_ray: 1.0,
    light_vertex: 0.5,
    merge: 1.8,
};

/// One candidate's pilot: how much its samples vary and what they cost.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The algorithm piloted.
    pub algorithm: Algorithm,
    /// Relative variance of one sample per pixel, v (see the [module](self)).
    pub relative_variance: Estimate,
    /// Cost of one sample per pixel, in closest-hit rays ([`COST_WEIGHTS`]).
    pub cost: f64,
    /// Wall-clock time of the pilot (reported; the choice does not depend on it).
    pub time: Duration,
}

impl Candidate {
    /// v · cost, with v two standard errors above its estimate: a render's relMSE after a
    /// given time, up to a factor common to every candidate, as high as the pilot leaves
    /// likely. The smaller, the better: a candidate whose low variance rests on a few pixels
    /// of a short pilot is not trusted with the render.
    pub fn inefficiency(&self) -> f64 {
        self.relative_variance.upper() * self.cost
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
    /// (width, height) of the pilot renders.
    pub pilot_size: (u32, u32),
    /// Why nothing was piloted, where nothing was (a stop before the first pilot aside).
    pub unpiloted: Option<Unpiloted>,
}

/// Why an algorithm is chosen without pilots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unpiloted {
    /// The image has fewer than [`MIN_PILOTED_PIXELS`]: its pilots would take longer than
    /// its render. Path tracing renders it, the cheapest per sample.
    SmallImage,
    /// Only merging finds all of the scene's light ([`only_merging_finds_all_light`]): VCM
    /// renders it, the one candidate that converges to the whole image.
    OnlyMergingFindsAllLight,
}

impl Choice {
    /// Wall-clock time of all pilots.
    pub fn time(&self) -> Duration {
        self.candidates.iter().map(|c| c.time).sum()
    }
}

/// Whether only merging finds all of `scene`'s light: where a point, spot or directional
/// light shines through delta lobes (mirrors, smooth glass, smooth coats). A camera path
/// finds such light neither by a light sample (no light sample passes a delta lobe) nor by
/// a BSDF sample (which never hits a delta light), so path tracing misses every caustic of
/// it; BPT's light paths find the caustics seen directly, but not those seen through a delta
/// lobe in turn (a connection needs a non-delta vertex on each side). Both converge to an
/// image without that light, however long they render, and their pilots' variance says
/// nothing of it; VCM's merging finds it.
pub fn only_merging_finds_all_light(scene: &Scene) -> bool {
    let lights = &scene.features.lights;
    let delta_lights = lights.point + lights.spot + lights.directional;
    delta_lights > 0 && scene.features.materials.specular
}

/// Chooses the algorithm to render `scene` with at `size` with `options` by piloting the
/// candidates (see the [module](self)). Where only merging finds all of the scene's light
/// ([`only_merging_finds_all_light`]) VCM is chosen without pilots; an image of fewer than
/// [`MIN_PILOTED_PIXELS`] is not piloted either: path tracing renders it ([`Unpiloted`]).
/// Once `stop` is raised the pilot in progress is dropped, and those finished before it
/// choose.
pub fn choose(
    scene: &Arc<Scene>,
    traversal: &Arc<dyn Traversal>,
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
        pilot_size,
        unpiloted: why,
    };
    if only_merging_finds_all_light(scene) {
        return Ok(unpiloted(Some(Unpiloted::OnlyMergingFindsAllLight)));
    }
    if u64::from(size.0) * u64::from(size.1) < u64::from(MIN_PILOTED_PIXELS) {
        return Ok(unpiloted(Some(Unpiloted::SmallImage)));
    }
    let options = pilot_options(options, size.0, pilot_size.0);
    let mut algorithms = vec![Algorithm::Pt, Algorithm::Bpt];
    if options.no_prune || scene.features.materials.specular_or_near() {
        algorithms.push(Algorithm::Vcm);
    }
    let mut pilots = Vec::new();
    for &algorithm in &algorithms {
        match pilot(algorithm, scene, traversal, (pilot_size, &options), stop)? {
            Some(pilot) => pilots.push(pilot),
            None => break,
        }
    }
    algorithms.truncate(pilots.len());
    let Some(robust) = pilots.last() else {
        return Ok(unpiloted(None));
    };
    let mean = smoothed(&robust.mean, pilot_size);
    let candidates: Vec<_> = algorithms
        .iter()
        .zip(&pilots)
        .map(|(&algorithm, pilot)| Candidate {
            algorithm,
            relative_variance: relative_variance(&pilot.variance, &mean),
            cost: cost(&pilot.stats, algorithm) / (mean.len() as f64 * f64::from(PILOT_FRAMES)),
            time: pilot.time,
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

/// A candidate's pilot, reduced per pixel.
struct Pilot {
    /// The mean of the frames.
    mean: Vec<DVec3>,
    /// s² = Σ (x − x̄)² / (n − 1): the unbiased sample variance of one frame's value.
    variance: Vec<DVec3>,
    stats: FrameStats,
    time: Duration,
}

/// Renders `PILOT_FRAMES` frames of `algorithm`, each into a film of its own; `None` if
/// `stop` cut one short, an error if the device it traces or shades on failed.
fn pilot(
    algorithm: Algorithm,
    scene: &Arc<Scene>,
    traversal: &Arc<dyn Traversal>,
    ((width, height), options): ((u32, u32), &IntegratorOptions),
    stop: &StopFlag,
) -> Result<Option<Pilot>, RenderError> {
    let start = Instant::now();
    let mut integrator = build(
        algorithm,
        scene,
        Arc::clone(traversal),
        (width, height),
        options,
    )?;
    integrator.set_schedule(Schedule::default())?;
    integrator.set_stop(stop.clone());
    let mut stats = FrameStats::default();
    let mut frames: Vec<Vec<Vec3>> = Vec::new();
    for sample in 0..PILOT_FRAMES {
        let mut film = Film::new(width, height);
        let frame = integrator.render_frame(&mut film, sample);
        if let Some(failure) = integrator.failure() {
            return Err(RenderError::DeviceFailed(failure));
        }
        if frame.interrupted {
            return Ok(None);
        }
        stats.accumulate(&frame);
        frames.push(film.mean());
    }
    let n = f64::from(PILOT_FRAMES);
    let (mean, variance) = (0..frames[0].len())
        .map(|pixel| {
            let values = frames.iter().map(|frame| frame[pixel].as_dvec3());
            let mean = values.clone().sum::<DVec3>() / n;
            let squares = values.map(|x| (x - mean) * (x - mean)).sum::<DVec3>();
            (mean, squares / (n - 1.0))
        })
        .unzip();
    Ok(Some(Pilot {
        mean,
        variance,
        stats,
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
    let terms: Vec<f64> = variance
        .iter()
        .zip(mean)
        .map(|(&s2, &mu)| (s2 / (mu * mu + RELMSE_EPSILON)).element_sum() / 3.0)
        .collect();
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

    #[test]
    fn smoothing_averages_the_neighbours_within_the_image() {
        let image: Vec<_> = (0..6).map(|i| DVec3::splat(f64::from(i))).collect();
        // 3 × 2: the corner (0, 0) averages pixels 0, 1, 3, 4; the middle of the top row all 6.
        let smooth = smoothed(&image, (3, 2));
        assert_eq!(smooth[0], DVec3::splat(2.0));
        assert_eq!(smooth[1], DVec3::splat(2.5));
    }

    #[test]
    fn merging_costs_each_camera_vertex_and_light_vertices_cost_half_a_ray() {
        let stats = FrameStats {
            camera_rays: 10,
            continuation_rays: 20,
            light_rays: 30,
            shadow_rays: 40,
            light_vertices: 50,
            ..FrameStats::default()
        };
        assert_eq!(cost(&stats, Algorithm::Bpt), 60.0 + 40.0 + 25.0);
        assert_eq!(
            cost(&stats, Algorithm::Vcm),
            60.0 + 40.0 + 25.0 + 1.8 * 30.0
        );
    }
}
