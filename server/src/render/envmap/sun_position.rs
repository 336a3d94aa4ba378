//! Where the sun stands at a time and place: NOAA's solar position
//! algorithm (after Meeus, "Astronomical Algorithms"), good to about 0.01
//! degrees between 1800 and 2100; no atmospheric refraction.

use std::f64::consts::PI;

/// The sun's elevation above the horizon and azimuth clockwise from north,
/// in radians, at `unix_seconds` (UTC) seen from `latitude_deg` (north
/// positive) and `longitude_deg` (east positive).
pub fn solar_position(unix_seconds: f64, latitude_deg: f64, longitude_deg: f64) -> (f64, f64) {
    let rad = |d: f64| d.to_radians();
    let julian_day = unix_seconds / 86_400.0 + 2_440_587.5;
    let t = (julian_day - 2_451_545.0) / 36_525.0; // Julian centuries since J2000
    let mean_long = (280.46646 + t * (36000.76983 + t * 0.0003032)).rem_euclid(360.0);
    let mean_anomaly = 357.52911 + t * (35999.05029 - 0.0001537 * t);
    let eccentricity = 0.016708634 - t * (0.000042037 + 0.0000001267 * t);
    let m = rad(mean_anomaly);
    let centre = m.sin() * (1.914602 - t * (0.004817 + 0.000014 * t))
        + (2.0 * m).sin() * (0.019993 - 0.000101 * t)
        + (3.0 * m).sin() * 0.000289;
    let omega = rad(125.04 - 1934.136 * t);
    let apparent_long = mean_long + centre - 0.00569 - 0.00478 * omega.sin();
    let mean_obliquity =
        23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0;
    let obliquity = rad(mean_obliquity + 0.00256 * omega.cos());
    let declination = (obliquity.sin() * rad(apparent_long).sin()).asin();
    // The equation of time, in minutes.
    let y = (obliquity / 2.0).tan().powi(2);
    let l0 = rad(mean_long);
    let eot = 4.0
        * (y * (2.0 * l0).sin() - 2.0 * eccentricity * m.sin()
            + 4.0 * eccentricity * y * m.sin() * (2.0 * l0).cos()
            - 0.5 * y * y * (4.0 * l0).sin()
            - 1.25 * eccentricity * eccentricity * (2.0 * m).sin())
        .to_degrees();
    let minutes_utc = (unix_seconds / 60.0).rem_euclid(1440.0);
    let solar_minutes = minutes_utc + eot + 4.0 * longitude_deg;
    let hour_angle = rad(solar_minutes / 4.0 - 180.0);
    let lat = rad(latitude_deg);
    let cos_zenith =
        lat.sin() * declination.sin() + lat.cos() * declination.cos() * hour_angle.cos();
    let elevation = cos_zenith.clamp(-1.0, 1.0).asin();
    let azimuth = hour_angle
        .sin()
        .atan2(hour_angle.cos() * lat.sin() - declination.tan() * lat.cos())
        + PI;
    (elevation, azimuth.rem_euclid(2.0 * PI))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seconds since 1970 of a UTC date and time (days from civil, Howard
    /// Hinnant's algorithm).
    fn unix(y: i64, mo: i64, d: i64, h: f64) -> f64 {
        let y = if mo <= 2 { y - 1 } else { y };
        let era = y.div_euclid(400);
        let yoe = y - era * 400;
        let doy = (153 * (mo + if mo > 2 { -3 } else { 9 }) + 2) / 5 + d - 1;
        let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
        let days = era * 146_097 + doe - 719_468;
        days as f64 * 86_400.0 + h * 3600.0
    }

    #[test]
    fn greenwich_at_the_june_solstice_noon_sees_the_sun_at_90_minus_latitude_plus_tilt() {
        // Solar noon at Greenwich falls at ~12:01:50 UTC on 21 June (the
        // equation of time is ~ -1.8 min); the declination is +23.44.
        let (e, a) = solar_position(unix(2026, 6, 21, 12.0 + 1.8 / 60.0), 51.4769, 0.0);
        assert!(
            (e.to_degrees() - (90.0 - 51.4769 + 23.44)).abs() < 0.05,
            "{}",
            e.to_degrees()
        );
        assert!(
            (a.to_degrees() - 180.0).abs() < 0.5,
            "due south: {}",
            a.to_degrees()
        );
        // In the morning the sun is in the east, lower.
        let (e, a) = solar_position(unix(2026, 6, 21, 6.0), 51.4769, 0.0);
        assert!(
            e.to_degrees() > 10.0 && e.to_degrees() < 30.0,
            "{}",
            e.to_degrees()
        );
        assert!(
            (60.0..100.0).contains(&a.to_degrees()),
            "{}",
            a.to_degrees()
        );
    }

    #[test]
    fn at_the_equator_on_the_equinox_the_sun_rises_due_east_and_culminates_overhead() {
        // March equinox 2027: 20 March ~14:25 UTC; the declination there is 0.
        let (e, _) = solar_position(unix(2027, 3, 20, 12.0 + 7.5 / 60.0), 0.0, 0.0);
        assert!(e.to_degrees() > 89.0, "{}", e.to_degrees());
        // Sunrise near 06:07 local solar time at longitude 0.
        let (e, a) = solar_position(unix(2027, 3, 20, 6.0 + 7.5 / 60.0), 0.0, 0.0);
        assert!(e.to_degrees().abs() < 0.5, "{}", e.to_degrees());
        assert!((a.to_degrees() - 90.0).abs() < 0.5, "{}", a.to_degrees());
        // East of Greenwich noon comes earlier: at 90 E, six hours earlier.
        let (e, _) = solar_position(unix(2027, 3, 20, 6.0 + 7.5 / 60.0), 0.0, 90.0);
        assert!(e.to_degrees() > 89.0, "{}", e.to_degrees());
    }

    #[test]
    fn the_southern_winter_sun_stands_low_in_the_north() {
        // Sydney (33.87 S, 151.21 E) at local solar noon on 21 June:
        // elevation 90 - 33.87 - 23.44 = 32.7, azimuth north.
        let noon_utc = 12.0 - 151.21 / 15.0 + 1.8 / 60.0;
        let (e, a) = solar_position(unix(2026, 6, 21, noon_utc), -33.87, 151.21);
        assert!((e.to_degrees() - 32.69).abs() < 0.1, "{}", e.to_degrees());
        let a = a.to_degrees();
        assert!(!(1.0..=359.0).contains(&a), "north: {a}");
    }
}
