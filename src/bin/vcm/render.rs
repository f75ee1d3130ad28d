//! `vcm render`: render a scene progressively, write linear EXR plus a tone-mapped PNG, and
//! optionally record the error against a reference over time.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::ArgMatches;
use clap::builder::RangedU64ValueParser;
use clap::parser::ValueSource;
use glam::Vec3;
use vcm::atomic_write::{writable_target, write_atomically};
use vcm::image_io::RgbImage;
use vcm::memory::MemoryCause;
use vcm::{Film, Integrator, RenderError, StopFlag};
use vcm_rs::gpu::GpuRenderError;
use vcm_rs::scene::{LoadOptions, Scene, ShadingPlan};
use vcm_rs::state::{RenderSettings, RenderState, SETTINGS, parse_range, scene_hash};
use vcm_rs::traversal::Traversal;
use vcm_rs::{Backend, BuiltTraversal, Shading};

use crate::progressive::{self, Budget, Checkpoint, Outcome, Periodic, Watch};
use vcm_rs::integrators::choice::{self, Pilots, Unpiloted};
use vcm_rs::integrators::{Algorithm, AlgorithmOption, IntegratorOptions, image_size};
use vcm_rs::plot::{Series, plot_relmse, plot_utilization};
use vcm_rs::render_loop::{Frames, ScheduleOptions};

/// What `vcm render` and `vcm convergence` both need to set up a render.
#[derive(clap::Args)]
pub struct RenderSetup {
    /// The file's camera to render from: its index in the glTF `cameras` array, or its name
    /// or its node's name (default: the first camera the file's nodes place).
    #[arg(long, value_name = "INDEX|NAME")]
    pub camera: Option<String>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..))]
    pub width: u32,
    /// Image height in pixels (default: from the camera's aspect ratio, else square).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub height: Option<u32>,
    /// Ray traversal backend.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// Worker threads (default: all cores; 1 to 1024).
    #[arg(long, value_parser = RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub integrator: IntegratorOptions,
    #[command(flatten)]
    pub schedule: ScheduleOptions,
    #[command(flatten)]
    pub limits: SceneLimits,
}

/// What a scene file may make the loader allocate and read (scene files are untrusted input).
#[derive(clap::Args, Clone, Debug)]
pub struct SceneLimits {
    /// Most triangles a scene may expand to, every instance counted (checked before loading).
    #[arg(long, value_name = "N", default_value_t = LoadOptions::DEFAULT_MAX_TRIANGLES)]
    pub max_triangles: u64,
    /// Most texels all of a scene's textures may decode to.
    #[arg(long, value_name = "N", default_value_t = LoadOptions::DEFAULT_MAX_TEXELS)]
    pub max_texels: u64,
    /// Let the scene's URIs and file names lead outside its folder (absolute paths, `..`).
    #[arg(long)]
    pub allow_outside_files: bool,
}

impl SceneLimits {
    /// The loader's options these limits give.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            max_triangles: self.max_triangles,
            max_texels: self.max_texels,
            allow_outside_files: self.allow_outside_files,
        }
    }
}

/// Most worker threads `--threads` takes: more only add start-up time and memory.
const MAX_THREADS: u64 = 1024;

impl RenderSetup {
    /// The integrator of `algorithm` with `options` for `scene` at `size`, traced by
    /// `traversal`, set up for the first of [these frames](Self::frames) (see
    /// [`Frames::integrator`]). A render over the memory budget fails with the options to
    /// lower.
    pub fn integrator(
        &self,
        algorithm: Algorithm,
        scene: &Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        size: (u32, u32),
        options: &IntegratorOptions,
        samples_left: Option<u32>,
    ) -> anyhow::Result<Box<dyn Integrator>> {
        self.frames()
            .integrator(algorithm, scene, traversal, size, options, samples_left)
            .map_err(|error| self.explain(error, size))
    }

    /// [`integrator`](Self::integrator) with its paths shaded where `shading` says, on the
    /// backend `built` (see [`Frames::shaded_integrator`]).
    pub fn shaded_integrator(
        &self,
        algorithm: (Algorithm, Shading),
        scene: &Arc<Scene>,
        built: &BuiltTraversal,
        size: (u32, u32),
        options: &IntegratorOptions,
        samples_left: Option<u32>,
    ) -> anyhow::Result<Box<dyn Integrator>> {
        let integrator =
            self.frames()
                .shaded_integrator(algorithm, scene, built, size, options, samples_left);
        integrator.map_err(|error| match error {
            GpuRenderError::Render(error) => self.explain(error, size),
            other => other.into(),
        })
    }

    /// `error`, and where it is a memory shortfall, the options that would lower it for a
    /// render of `size`.
    fn explain(&self, error: RenderError, (width, height): (u32, u32)) -> anyhow::Error {
        let RenderError::OutOfMemory(shortfall) = &error else {
            return error.into();
        };
        let lower = match shortfall.cause {
            MemoryCause::ImageSize if self.height.is_none() => format!(
                "--width, or give --height (the image is {width}×{height}, its height from \
                 the camera's aspect ratio)"
            ),
            MemoryCause::ImageSize => {
                format!("--width or --height (the image is {width}×{height})")
            }
            MemoryCause::SamplesPerFrame => "--spp-per-frame".into(),
            MemoryCause::Connections => "--connections".into(),
            MemoryCause::Scheduler => {
                "the paths in flight: --scheduler, --tile-size or --queues".into()
            }
        };
        anyhow::anyhow!("{error}; lower {lower}")
    }

    /// The frames to render with: sized and scheduled as these options ask on their backend.
    pub fn frames(&self) -> Frames {
        Frames::new(self.schedule, self.backend)
    }
}

/// Arguments of `vcm render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file (.gltf, .glb or .obj).
    #[arg(default_value = "scenes/cornell-box.gltf")]
    scene: PathBuf,
    /// The light transport algorithm (`auto`: the most efficient of pt, bpt and vcm for the
    /// scene, from short pilot renders; see docs/algorithms.md).
    #[arg(long, value_enum, default_value_t = AlgorithmOption::Auto)]
    algo: AlgorithmOption,
    /// Samples per pixel to render (default 16 unless --time is given; with --resume, the
    /// total the resumed render reaches, by default the count it was first asked for).
    #[arg(long, conflicts_with = "time")]
    spp: Option<u32>,
    /// Render for this many seconds instead of a fixed sample count (with --resume: this
    /// many more seconds), counting the pilots of --algo auto, and at least one frame.
    #[arg(long, allow_negative_numbers = true)]
    time: Option<f64>,
    /// Render exactly the global samples A to B − 1 (iterations, for the VCM family): one
    /// shard of an image that `vcm merge` puts together.
    #[arg(long, value_name = "A..B", value_parser = parse_range,
          conflicts_with_all = ["spp", "time", "resume"])]
    samples: Option<Range<u32>>,
    /// Write the render's state (film sums, samples held, settings) to this file at the end,
    /// to resume or merge later (a safetensors file, see docs/render-state.md).
    #[arg(long, value_name = "FILE")]
    state: Option<PathBuf>,
    /// Also write the state every this many seconds while rendering (with --state or
    /// --resume).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    checkpoint_every: Option<f64>,
    /// Continue the render whose state is in this file: its scene and settings (options given
    /// as well must agree with them), its output unless -o is given; the state is written
    /// back to it unless --state names another file.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    #[command(flatten)]
    setup: RenderSetup,
    /// Where paths are shaded: `gpu` follows each whole path in one WGSL kernel on the GPU
    /// backend's device and brings back only the film (needs --backend gpu; --algo auto
    /// means pt there; see docs/gpu.md).
    #[arg(long, value_enum, default_value_t = Shading::Cpu)]
    shading: Shading,
    /// Output EXR (linear radiance); a tone-mapped PNG is written beside it (default out.exr,
    /// or with --resume the resumed render's).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Reference EXR to measure the error against while rendering.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// CSV file for the error over time: seconds,spp,rmse,relmse,mae at 1, 2, 4, … s and at
    /// the end; a log-log plot of relMSE against seconds is drawn beside it (PNG).
    #[arg(long, requires = "reference")]
    report: Option<PathBuf>,
    /// CSV file for the CPU utilization over time: seconds,utilization (percent of all worker
    /// threads) per interval of whole frames (≥ 0.25 s); a plot is drawn beside it (PNG).
    #[arg(long)]
    utilization: Option<PathBuf>,
    /// Print what the scene contains and, for each part of the render (light paths, cache,
    /// merging, shading, alpha test), whether it runs or is left out and why.
    #[arg(long)]
    explain: bool,
}

/// The output EXR when none is given.
const DEFAULT_OUTPUT: &str = "out.exr";

/// A render resolved from the arguments and, with `--resume`, the state it continues.
struct Plan {
    scene_path: PathBuf,
    settings: RenderSettings,
    output: PathBuf,
    /// Where the state is written, if anywhere.
    state_path: Option<PathBuf>,
    /// The state so far (empty for a new render), when one is written or resumed.
    state: Option<RenderState>,
    /// The first global sample to render.
    first_sample: u32,
    budget: Budget,
}

impl RenderArgs {
    /// Every file the render writes, with what it is: the EXR, and beside it the PNG; the
    /// report and the utilization CSVs and their plots, and the state, when asked for.
    fn outputs(&self, plan: &Plan) -> Vec<(&'static str, PathBuf)> {
        let mut outputs = vec![
            ("the EXR image", plan.output.clone()),
            ("the tone-mapped PNG", png_beside(&plan.output)),
        ];
        if let Some(csv) = &self.report {
            outputs.push(("the error report", csv.clone()));
            outputs.push(("the error plot", png_beside(csv)));
        }
        if let Some(csv) = &self.utilization {
            outputs.push(("the utilization CSV", csv.clone()));
            outputs.push(("the utilization plot", png_beside(csv)));
        }
        if let Some(state) = &plan.state_path {
            outputs.push(("the render state", state.clone()));
        }
        outputs
    }

    /// Every file the render reads (the resumed state is rewritten, so it is not listed).
    fn inputs<'a>(&'a self, plan: &'a Plan) -> Vec<&'a Path> {
        let mut inputs = vec![plan.scene_path.as_path()];
        inputs.extend(self.reference.as_deref());
        inputs
    }

    /// The estimator settings the arguments give, with the image height `height` (and, for
    /// `--algo auto`, path tracing until the algorithm is chosen).
    fn settings(&self, height: u32) -> RenderSettings {
        RenderSettings {
            algorithm: self.algo.fixed().unwrap_or(Algorithm::Pt),
            width: self.setup.width,
            height,
            camera: self.setup.camera.clone(),
            options: self.setup.integrator.clone(),
        }
    }

    /// The render the arguments ask for: a new one, a shard (`--samples`) or the
    /// continuation of a state (`--resume`), whose settings `matches` may only repeat.
    fn plan(&self, matches: &ArgMatches) -> anyhow::Result<Plan> {
        let given = |id: &str| matches.value_source(id) == Some(ValueSource::CommandLine);
        if self.checkpoint_every.is_some() && self.state.is_none() && self.resume.is_none() {
            bail!("--checkpoint-every needs a file to write the state to: add --state FILE");
        }
        let Some(resume) = &self.resume else {
            let (first_sample, budget) = match &self.samples {
                Some(range) => (range.start, Budget::Samples(range.end - range.start)),
                None => (0, progressive::budget_from_options(self.spp, self.time)?),
            };
            return Ok(Plan {
                scene_path: self.scene.clone(),
                // The height is settled once the scene's camera is known.
                settings: self.settings(self.setup.height.unwrap_or(0)),
                output: self.output.clone().unwrap_or_else(|| DEFAULT_OUTPUT.into()),
                state_path: self.state.clone(),
                state: None,
                first_sample,
                budget,
            });
        };
        let state = RenderState::load(resume)?;
        let requested = self.settings(self.setup.height.unwrap_or(0)).to_metadata();
        let recorded = state.settings.to_metadata();
        // `--algo auto` keeps the algorithm chosen when the render began.
        let auto = |key| key == "algorithm" && self.algo == AlgorithmOption::Auto;
        for (key, argument) in SETTINGS {
            if given(argument) && !auto(key) && requested[key] != recorded[key] {
                bail!(
                    "{}: the render was made with {key} {}, and --resume cannot change it \
                     (the command asks for {}); leave the option out to keep it",
                    resume.display(),
                    recorded[key],
                    requested[key]
                );
            }
        }
        let done = state.samples.count();
        let budget = match (self.spp, self.time, state.target_spp) {
            (_, Some(_), _) => progressive::budget_from_options(None, self.time)?,
            (Some(total), None, _) | (None, None, Some(total)) => {
                if u64::from(total) <= done {
                    bail!(
                        "{}: already holds {done} samples per pixel; ask for more with --spp \
                         N (the total to reach) or --time SECONDS",
                        resume.display()
                    );
                }
                Budget::Samples(total - done as u32)
            }
            (None, None, None) => bail!(
                "{}: the render was given a time, not a sample count: say how much more to \
                 render with --spp N (the total to reach) or --time SECONDS",
                resume.display()
            ),
        };
        let output = match (&self.output, &state.output) {
            (Some(output), _) | (None, Some(output)) => output.clone(),
            (None, None) => DEFAULT_OUTPUT.into(),
        };
        Ok(Plan {
            scene_path: if given("scene") {
                self.scene.clone()
            } else {
                state.scene_path.clone()
            },
            settings: state.settings.clone(),
            output,
            state_path: Some(self.state.clone().unwrap_or_else(|| resume.clone())),
            first_sample: state.samples.end(),
            budget,
            state: Some(state),
        })
    }
}

/// Renders as the arguments say; `matches` tells which options the command line gave.
pub fn run(args: &RenderArgs, matches: &ArgMatches) -> anyhow::Result<()> {
    if args.shading == Shading::Gpu && args.setup.backend != Backend::Gpu {
        bail!("--shading gpu shades on the GPU backend's device: give --backend gpu too");
    }
    set_threads(args.setup.threads)?;
    let mut plan = args.plan(matches)?;
    check_outputs(&args.outputs(&plan), &args.inputs(&plan))?;
    let camera = plan.settings.camera.as_deref();
    let scene = load_scene(&plan.scene_path, camera, &args.setup.limits)?;
    let settings = &mut plan.settings;
    if settings.height == 0 {
        settings.height = image_size(&scene, settings.width, None).1;
    }
    let (width, height) = (settings.width, settings.height);
    let reference = match &args.reference {
        Some(path) => Some(read_reference(path, (width, height))?),
        None => None,
    };
    let built = build_backend(args.setup.backend, &scene)?;
    let started = Instant::now();
    let stop = stop_flag()?;
    // A resumed render keeps the algorithm its state records.
    let algorithm = match &plan.state {
        Some(_) => AlgorithmOption::Fixed(plan.settings.algorithm),
        None => args.algo,
    };
    let options = &plan.settings.options;
    let how = (&stop, args.explain);
    let pilots = Pilots::of(&built, args.shading)?;
    plan.settings.algorithm =
        settle_algorithm(algorithm, (&scene, pilots), (width, height), options, how)?;
    let mut state = prepare_state(&mut plan, &scene, args)?;
    let samples_left = plan.budget.remaining(0, Duration::ZERO).samples;
    let mut integrator = args.setup.shaded_integrator(
        (plan.settings.algorithm, args.shading),
        &scene,
        &built,
        (width, height),
        &plan.settings.options,
        samples_left,
    )?;
    if args.explain {
        let shading = plan.settings.options.shading_plan(&scene);
        print_explanation(&scene, shading, args.setup.backend, integrator.as_ref());
    }
    let mut film = match &mut state {
        Some(state) => std::mem::replace(&mut state.film, Film::new(1, 1)),
        None => Film::new(width, height),
    };
    let first = plan.first_sample;
    let mut write_checkpoint = |film: &Film, spp: u32| -> anyhow::Result<()> {
        if let (Some(state), Some(path)) = (&state, &plan.state_path) {
            state.save_with(film, first..first + spp, path)?;
        }
        Ok(())
    };
    let periodic = match args.checkpoint_every {
        Some(seconds) if !(seconds.is_finite() && seconds > 0.0) => {
            bail!("--checkpoint-every must be a positive number of seconds")
        }
        Some(seconds) => Some(Periodic {
            every: Duration::from_secs_f64(seconds),
            action: &mut write_checkpoint,
        }),
        None => None,
    };
    let frames = args.setup.frames().starting_at(first);
    let outcome = progressive::render(
        integrator.as_mut(),
        frames,
        &mut film,
        plan.budget,
        &stop,
        Watch {
            reference: reference.as_deref(),
            periodic,
            label: None,
            part: None,
            started: Some(started),
        },
    )?;
    if stop.is_raised() {
        tell!(
            "interrupted: writing the {} samples per pixel rendered so far",
            outcome.spp
        );
    }
    if let Some(failure) = &outcome.failure {
        tell!(
            "{failure}: writing the {} samples per pixel rendered before it",
            outcome.spp
        );
    }
    let image = film.image();
    image.write_exr(&plan.output)?;
    let png = png_beside(&plan.output);
    image.write_png(&png, 0.0)?;
    if let (Some(mut state), Some(path)) = (state, &plan.state_path) {
        let start = std::time::Instant::now();
        state.save_with(&film, first..first + outcome.spp, path)?;
        let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
        state.samples.insert(first..first + outcome.spp);
        say!(
            "wrote the render state {} (samples {}, {:.1} MiB in {:.2} s)",
            path.display(),
            state.samples,
            bytes as f64 / f64::from(1 << 20),
            start.elapsed().as_secs_f64()
        );
    }
    if let Some(report) = &args.report {
        write_report(report, &outcome.checkpoints)?;
        let plot = png_beside(report);
        let series = Series {
            label: plan.settings.algorithm.name().to_string(),
            points: relmse_points(&outcome.checkpoints),
        };
        let title = format!("relMSE over time: {}", plan.scene_path.display());
        plot_relmse(&plot, &title, &[series])?;
        say!("wrote {} and {}", report.display(), plot.display());
    }
    if let Some(path) = &args.utilization {
        write_utilization(path, &outcome.utilization)?;
        let series = Series {
            label: plan.settings.algorithm.name().to_string(),
            points: outcome
                .utilization
                .iter()
                .map(|&(t, u)| (t, u * 100.0))
                .collect(),
        };
        let plot = png_beside(path);
        let title = format!("CPU utilization: {}", plan.scene_path.display());
        plot_utilization(&plot, &title, &[series])?;
        say!("wrote {} and {}", path.display(), plot.display());
    }
    print_summary(&film, &outcome);
    say!("wrote {} and {}", plan.output.display(), png.display());
    match outcome.failure {
        Some(failure) => bail!("{failure}"),
        None => Ok(()),
    }
}

/// The state the render adds to, when one is written: the resumed one, checked against
/// `scene`, or a new one. `None` when no state is asked for.
fn prepare_state(
    plan: &mut Plan,
    scene: &Scene,
    args: &RenderArgs,
) -> anyhow::Result<Option<RenderState>> {
    if plan.state_path.is_none() {
        return Ok(None);
    }
    let hash = scene_hash(scene);
    let mut state = match plan.state.take() {
        Some(state) => {
            if state.scene_hash != hash {
                bail!(
                    "{}: its content differs from the scene the resumed render was made from \
                     ({}); give the same scene",
                    plan.scene_path.display(),
                    state.scene_path.display()
                );
            }
            state
        }
        None => {
            let mut state = RenderState::new(plan.settings.clone(), hash, plan.scene_path.clone());
            if let Budget::Samples(spp) = plan.budget
                && args.samples.is_none()
            {
                state.target_spp = Some(spp);
            }
            state
        }
    };
    state.output = Some(plan.output.clone());
    Ok(Some(state))
}

/// The algorithm `algorithm` names, or for `auto` the one that renders `scene` at `size`
/// with `options` ([`choice::choose`], its pilots shaded where `pilots` says), told in one
/// line, or with `explain` in a table of the candidates.
pub fn settle_algorithm(
    algorithm: AlgorithmOption,
    (scene, pilots): (&Arc<Scene>, Pilots),
    size: (u32, u32),
    options: &IntegratorOptions,
    (stop, explain): (&StopFlag, bool),
) -> anyhow::Result<Algorithm> {
    if let Some(algorithm) = algorithm.fixed() {
        return Ok(algorithm);
    }
    let choice =
        choice::choose(scene, pilots, size, options, stop).context("choosing the algorithm")?;
    let (width, height) = choice.pilot_size;
    match choice.unpiloted {
        Some(Unpiloted::SmallImage) => tell!(
            "algorithm: {} (an image of fewer than {} pixels is not piloted: its pilots would \
             take longer than its render)",
            choice.algorithm.name(),
            choice::MIN_PILOTED_PIXELS
        ),
        Some(Unpiloted::OnlyMergingFindsAllLight) => tell!(
            "algorithm: {} (not piloted: a point, spot or directional light shines through \
             mirrors or smooth glass, light that path tracing misses and BPT misses where it \
             is seen through them again; only merging finds all of it, and {})",
            choice.algorithm.name(),
            match choice.candidates.is_empty() {
                true => "the image is too small for pilots to measure how much",
                false => "VCM's pilot did not finish to measure how much",
            }
        ),
        None => {}
    }
    for left_out in &choice.too_costly {
        tell!(
            "algorithm: {} left out after one pilot frame ({:.2} s): a sample costs {:.0} rays, \
             more than {} samples of the cheapest candidate",
            left_out.algorithm.name(),
            left_out.time.as_secs_f64(),
            left_out.cost,
            choice::COMPARED_AT_SPP
        );
    }
    if choice.candidates.is_empty() {
        return Ok(choice.algorithm);
    }
    let pilots = format!(
        "pilots of {} samples per pixel at {width}×{height}, {:.2} s",
        choice::PILOT_FRAMES,
        choice.time().as_secs_f64()
    );
    if !explain {
        let each = choice
            .candidates
            .iter()
            .map(|c| format!("{} {:.3}", c.algorithm.name(), c.inefficiency()));
        let missed = choice
            .candidates
            .iter()
            .filter_map(|c| Some((c.algorithm.name(), c.missed_light?)))
            .map(|(name, b2)| format!("{name} {:.2e}", b2.value));
        let missed = missed.collect::<Vec<_>>();
        let (measure, missed) = match missed.is_empty() {
            true => ("variance × cost", String::new()),
            false => (
                "(variance + spp × b²) × cost",
                format!(
                    "; b², the relMSE of the light missed: {}",
                    missed.join(", ")
                ),
            ),
        };
        tell!(
            "algorithm: {} ({pilots}; {measure}: {}{missed})",
            choice.algorithm.name(),
            each.collect::<Vec<_>>().join(", "),
        );
        return Ok(choice.algorithm);
    }
    say!(
        "algorithm: {}, the least relative variance (+ 2 standard errors; where a candidate \
         misses light, + spp × its relMSE b² as estimated) × cost of its {pilots}:",
        choice.algorithm.name()
    );
    for candidate in &choice.candidates {
        let [v1, v4] = candidate.measured;
        let v = candidate.relative_variance;
        let chosen = candidate.algorithm == choice.algorithm;
        let missed = candidate.missed_light.map_or(String::new(), |b2| {
            format!(
                " + {:.0} spp × missed light b² {:.2e} ± {:.2e}",
                candidate.samples, b2.value, b2.standard_error
            )
        });
        say!(
            "  {:<4} variance per sample {:.4} (frames), {:.4} (halves): γ {:.2}; at {:.0} spp \
             ({:.4} ± {:.4}{missed}) × cost {:.2} rays = {:.4}{}",
            candidate.algorithm.name(),
            v1.value,
            v4.value,
            candidate.stratification,
            candidate.samples,
            v.value,
            v.standard_error,
            candidate.cost,
            candidate.inefficiency(),
            if chosen { "  ← chosen" } else { "" }
        );
    }
    Ok(choice.algorithm)
}

/// Prints the scene's features and every part of the render with whether it runs and why.
fn print_explanation(
    scene: &Scene,
    shading: ShadingPlan,
    backend: Backend,
    integrator: &dyn Integrator,
) {
    say!("scene {}:", scene.path.display());
    for line in scene.features.to_string().lines() {
        say!("  {line}");
    }
    let decisions = integrator
        .decisions()
        .into_iter()
        .chain(shading.decisions(&scene.features))
        .chain(backend.decisions(scene));
    say!("plan:");
    for decision in decisions {
        say!("  {decision}");
    }
}

/// Builds `backend` for `scene` and says on stderr what it runs on.
pub fn build_traversal(backend: Backend, scene: &Arc<Scene>) -> anyhow::Result<Arc<dyn Traversal>> {
    Ok(build_backend(backend, scene)?.traversal)
}

/// [`build_traversal`], keeping what the GPU backend offers besides traversal.
fn build_backend(backend: Backend, scene: &Arc<Scene>) -> anyhow::Result<BuiltTraversal> {
    let built = backend
        .build(scene)
        .context("building the ray traversal backend")?;
    tell_traversal(&built);
    Ok(built)
}

/// Says what a traversal backend just built runs on.
pub fn tell_traversal(built: &BuiltTraversal) {
    tell!("traversal: {}", built.description);
}

/// Sets the number of worker threads (default: all cores).
pub fn set_threads(threads: Option<usize>) -> anyhow::Result<()> {
    if let Some(threads) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("setting up the worker threads")?;
    }
    Ok(())
}

/// Loads a scene within `limits`, prints its warnings and renders it from the file's camera
/// `camera`, if given.
pub fn load_scene(
    path: &Path,
    camera: Option<&str>,
    limits: &SceneLimits,
) -> anyhow::Result<Arc<Scene>> {
    let mut scene = Scene::load_with(path, &limits.load_options())?;
    for warning in &scene.warnings {
        tell!("warning: {warning}");
    }
    if let Some(choice) = camera {
        scene.use_camera(choice)?;
    }
    Ok(Arc::new(scene))
}

/// Reads a reference EXR and checks that it has the render's size and finite pixels.
pub fn read_reference(path: &Path, (width, height): (u32, u32)) -> anyhow::Result<Vec<Vec3>> {
    let image = RgbImage::read_exr(path)?;
    if (image.width, image.height) != (width as usize, height as usize) {
        bail!(
            "{}: reference is {}×{}, the render {width}×{height}",
            path.display(),
            image.width,
            image.height
        );
    }
    crate::compare::check_finite(path, &image.pixels)?;
    Ok(image.pixels)
}

/// A flag that Ctrl-C (SIGINT), SIGTERM and SIGHUP raise (installed once per process): the
/// render stops within a frame's tile or pass and writes what it has.
pub fn stop_flag() -> anyhow::Result<StopFlag> {
    let stop = StopFlag::new();
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.raise()).context("installing the signal handler")?;
    Ok(stop)
}

/// (seconds, relMSE) of each checkpoint, for plotting.
pub fn relmse_points(checkpoints: &[Checkpoint]) -> Vec<(f64, f64)> {
    checkpoints
        .iter()
        .map(|c| (c.seconds, c.metrics.relmse))
        .collect()
}

/// Fails early, before rendering, when an output cannot be written where it is asked for:
/// its folder does not exist, it names a folder or another file that is not a regular one (a
/// device, a FIFO: a write would replace it), two outputs are the same file (an EXR named
/// `.png` would be replaced by its own PNG) or an output would replace one of the `inputs`.
/// Each output comes with what it is, for the message.
pub fn check_outputs(outputs: &[(&str, PathBuf)], inputs: &[&Path]) -> anyhow::Result<()> {
    let mut written: Vec<(PathBuf, &str)> = Vec::new();
    for (what, output) in outputs {
        if !folder_of(output).is_dir() {
            bail!("{}: the output folder does not exist", output.display());
        }
        if output.is_dir() {
            bail!("{}: is a folder, not a file to write", output.display());
        }
        if let Err(e) = writable_target(output) {
            bail!("{}: {e}", output.display());
        }
        let file = same_file_key(output);
        if let Some((_, first)) = written.iter().find(|(key, _)| *key == file) {
            bail!(
                "{}: both {first} and {what} would be written there; choose another name",
                output.display()
            );
        }
        if let Some(input) = inputs.iter().find(|input| same_file_key(input) == file) {
            bail!(
                "{}: {what} would replace the input {}",
                output.display(),
                input.display()
            );
        }
        written.push((file, what));
    }
    Ok(())
}

/// The PNG written beside the EXR or CSV at `path` (the tone-mapped image, or the plot).
pub fn png_beside(path: &Path) -> PathBuf {
    path.with_extension("png")
}

/// The folder that holds `path` (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// `path` with its folder made absolute and free of links, so that two spellings of one file
/// compare equal (the file itself need not exist).
fn same_file_key(path: &Path) -> PathBuf {
    let folder = folder_of(path);
    let folder = folder
        .canonicalize()
        .unwrap_or_else(|_| folder.to_path_buf());
    match path.file_name() {
        Some(name) => folder.join(name),
        None => folder,
    }
}

/// Writes the convergence CSV through a temporary file.
pub fn write_report(path: &Path, checkpoints: &[Checkpoint]) -> anyhow::Result<()> {
    let mut csv = String::from("seconds,spp,rmse,relmse,mae\n");
    for c in checkpoints {
        csv += &c.csv_row();
        csv.push('\n');
    }
    write_text(path, csv)
}

/// Writes the CPU utilization CSV through a temporary file.
fn write_utilization(path: &Path, samples: &[(f64, f64)]) -> anyhow::Result<()> {
    let mut csv = String::from("seconds,utilization\n");
    for (seconds, utilization) in samples {
        csv += &format!("{seconds:.3},{:.1}\n", utilization * 100.0);
    }
    write_text(path, csv)
}

/// Writes `text` to `path` through a temporary file.
pub fn write_text(path: &Path, text: String) -> anyhow::Result<()> {
    write_atomically(path, |temporary| std::fs::write(temporary, text), |e| e)
        .with_context(|| format!("{}: cannot write", path.display()))
}

fn print_summary(film: &Film, outcome: &Outcome) {
    let Outcome {
        spp,
        seconds,
        totals,
        checkpoints,
        mean_utilization,
        frames,
        ..
    } = outcome;
    let pixels = f64::from(film.width()) * f64::from(film.height());
    let samples = pixels * f64::from(*spp);
    let elapsed = seconds.max(1e-9);
    let per_second = |n: u64| n as f64 / elapsed / 1e6;
    let busy = (totals.traversal_time + totals.shading_time + totals.grid_build_time)
        .as_secs_f64()
        .max(1e-9);
    let share = |d: std::time::Duration| 100.0 * d.as_secs_f64() / busy;
    say!(
        "rendered {spp} spp at {}×{} in {seconds:.2} s: {:.2} M samples/s",
        film.width(),
        film.height(),
        samples / elapsed / 1e6
    );
    let sizes = if frames.fewest == frames.most {
        format!("{}", frames.most)
    } else {
        format!("{} to {}", frames.fewest, frames.most)
    };
    say!("frames: {} ({sizes} samples per pixel each)", frames.count);
    say!(
        "rays: {:.2} M/s (camera {:.2}, continuation {:.2}, light {:.2}, shadow {:.2})",
        per_second(totals.rays()),
        per_second(totals.camera_rays),
        per_second(totals.continuation_rays),
        per_second(totals.light_rays),
        per_second(totals.shadow_rays)
    );
    say!(
        "time: traversal {:.2} s ({:.0}%), shading {:.2} s ({:.0}%), hash grid {:.2} s ({:.0}%)",
        totals.traversal_time.as_secs_f64(),
        share(totals.traversal_time),
        totals.shading_time.as_secs_f64(),
        share(totals.shading_time),
        totals.grid_build_time.as_secs_f64(),
        share(totals.grid_build_time)
    );
    if !totals.device_time.is_zero() {
        say!(
            "GPU kernels: {:.2} s ({:.0}% of the render's time)",
            totals.device_time.as_secs_f64(),
            100.0 * totals.device_time.as_secs_f64() / elapsed
        );
    }
    if totals.light_vertices + totals.discarded_light_vertices > 0 {
        say!(
            "light vertex cache: {:.0} vertices per iteration, {} discarded for lack of room",
            totals.light_vertices as f64 / f64::from((*spp).max(1)),
            totals.discarded_light_vertices
        );
    }
    say!("dropped non-finite samples: {}", film.dropped());
    say!(
        "queue memory: peak {:.1} MiB (paths in flight and their ray buffers)",
        totals.queue_memory as f64 / f64::from(1 << 20)
    );
    if let Some(mean) = mean_utilization {
        say!(
            "cpu utilization: {:.0}% of {} threads",
            100.0 * mean,
            rayon::current_num_threads()
        );
    }
    if let Some(mib) = crate::process::peak_memory_mib() {
        say!("peak memory: {mib:.0} MiB");
    }
    if let Some(last) = checkpoints.last() {
        let m = &last.metrics;
        say!(
            "error: rmse {:.4e}, relMSE {:.4e}, mae {:.4e}",
            m.rmse,
            m.relmse,
            m.mae
        );
    }
}
