//! The light transport algorithms, their options and one builder for any of them, shared by
//! `vcm render`, `vcm convergence` and the viewer. How the frames of a render are sized and
//! scheduled is the [render loop](crate::render_loop)'s.

use std::sync::Arc;

pub mod choice;

pub use vcm::{Algorithm, MergeRadius};
use vcm::{DEFAULT_ALPHA, Integrator, PathTracer, PtSettings, RenderError, Vcm, VcmSettings};
use vcm_gpu::{GpuBidirectional, GpuPathTracer, GpuRenderError};
use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Scene, ShadingPlan};
use vcm_traversal::Traversal;
use vcm_traversal_wgpu::GpuBvh;

/// What `--algo` asks for: one algorithm, or `auto`, the one [`choice::choose`] finds the
/// most efficient for the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AlgorithmOption {
    /// Chosen per scene from short pilot renders of the candidates.
    #[default]
    Auto,
    /// This algorithm.
    Fixed(Algorithm),
}

impl AlgorithmOption {
    /// `auto`, then every algorithm, as `--help` and the viewer list them.
    pub const ALL: [AlgorithmOption; 7] = [
        AlgorithmOption::Auto,
        AlgorithmOption::Fixed(Algorithm::Pt),
        AlgorithmOption::Fixed(Algorithm::LightTracing),
        AlgorithmOption::Fixed(Algorithm::Bpt),
        AlgorithmOption::Fixed(Algorithm::Ppm),
        AlgorithmOption::Fixed(Algorithm::Bpm),
        AlgorithmOption::Fixed(Algorithm::Vcm),
    ];

    /// The name `--algo` takes: `auto` or the algorithm's.
    pub fn name(self) -> &'static str {
        match self {
            AlgorithmOption::Auto => "auto",
            AlgorithmOption::Fixed(algorithm) => algorithm.name(),
        }
    }

    /// The algorithm it names, `None` for `auto`.
    pub fn fixed(self) -> Option<Algorithm> {
        match self {
            AlgorithmOption::Auto => None,
            AlgorithmOption::Fixed(algorithm) => Some(algorithm),
        }
    }
}

impl clap::ValueEnum for AlgorithmOption {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        match self {
            AlgorithmOption::Auto => Some(clap::builder::PossibleValue::new("auto").help(
                "The most efficient of pt, bpt and vcm for the scene, measured by short pilot \
                 renders",
            )),
            AlgorithmOption::Fixed(algorithm) => algorithm.to_possible_value(),
        }
    }
}

/// How the samples of a pixel relate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SamplerKind {
    /// Stratified: the points of an Owen-scrambled Sobol sequence per pixel (and per frame's
    /// light paths), which lowers the error at the same sample count.
    #[default]
    Sobol,
    /// Independent random numbers for every sample.
    Independent,
}

impl SamplerKind {
    fn sequence(self) -> SampleSequence {
        match self {
            SamplerKind::Sobol => SampleSequence::Sobol,
            SamplerKind::Independent => SampleSequence::Independent,
        }
    }
}

/// Options of every integrator.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct IntegratorOptions {
    /// Seed of all random numbers: a render is a pure function of scene, settings and seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How the samples of a pixel relate: stratified (sobol) or independent.
    #[arg(long, value_enum, default_value_t = SamplerKind::Sobol)]
    pub sampler: SamplerKind,
    /// Maximum path length in segments (a directly seen light is 1); default unlimited with
    /// Russian roulette.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Light vertices each camera vertex connects to (bpt, vcm; 1 to 1024).
    #[arg(long, default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(vcm::MAX_CONNECTIONS)))]
    pub connections: u32,
    /// Light paths each iteration traces per pixel (lt, bpt, ppm, bpm, vcm; 1/16 to 16;
    /// default 1).
    #[arg(long, default_value_t = 1.0, value_parser = parse_light_paths)]
    pub light_paths: f32,
    /// Initial merge radius (ppm, bpm, vcm): pixel footprints at the surfaces the camera
    /// sees (2px), or a fraction of the scene's bounding-sphere radius (0.003).
    #[arg(long, default_value_t = MergeRadius::default(), allow_hyphen_values = true)]
    pub radius: MergeRadius,
    /// Radius reduction exponent: frame i merges within r₀ · i^((α − 1) / 2) (ppm, bpm, vcm).
    #[arg(long, default_value_t = DEFAULT_ALPHA, allow_negative_numbers = true)]
    pub alpha: f32,
    /// Run every part of the algorithm and of shading, even those the scene does not need
    /// (`vcm render --explain` lists them); the image's expectation is the same.
    #[arg(long)]
    pub no_prune: bool,
}

/// `--light-paths`: a number of light paths per pixel within the range the integrator takes
/// ([`vcm::light_paths_per_pixel`]).
fn parse_light_paths(text: &str) -> Result<f32, String> {
    let n = text.parse::<f32>().map_err(|e| e.to_string())?;
    vcm::light_paths_per_pixel(n)
}

impl IntegratorOptions {
    /// The shading plan renders with these options use on `scene`: every part with
    /// `--no-prune`, else the scene's own.
    pub fn shading_plan(&self, scene: &Scene) -> ShadingPlan {
        if self.no_prune {
            ShadingPlan::FULL
        } else {
            scene.shading
        }
    }
}

impl Default for IntegratorOptions {
    fn default() -> Self {
        IntegratorOptions {
            seed: 0,
            sampler: SamplerKind::Sobol,
            max_depth: None,
            connections: 1,
            light_paths: 1.0,
            radius: MergeRadius::default(),
            alpha: DEFAULT_ALPHA,
            no_prune: false,
        }
    }
}

/// The integrator of `algorithm` for a `width` × `height` image. With `options.no_prune`
/// it renders a copy of the scene whose shading runs every part ([`ShadingPlan::FULL`]),
/// every vertex through the general BSDF (no SIMD lanes).
pub fn build(
    algorithm: Algorithm,
    scene: &Arc<Scene>,
    traversal: Arc<dyn Traversal>,
    (width, height): (u32, u32),
    options: &IntegratorOptions,
) -> Result<Box<dyn Integrator>, RenderError> {
    let shading = options.shading_plan(scene);
    let scene = if shading != scene.shading {
        Arc::new(Scene {
            shading,
            ..Scene::clone(scene)
        })
    } else {
        Arc::clone(scene)
    };
    Ok(match algorithm {
        Algorithm::Pt => {
            let settings = pt_settings(options, (width, height));
            Box::new(PathTracer::new(scene, traversal, settings)?)
        }
        bidirectional => {
            let settings = vcm_settings(bidirectional, options, (width, height));
            Box::new(Vcm::new(scene, traversal, settings)?)
        }
    })
}

/// The settings of a bidirectional `algorithm` for `options` at `width` × `height`.
fn vcm_settings(
    algorithm: Algorithm,
    options: &IntegratorOptions,
    (width, height): (u32, u32),
) -> VcmSettings {
    VcmSettings {
        seed: options.seed,
        sequence: options.sampler.sequence(),
        max_depth: options.max_depth,
        connections: options.connections,
        light_paths_per_pixel: options.light_paths,
        radius: options.radius,
        alpha: options.alpha,
        prune: !options.no_prune,
        lambert_lanes: !options.no_prune,
        ..VcmSettings::new(algorithm, width, height)
    }
}

/// The path tracer's settings for `options` at `width` × `height`.
fn pt_settings(options: &IntegratorOptions, (width, height): (u32, u32)) -> PtSettings {
    PtSettings {
        seed: options.seed,
        sequence: options.sampler.sequence(),
        max_depth: options.max_depth,
        lambert_lanes: !options.no_prune,
        ..PtSettings::new(width, height)
    }
}

/// `algorithm` with every path shaded on the GPU ([`GpuPathTracer`], [`GpuBidirectional`]), on
/// the GPU backend's hierarchy `bvh`, for a `width` × `height` image: the same image as
/// [`build`]'s integrator up to rounding.
pub fn build_on_gpu(
    algorithm: Algorithm,
    scene: &Arc<Scene>,
    bvh: &GpuBvh,
    size: (u32, u32),
    options: &IntegratorOptions,
) -> Result<Box<dyn Integrator>, GpuRenderError> {
    let scene = Arc::clone(scene);
    Ok(match algorithm {
        Algorithm::Pt => Box::new(GpuPathTracer::new(scene, bvh, pt_settings(options, size))?),
        bidirectional => {
            let settings = vcm_settings(bidirectional, options, size);
            Box::new(GpuBidirectional::new(scene, bvh, settings)?)
        }
    })
}

/// The image size: `width`, and `height` or else the one the camera's aspect ratio gives
/// (square without one).
pub fn image_size(scene: &Scene, width: u32, height: Option<u32>) -> (u32, u32) {
    let height = height.unwrap_or_else(|| {
        let aspect = scene.camera.aspect_ratio.unwrap_or(1.0);
        ((width as f32 / aspect).round() as u32).max(1)
    });
    (width, height)
}
