//! Tests of `adaptive.rs`: tiles, rates, rounds and their layers.

use super::*;

fn flat(tiles: &Tiles, n: u64, err2: impl Fn(usize) -> f64) -> (Vec<u64>, Vec<TileError>) {
    let counts = vec![n; tiles.count()];
    let errors = (0..tiles.count())
        .map(|t| TileError {
            err2: err2(t),
            sig2: tiles.pixels(t) as f64 * 3.0,
        })
        .collect();
    (counts, errors)
}

const T: u32 = TILE_SIZE;
const P: u64 = (TILE_SIZE * TILE_SIZE) as u64;

#[test]
fn tiles_cover_the_image_once() {
    let tiles = Tiles::new(2 * T + 1, T + 1);
    assert_eq!((tiles.cols, tiles.rows), (3, 2));
    let total: u64 = (0..tiles.count()).map(|t| tiles.pixels(t)).sum();
    assert_eq!(total, u64::from((2 * T + 1) * (T + 1)));
    assert_eq!(tiles.rect(5), (2 * T..2 * T + 1, T..T + 1));
    assert_eq!(tiles.at(2 * T, T), 5);
    assert_eq!(tiles.pixels(5), 1);
}

#[test]
fn a_rate_is_the_deviation_of_the_tile_and_its_neighbours() {
    // 3x3 tiles of 16 samples; the middle one has 9x the variance.
    let tiles = Tiles::new(3 * T, 3 * T);
    let (counts, errors) = flat(&tiles, 16, |t| if t == 4 { 9.0 } else { 1.0 });
    let var = smoothed_variances(&tiles, &counts, &errors);
    let rate: Vec<f64> = var.iter().map(|v| v.sqrt()).collect();
    let per_pixel = |e: f64| e * 16.0 / P as f64;
    let expect = |sum: f64, weight: f64| (per_pixel(sum) / weight).sqrt();
    // Middle: itself, 4 edge and 4 corner neighbours of variance 1.
    assert!((rate[4] - expect(9.0 + 4.0 * 0.5 + 4.0 * 0.25, 4.0)).abs() < 1e-12);
    // Top middle: itself, 3 edge neighbours (one the middle), 2 corners.
    assert!((rate[1] - expect(1.0 + 0.5 * 11.0 + 0.25 * 2.0, 3.0)).abs() < 1e-12);
    // Corner: itself, 2 edge neighbours, the middle as its corner.
    assert!((rate[0] - expect(1.0 + 0.5 * 2.0 + 0.25 * 9.0, 2.25)).abs() < 1e-12);
}

#[test]
fn samples_go_to_noisy_tiles_in_proportion_to_their_deviation() {
    // A row of 12 tiles: the left half has 4x the variance of the right
    // and already twice its samples (as the allocation wants), so the
    // round keeps the proportion: the left's inner tiles get twice what
    // the right's get.
    let tiles = Tiles::new(12 * T, T);
    let counts: Vec<u64> = (0..12).map(|t| if t < 6 { 32 } else { 16 }).collect();
    let errors: Vec<TileError> = (0..12)
        .map(|t| TileError {
            // err2 = v P / n with v = 4 on the left, 1 on the right.
            err2: if t < 6 {
                4.0 * P as f64 / 32.0
            } else {
                P as f64 / 16.0
            },
            sig2: P as f64 * 3.0,
        })
        .collect();
    let mut done = vec![false; 12];
    let taken = (6 * 32 + 6 * 16) * P;
    let work = plan_round(&tiles, &counts, &errors, &mut done, Goal::default(), taken);
    let got: Vec<u32> = (0..12)
        .map(|t| work.iter().find(|w| w.tile == t).map_or(0, |w| w.count))
        .collect();
    // (Tiles 5 and 6 see both halves; flooring moves a count by one.)
    for (l, r) in got[..5].iter().zip(&got[7..]) {
        assert!(*r > 0 && l.abs_diff(2 * r) <= 1, "{got:?}");
    }
    let paths: u64 = work.iter().map(|w| u64::from(w.count) * P).sum();
    assert_eq!(paths, taken / 2, "the round adds half the samples taken");
}

#[test]
fn no_tile_more_than_doubles_in_a_round() {
    // A row of 12 tiles of 16 samples; tiles 0 and 1 have 100x the variance
    // of the rest (10x the rate: 144 more each), but double at most (16),
    // and the rest of the budget (8 spp a tile on average) goes elsewhere.
    let tiles = Tiles::new(12 * T, T);
    let (counts, errors) = flat(&tiles, 16, |t| if t < 2 { 100.0 } else { 1.0 });
    let mut done = vec![false; 12];
    let work = plan_round(
        &tiles,
        &counts,
        &errors,
        &mut done,
        Goal::default(),
        16 * 12 * P,
    );
    let got: Vec<u32> = (0..12)
        .map(|t| work.iter().find(|w| w.tile == t).map_or(0, |w| w.count))
        .collect();
    assert_eq!(got[..2], [16, 16], "capped at doubling: {got:?}");
    assert!(got.iter().all(|&n| n <= 16), "{got:?}");
    assert!(
        (1..16).contains(&got[11]),
        "the rest share what is left: {got:?}"
    );
    let paths: u64 = work.iter().map(|w| u64::from(w.count) * P).sum();
    assert_eq!(paths, 8 * 12 * P);
}

#[test]
fn done_tiles_get_nothing_and_the_round_ends_when_all_are() {
    // Signal 3 per pixel: allowance 0.01^2 * 3 * P per tile.
    let allowance = 3e-4 * P as f64;
    let goal = Goal {
        target_error: Some(0.01),
        spp: None,
    };
    // A row of 4 tiles: two quiet, two noisy. Smoothed (in allowances):
    // 0.6, (0.6 + 0.5 * 4.6) / 2 = 1.45, (4 + 0.5 * 4.6) / 2 = 3.15, 4.
    let tiles = Tiles::new(4 * T, T);
    let (counts, errors) = flat(&tiles, 16, |t| allowance * if t < 2 { 0.6 } else { 4.0 });
    let mut done = vec![false; 4];
    let work = plan_round(&tiles, &counts, &errors, &mut done, goal, 16 * 4 * P);
    assert_eq!(done, [true, false, false, false]);
    let got: Vec<(u32, u32)> = work.iter().map(|w| (w.tile, w.count)).collect();
    // Tile 1 lacks 16 * 0.45 = 7.2 samples by its estimate (so 8), 2
    // and 3 lack 34 and 48, capped at doubling (16); the budget is 32 a
    // tile, so c is cut and tile 3 gets the most.
    assert_eq!(got.len(), 3, "{got:?}");
    assert!(got
        .iter()
        .all(|&(t, n)| t > 0 && n <= if t == 1 { 8 } else { 16 }));
    assert!(got[0].1 < got[1].1 && got[1].1 <= got[2].1, "{got:?}");
    let paths: u64 = work.iter().map(|w| u64::from(w.count) * P).sum();
    assert_eq!(paths, 16 * 4 * P / 2, "{got:?}");
    // Quiet everywhere: everything done, nothing to do.
    let (_, quiet) = flat(&tiles, 16, |_| allowance * 0.5);
    assert!(plan_round(&tiles, &counts, &quiet, &mut done, goal, 16 * 4 * P).is_empty());
    assert_eq!(done, [true; 4]);
    // Nearly there: a live tile gets what its estimate says it lacks.
    let mut fresh = vec![false; 4];
    let (_, close) = flat(&tiles, 16, |_| allowance * 1.25);
    let work = plan_round(&tiles, &counts, &close, &mut fresh, goal, 16 * 4 * P);
    assert_eq!(work.iter().map(|w| w.count).collect::<Vec<_>>(), [4; 4]);
}

#[test]
fn the_spp_budget_is_never_exceeded() {
    let tiles = Tiles::new(3 * T, 3 * T);
    let (counts, errors) = flat(&tiles, 16, |t| 1.0 + t as f64);
    let mut done = vec![false; 9];
    let goal = Goal {
        target_error: None,
        spp: Some(17),
    };
    let work = plan_round(&tiles, &counts, &errors, &mut done, goal, 16 * 9 * P);
    let paths: u64 = work.iter().map(|w| u64::from(w.count) * P).sum();
    assert_eq!(
        paths,
        9 * P,
        "one spp left, spent to the last tile: {work:?}"
    );
}

#[test]
fn a_round_goes_layer_by_layer_and_a_pass_may_end_mid_layer() {
    let tiles = Tiles::new(3 * T, T);
    let mut state = TileState {
        round: Round::new(vec![
            TileWork { tile: 0, count: 1 },
            TileWork { tile: 1, count: 4 },
            TileWork { tile: 2, count: 2 },
        ]),
        rounds: 1,
        ..TileState::start(&tiles)
    };
    // Layer 0 (tiles 1, 2, 0), then tile 1 of layer 1: four samples.
    let first = state.round.front(&tiles, 4 * P + P / 2);
    assert_eq!(
        first,
        [
            TileWork { tile: 0, count: 1 },
            TileWork { tile: 1, count: 2 },
            TileWork { tile: 2, count: 1 },
        ]
    );
    state.commit(&tiles, &first);
    // At least one sample, however small the pass.
    assert_eq!(
        state.round.front(&tiles, 1),
        [TileWork { tile: 2, count: 1 }]
    );
    let rest = state.round.front(&tiles, u64::MAX);
    assert_eq!(
        rest,
        [
            TileWork { tile: 1, count: 2 },
            TileWork { tile: 2, count: 1 }
        ]
    );
    state.commit(&tiles, &rest);
    assert!(state.round.is_empty());
    assert!(state.round.front(&tiles, u64::MAX).is_empty());
    assert_eq!(state.extra, [1, 4, 2]);
    assert_eq!(
        state.pixels_at,
        BTreeMap::from([(1, P), (2, P), (4, P)]),
        "pixels at each count"
    );
}
