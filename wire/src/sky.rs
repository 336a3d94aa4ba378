//! A physically based clear sky with a sun, in place of an environment map
//! (`"environment": {"sky": {...}, "intensity": ...}`): scene JSON, the API
//! and the client share this one description. Where the sun stands is
//! given one way of three: `sun_elevation_deg` and `sun_azimuth_deg`,
//! `sun_direction`, or `time` with `latitude_deg` and `longitude_deg`;
//! none of them puts it 45 degrees up in the south-east.
//!
//! Compass: -z is north, +x east (so +z is south); azimuths run clockwise
//! from north seen from above.

use serde::{Deserialize, Serialize};

/// The sky's settings; every field has a default.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sky {
    /// Degrees above the horizon (-90 to 90).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun_elevation_deg: Option<f64>,
    /// Degrees clockwise from north (-z) seen from above: 90 is east (+x).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun_azimuth_deg: Option<f64>,
    /// A direction towards the sun (any length), in place of the angles.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun_direction: Option<[f64; 3]>,
    /// An RFC 3339 time ("2026-06-21T12:00:00Z", "2026-06-21T14:00:00+02:00"):
    /// the sun where it stands then, seen from `latitude_deg`, `longitude_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<String>,
    /// Degrees north (negative: south).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latitude_deg: Option<f64>,
    /// Degrees east (negative: west).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub longitude_deg: Option<f64>,
    /// The sun's angular diameter in degrees (default 0.545, as seen from
    /// the earth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun_size_deg: Option<f64>,
    /// Scales the sun's disc alone (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun_intensity: Option<f64>,
    /// Air (Rayleigh scattering) density, 1 = the standard atmosphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub air: Option<f64>,
    /// Dust and haze (Mie scattering) density, 1 = clear day.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dust: Option<f64>,
    /// Ozone density, 1 = 300 Dobson units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ozone: Option<f64>,
    /// The viewer's height above the ground in metres (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
}
