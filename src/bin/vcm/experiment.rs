//! `vcm experiment`: renders every scene of an experiment file with every run configuration
//! for the same time (or sample count), measures each against a reference over time, and
//! writes per run an EXR, a PNG, a false-colour error image and CSVs, per scene a relMSE plot,
//! and for the whole experiment an equal-time table (CSV) and a Markdown report. A finished
//! run is recognised by its totals file and read back instead of rendered again, so an
//! interrupted experiment resumes where it stopped.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use clap::Parser;
use glam::Vec3;
use serde::Deserialize;
use vcm::Film;
use vcm::image_io::{RgbImage, write_error_png};
use vcm::metrics::relative_error_per_pixel;
use vcm_rs::integrators::choice::Pilots;
use vcm_rs::integrators::{AlgorithmOption, IntegratorOptions, image_size};
use vcm_rs::plot::{Series, plot_relmse};
use vcm_rs::render_loop::{Frames, ScheduleOptions};
use vcm_rs::scene::Scene;
use vcm_rs::scene::relight::lit_by_bulb_and_sky;
use vcm_rs::{Backend, Shading, Traversals};

use crate::crops::Crop;
use crate::progressive::{self, Budget, Checkpoint, Part, Watch};
use crate::render::{
    SceneLimits, load_scene, relmse_points, stop_flag, tell_traversal, write_report, write_text,
};

/// Arguments of `vcm experiment`.
#[derive(clap::Args)]
pub struct ExperimentArgs {
    /// The experiment file (TOML; see docs/experiments.md).
    file: PathBuf,
    /// The folder for the results (default: beside the file, named after it).
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    limits: SceneLimits,
}

/// An experiment file. Paths in it are relative to its folder.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Experiment {
    /// The report's title.
    title: String,
    /// Image width in pixels (the height comes from each scene's camera).
    #[serde(default = "default_width")]
    width: u32,
    /// Seconds each run renders (equal time); or `spp`.
    seconds: Option<f64>,
    /// Samples per pixel each run renders (equal samples); or `seconds`.
    spp: Option<u32>,
    /// The run the speed-ups are measured against (default: the first).
    baseline: Option<String>,
    /// How references are made, for scenes that do not name a reference file.
    reference: Option<ReferenceSpec>,
    /// The scenes, each rendered by every run.
    scenes: Vec<SceneEntry>,
    /// The run configurations.
    runs: Vec<Run>,
}

/// A reference rendered by the experiment (once per scene; kept in the results folder).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReferenceSpec {
    /// Options as for a run.
    #[serde(default)]
    options: String,
    /// Samples per pixel.
    spp: u32,
}

/// A scene of the experiment.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneEntry {
    /// The scene file.
    path: PathBuf,
    /// The file's camera to render from.
    camera: Option<String>,
    /// A reference EXR of the image size (instead of rendering one).
    reference: Option<PathBuf>,
    /// The square the report shows enlarged, `[x, y, size]` in pixels (default: where the
    /// runs' errors sum to the most).
    crop: Option<[usize; 3]>,
    /// Lights that replace the file's (default: the file's own).
    lights: Option<SceneLights>,
}

/// Lights an experiment gives a scene in place of its file's.
#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum SceneLights {
    /// A point light above the model's front right and a dim constant sky
    /// ([`lit_by_bulb_and_sky`]), for models that come without lights.
    BulbAndSky,
}

/// A run configuration: a name and `vcm render` options.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Run {
    /// The name in tables, plots and file names.
    name: String,
    /// `vcm render` options: the algorithm, its options, the backend and the schedule.
    #[serde(default)]
    options: String,
}

fn default_width() -> u32 {
    256
}

/// The options a run's `options` string may give.
#[derive(Parser)]
#[command(no_binary_name = true)]
struct RunOptions {
    #[arg(long, value_enum, default_value_t = AlgorithmOption::Auto)]
    algo: AlgorithmOption,
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    #[arg(long, value_enum, default_value_t = Shading::Cpu)]
    shading: Shading,
    #[command(flatten)]
    integrator: IntegratorOptions,
    #[command(flatten)]
    schedule: ScheduleOptions,
}

/// What a finished run measured.
struct Measured {
    /// Samples per pixel rendered.
    spp: u32,
    /// Wall-clock seconds of the render loop.
    seconds: f64,
    /// Frames rendered.
    frames: u32,
    /// The error over time; the last row is the final error.
    checkpoints: Vec<Checkpoint>,
}

/// Runs the experiment in `args.file`.
pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let file = &args.file;
    let text = std::fs::read_to_string(file)
        .with_context(|| format!("{}: cannot read the experiment", file.display()))?;
    let experiment: Experiment =
        toml::from_str(&text).with_context(|| format!("{}: not an experiment", file.display()))?;
    let base = file.parent().unwrap_or(Path::new("."));
    let budget = match (experiment.seconds, experiment.spp) {
        (Some(_), Some(_)) | (None, None) => {
            bail!("{}: give `seconds` or `spp` (one of them)", file.display())
        }
        (seconds, spp) => progressive::budget_from_options(spp, seconds)
            .with_context(|| format!("{}: `seconds` or `spp`", file.display()))?,
    };
    let runs = parse_runs(file, &experiment.runs)?;
    let baseline = match &experiment.baseline {
        Some(name) => runs
            .iter()
            .position(|(run, _)| &run.name == name)
            .with_context(|| format!("{}: the baseline `{name}` is not a run", file.display()))?,
        None => 0,
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| file.with_extension(""));
    std::fs::create_dir_all(&output)
        .with_context(|| format!("{}: cannot create the results folder", output.display()))?;
    let stop = stop_flag()?;
    let mut report = report_header(&experiment, file, budget);
    let mut table = String::from(
        "scene,run,spp,seconds,m_samples_per_second,frames_per_second,relmse,rmse,speedup\n",
    );
    let mut position = Position {
        total: experiment.scenes.len() * runs.len(),
        ..Position::default()
    };
    let screen = Screen::new(position.total);
    for entry in &experiment.scenes {
        let path = base.join(&entry.path);
        let scene = load_scene(&path, entry.camera.as_deref(), &args.limits)?;
        let scene = match entry.lights {
            Some(SceneLights::BulbAndSky) => {
                Arc::new(lit_by_bulb_and_sky(Arc::unwrap_or_clone(scene)))
            }
            None => scene,
        };
        let size = image_size(&scene, experiment.width, None);
        let chosen_crop = entry
            .crop
            .map(|crop| Crop::inside(crop, size.0 as usize, size.1 as usize))
            .transpose()
            .with_context(|| format!("{}: scene {}", file.display(), path.display()))?;
        let name = file_stem(&path);
        let folder = output.join(&name);
        std::fs::create_dir_all(&folder)
            .with_context(|| format!("{}: cannot create the folder", folder.display()))?;
        let mut traversals = Traversals::new(Arc::clone(&scene));
        // Loaded or rendered when the first run that is not finished needs it.
        let mut reference: Option<Vec<Vec3>> = None;
        let mut results = Vec::new();
        for (run, options) in &runs {
            let label = position.label(budget, &name, &run.name);
            say!("{label}");
            screen.job.set_message(label.clone());
            let span = screen.span(position.done);
            position.done += 1;
            if let Some(measured) = finished(&folder, run) {
                screen.job.set_position(span.end);
                results.push(measured);
                continue;
            }
            let reference: &[Vec3] = match &mut reference {
                Some(reference) => reference,
                None => reference.insert(match &entry.reference {
                    Some(file) => crate::render::read_reference(&base.join(file), size)?,
                    None => {
                        let spec = (&experiment, file.as_path());
                        let at = screen.part(span.start..span.start);
                        reference_for(spec, (&scene, &mut traversals, size), &folder, &stop, at)?
                    }
                }),
            };
            let setup = Setup {
                scene: &scene,
                traversals: &mut traversals,
                options,
                size,
                label: format!("{name}: {}", run.name),
                part: screen.part(span),
            };
            let measured = measure(setup, budget, reference, &folder, run, &stop)?;
            if stop.is_raised() {
                say!("interrupted: run the same command again to resume");
                return Ok(());
            }
            position.rendered += 1;
            position.seconds += measured.seconds;
            results.push(measured);
        }
        let reference = match reference {
            Some(reference) => Some(reference),
            None => reference_on_disk(entry, base, &folder, size)?,
        };
        let crop = reference
            .map(|reference| write_crops(&folder, &runs, &reference, size, chosen_crop))
            .transpose()?;
        let series: Vec<Series> = runs
            .iter()
            .zip(&results)
            .map(|((run, _), m)| Series {
                label: run.name.clone(),
                points: relmse_points(&m.checkpoints),
            })
            .collect();
        plot_relmse(&folder.join("relmse.png"), &name, &series)?;
        let pixels = f64::from(size.0) * f64::from(size.1);
        let results_of_scene = SceneResults {
            name: &name,
            runs: &runs,
            results: &results,
            crop,
            crop_chosen: chosen_crop.is_some(),
        };
        report_scene(&mut report, &results_of_scene, baseline, pixels);
        for ((run, _), m) in runs.iter().zip(&results) {
            let row = m.summary(pixels, &results[baseline]);
            let _ = writeln!(
                table,
                "{},{},{},{:.3},{:.4},{:.3},{:.6e},{:.6e},{:.3}",
                csv_field(&name),
                csv_field(&run.name),
                m.spp,
                m.seconds,
                row.samples_per_second / 1e6,
                row.frames_per_second,
                row.last.relmse,
                row.last.rmse,
                row.speedup
            );
        }
    }
    write_text(&output.join("table.csv"), table)?;
    write_text(&output.join("report.md"), report)?;
    say!(
        "wrote {} and {}",
        output.join("report.md").display(),
        output.join("table.csv").display()
    );
    Ok(())
}

/// The runs with their options parsed (as `vcm render` parses them); their names must give
/// distinct file names.
fn parse_runs<'a>(file: &Path, runs: &'a [Run]) -> anyhow::Result<Vec<(&'a Run, RunOptions)>> {
    if runs.is_empty() {
        bail!("{}: the experiment has no [[runs]]", file.display());
    }
    let mut parsed: Vec<(&Run, RunOptions)> = Vec::new();
    for run in runs {
        if parsed.iter().any(|(r, _)| slug(&r.name) == slug(&run.name)) || run.name.is_empty() {
            bail!(
                "{}: the run name `{}` is empty or names the files of another run",
                file.display(),
                run.name
            );
        }
        let options = RunOptions::try_parse_from(run.options.split_whitespace())
            .map_err(|e| anyhow::anyhow!("{}: run `{}`: {e}", file.display(), run.name))?;
        parsed.push((run, options));
    }
    Ok(parsed)
}

/// The reference of `scene`: `reference.exr` in `folder` if an earlier run of the experiment
/// rendered it, else rendered now as `[reference]` says.
fn reference_for(
    (experiment, file): (&Experiment, &Path),
    (scene, traversals, size): (&Arc<Scene>, &mut Traversals, (u32, u32)),
    folder: &Path,
    stop: &vcm::StopFlag,
    part: Part<'_>,
) -> anyhow::Result<Vec<Vec3>> {
    let path = folder.join("reference.exr");
    if path.is_file() {
        say!(
            "reference: {} (delete it to render it again)",
            path.display()
        );
        return crate::render::read_reference(&path, size);
    }
    let Some(spec) = &experiment.reference else {
        bail!(
            "{}: {} names no reference file and there is no [reference] to render one",
            file.display(),
            scene.path.display()
        );
    };
    let options = RunOptions::try_parse_from(spec.options.split_whitespace())
        .map_err(|e| anyhow::anyhow!("{}: [reference]: {e}", file.display()))?;
    say!("reference: {} spp of {}", spec.spp, options.algo.name());
    let setup = Setup {
        scene,
        traversals,
        options: &options,
        size,
        label: format!("reference of {}", file_stem(&scene.path)),
        part,
    };
    let (film, _) = render(setup, Budget::Samples(spec.spp), None, stop)?;
    if stop.is_raised() {
        bail!("interrupted while rendering the reference; nothing was written");
    }
    let image = film.image();
    image.write_exr(&path)?;
    Ok(image.pixels)
}

/// How far an experiment has come, for the label of each run's progress bar.
#[derive(Default)]
struct Position {
    /// Renders in the experiment (scenes × runs).
    total: usize,
    /// Renders started or found finished, in this invocation or an earlier one.
    done: usize,
    /// Renders finished in this invocation, and the seconds they took.
    rendered: usize,
    seconds: f64,
}

impl Position {
    /// `[k/total] scene: run`, and the time the experiment has left where it can tell: its
    /// budgets for time budgets, else the mean time of the runs rendered so far.
    fn label(&self, budget: Budget, scene: &str, run: &str) -> String {
        let left = (self.total - self.done) as f64;
        let seconds_left = match budget {
            Budget::Seconds(seconds) => Some(seconds * left),
            Budget::Samples(_) if self.rendered > 0 => {
                Some(self.seconds / self.rendered as f64 * left)
            }
            Budget::Samples(_) => None,
        };
        let count = format!("[{}/{}] {scene}: {run}", self.done + 1, self.total);
        match seconds_left {
            Some(seconds) => format!("{count} (about {} left)", duration_text(seconds)),
            None => count,
        }
    }
}

/// The experiment's progress on screen: one bar over all its renders, above the bar of the
/// render in progress; lines of output are written above both while it lasts.
struct Screen {
    bars: indicatif::MultiProgress,
    job: indicatif::ProgressBar,
}

/// Length of one render on the experiment's bar.
const RENDER_STEPS: u64 = 1000;

impl Screen {
    /// The bar of an experiment of `renders` renders, on stderr (hidden where that is not a
    /// terminal).
    fn new(renders: usize) -> Screen {
        let bars = indicatif::MultiProgress::new();
        let job = bars.add(indicatif::ProgressBar::new(renders as u64 * RENDER_STEPS));
        if let Ok(style) = indicatif::ProgressStyle::with_template("experiment {bar:40} {msg}") {
            job.set_style(style);
        }
        crate::say::write_above(Some(bars.clone()));
        Screen { bars, job }
    }

    /// The span of render `index` (0-based) on the experiment's bar.
    fn span(&self, index: usize) -> std::ops::Range<u64> {
        let start = index as u64 * RENDER_STEPS;
        start..start + RENDER_STEPS
    }

    /// A render covering `span` of the experiment's bar.
    fn part(&self, span: std::ops::Range<u64>) -> Part<'_> {
        Part {
            bars: &self.bars,
            job: &self.job,
            span,
        }
    }
}

impl Drop for Screen {
    /// Takes the experiment's bar away; lines are written where the cursor is again.
    fn drop(&mut self) {
        self.job.finish_and_clear();
        crate::say::write_above(None);
    }
}

/// `seconds` rounded for people: "40 s", "12 min", "2 h 05 min".
fn duration_text(seconds: f64) -> String {
    let seconds = seconds.max(0.0).round() as u64;
    match seconds {
        0..90 => format!("{seconds} s"),
        90..5400 => format!("{} min", (seconds + 30) / 60),
        _ => {
            let minutes = (seconds + 30) / 60;
            format!("{} h {:02} min", minutes / 60, minutes % 60)
        }
    }
}

/// What a render of one configuration needs.
struct Setup<'a> {
    scene: &'a Arc<Scene>,
    traversals: &'a mut Traversals,
    options: &'a RunOptions,
    size: (u32, u32),
    /// Shown before the render's progress bar.
    label: String,
    /// Where on the experiment's bar the render is.
    part: Part<'a>,
}

/// Renders `setup` within `budget`, measuring against `reference` if given, its progress bar
/// after the setup's label.
fn render(
    setup: Setup<'_>,
    budget: Budget,
    reference: Option<&[Vec3]>,
    stop: &vcm::StopFlag,
) -> anyhow::Result<(Film, progressive::Outcome)> {
    let Setup {
        scene,
        traversals,
        options,
        size,
        label,
        part,
    } = setup;
    let built = traversals
        .built(options.backend, tell_traversal)
        .context("building the ray traversal backend")?;
    let started = std::time::Instant::now();
    let algorithm = crate::render::settle_algorithm(
        options.algo,
        (scene, Pilots::of(built, options.shading)?),
        size,
        &options.integrator,
        (stop, false),
    )?;
    let frames = Frames::new(options.schedule, options.backend);
    let samples_left = budget.remaining(0, std::time::Duration::ZERO).samples;
    let mut integrator = frames.shaded_integrator(
        (algorithm, options.shading),
        scene,
        built,
        size,
        &options.integrator,
        samples_left,
    )?;
    let mut film = Film::new(size.0, size.1);
    let mut outcome = progressive::render(
        integrator.as_mut(),
        frames,
        &mut film,
        budget,
        stop,
        Watch {
            reference,
            periodic: None,
            label: Some(label),
            part: Some(part),
            started: Some(started),
        },
    )?;
    if let Some(failure) = outcome.failure.take() {
        bail!("{failure}");
    }
    Ok((film, outcome))
}

/// The measurements of `run` if an earlier invocation finished it (its totals file exists).
fn finished(folder: &Path, run: &Run) -> Option<Measured> {
    let name = slug(&run.name);
    let totals = folder.join(format!("{name}.totals.csv"));
    let measured = read_back(&totals, &folder.join(format!("{name}.csv")))?;
    say!("  finished earlier: {}", totals.display());
    Some(measured)
}

/// Renders `run` and writes its results (the totals file last, so that it marks a finished
/// run); what it measured.
fn measure(
    setup: Setup<'_>,
    budget: Budget,
    reference: &[Vec3],
    folder: &Path,
    run: &Run,
    stop: &vcm::StopFlag,
) -> anyhow::Result<Measured> {
    let name = slug(&run.name);
    let totals = folder.join(format!("{name}.totals.csv"));
    let report = folder.join(format!("{name}.csv"));
    let (film, outcome) = render(setup, budget, Some(reference), stop)?;
    let measured = Measured {
        spp: outcome.spp,
        seconds: outcome.seconds,
        frames: outcome.frames.count,
        checkpoints: outcome.checkpoints,
    };
    if stop.is_raised() {
        return Ok(measured);
    }
    let image = film.image();
    image.write_exr(&folder.join(format!("{name}.exr")))?;
    image.write_png(&folder.join(format!("{name}.png")), 0.0)?;
    write_error_image(&folder.join(format!("{name}.error.png")), &image, reference)?;
    write_report(&report, &measured.checkpoints)?;
    write_text(
        &totals,
        format!(
            "seconds,spp,frames\n{:.6},{},{}\n",
            measured.seconds, measured.spp, measured.frames
        ),
    )?;
    Ok(measured)
}

/// The false-colour relative error of `image` against `reference`.
fn write_error_image(path: &Path, image: &RgbImage, reference: &[Vec3]) -> anyhow::Result<()> {
    let errors = relative_error_per_pixel(&image.pixels, reference);
    write_error_png(path, image.width, image.height, &errors)?;
    Ok(())
}

/// A finished run's measurements from its totals and error CSVs (`None` if either is
/// missing or unreadable: the run is rendered again).
fn read_back(totals: &Path, report: &Path) -> Option<Measured> {
    let totals = std::fs::read_to_string(totals).ok()?;
    let row: Vec<&str> = totals.lines().nth(1)?.split(',').collect();
    let checkpoints = std::fs::read_to_string(report)
        .ok()?
        .lines()
        .skip(1)
        .map(Checkpoint::from_csv_row)
        .collect::<Option<Vec<_>>>()?;
    if checkpoints.is_empty() {
        return None;
    }
    Some(Measured {
        seconds: row.first()?.parse().ok()?,
        spp: row.get(1)?.parse().ok()?,
        frames: row.get(2)?.parse().ok()?,
        checkpoints,
    })
}

/// A run's figures for the table and the report.
struct Summary {
    samples_per_second: f64,
    frames_per_second: f64,
    /// The error at the end.
    last: vcm::metrics::ErrorMetrics,
    /// The baseline's final relMSE over this run's.
    speedup: f64,
}

impl Measured {
    /// The figures of this run of an image of `pixels`, against `baseline`.
    fn summary(&self, pixels: f64, baseline: &Measured) -> Summary {
        let last = final_error(self);
        Summary {
            samples_per_second: f64::from(self.spp) * pixels / self.seconds,
            frames_per_second: f64::from(self.frames) / self.seconds,
            last,
            speedup: final_error(baseline).relmse / last.relmse,
        }
    }
}

/// The error at the end of a run.
fn final_error(measured: &Measured) -> vcm::metrics::ErrorMetrics {
    measured
        .checkpoints
        .last()
        .expect("a run with a reference has a final checkpoint")
        .metrics
}

/// The report's title, machine and command.
fn report_header(experiment: &Experiment, file: &Path, budget: Budget) -> String {
    let each = match budget {
        Budget::Seconds(s) => format!("{s} s"),
        Budget::Samples(n) => format!("{n} samples per pixel"),
    };
    format!(
        "# {}\n\nEach run rendered {each}, {} pixels wide, on {} ({} threads). \
         Regenerate with `vcm experiment {}`; speed-up is the baseline's relMSE over the \
         run's at the end (at equal time, the ratio of efficiencies).\n",
        experiment.title,
        experiment.width,
        cpu_model(),
        rayon::current_num_threads(),
        file.display()
    )
}

/// What a scene's section of the report shows.
struct SceneResults<'a> {
    /// The scene's name, also its folder's.
    name: &'a str,
    runs: &'a [(&'a Run, RunOptions)],
    /// What each run measured, in the order of `runs`.
    results: &'a [Measured],
    /// The square shown enlarged, where there was a reference to compute errors with.
    crop: Option<Crop>,
    /// Whether the experiment file chose the square.
    crop_chosen: bool,
}

/// One scene's section: the plot, the table, the images with their error images and the
/// crops.
fn report_scene(report: &mut String, scene: &SceneResults<'_>, baseline: usize, pixels: f64) {
    let SceneResults {
        name,
        runs,
        results,
        crop,
        crop_chosen,
    } = *scene;
    let _ = write!(
        report,
        "\n## {name}\n\n![relMSE against time]({name}/relmse.png)\n\n\
         | run | spp | M samples/s | frames/s | relMSE | RMSE | speed-up vs {} |\n\
         | --- | --- | --- | --- | --- | --- | --- |\n",
        runs[baseline].0.name
    );
    for ((run, _), m) in runs.iter().zip(results) {
        let row = m.summary(pixels, &results[baseline]);
        let _ = writeln!(
            report,
            "| {} | {} | {:.3} | {:.2} | {:.3e} | {:.3e} | {:.2}× |",
            run.name,
            m.spp,
            row.samples_per_second / 1e6,
            row.frames_per_second,
            row.last.relmse,
            row.last.rmse,
            row.speedup
        );
    }
    let _ = writeln!(
        report,
        "\n| run | image | relative error |\n| --- | --- | --- |"
    );
    image_rows(report, name, runs, ["png", "error.png"]);
    let Some(crop) = crop else {
        return;
    };
    let chosen = if crop_chosen {
        "as the experiment file sets it"
    } else {
        "where the runs' errors sum to the most"
    };
    let _ = writeln!(
        report,
        "\nThe {size}×{size} pixels at ({x}, {y}), {chosen}, each pixel shown {scale}× \
         larger:\n\n| run | crop | relative error |\n| --- | --- | --- |\n\
         | reference | ![]({name}/reference.crop.png) | |",
        size = crop.size,
        x = crop.x,
        y = crop.y,
        scale = crop.scale(),
    );
    image_rows(report, name, runs, ["crop.png", "error-crop.png"]);
}

/// One table row per run: its name, then its images `RUN.{kinds[0]}` and `RUN.{kinds[1]}`
/// in the scene's folder `name`.
fn image_rows(report: &mut String, name: &str, runs: &[(&Run, RunOptions)], kinds: [&str; 2]) {
    let [left, right] = kinds;
    for (run, _) in runs {
        let file = slug(&run.name);
        let _ = writeln!(
            report,
            "| {} | ![]({name}/{file}.{left}) | ![]({name}/{file}.{right}) |",
            run.name
        );
    }
}

/// The reference of a scene whose runs all finished earlier, if it is still on disk: the
/// file the experiment names, or the one it rendered.
fn reference_on_disk(
    entry: &SceneEntry,
    base: &Path,
    folder: &Path,
    size: (u32, u32),
) -> anyhow::Result<Option<Vec<Vec3>>> {
    let path = match &entry.reference {
        Some(file) => base.join(file),
        None => folder.join("reference.exr"),
    };
    if !path.is_file() {
        return Ok(None);
    }
    crate::render::read_reference(&path, size).map(Some)
}

/// Writes the crops of the reference (`reference.crop.png`) and of each run's image and
/// relative error (`RUN.crop.png`, `RUN.error-crop.png`): at `chosen`, or where the runs'
/// errors sum to the most. Returns the square.
fn write_crops(
    folder: &Path,
    runs: &[(&Run, RunOptions)],
    reference: &[Vec3],
    size: (u32, u32),
    chosen: Option<Crop>,
) -> anyhow::Result<Crop> {
    let width = size.0 as usize;
    let mut images = Vec::with_capacity(runs.len());
    for (run, _) in runs {
        let path = folder.join(format!("{}.exr", slug(&run.name)));
        images.push(RgbImage::read_exr(&path)?);
    }
    let errors: Vec<Vec<f64>> = images
        .iter()
        .map(|image| relative_error_per_pixel(&image.pixels, reference))
        .collect();
    let crop = chosen.unwrap_or_else(|| {
        let total: Vec<f64> = (0..reference.len())
            .map(|pixel| errors.iter().map(|e| e[pixel]).sum())
            .collect();
        Crop::worst(&total, width, size.1 as usize)
    });
    let side = crop.size * crop.scale();
    let write_image = |pixels: &[Vec3], file: String| {
        let image = RgbImage {
            width: side,
            height: side,
            pixels: crop.cut(pixels, width),
        };
        image.write_png(&folder.join(file), 0.0)
    };
    write_image(reference, "reference.crop.png".into())?;
    for (((run, _), image), error) in runs.iter().zip(&images).zip(&errors) {
        let file = slug(&run.name);
        write_image(&image.pixels, format!("{file}.crop.png"))?;
        let path = folder.join(format!("{file}.error-crop.png"));
        write_error_png(&path, side, side, &crop.cut(error, width))?;
    }
    Ok(crop)
}

/// The CPU's model name (from /proc/cpuinfo where there is one).
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("model name"))
                .map(|l| l.trim_start_matches([' ', '\t', ':']).to_string())
        })
        .unwrap_or_else(|| "an unknown CPU".into())
}

/// `text` as a CSV field: quoted (with quotes doubled) where it holds a comma or a quote.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// A file's name without its extension.
fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

/// `name` as a file name: letters, digits, `-` and `_`, the rest as `-`.
fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_in_seconds_minutes_or_hours() {
        assert_eq!(duration_text(40.4), "40 s");
        assert_eq!(duration_text(720.0), "12 min");
        assert_eq!(duration_text(2.0 * 3600.0 + 5.0 * 60.0), "2 h 05 min");
        assert_eq!(duration_text(-1.0), "0 s");
    }

    #[test]
    fn the_time_left_counts_the_runs_not_yet_started() {
        let mut position = Position {
            total: 6,
            done: 2,
            ..Position::default()
        };
        let time = Budget::Seconds(30.0);
        let samples = Budget::Samples(64);
        // Four runs of 30 s, this one included.
        assert_eq!(
            position.label(time, "water", "vcm"),
            "[3/6] water: vcm (about 2 min left)"
        );
        // Sample budgets: unknown until a run has been timed, then their mean.
        assert_eq!(position.label(samples, "water", "vcm"), "[3/6] water: vcm");
        (position.rendered, position.seconds) = (2, 40.0);
        assert_eq!(
            position.label(samples, "water", "vcm"),
            "[3/6] water: vcm (about 80 s left)"
        );
    }
}
