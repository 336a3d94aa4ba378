//! `pathstream diff`: the relative RMS error of an image against a reference
//! (both linear PFM), the measure the film's error estimate predicts.

use super::{outln, CliError};
use pathstream::render::film::relative_rms_error;
use pathstream::render::output::decode_pfm;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct DiffArgs {
    /// Reference image (.pfm), e.g. a long render.
    reference: PathBuf,
    /// Image to measure (.pfm), same size.
    image: PathBuf,
}

fn read(path: &PathBuf) -> Result<(u32, u32, Vec<[f32; 3]>), CliError> {
    let bytes =
        std::fs::read(path).map_err(|e| CliError::Usage(format!("{}: {e}", path.display())))?;
    decode_pfm(&bytes).map_err(|e| CliError::Usage(format!("{}: {e}", path.display())))
}

pub fn run(args: DiffArgs) -> Result<(), CliError> {
    let (rw, rh, reference) = read(&args.reference)?;
    let (w, h, image) = read(&args.image)?;
    if (rw, rh) != (w, h) {
        return Err(CliError::Usage(format!(
            "{}: size {w}x{h} differs from the reference's {rw}x{rh}",
            args.image.display()
        )));
    }
    outln!(
        "relative RMS error {:.4}%",
        relative_rms_error(&image, &reference) * 100.0
    )?;
    Ok(())
}
