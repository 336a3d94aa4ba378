//! `environment ID (--map FILE|NAME|ASSET_ID [--intensity S] [--rotation
//! DEG] [--hidden] | --color r,g,b)`: replace a session's environment
//! alone. A map that names an `.hdr` or `.exr` file is uploaded first; any
//! other name is sent as it is (a built-in map's name, or an asset id).

use crate::scene::upload;
use crate::{print_status, vec3, Failure};
use clap::Args;
use pathstream_client::wire::asset::is_environment_name;
use pathstream_client::{Client, Environment, EnvironmentMap};
use std::path::Path;

#[derive(Args, Debug)]
pub struct EnvironmentArgs {
    id: String,
    /// An .hdr/.exr file (uploaded), a built-in map's name (courtyard,
    /// interior, studio, sunset: `GET /api/environments`) or an asset id.
    #[arg(long, conflicts_with = "color", required_unless_present = "color")]
    map: Option<String>,
    /// Scales the map's radiance.
    #[arg(long, default_value_t = 1.0, requires = "map")]
    intensity: f64,
    /// Turns the map about +y, in degrees.
    #[arg(long, default_value_t = 0.0, requires = "map")]
    rotation: f64,
    /// Keep the map's light but show black behind the scene.
    #[arg(long, requires = "map")]
    hidden: bool,
    /// A uniform environment instead: radiance r,g,b.
    #[arg(long, value_parser = vec3)]
    color: Option<[f64; 3]>,
}

pub async fn set(client: &Client, a: &EnvironmentArgs) -> Result<(), Failure> {
    let environment = match (&a.map, a.color) {
        (Some(map), _) => {
            let map = match is_environment_name(map) {
                true => upload(client, Path::new(map), "--map").await?,
                false => map.clone(),
            };
            Environment::Map(EnvironmentMap {
                map,
                intensity: a.intensity,
                rotation_deg: a.rotation,
                visible: !a.hidden,
                background: None,
            })
        }
        (None, Some(c)) => Environment::Color(c),
        (None, None) => unreachable!("clap requires --map or --color"),
    };
    print_status(&client.set_environment(&a.id, &environment).await?)
}
