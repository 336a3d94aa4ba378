//! `pathstream devices`: OpenCL platforms and devices, and what `auto` picks.

use super::{outln, CliError};
use pathstream::render::backend::opencl::{auto_pick, list_devices};

#[derive(clap::Args, Debug)]
pub struct DevicesArgs {
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: DevicesArgs) -> Result<(), CliError> {
    let listed = list_devices();
    let auto = match &listed {
        Ok(devices) => match auto_pick(devices) {
            Some(d) => format!("OpenCL device {} ({})", d.index, d.name.trim()),
            None => "rayon on the CPU (no OpenCL GPU)".to_owned(),
        },
        Err(why) => format!("rayon on the CPU ({why})"),
    };
    if args.json {
        let value = serde_json::json!({
            "devices": listed.as_ref().ok(),
            "error": listed.as_ref().err(),
            "auto": auto,
        });
        outln!("{value}")?;
        return Ok(());
    }
    match &listed {
        Ok(devices) => {
            outln!("OpenCL devices:")?;
            for d in devices {
                outln!("  [{}] {}", d.index, d.describe())?;
            }
        }
        Err(why) => outln!("OpenCL: {why}")?,
    }
    outln!("auto picks: {auto}")?;
    Ok(())
}
