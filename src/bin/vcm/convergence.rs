//! `vcm convergence`: renders a scene with several algorithms in turn for the same time,
//! records each one's error against a reference over time, draws all relMSE curves in one
//! plot and prints a table of throughput per algorithm.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::bail;
use vcm::Film;

use crate::progressive::{self, Outcome, Watch};
use crate::render::{
    RenderSetup, build_traversal, check_outputs, load_scene, read_reference, relmse_points,
    set_threads, stop_flag, write_text,
};
use vcm_rs::integrators::{Algorithm, image_size};
use vcm_rs::plot::{Series, plot_relmse};

/// Arguments of `vcm convergence`.
#[derive(clap::Args)]
pub struct ConvergenceArgs {
    /// The scene file (.gltf, .glb or .obj).
    scene: PathBuf,
    /// The algorithms to compare, in order.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "pt,lt,bpt,ppm,vcm"
    )]
    algos: Vec<Algorithm>,
    /// Seconds each algorithm renders.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    time: f64,
    /// Reference EXR (of the same size) that errors are measured against.
    #[arg(long)]
    reference: PathBuf,
    #[command(flatten)]
    setup: RenderSetup,
    /// The plot (PNG); the CSV of every checkpoint (algorithm,seconds,spp,rmse,relmse,mae) is
    /// written beside it.
    #[arg(short, long, default_value = "convergence.png")]
    output: PathBuf,
}

/// Renders with every algorithm, then writes the CSV and the plot and prints the table.
pub fn run(args: &ConvergenceArgs) -> anyhow::Result<()> {
    set_threads(args.setup.threads)?;
    let budget = progressive::budget_from_options(None, Some(args.time))?;
    let csv_path = args.output.with_extension("csv");
    let outputs = [
        ("the plot", args.output.clone()),
        ("the CSV", csv_path.clone()),
    ];
    check_outputs(&outputs, &[&args.scene, &args.reference])?;
    let camera = args.setup.camera.as_deref();
    let scene = load_scene(&args.scene, camera, &args.setup.limits)?;
    let size = image_size(&scene, args.setup.width, args.setup.height);
    let reference = read_reference(&args.reference, size)?;
    let traversal = build_traversal(args.setup.backend, &scene)?;
    let interrupted = stop_flag()?;
    let mut outcomes = Vec::new();
    for &algorithm in &args.algos {
        tell!("rendering with {} for {} s", algorithm.name(), args.time);
        let traversal = Arc::clone(&traversal) as _;
        let options = &args.setup.integrator;
        let mut integrator = args
            .setup
            .integrator(algorithm, &scene, traversal, size, options, None)?;
        let mut film = Film::new(size.0, size.1);
        let mut outcome = progressive::render(
            integrator.as_mut(),
            args.setup.frames(),
            &mut film,
            budget,
            &interrupted,
            Watch {
                reference: Some(&reference),
                ..Watch::default()
            },
        )?;
        if let Some(failure) = outcome.failure.take() {
            bail!("{}: {failure}", algorithm.name());
        }
        outcomes.push((algorithm, outcome));
        if interrupted.is_raised() {
            tell!("interrupted: writing the results so far");
            break;
        }
    }
    let mut csv = String::from("algorithm,seconds,spp,rmse,relmse,mae\n");
    for (algorithm, outcome) in &outcomes {
        for checkpoint in &outcome.checkpoints {
            csv += &format!("{},{}\n", algorithm.name(), checkpoint.csv_row());
        }
    }
    write_text(&csv_path, csv)?;
    let series: Vec<Series> = outcomes
        .iter()
        .map(|(algorithm, outcome)| Series {
            label: algorithm.name().to_string(),
            points: relmse_points(&outcome.checkpoints),
        })
        .collect();
    let title = format!("relMSE over time: {}", args.scene.display());
    plot_relmse(&args.output, &title, &series)?;
    print_table(&outcomes, size);
    say!("wrote {} and {}", args.output.display(), csv_path.display());
    Ok(())
}

/// Throughput and final error per algorithm (the thesis's Table 5.1).
fn print_table(outcomes: &[(Algorithm, Outcome)], (width, height): (u32, u32)) {
    say!(
        "{:<5} {:>10} {:>12} {:>10} {:>8} {:>12}",
        "algo",
        "M rays/s",
        "M samples/s",
        "frames/s",
        "frames",
        "final relMSE"
    );
    let pixels = f64::from(width) * f64::from(height);
    for (algorithm, outcome) in outcomes {
        let seconds = outcome.seconds.max(1e-9);
        let frames = f64::from(outcome.spp);
        let relmse = outcome
            .checkpoints
            .last()
            .map_or(f64::NAN, |c| c.metrics.relmse);
        say!(
            "{:<5} {:>10.2} {:>12.3} {:>10.2} {:>8} {:>12.4e}",
            algorithm.name(),
            outcome.totals.rays() as f64 / seconds / 1e6,
            frames * pixels / seconds / 1e6,
            frames / seconds,
            outcome.spp,
            relmse
        );
    }
}
