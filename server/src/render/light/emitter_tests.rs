//! `Emitter::pdf_direction` against `Emitter::sample_direction`: for every
//! kind, the density of a sampled direction at the point it meets the
//! emitter is 1 / the weight sampling returned (what MIS needs for its two
//! weights to sum to one), and directions sampling cannot give have none.

use super::*;
use crate::render::math::DVec3;
use crate::render::math::{basis, sincos_turns};
use crate::render::sampler::mix64;

fn u(i: u64, k: u64) -> f32 {
    (mix64(i.wrapping_mul(31).wrapping_add(k)) >> 40) as f32 / (1u64 << 24) as f32
}

fn unit(i: u64, k: u64) -> Vec3A {
    let z = 1.0 - 2.0 * u(i, k);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = sincos_turns(u(i, k + 1));
    Vec3A::new(r * c, r * s, z)
}

/// Where the ray p + t dir (t > 0) first meets a plane through `o` with
/// normal `n`, or a sphere (from inside: where it leaves).
fn plane_hit(p: Vec3A, dir: Vec3A, o: Vec3A, n: Vec3A) -> Vec3A {
    p + dir * ((o - p).dot(n) / dir.dot(n))
}

fn sphere_hit(p: Vec3A, dir: Vec3A, s: &Sphere) -> Vec3A {
    let oc = s.center - p;
    let b = dir.dot(oc);
    let c = oc.length_squared() - s.radius * s.radius;
    let root = (b * b - c).max(0.0).sqrt();
    let t = if c > 0.0 { b - root } else { b + root };
    p + dir * t
}

fn emitter(object: u32, prim: u32, shape: EmitterShape) -> Emitter {
    Emitter {
        object,
        prim,
        emission: Vec3A::ONE,
        shape,
        maps: crate::render::material::NO_MAPS,
        mean: Vec3A::ONE,
    }
}

#[test]
fn the_density_of_every_sampled_direction_is_one_over_its_weight() {
    let sphere = Sphere::new(DVec3::new(1.0, 2.0, -3.0), 0.7);
    let quad = Quad::new(
        DVec3::new(-1.0, 3.0, -1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.3, 1.5),
    );
    let (a, b, c) = (
        Vec3A::new(2.0, -1.0, 0.5),
        Vec3A::new(3.0, -1.0, 1.0),
        Vec3A::new(2.5, 0.5, 0.0),
    );
    let cross = (b - a).cross(c - a);
    let tri = LightTri {
        p0: a,
        e1: b - a,
        e2: c - a,
        n: cross.normalize(),
        area: 0.5 * cross.length(),
    };
    let emitters = [
        emitter(0, u32::MAX, EmitterShape::Sphere(sphere)),
        emitter(1, u32::MAX, EmitterShape::Quad(quad)),
        emitter(2, 5, EmitterShape::Triangle(tri)),
        emitter(u32::MAX, u32::MAX, EmitterShape::Environment),
        emitter(
            u32::MAX,
            u32::MAX - 1,
            EmitterShape::Sun(SunLight::new(unit(99, 1), 0.05)),
        ),
    ];
    let mut checked = [0usize; 6];
    for i in 0..24_000u64 {
        let which = if i < 20_000 { (i % 5) as usize } else { 5 };
        // 4: the environment again (from a point on the sphere); 5: the sun.
        let e = &emitters[[0, 1, 2, 3, 3, 4][which]];
        let n = unit(i, 1);
        let mut r = Receiver {
            p: Vec3A::new(u(i, 3), u(i, 4), u(i, 5)) * 8.0 - 4.0,
            object: 9,
            prim: 9,
            nl: n,
            ns: n,
        };
        if which == 4 {
            // On the sphere's own surface (the furnace's inside).
            r.p = sphere.center + unit(i, 6) * sphere.radius;
            r.object = 0;
            r.prim = u32::MAX;
        }
        let Some((dir, weight)) = e.sample_direction(&r, u(i, 7), u(i, 8)) else {
            continue;
        };
        let q = match &e.shape {
            EmitterShape::Sphere(s) => sphere_hit(r.p, dir, s),
            EmitterShape::Quad(q) => plane_hit(r.p, dir, q.corner, q.normal),
            EmitterShape::Triangle(t) => plane_hit(r.p, dir, t.p0, t.n),
            EmitterShape::Environment | EmitterShape::Map(_) | EmitterShape::Sun(_) => Vec3A::ZERO,
        };
        let pdf = e.pdf_direction(&r, dir, q);
        let product = pdf * weight;
        // Grazing samples lose digits in the intersection above.
        let tolerance = if which == 0 || which == 4 { 2e-3 } else { 1e-3 };
        assert!(
            (product - 1.0).abs() < tolerance,
            "{:?} from {:?}: pdf {pdf} x weight {weight} = {product}",
            e.shape,
            r.p
        );
        checked[which] += 1;
    }
    assert!(
        checked.iter().all(|&c| c > 1000),
        "each kind sampled: {checked:?}"
    );
}

#[test]
fn the_sun_samples_its_cone_uniformly_and_its_disc_test_agrees() {
    // 1 - cos over the disc's, and the azimuth about its centre, are
    // uniform: chi-square over 10 x 8 cells, and every sample is in the
    // disc (at 0.27 degrees, where cos(radius) is 1 - 1.1e-5).
    for radius in [0.00476f64, 0.2] {
        let sun = SunLight::new(unit(7, 3), radius);
        let (t, b) = basis(sun.dir);
        let n = 80_000u64;
        let mut cells = [0u32; 80];
        for i in 0..n {
            let (d, w) = sun.sample(u(i, 11), u(i, 12));
            assert!(sun.covers(d), "{d:?} outside the disc");
            assert_eq!(w, sun.solid_angle());
            let a = (0.5 * (d - sun.dir).length_squared() / sun.one_minus_cos).min(0.999_999);
            let phi = (d.dot(b).atan2(d.dot(t)) / TAU)
                .rem_euclid(1.0)
                .min(0.999_999);
            cells[(a * 10.0) as usize * 8 + (phi * 8.0) as usize] += 1;
        }
        let expected = n as f64 / 80.0;
        let chi2: f64 = cells
            .iter()
            .map(|&c| (f64::from(c) - expected).powi(2) / expected)
            .sum();
        // 79 degrees of freedom: p = 1e-6 at ~140.
        assert!(chi2 < 140.0, "radius {radius}: chi-square {chi2:.1}");
        let outside = sun.dir + t * (2.0 * radius as f32);
        assert!(!sun.covers(outside.normalize()));
    }
}

#[test]
fn directions_sampling_cannot_give_have_no_density() {
    let quad = Quad::new(
        DVec3::new(-1.0, 3.0, -1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.0),
    );
    let on_quad = Receiver {
        p: Vec3A::new(0.0, 3.0, 0.0),
        object: 1,
        prim: u32::MAX,
        nl: Vec3A::NEG_Y,
        ns: Vec3A::NEG_Y,
    };
    let e = emitter(1, u32::MAX, EmitterShape::Quad(quad));
    assert_eq!(
        e.pdf_direction(&on_quad, Vec3A::Y, Vec3A::new(0.5, 3.0, 0.5)),
        0.0
    );
    let sky = emitter(u32::MAX, u32::MAX, EmitterShape::Environment);
    assert_eq!(sky.pdf_direction(&on_quad, Vec3A::Y, Vec3A::ZERO), 0.0);
    assert!(sky.pdf_direction(&on_quad, Vec3A::NEG_Y, Vec3A::ZERO) > 0.0);
    let sphere = Sphere::new(DVec3::ZERO, 1.0);
    let outside = Receiver {
        p: Vec3A::new(0.0, 0.0, 1.0),
        object: 0,
        prim: u32::MAX,
        nl: Vec3A::Z,
        ns: Vec3A::Z,
    };
    let ball = emitter(0, u32::MAX, EmitterShape::Sphere(sphere));
    assert_eq!(ball.pdf_direction(&outside, Vec3A::X, Vec3A::X), 0.0);
}

#[test]
fn emitters_are_found_by_object_and_triangle() {
    let tri = |prim| {
        emitter(
            3,
            prim,
            EmitterShape::Triangle(LightTri {
                p0: Vec3A::ZERO,
                e1: Vec3A::X,
                e2: Vec3A::Y,
                n: Vec3A::Z,
                area: 0.5,
            }),
        )
    };
    let sphere = Sphere::new(DVec3::ZERO, 1.0);
    let lights = Lights::new(
        vec![
            emitter(1, u32::MAX, EmitterShape::Sphere(sphere)),
            tri(0),
            tri(4),
            tri(7),
            emitter(
                u32::MAX,
                u32::MAX - 1,
                EmitterShape::Sun(SunLight::new(Vec3A::Y, 0.01)),
            ),
            emitter(u32::MAX, u32::MAX, EmitterShape::Environment),
        ],
        10.0,
    );
    assert_eq!(lights.sun(), Some(4));
    assert_eq!(lights.distant().collect::<Vec<_>>(), [4, 5]);
    assert_eq!(lights.index_of(1, u32::MAX), Some(0));
    assert_eq!(lights.index_of(3, 4), Some(2));
    assert_eq!(lights.index_of(3, 7), Some(3));
    assert_eq!(lights.index_of(3, 5), None);
    assert_eq!(lights.index_of(2, u32::MAX), None);
    assert_eq!(lights.environment(), Some(5));
    let total: f32 = (0..6).map(|i| lights.pick_pmf(i)).sum();
    assert!((total - 1.0).abs() < 1e-6, "pmfs sum to {total}");
    let one = Lights::new(vec![tri(0)], 1.0);
    assert_eq!((one.pick_pmf(0), one.environment()), (1.0, None));
}
