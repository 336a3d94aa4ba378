//! Unbiased settings converge to the same image: NEE on vs off, box vs tent
//! filter, sphere walls vs quad walls, and the scene scaled or moved far
//! from the origin. Compared region by region within statistical error.

mod common;

use common::{assert_agree, assert_clean, render, scene};
use pathstream::render::math::DVec3;
use pathstream::render::Quality;

const W: u32 = 32;
const H: u32 = 32;

#[test]
fn nee_on_and_off_agree_on_cornell_and_smallpt() {
    for (name, spp_off) in [("cornell", 4096), ("smallpt", 1024)] {
        let s = scene(name);
        let on = Quality {
            nee: true,
            seed: 1,
            ..Quality::default()
        };
        let off = Quality {
            nee: false,
            seed: 2,
            ..Quality::default()
        };
        let a = render(&s, W, H, &on, 512);
        let b = render(&s, W, H, &off, spp_off);
        assert_clean(&a, name);
        assert_clean(&b, name);
        assert_agree(&a, &b, 8, 4.5, 0.0, &format!("{name}: NEE on vs off"));
    }
}

#[test]
fn nee_on_and_off_agree_unbounded_and_at_every_cap() {
    let s = scene("cornell");
    for depth in [1u32, 2, 4, 0] {
        let on = Quality {
            max_depth: depth,
            nee: true,
            seed: 3,
            ..Quality::default()
        };
        let off = Quality {
            max_depth: depth,
            nee: false,
            seed: 4,
            ..Quality::default()
        };
        let a = render(&s, 16, 16, &on, 512);
        let b = render(&s, 16, 16, &off, 4096);
        assert_agree(
            &a,
            &b,
            8,
            4.5,
            0.0,
            &format!("cornell depth {depth}: NEE on vs off"),
        );
    }
}

#[test]
fn box_and_tent_filters_agree_on_region_means() {
    // Filters move samples within (tent: slightly beyond) their pixel, so
    // region means over 8x8 blocks of a smooth scene agree.
    let s = scene("cornell");
    let tent = Quality {
        seed: 5,
        ..Quality::default()
    };
    let boxed = Quality {
        filter: pathstream::render::Filter::Box,
        seed: 6,
        ..Quality::default()
    };
    let a = render(&s, W, H, &tent, 512);
    let b = render(&s, W, H, &boxed, 512);
    assert_agree(&a, &b, 8, 4.5, 0.01, "tent2x2 vs box");
}

#[test]
fn sphere_walls_and_quad_walls_agree() {
    // cornell-quads is cornell-glass with the radius-1e5 walls as quads.
    let q = Quality {
        seed: 7,
        ..Quality::default()
    };
    let a = render(&scene("cornell-glass"), W, H, &q, 512);
    let b = render(
        &scene("cornell-quads"),
        W,
        H,
        &Quality { seed: 8, ..q },
        512,
    );
    assert_clean(&a, "sphere walls");
    assert_clean(&b, "quad walls");
    // The 1e5 walls bulge by r - sqrt(r^2 - 85^2) ~ 0.04 units over the box.
    assert_agree(&a, &b, 8, 4.5, 0.005, "sphere walls vs quad walls");
}

#[test]
fn cornell_glass_is_invariant_under_scale_and_translation() {
    let base = scene("cornell-glass");
    let q = Quality::default();
    let reference = render(&base, W, H, &Quality { seed: 100, ..q }, 512);
    let variants = [
        ("scaled 1e-3", base.scaled(1e-3)),
        ("scaled 1e3", base.scaled(1e3)),
        ("moved 1e4", base.translated(DVec3::new(1e4, -1e4, 1e4))),
        (
            "smallpt box moved 1e4 along x",
            base.translated(DVec3::new(1e4, 0.0, 0.0)),
        ),
    ];
    for (i, (what, s)) in variants.iter().enumerate() {
        let film = render(
            s,
            W,
            H,
            &Quality {
                seed: 101 + i as u64,
                ..q
            },
            512,
        );
        assert_clean(&film, what);
        assert_agree(&reference, &film, 8, 4.5, 0.0, what);
    }
}
