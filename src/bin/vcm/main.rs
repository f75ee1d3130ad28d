//! `vcm`: the command line front end of vcm-rs.

// First, so that its `say!` and `tell!` macros are in scope in the modules below.
#[macro_use]
mod say;

mod compare;
mod convergence;
mod crops;
mod experiment;
mod info;
mod merge;
mod process;
mod progressive;
mod render;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// vcm-rs: a physically based renderer built around Vertex Connection and Merging.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to a linear EXR and a tone-mapped PNG beside it.
    Render(render::RenderArgs),
    /// Render a scene with several algorithms for the same time each and compare their error
    /// against a reference over time: one relMSE plot, a CSV and a throughput table.
    Convergence(convergence::ConvergenceArgs),
    /// Render every scene of an experiment file with every run configuration for the same
    /// time, against a reference: images, error images, CSVs, relMSE plots, an equal-time
    /// table and a Markdown report (docs/experiments.md); resumes where it was interrupted.
    Experiment(experiment::ExperimentArgs),
    /// Merge render states of one image (shards from `vcm render --samples A..B --state`)
    /// into an EXR, a PNG and, if asked, one state.
    Merge(merge::MergeArgs),
    /// Error metrics (RMSE, relMSE, MAE) between two EXR images, and a false-colour error image.
    Compare(compare::CompareArgs),
    /// Load a scene and print what it contains (geometry, materials, lights, features,
    /// warnings), and the CPU BVH's build time and size.
    Info(info::InfoArgs),
}

fn main() -> std::process::ExitCode {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let result = match cli.command {
        Command::Render(args) => {
            let render = matches.subcommand_matches("render").unwrap_or(&matches);
            render::run(&args, render)
        }
        Command::Compare(args) => compare::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Convergence(args) => convergence::run(&args),
        Command::Experiment(args) => experiment::run(&args),
        Command::Info(args) => info::run(&args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            tell!("error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
