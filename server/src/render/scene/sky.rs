//! A scene's clear sky (`environment.sky`): its settings validated, the
//! sun placed, and the sky computed as an environment map (cached, so that
//! every edit of a scene under the same sky shares one map) with its sun
//! disc.

use super::json::SkyJson;
use super::{SceneError, MAX_EMISSION};
use crate::render::envmap::sky_model::{sun_direction, Atmosphere, SkyModel, SunDisc};
use crate::render::envmap::sun_position::solar_position;
use crate::render::envmap::EnvMap;
use crate::render::math::DVec3;
use std::sync::{Arc, Mutex};

/// The sky map's size: 0.7 degrees a texel (the sky is smooth; the sun
/// is a disc of its own, not texels).
pub const SKY_MAP_WIDTH: u32 = 512;
pub const SKY_MAP_HEIGHT: u32 = 256;
/// The sun seen from the earth: 0.545 degrees across (Cycles' default).
pub const SUN_SIZE_DEG: f64 = 0.545;
/// Where the sun stands when nothing says: 45 degrees up in the south-east.
const DEFAULT_ELEVATION_DEG: f64 = 45.0;
const DEFAULT_AZIMUTH_DEG: f64 = 135.0;
/// Sky maps kept for reuse (each 1.5 MB with its tables).
const CACHED_SKIES: usize = 8;

/// A validated sky: the atmosphere, the sun's direction (map frame) and
/// its disc's angular radius and strength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkySetup {
    pub atmosphere: Atmosphere,
    pub sun: DVec3,
    pub sun_radius: f64,
    pub sun_strength: f64,
}

fn field(name: &str) -> String {
    format!("environment.sky.{name}")
}

fn within(name: &str, v: Option<f64>, default: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
    let v = v.unwrap_or(default);
    if !(v.is_finite() && (lo..=hi).contains(&v)) {
        return Err(SceneError::new(
            field(name),
            format!("must be between {lo} and {hi}"),
        ));
    }
    Ok(v)
}

/// Where `j` puts the sun: a unit direction in the map's frame.
fn sun(j: &SkyJson) -> Result<DVec3, SceneError> {
    let angles = j.sun_elevation_deg.is_some() || j.sun_azimuth_deg.is_some();
    let place = j.time.is_some() || j.latitude_deg.is_some() || j.longitude_deg.is_some();
    let ways = [angles, j.sun_direction.is_some(), place];
    if ways.iter().filter(|w| **w).count() > 1 {
        return Err(SceneError::new(
            "environment.sky",
            "give the sun's place one way: sun_elevation_deg/sun_azimuth_deg, sun_direction, \
             or time with latitude_deg and longitude_deg",
        ));
    }
    if let Some(d) = j.sun_direction {
        let d = DVec3::from_array(d);
        if !(d.is_finite() && d.length() > 1e-9) {
            return Err(SceneError::new(
                field("sun_direction"),
                "must be a finite, non-zero vector",
            ));
        }
        return Ok(d.normalize());
    }
    if place {
        let (Some(time), Some(lat), Some(lon)) = (&j.time, j.latitude_deg, j.longitude_deg) else {
            return Err(SceneError::new(
                "environment.sky",
                "time, latitude_deg and longitude_deg go together",
            ));
        };
        let lat = within("latitude_deg", Some(lat), 0.0, -90.0, 90.0)?;
        let lon = within("longitude_deg", Some(lon), 0.0, -180.0, 180.0)?;
        let t = chrono::DateTime::parse_from_rfc3339(time).map_err(|e| {
            SceneError::new(
                field("time"),
                format!("{e}: expected an RFC 3339 time such as 2026-06-21T12:00:00Z"),
            )
        })?;
        let seconds = t.timestamp() as f64 + f64::from(t.timestamp_subsec_nanos()) * 1e-9;
        let (elevation, azimuth) = solar_position(seconds, lat, lon);
        return Ok(sun_direction(elevation, azimuth));
    }
    let e = within(
        "sun_elevation_deg",
        j.sun_elevation_deg,
        DEFAULT_ELEVATION_DEG,
        -90.0,
        90.0,
    )?;
    let a = within(
        "sun_azimuth_deg",
        j.sun_azimuth_deg,
        DEFAULT_AZIMUTH_DEG,
        -1e6,
        1e6,
    )?;
    Ok(sun_direction(e.to_radians(), a.to_radians()))
}

/// `environment.sky` validated; errors name the field.
pub fn setup(j: &SkyJson) -> Result<SkySetup, SceneError> {
    let atmosphere = Atmosphere {
        air: within("air", j.air, 1.0, 0.0, 10.0)?,
        dust: within("dust", j.dust, 1.0, 0.0, 10.0)?,
        ozone: within("ozone", j.ozone, 1.0, 0.0, 10.0)?,
        altitude_m: within("altitude_m", j.altitude_m, 0.0, 0.0, 50_000.0)?,
    };
    let size = j.sun_size_deg.unwrap_or(SUN_SIZE_DEG);
    if !(size.is_finite() && size > 0.0 && size <= 30.0) {
        return Err(SceneError::new(
            field("sun_size_deg"),
            "must be above 0 and at most 30",
        ));
    }
    Ok(SkySetup {
        atmosphere,
        sun: sun(j)?,
        sun_radius: (size / 2.0).to_radians(),
        sun_strength: within("sun_intensity", j.sun_intensity, 1.0, 0.0, MAX_EMISSION)?,
    })
}

/// The map of the sky `s` describes and its sun disc (None below the
/// horizon or at strength 0). Both come from a cache of the last skies
/// (the map and the sunlight's irradiance, by atmosphere and sun), so that
/// revalidating a scene under the same sky computes nothing.
pub fn sky_map(s: &SkySetup) -> (Arc<EnvMap>, Option<SunDisc>) {
    /// Maps and sunlight by atmosphere and sun direction (as bits), oldest first.
    type Cache = Vec<((Atmosphere, [u64; 3]), Arc<EnvMap>, Option<[f64; 3]>)>;
    static CACHE: Mutex<Cache> = Mutex::new(Vec::new());
    let key = (s.atmosphere, s.sun.to_array().map(f64::to_bits));
    let cached = {
        let cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        (cache.iter())
            .find(|(k, _, _)| *k == key)
            .map(|(_, m, sun)| (m.clone(), *sun))
    };
    let (map, sunlight) = cached.unwrap_or_else(|| {
        let model = SkyModel::new(&s.atmosphere, s.sun);
        let texels = model.image(SKY_MAP_WIDTH, SKY_MAP_HEIGHT);
        let map = Arc::new(EnvMap::new("sky", SKY_MAP_WIDTH, SKY_MAP_HEIGHT, texels));
        let sunlight = model.sun_irradiance();
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= CACHED_SKIES {
            cache.remove(0);
        }
        cache.push((key, map.clone(), sunlight));
        (map, sunlight)
    });
    let disc = sunlight.and_then(|e| SunDisc::new(s.sun, e, s.sun_radius, s.sun_strength));
    (map, disc)
}
