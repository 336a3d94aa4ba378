//! Helpers of the routine-parity tests: the device, counters turned into
//! uniform numbers and directions, distances in ulps, the check program.
#![allow(dead_code)]

use pathstream::render::backend::opencl::{Checks, OpenClBackend};
use pathstream::render::math::{sincos_turns, Vec3A};
use pathstream::render::sampler::mix64;

pub fn device() -> Option<OpenClBackend> {
    match OpenClBackend::new(None) {
        Ok(b) => Some(b),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => {
            eprintln!("skipping: {e}");
            None
        }
    }
}

/// Distance in units in the last place (0 for equal values, infinities
/// included; u64::MAX when only one is NaN or infinite).
pub fn ulps(a: f32, b: f32) -> u64 {
    if a == b {
        return 0;
    }
    if !(a.is_finite() && b.is_finite()) {
        return u64::MAX;
    }
    let key = |x: f32| {
        let i = i64::from(x.to_bits() as i32);
        if i < 0 {
            i64::from(i32::MIN) - i
        } else {
            i
        }
    };
    key(a).abs_diff(key(b))
}

/// Uniform numbers in [0, 1) from a counter.
pub fn uniform(i: u64, salt: u64) -> f32 {
    (mix64(i ^ mix64(salt)) >> 40) as f32 / 16_777_216.0
}

pub fn unit(i: u64, salt: u64) -> Vec3A {
    let z = 1.0 - 2.0 * uniform(i, salt);
    let (s, c) = sincos_turns(uniform(i, salt + 1));
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * c, r * s, z)
}

/// The check program; `PARITY_OPTIONS` adds compiler options, to measure
/// what each floating-point choice changes (docs/OPENCL.md).
pub fn checks(d: &OpenClBackend) -> Checks<'_> {
    let extra = std::env::var("PARITY_OPTIONS").unwrap_or_default();
    d.checks(&extra).expect("the check program builds")
}
