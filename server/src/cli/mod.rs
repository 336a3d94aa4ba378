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

/// `println!` for a command's output: `Ok` also when the reader has gone
/// (`pathstream scenes --json cornell | head`), which `println!` answers
/// with a panic; any other failure to write is the command's failure.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use outln;

/// Writes `text` to standard output (see [`outln`]).
pub fn write_out(text: std::fmt::Arguments) -> Result<(), CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_fmt(text).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(CliError::Failed(format!("writing to standard output: {e}")))
        }
        _ => Ok(()),
    }
}

/// `on` / `off` switches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}
