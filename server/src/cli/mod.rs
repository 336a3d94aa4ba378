//! Subcommands of the `pathstream` binary.

pub mod bench;
pub mod devices;
pub mod diff;
pub mod render;
pub mod scenes;
pub mod serve;

use std::process::ExitCode;

/// A failed command: bad input (exit 2) or a failure while working (exit 1).
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error("{0}")]
    Usage(String),
    #[error("{0}")]
    Failed(String),
}

impl CliError {
    pub fn exit_code(&self) -> ExitCode {
        match self {
            CliError::Usage(_) => ExitCode::from(2),
            CliError::Failed(_) => ExitCode::from(1),
        }
    }
}

/// `on` / `off` switches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}
