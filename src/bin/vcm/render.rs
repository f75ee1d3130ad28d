//! `vcm render`: render a scene progressively, write linear EXR plus a tone-mapped PNG, and
//! optionally record the error against a reference over time.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use vcm::atomic_write::write_atomically;
use vcm::image_io::RgbImage;
use vcm::metrics::{ErrorMetrics, compare};
use vcm::{Film, FrameStats, PathTracer, PtSettings};
use vcm_rs::scene::Scene;

use crate::plot::{Series, plot_relmse};

/// Light transport algorithms (more arrive with the VCM integrator).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Algorithm {
    /// Path tracing with next event estimation and MIS.
    Pt,
}

/// Ray traversal backends (the GPU backend arrives with its crate).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Backend {
    /// obvhs 8-wide BVH on rayon threads.
    Cpu,
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
    #[arg(long)]
    time: Option<f64>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels (default: from the camera's aspect ratio, else square).
    #[arg(long)]
    height: Option<u32>,
    /// Seed of all random numbers: a render is a pure function of scene, settings and seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Ray traversal backend.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Maximum path length in segments (a directly seen light is 1); default unlimited with
    /// Russian roulette.
    #[arg(long)]
    max_depth: Option<u32>,
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
}

/// Totals over all frames.
#[derive(Default)]
struct Totals {
    camera_rays: u64,
    continuation_rays: u64,
    shadow_rays: u64,
    traversal: Duration,
    shading: Duration,
}

impl Totals {
    fn add(&mut self, s: &FrameStats) {
        self.camera_rays += s.camera_rays;
        self.continuation_rays += s.continuation_rays;
        self.shadow_rays += s.shadow_rays;
        self.traversal += s.traversal_time;
        self.shading += s.shading_time;
    }
}

/// One row of the convergence report.
struct Checkpoint {
    seconds: f64,
    spp: u32,
    metrics: ErrorMetrics,
}

/// When to stop rendering.
enum Budget {
    Samples(u32),
    Seconds(f64),
}

impl Budget {
    fn done(&self, spp: u32, elapsed: Duration) -> bool {
        match *self {
            Budget::Samples(n) => spp >= n,
            Budget::Seconds(s) => elapsed.as_secs_f64() >= s,
        }
    }
}

/// Renders as the arguments say.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    if let Some(threads) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("setting up the worker threads")?;
    }
    let budget = match (args.spp, args.time) {
        (_, Some(t)) if !(t.is_finite() && t > 0.0) => {
            bail!("--time must be a positive number of seconds")
        }
        (_, Some(t)) => Budget::Seconds(t),
        (Some(0), _) => bail!("--spp must be at least 1"),
        (spp, None) => Budget::Samples(spp.unwrap_or(16)),
    };
    check_writable(&args.output)?;
    let scene = Arc::new(Scene::load(&args.scene)?);
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let height = args.height.unwrap_or_else(|| {
        let aspect = scene.camera.aspect_ratio.unwrap_or(1.0);
        ((args.width as f32 / aspect).round() as u32).max(1)
    });
    let (width, height) = (args.width, height);
    let reference = match &args.reference {
        Some(path) => {
            let image = RgbImage::read_exr(path)?;
            if (image.width, image.height) != (width as usize, height as usize) {
                bail!(
                    "{}: reference is {}×{}, the render {width}×{height}",
                    path.display(),
                    image.width,
                    image.height
                );
            }
            Some(image.pixels)
        }
        None => None,
    };
    let traversal = Arc::new(vcm_rs::cpu_traversal(&scene).context("building the BVH")?);
    let settings = PtSettings {
        width,
        height,
        seed: args.seed,
        max_depth: args.max_depth,
    };
    let mut tracer = PathTracer::new(Arc::clone(&scene), traversal, settings)?;
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&interrupted);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .context("installing the Ctrl-C handler")?;

    let progress = progress_bar(&budget);
    let mut film = Film::new(width, height);
    let mut totals = Totals::default();
    let mut checkpoints = Vec::new();
    let mut next_checkpoint = 1.0;
    let start = Instant::now();
    let mut spp = 0;
    while !budget.done(spp, start.elapsed()) && !interrupted.load(Ordering::SeqCst) {
        totals.add(&tracer.render_frame(&mut film, spp));
        spp += 1;
        let seconds = start.elapsed().as_secs_f64();
        progress.set_position(match budget {
            Budget::Samples(_) => u64::from(spp),
            Budget::Seconds(_) => (seconds * 10.0) as u64,
        });
        if let Some(reference) = &reference
            && seconds >= next_checkpoint
        {
            checkpoints.push(checkpoint(&film, reference, seconds, spp));
            while next_checkpoint <= seconds {
                next_checkpoint *= 2.0;
            }
        }
    }
    progress.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    if interrupted.load(Ordering::SeqCst) {
        eprintln!("interrupted: writing the {spp} samples per pixel rendered so far");
    }
    if let Some(reference) = &reference {
        checkpoints.push(checkpoint(&film, reference, elapsed, spp));
    }

    let image = RgbImage {
        width: width as usize,
        height: height as usize,
        pixels: film.mean(),
    };
    image.write_exr(&args.output)?;
    let png = args.output.with_extension("png");
    image.write_png(&png, 0.0)?;
    if let Some(report) = &args.report {
        write_report(report, &checkpoints)?;
        let plot = report.with_extension("png");
        let series = Series {
            label: format!("{:?}", args.algo).to_lowercase(),
            points: checkpoints
                .iter()
                .map(|c| (c.seconds, c.metrics.relmse))
                .collect(),
        };
        let title = format!("relMSE over time: {}", args.scene.display());
        plot_relmse(&plot, &title, &[series])?;
        println!("wrote {} and {}", report.display(), plot.display());
    }
    print_summary(&film, &totals, spp, elapsed, &checkpoints);
    println!("wrote {} and {}", args.output.display(), png.display());
    Ok(())
}

/// Fails early, before rendering, when the output folder does not exist.
fn check_writable(output: &Path) -> anyhow::Result<()> {
    let folder = match output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        bail!("{}: the output folder does not exist", output.display());
    }
    Ok(())
}

fn progress_bar(budget: &Budget) -> indicatif::ProgressBar {
    let (length, template) = match *budget {
        Budget::Samples(n) => (
            u64::from(n),
            "{bar:40} {pos}/{len} spp, {elapsed} elapsed, {eta} left",
        ),
        Budget::Seconds(s) => ((s * 10.0) as u64, "{bar:40} {elapsed} of the time budget"),
    };
    let bar = indicatif::ProgressBar::new(length);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

fn checkpoint(film: &Film, reference: &[glam::Vec3], seconds: f64, spp: u32) -> Checkpoint {
    let metrics = compare(&film.mean(), reference).expect("sizes were checked when loading");
    Checkpoint {
        seconds,
        spp,
        metrics,
    }
}

/// Writes the convergence CSV through a temporary file.
fn write_report(path: &Path, checkpoints: &[Checkpoint]) -> anyhow::Result<()> {
    let mut csv = String::from("seconds,spp,rmse,relmse,mae\n");
    for c in checkpoints {
        let m = &c.metrics;
        csv += &format!(
            "{:.3},{},{:.6e},{:.6e},{:.6e}\n",
            c.seconds, c.spp, m.rmse, m.relmse, m.mae
        );
    }
    write_atomically(path, |temporary| std::fs::write(temporary, csv), |e| e)
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// Peak resident memory of this process in MiB (Linux), if known.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

fn print_summary(film: &Film, totals: &Totals, spp: u32, elapsed: f64, checkpoints: &[Checkpoint]) {
    let pixels = f64::from(film.width()) * f64::from(film.height());
    let samples = pixels * f64::from(spp);
    let per_second = |n: u64| n as f64 / elapsed.max(1e-9) / 1e6;
    let rays = totals.camera_rays + totals.continuation_rays + totals.shadow_rays;
    let busy = (totals.traversal + totals.shading).as_secs_f64().max(1e-9);
    println!(
        "rendered {spp} spp at {}×{} in {elapsed:.2} s: {:.2} M samples/s",
        film.width(),
        film.height(),
        samples / elapsed.max(1e-9) / 1e6
    );
    println!(
        "rays: {:.2} M/s (camera {:.2}, continuation {:.2}, shadow {:.2})",
        per_second(rays),
        per_second(totals.camera_rays),
        per_second(totals.continuation_rays),
        per_second(totals.shadow_rays)
    );
    println!(
        "time: traversal {:.2} s ({:.0}%), shading {:.2} s ({:.0}%)",
        totals.traversal.as_secs_f64(),
        100.0 * totals.traversal.as_secs_f64() / busy,
        totals.shading.as_secs_f64(),
        100.0 * totals.shading.as_secs_f64() / busy
    );
    println!("dropped non-finite samples: {}", film.dropped());
    if let Some(mib) = peak_memory_mib() {
        println!("peak memory: {mib:.0} MiB");
    }
    if let Some(last) = checkpoints.last() {
        let m = &last.metrics;
        println!(
            "error: rmse {:.4e}, relMSE {:.4e}, mae {:.4e}",
            m.rmse, m.relmse, m.mae
        );
    }
}
