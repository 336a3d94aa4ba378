//! How much of the sky reaches what the camera sees. Power-proportional
//! light selection counts the environment as lighting everything from
//! every direction, so in a closed room (or a Cornell box under a sky) it
//! spends nearly every shadow ray on a sky that walls hide. Before a job
//! renders, a fixed grid of camera rays finds the first surfaces that
//! gather light; from each, one shadow ray goes towards the sky as the sky
//! emitter samples it; the fraction that reaches it scales the sky's weight
//! in the selection table. Only the choice of emitter changes, and every
//! estimate divides by the probability it was chosen with, so images stay
//! unbiased; the probe is a pure function of the scene and the camera, so
//! every device and pass split uses the same table (the kernel reads it as
//! the CPU does). Where the whole sky is seen, nothing changes.

use crate::render::camera::CameraRays;
use crate::render::isa::Portable;
use crate::render::sampler::mix64;
use crate::render::world::{Origin, World};

/// Camera rays per side of the probe's grid.
pub const PROBE_SIDE: u32 = 32;

/// The chance of a pick that a sky no probe ray saw keeps (the probe may
/// miss a window smaller than one ray in 1024 sees).
pub const HIDDEN_SKY_SHARE: f64 = 1.0 / 1024.0;

/// The fraction of the probe's shadow rays towards the sky that reach it,
/// or None where it does not matter or says nothing: no sky, the sky the
/// only emitter, or no probed surface that gathers light.
pub fn sky_visibility(world: &World, camera: &CameraRays) -> Option<f64> {
    visibility(world, camera, world.lights.environment()?)
}

/// [`sky_visibility`] for distant emitter `i` (the sky or the sun).
pub fn visibility(world: &World, camera: &CameraRays, i: usize) -> Option<f64> {
    let lights = &world.lights;
    let sky = &lights.emitters[i];
    if lights.emitters.len() < 2 {
        return None;
    }
    let uniform = |k: u64| (mix64(k) >> 40) as f32 / 16_777_216.0;
    let (mut tried, mut seen) = (0u32, 0u32);
    for k in 0..PROBE_SIDE * PROBE_SIDE {
        let (i, j) = (k % PROBE_SIDE, k / PROBE_SIDE);
        let x = (i as f32 + 0.5) / PROBE_SIDE as f32 * camera.width as f32;
        let y = (j as f32 + 0.5) / PROBE_SIDE as f32 * camera.height as f32;
        let ray = camera.ray(x, y);
        let Some(hit) = world.intersect(Portable, &ray, Origin::NONE) else {
            continue;
        };
        let s = world.surface(&hit, &ray);
        if !world.material(s.material).bsdf.gathers_light() {
            continue;
        }
        // The side the camera sees.
        let nl = if s.ng.dot(ray.dir) < 0.0 { s.ng } else { -s.ng };
        let ns = if s.ns.dot(nl) < 0.0 { -s.ns } else { s.ns };
        let k = u64::from(k);
        let Some((dir, _)) =
            sky.sample_direction(&s.receiver(nl, ns), uniform(2 * k), uniform(2 * k + 1))
        else {
            continue;
        };
        // Below the surface the sky lights nothing here, hidden or not.
        if !(nl.dot(dir) > 0.0) {
            continue;
        }
        tried += 1;
        let from = Origin {
            object: s.object,
            prim: s.prim,
            entering: dir.dot(s.ng) < 0.0,
        };
        if world
            .intersect(Portable, &world.spawn(&s, dir), from)
            .is_none()
        {
            seen += 1;
        }
    }
    (tried > 0).then(|| f64::from(seen) / f64::from(tried))
}

/// Weighs `world`'s sky (and a computed sky's sun, each on its own) in
/// light selection by the fraction of it the probe sees from `camera`; one
/// it never saw keeps a [`HIDDEN_SKY_SHARE`] chance of a pick. Returns the
/// sky's fraction (1 where nothing changed).
pub fn weigh_sky(world: &mut World, camera: &CameraRays) -> f64 {
    let distant: Vec<usize> = world.lights.distant().collect();
    // Every fraction first: each is measured with the table as it was.
    let seen: Vec<(usize, f64)> = (distant.iter())
        .filter_map(|&i| Some((i, visibility(world, camera, i)?)))
        .collect();
    for &(i, v) in &seen {
        match v {
            v if v >= 1.0 => {}
            v if v > 0.0 => world.lights.scale_power(i, v),
            _ => world.lights.set_share(i, HIDDEN_SKY_SHARE),
        }
    }
    let sky = world.lights.environment();
    (seen.iter())
        .find(|(i, _)| Some(*i) == sky)
        .map_or(1.0, |&(_, v)| v.min(1.0))
}
