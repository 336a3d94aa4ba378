//! The tables the GGX lobes read, integrated: what `tables/*.f32` store
//! (the renderer reads those, so that no process pays for the integration:
//! 0.13 s for the metallic-roughness tables, 1.3 s on two cores for the
//! rough glass's). The test below holds the stored floats to a fresh
//! integration; with `PATHSTREAM_WRITE_TABLES=1` it writes them instead:
//!
//! ```text
//! PATHSTREAM_WRITE_TABLES=1 cargo test --release -p pathstream --lib stored_tables
//! ```

use super::glass::{self, split, IOR_N, IOR_SCALE};
use super::{
    pow5, reflect_about, smith_r, visible_normal, ALPHA_MIN, AVG_A, AVG_B, TABLE_LEN, TABLE_N,
};
use crate::render::math::Vec3A;
use crate::render::sampler::sobol::sobol_2d;
use rayon::prelude::*;

/// Points per entry of the metallic-roughness tables (a Sobol
/// (0,2)-sequence; the integrand is smooth).
const TABLE_POINTS: u32 = 4096;
/// Points per entry of the glass table.
const GLASS_POINTS: u32 = 512;

/// The metallic-roughness tables ([`Tables`]'s data), integrated.
pub(super) fn ggx() -> Vec<f32> {
    {
        let n = TABLE_N;
        let mut data = vec![0.0f32; TABLE_LEN];
        for j in 0..n {
            let r = j as f32 / (n - 1) as f32;
            let alpha = (r * r).max(ALPHA_MIN);
            for i in 0..n {
                let mu = (i as f32 / (n - 1) as f32).max(1e-4);
                let wo = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let (mut a, mut b) = (0.0f64, 0.0f64);
                for k in 0..TABLE_POINTS {
                    let (x, y) = sobol_2d(k);
                    let u1 = ((f64::from(x) + 0.5) / 4_294_967_296.0) as f32;
                    let u2 = ((f64::from(y) + 0.5) / 4_294_967_296.0) as f32;
                    let h = visible_normal(wo, alpha, u1, u2);
                    let wi = reflect_about(wo, h);
                    if wi.z <= 0.0 {
                        continue;
                    }
                    // f cos / pdf of a visible-normal sample: G2 / G1(wo).
                    let (ro, ri) = (smith_r(wo, alpha), smith_r(wi, alpha));
                    let w = f64::from((wo.z + ro) * wi.z / (ro * wi.z + ri * wo.z));
                    let c5 = f64::from(pow5(1.0 - wo.dot(h).clamp(0.0, 1.0)));
                    a += w * (1.0 - c5);
                    b += w * c5;
                }
                data[j * n + i] = (a / f64::from(TABLE_POINTS)) as f32;
                data[n * n + j * n + i] = (b / f64::from(TABLE_POINTS)) as f32;
            }
            // 2 * integral of E(mu) mu over the table's piecewise-linear E,
            // exactly, so that the multiple-scattering lobes integrate to
            // what their formula says.
            for (part, avg) in [(0, AVG_A), (n * n, AVG_B)] {
                let mut sum = 0.0f64;
                let h = 1.0 / (n - 1) as f64;
                for i in 0..n - 1 {
                    let (ea, eb) = (
                        f64::from(data[part + j * n + i]),
                        f64::from(data[part + j * n + i + 1]),
                    );
                    let mu_a = i as f64 * h;
                    sum += h * (ea * (mu_a / 2.0 + h / 6.0) + eb * (mu_a / 2.0 + h / 3.0));
                }
                data[avg + j] = (2.0 * sum) as f32;
            }
        }
        data
    }
}

/// The rough glass's table ([`glass::Table`]'s data), integrated.
pub(super) fn glass() -> Vec<f32> {
    {
        let n = TABLE_N;
        let points: Vec<(f32, f32)> = (0..GLASS_POINTS)
            .map(|k| {
                let (x, y) = sobol_2d(k);
                let u = |b: u32| ((f64::from(b) + 0.5) / 4_294_967_296.0) as f32;
                (u(x), u(y))
            })
            .collect();
        let mut data = vec![0.0f32; glass::TABLE_LEN];
        data.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
            let j = row % n;
            let k = (row / n) % IOR_N;
            let side = (row / (n * IOR_N)) % 2;
            let clear = row >= 2 * n * IOR_N;
            let x = k as f32 / (IOR_N - 1) as f32 / IOR_SCALE;
            let ior = (1.0 + x) / (1.0 - x);
            let eta = if side == 0 { ior } else { 1.0 / ior };
            let r = j as f32 / (n - 1) as f32;
            let alpha = (r * r).max(ALPHA_MIN);
            for (i, e) in out.iter_mut().enumerate() {
                let mu = (i as f32 / (n - 1) as f32).max(1e-4);
                let wo = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let mut sum = 0.0f64;
                for &(u1, u2) in &points {
                    let h = visible_normal(wo, alpha, u1, u2);
                    let (f, wt) = split(wo, h, eta);
                    // The clear glass reflects only where nothing crosses.
                    let f = if clear && f < 1.0 { 0.0 } else { f };
                    let wr = reflect_about(wo, h);
                    if f > 0.0 && wr.z > 0.0 {
                        sum += f64::from(f * masking_ratio(wo, wr, alpha));
                    }
                    if f < 1.0 && wt.z < 0.0 {
                        sum += f64::from((1.0 - f) * masking_ratio(wo, wt, alpha));
                    }
                }
                *e = (sum / f64::from(GLASS_POINTS)) as f32;
            }
        });
        data
    }
}

/// G2(wo, wi) / G1(wo), height-correlated, wi on either side.
#[inline(always)]
fn masking_ratio(wo: Vec3A, wi: Vec3A, alpha: f32) -> f32 {
    let (ro, ri) = (smith_r(wo, alpha), smith_r(wi, alpha));
    let ci = wi.z.abs();
    (wo.z + ro) * ci / (ro * ci + ri * wo.z)
}

#[test]
fn stored_tables_are_the_integrated_ones() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render/ggx/tables");
    let write = std::env::var_os("PATHSTREAM_WRITE_TABLES").is_some();
    for (name, fresh, stored) in [
        ("ggx.f32", ggx(), &super::tables().data),
        ("glass.f32", glass(), &glass::table().data),
    ] {
        if write {
            let bytes: Vec<u8> = fresh.iter().flat_map(|v| v.to_le_bytes()).collect();
            std::fs::write(dir.join(name), bytes).expect("tables written");
            continue;
        }
        assert_eq!(fresh.len(), stored.len(), "{name}: length");
        // The same bits where the integration ran on the machine that wrote
        // them; another libm may round its sines in the last place.
        for (i, (a, b)) in fresh.iter().zip(stored.iter()).enumerate() {
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(1.0),
                "{name}[{i}]: stored {b}, integrated {a}: rewrite the tables \
                 (PATHSTREAM_WRITE_TABLES=1, see render/ggx/integrate.rs)"
            );
        }
    }
}
