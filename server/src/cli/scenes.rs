//! `pathstream scenes`: the built-in scene names, or one scene's JSON.

use super::{outln, CliError};
use pathstream::bench::scenes as bench;
use pathstream::render::scene::{builtin, BUILTIN_NAMES};

#[derive(clap::Args, Debug)]
pub struct ScenesArgs {
    /// Print this built-in or bench scene as scene JSON (a starting point for
    /// your own).
    #[arg(long, value_name = "NAME")]
    json: Option<String>,
}

fn describe(name: &str) -> &'static str {
    match name {
        "cornell" => "thesis scene 1: smallpt's box, two white diffuse balls, small light",
        "cornell-glass" => "thesis scene 2: mirror ball, glass ball, mirror back wall, small light",
        "cornell-quads" => "cornell-glass with the six walls as quads",
        "smallpt" => "smallpt's scene exactly (radius-1e5 walls, big light, Schlick glass)",
        "furnace" => {
            "white furnace: closed sphere, albedo 0.5, emission 0.5; radiance 1 everywhere"
        }
        _ => "",
    }
}

pub fn run(args: ScenesArgs) -> Result<(), CliError> {
    if let Some(name) = args.json {
        let scene = match builtin(&name) {
            Some(scene) => scene,
            None if name == bench::CORNELL_MESH_TEXTURED => {
                return Err(CliError::Usage(format!(
                    "--json: {name} has no JSON form: its balls' models and textures are made in memory \
                     (render it by name: `pathstream render --scene {name}`)"
                )))
            }
            None if bench::NAMES.iter().any(|(n, _)| *n == name) => {
                bench::load(&name).map_err(|e| CliError::Failed(e.to_string()))?
            }
            None => {
                let known: Vec<&str> = BUILTIN_NAMES
                    .iter()
                    .copied()
                    .chain(bench::NAMES.iter().map(|(n, _)| *n))
                    .collect();
                return Err(CliError::Usage(format!(
                    "--json: unknown scene '{name}' (known: {})",
                    known.join(", ")
                )));
            }
        };
        let text = serde_json::to_string_pretty(&scene.to_json())
            .map_err(|e| CliError::Failed(e.to_string()))?;
        outln!("{text}")?;
        return Ok(());
    }
    for name in BUILTIN_NAMES {
        outln!("{name:<20} {}", describe(name))?;
    }
    outln!("\nbench scenes (`pathstream bench --scenes`, `pathstream scenes --json`):")?;
    for (name, what) in bench::NAMES {
        outln!("{name:<20} {what}")?;
    }
    Ok(())
}
