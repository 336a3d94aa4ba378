//! `pathstream`: the command line. Each subcommand lives in `cli/`.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// A remote progressive path tracer: renders scenes on OpenCL devices or the
/// CPU and streams the converging image.
#[derive(Parser, Debug)]
#[command(name = "pathstream", version, about, long_about = None)]
struct Args {
    /// What to do; without one, `serve` with its defaults.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the render service: HTTP API, WebSocket stream, browser client (the default).
    Serve(cli::serve::ServeArgs),
    /// Render a scene to a PNG or PFM file, with a progress bar.
    Render(cli::render::RenderArgs),
    /// Measure throughput and the speed/accuracy trade of every quality setting.
    Bench(cli::bench::BenchArgs),
    /// List the built-in scenes, or print one as scene JSON.
    Scenes(cli::scenes::ScenesArgs),
    /// List OpenCL platforms and devices, and which one `auto` picks.
    Devices(cli::devices::DevicesArgs),
    /// Relative RMS error of a PFM image against a reference PFM.
    Diff(cli::diff::DiffArgs),
}

fn main() -> ExitCode {
    let mut args = Args::parse();
    if args.command.is_none() {
        // `pathstream` alone serves, reading PATHSTREAM_ADDR / PATHSTREAM_TOKEN.
        args = Args::parse_from(["pathstream", "serve"]);
    }
    let serving = matches!(args.command, Some(Command::Serve(_)));
    let default_filter = if serving { "info" } else { "warn" };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_filter)),
        )
        .with_writer(std::io::stderr)
        .init();
    let result = match args.command {
        Some(Command::Serve(a)) => cli::serve::run(a),
        None => cli::serve::run(cli::serve::ServeArgs::default()),
        Some(Command::Render(a)) => cli::render::run(a),
        Some(Command::Bench(a)) => cli::bench::run(a),
        Some(Command::Scenes(a)) => cli::scenes::run(a),
        Some(Command::Diff(a)) => cli::diff::run(a),
        Some(Command::Devices(a)) => cli::devices::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}
