//! `vcm render`: render a scene progressively, write linear EXR plus a tone-mapped PNG, and
//! optionally record the error against a reference over time.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, bail};
use glam::Vec3;
use vcm::atomic_write::write_atomically;
use vcm::image_io::RgbImage;
use vcm::{Film, Integrator};
use vcm_rs::Backend;
use vcm_rs::frames::Frames;
use vcm_rs::scene::Scene;
use vcm_rs::traversal::Traversal;

use crate::progressive::{self, Budget, Checkpoint, Outcome};
use vcm_rs::integrators::{self, Algorithm, IntegratorOptions, ScheduleOptions, image_size};
use vcm_rs::plot::{Series, plot_relmse, plot_utilization};

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
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub integrator: IntegratorOptions,
    #[command(flatten)]
    pub schedule: ScheduleOptions,
}

impl RenderSetup {
    /// The integrator of `algorithm` for `scene` at `size`, traced by `traversal`, with the
    /// schedule of the first frame these options ask for on their backend (which checks it).
    pub fn integrator(
        &self,
        algorithm: Algorithm,
        scene: &Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        size: (u32, u32),
    ) -> anyhow::Result<Box<dyn Integrator>> {
        let mut integrator =
            integrators::build(algorithm, scene, traversal, size, &self.integrator)?;
        integrator.set_schedule(self.schedule.first_schedule_on(self.backend))?;
        Ok(integrator)
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
    /// The light transport algorithm.
    #[arg(long, value_enum, default_value_t = Algorithm::Pt)]
    algo: Algorithm,
    /// Samples per pixel to render (default 16 unless --time is given).
    #[arg(long, conflicts_with = "time")]
    spp: Option<u32>,
    /// Render for this many seconds instead of a fixed sample count.
    #[arg(long, allow_negative_numbers = true)]
    time: Option<f64>,
    #[command(flatten)]
    setup: RenderSetup,
    /// Output EXR (linear radiance); a tone-mapped PNG is written beside it.
    #[arg(short, long, default_value = "out.exr")]
    output: PathBuf,
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

impl RenderArgs {
    /// Every file the render writes, with what it is: the EXR, and beside it the PNG; the
    /// report and the utilization CSVs and their plots when asked for.
    fn outputs(&self) -> Vec<(&'static str, PathBuf)> {
        let mut outputs = vec![
            ("the EXR image", self.output.clone()),
            ("the tone-mapped PNG", png_beside(&self.output)),
        ];
        if let Some(csv) = &self.report {
            outputs.push(("the error report", csv.clone()));
            outputs.push(("the error plot", png_beside(csv)));
        }
        if let Some(csv) = &self.utilization {
            outputs.push(("the utilization CSV", csv.clone()));
            outputs.push(("the utilization plot", png_beside(csv)));
        }
        outputs
    }

    /// Every file the render reads.
    fn inputs(&self) -> Vec<&Path> {
        let mut inputs = vec![self.scene.as_path()];
        inputs.extend(self.reference.as_deref());
        inputs
    }
}

/// Renders as the arguments say.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    set_threads(args.setup.threads)?;
    let budget = Budget::from_options(args.spp, args.time)?;
    check_outputs(&args.outputs(), &args.inputs())?;
    let scene = load_scene(&args.scene, args.setup.camera.as_deref())?;
    let (width, height) = image_size(&scene, args.setup.width, args.setup.height);
    let reference = match &args.reference {
        Some(path) => Some(read_reference(path, (width, height))?),
        None => None,
    };
    let traversal = build_traversal(args.setup.backend, &scene)?;
    let mut integrator = args
        .setup
        .integrator(args.algo, &scene, traversal, (width, height))?;
    if args.explain {
        print_explanation(&scene, &args.setup, integrator.as_ref());
    }
    let interrupted = interrupt_flag()?;
    let mut film = Film::new(width, height);
    let outcome = progressive::render(
        integrator.as_mut(),
        args.setup.frames(),
        &mut film,
        budget,
        reference.as_deref(),
        &interrupted,
    )?;
    if interrupted.load(Ordering::SeqCst) {
        tell!(
            "interrupted: writing the {} samples per pixel rendered so far",
            outcome.spp
        );
    }
    let image = film.image();
    image.write_exr(&args.output)?;
    let png = png_beside(&args.output);
    image.write_png(&png, 0.0)?;
    if let Some(report) = &args.report {
        write_report(report, &outcome.checkpoints)?;
        let plot = png_beside(report);
        let series = Series {
            label: args.algo.name().to_string(),
            points: relmse_points(&outcome.checkpoints),
        };
        let title = format!("relMSE over time: {}", args.scene.display());
        plot_relmse(&plot, &title, &[series])?;
        say!("wrote {} and {}", report.display(), plot.display());
    }
    if let Some(path) = &args.utilization {
        write_utilization(path, &outcome.utilization)?;
        let series = Series {
            label: args.algo.name().to_string(),
            points: outcome
                .utilization
                .iter()
                .map(|&(t, u)| (t, u * 100.0))
                .collect(),
        };
        let plot = png_beside(path);
        let title = format!("CPU utilization: {}", args.scene.display());
        plot_utilization(&plot, &title, &[series])?;
        say!("wrote {} and {}", path.display(), plot.display());
    }
    print_summary(&film, &outcome);
    say!("wrote {} and {}", args.output.display(), png.display());
    Ok(())
}

/// Prints the scene's features and every part of the render with whether it runs and why.
fn print_explanation(scene: &Scene, setup: &RenderSetup, integrator: &dyn Integrator) {
    say!("scene {}:", scene.path.display());
    for line in scene.features.to_string().lines() {
        say!("  {line}");
    }
    let shading = setup.integrator.shading_plan(scene);
    let decisions = integrator
        .decisions()
        .into_iter()
        .chain(shading.decisions(&scene.features))
        .chain(setup.backend.decisions(scene));
    say!("plan:");
    for decision in decisions {
        say!("  {decision}");
    }
}

/// Builds `backend` for `scene` and says on stderr what it runs on.
pub fn build_traversal(backend: Backend, scene: &Arc<Scene>) -> anyhow::Result<Arc<dyn Traversal>> {
    let built = backend
        .build(scene)
        .context("building the ray traversal backend")?;
    tell!("traversal: {}", built.description);
    Ok(built.traversal)
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

/// Loads a scene, prints its warnings and renders it from the file's camera `camera`, if
/// given.
pub fn load_scene(path: &Path, camera: Option<&str>) -> anyhow::Result<Arc<Scene>> {
    let mut scene = Scene::load(path)?;
    for warning in &scene.warnings {
        tell!("warning: {warning}");
    }
    if let Some(choice) = camera {
        scene.use_camera(choice)?;
    }
    Ok(Arc::new(scene))
}

/// Reads a reference EXR and checks that it has the render's size.
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
    Ok(image.pixels)
}

/// A flag that Ctrl-C sets (installed once per process).
pub fn interrupt_flag() -> anyhow::Result<Arc<AtomicBool>> {
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&interrupted);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .context("installing the Ctrl-C handler")?;
    Ok(interrupted)
}

/// (seconds, relMSE) of each checkpoint, for plotting.
pub fn relmse_points(checkpoints: &[Checkpoint]) -> Vec<(f64, f64)> {
    checkpoints
        .iter()
        .map(|c| (c.seconds, c.metrics.relmse))
        .collect()
}

/// Fails early, before rendering, when an output cannot be written where it is asked for:
/// its folder does not exist, it names a folder, two outputs are the same file (an EXR named
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
