//! `vcm`: the command line front end of vcm-rs.

mod info;

use clap::{Parser, Subcommand};

/// vcm-rs: a physically based renderer built around Vertex Connection and Merging.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Load a scene and print what it contains (geometry, materials, lights, features,
    /// warnings), and the CPU BVH's build time and size.
    Info(info::InfoArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => info::run(&args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
