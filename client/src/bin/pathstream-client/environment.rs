//! `environment ID (--map FILE|NAME|ASSET_ID | --sky [--sun-elevation DEG
//! --sun-azimuth DEG | --time T --latitude DEG --longitude DEG] [--dust D]
//! [--sun-size DEG]) [--intensity S] [--rotation DEG] [--hidden] | --color
//! r,g,b`: replace a session's environment alone. A map that names an
//! `.hdr` or `.exr` file is uploaded first; any other name is sent as it is
//! (a built-in map's name, or an asset id). `--sky` computes a clear sky
//! and sun; the server checks its settings and names a bad one.

use crate::scene::upload;
use crate::{print_status, vec3, Failure};
use clap::Args;
use pathstream_client::wire::asset::is_environment_name;
use pathstream_client::wire::Sky;
use pathstream_client::{Client, Environment, EnvironmentMap};
use std::path::Path;

#[derive(Args, Debug)]
pub struct EnvironmentArgs {
    id: String,
    /// An .hdr/.exr file (uploaded), a built-in map's name (courtyard,
    /// interior, studio, sunset: `GET /api/environments`) or an asset id.
    #[arg(long, conflicts_with_all = ["color", "sky"], required_unless_present_any = ["color", "sky"])]
    map: Option<String>,
    /// A clear sky and sun computed for the sun's place (default: 45
    /// degrees up in the south-east).
    #[arg(long, conflicts_with = "color")]
    sky: bool,
    /// The sun's height above the horizon, degrees (with --sky).
    #[arg(long, requires = "sky", allow_negative_numbers = true)]
    sun_elevation: Option<f64>,
    /// The sun's compass direction, degrees clockwise from north (-z);
    /// 90 is east (+x) (with --sky).
    #[arg(long, requires = "sky", allow_negative_numbers = true)]
    sun_azimuth: Option<f64>,
    /// The sun where it stands at this RFC 3339 time (with --latitude and
    /// --longitude), e.g. 2026-06-21T18:30:00+01:00.
    #[arg(long, requires_all = ["sky", "latitude", "longitude"])]
    time: Option<String>,
    /// Degrees north (with --time).
    #[arg(long, requires = "time", allow_negative_numbers = true)]
    latitude: Option<f64>,
    /// Degrees east (with --time).
    #[arg(long, requires = "time", allow_negative_numbers = true)]
    longitude: Option<f64>,
    /// Haze: the dust density, 1 = a clear day (with --sky).
    #[arg(long, requires = "sky")]
    dust: Option<f64>,
    /// The sun's angular diameter in degrees (default 0.545; with --sky).
    #[arg(long, requires = "sky")]
    sun_size: Option<f64>,
    /// Scales the map's (or sky's) radiance.
    #[arg(long, default_value_t = 1.0, conflicts_with = "color")]
    intensity: f64,
    /// Turns the map (or sky) about +y, in degrees.
    #[arg(
        long,
        default_value_t = 0.0,
        conflicts_with = "color",
        allow_negative_numbers = true
    )]
    rotation: f64,
    /// Keep the map's light but show black behind the scene.
    #[arg(long, conflicts_with = "color")]
    hidden: bool,
    /// A uniform environment instead: radiance r,g,b.
    #[arg(long, value_parser = vec3)]
    color: Option<[f64; 3]>,
}

pub async fn set(client: &Client, a: &EnvironmentArgs) -> Result<(), Failure> {
    let lit = |map: String, sky: Option<Sky>| {
        Environment::Map(EnvironmentMap {
            map,
            sky,
            intensity: a.intensity,
            rotation_deg: a.rotation,
            visible: !a.hidden,
            background: None,
        })
    };
    let environment = match (&a.map, a.color) {
        (Some(map), _) => {
            let map = match is_environment_name(map) {
                true => upload(client, Path::new(map), "--map").await?,
                false => map.clone(),
            };
            lit(map, None)
        }
        (None, Some(c)) => Environment::Color(c),
        (None, None) => lit(
            String::new(),
            Some(Sky {
                sun_elevation_deg: a.sun_elevation,
                sun_azimuth_deg: a.sun_azimuth,
                time: a.time.clone(),
                latitude_deg: a.latitude,
                longitude_deg: a.longitude,
                dust: a.dust,
                sun_size_deg: a.sun_size,
                ..Sky::default()
            }),
        ),
    };
    print_status(&client.set_environment(&a.id, &environment).await?)
}
