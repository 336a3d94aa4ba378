//! Multiple importance sampling at glossy (`pbr`) surfaces: a rough metal
//! plane reflecting a small bright sphere, a large dim quad, a glowing mesh
//! and the sky renders the same image with MIS, with next-event estimation
//! alone and with BSDF sampling alone (statistics), on every backend that
//! can run each strategy; and MIS has the least error of the three at equal
//! samples.

mod common;

use common::{assert_agree, assert_clean, backends, regions};
use pathstream::render::integrator::Combine;
use pathstream::render::sampler::SamplerKind;
use pathstream::render::{Backend, BackendChoice, Film, Filter, Quality, RenderJob, Scene};

const W: u32 = 32;
const H: u32 = 24;

/// The bench's `glossy-plane` with its metal of `roughness`: a small bright
/// sphere light, a large dim quad, a glowing 80-triangle ball and a sky.
fn glossy_plane(roughness: f64) -> Scene {
    pathstream::bench::scenes::glossy_plane(roughness).expect("valid scene")
}

fn quality(nee: bool) -> Quality {
    Quality {
        filter: Filter::Box,
        sampler: SamplerKind::Random, // independent halves for the error estimate
        nee,
        seed: 3,
        ..Quality::default()
    }
}

/// Renders on the CPU with the strategies `combine` joins.
fn render_cpu(scene: &Scene, nee: bool, combine: Combine, spp: u64) -> Film {
    let mut backend = Backend::choose(BackendChoice::Cpu).expect("cpu");
    let mut job = RenderJob::new(scene, W, H, &quality(nee));
    job.settings.combine = combine;
    let mut film = Film::new(W, H);
    backend.render(&job, &mut film, spp).expect("render");
    film
}

/// The image's mean relative variance: each pixel's estimated variance of
/// its mean over its squared mean (4 x 4 regions, where the squared mean
/// is not tiny), averaged.
fn relative_error(film: &Film) -> f64 {
    let rs = regions(film, 4);
    let mut sum = 0.0;
    let mut count = 0.0;
    for r in &rs {
        for c in 0..3 {
            if r.mean[c] > 0.02 {
                sum += r.var[c] / (r.mean[c] * r.mean[c]);
                count += 1.0;
            }
        }
    }
    (sum / count).sqrt()
}

#[test]
fn mis_nee_only_and_bsdf_only_agree() {
    let s = glossy_plane(0.3);
    // BSDF sampling alone finds the small light rarely: its estimate of
    // its own error needs the most samples to be trusted.
    let mis = render_cpu(&s, true, Combine::Mis, 1024);
    let nee_only = render_cpu(&s, true, Combine::NeeOnly, 1024);
    let bsdf_only = render_cpu(&s, false, Combine::Mis, 4096);
    for (f, name) in [
        (&mis, "MIS"),
        (&nee_only, "NEE only"),
        (&bsdf_only, "BSDF only"),
    ] {
        assert_clean(f, name);
    }
    assert_agree(&mis, &nee_only, 8, 4.5, 0.005, "MIS vs NEE only");
    assert_agree(&mis, &bsdf_only, 8, 4.5, 0.005, "MIS vs BSDF only");
}

#[test]
fn mis_has_the_least_error_at_equal_samples() {
    for roughness in [0.1, 0.3, 0.6] {
        let s = glossy_plane(roughness);
        let spp = 256;
        let mis = relative_error(&render_cpu(&s, true, Combine::Mis, spp));
        let nee_only = relative_error(&render_cpu(&s, true, Combine::NeeOnly, spp));
        let bsdf_only = relative_error(&render_cpu(&s, false, Combine::Mis, spp));
        eprintln!(
            "roughness {roughness}: relative error MIS {mis:.4}, NEE only {nee_only:.4}, BSDF only {bsdf_only:.4}"
        );
        assert!(
            mis < nee_only && mis < bsdf_only,
            "roughness {roughness}: MIS {mis:.4} vs NEE only {nee_only:.4}, BSDF only {bsdf_only:.4}"
        );
    }
}

#[test]
fn every_backend_weighs_its_samples_to_the_bsdf_only_image() {
    let s = glossy_plane(0.4);
    for (name, mut backend) in backends() {
        let q = quality(true);
        let job = RenderJob::new(&s, W, H, &q);
        let mut mis = Film::new(W, H);
        backend.render(&job, &mut mis, 1024).expect("render");
        let job = RenderJob::new(&s, W, H, &quality(false));
        let mut bsdf_only = Film::new(W, H);
        backend.render(&job, &mut bsdf_only, 4096).expect("render");
        assert_clean(&mis, name);
        assert_agree(
            &mis,
            &bsdf_only,
            8,
            4.5,
            0.005,
            &format!("{name}: MIS vs BSDF only"),
        );
    }
}
