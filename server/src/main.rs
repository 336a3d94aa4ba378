//! `pathstream`: the command line. Each subcommand lives in `cli/`.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// A remote progressive path tracer: renders scenes on OpenCL devices or the
/// CPU and streams the converging image.
#[derive(Parser, Debug)]
#[command(name = "pathstream", version, about, long_about = None)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to a PNG or PFM file, with a progress bar.
    Render(cli::render::RenderArgs),
    /// List the built-in scenes, or print one as scene JSON.
    Scenes(cli::scenes::ScenesArgs),
    /// List OpenCL platforms and devices, and which one `auto` picks.
    Devices(cli::devices::DevicesArgs),
    /// Relative RMS error of a PFM image against a reference PFM.
    Diff(cli::diff::DiffArgs),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let args = Args::parse();
    let result = match args.command {
        Command::Render(a) => cli::render::run(a),
        Command::Scenes(a) => cli::scenes::run(a),
        Command::Diff(a) => cli::diff::run(a),
        Command::Devices(a) => cli::devices::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}
