//! A pass on an expensive scene renders a slice of one sample (a range of
//! pixels) instead of whole samples. Slices of any size, interleaved with
//! other jobs on the same device, give the image that whole samples give,
//! bit for bit, on every backend; mid-sample the film's mean and error
//! estimate count each pixel's own samples.

mod common;

use common::{backends, scene};
use pathstream::render::backend::opencl::OpenClBackend;
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob};

const NEVER: &(dyn Fn() -> bool + Sync) = &|| false;

fn job(name: &str, w: u32, h: u32) -> RenderJob {
    let q = Quality {
        seed: 11,
        ..Quality::default()
    };
    RenderJob::new(&scene(name), w, h, &q)
}

/// Renders samples `film.spp()..spp` in slices of `len` pixels.
fn slices(backend: &mut Backend, job: &RenderJob, film: &mut Film, len: usize, spp: u64) {
    let pixels = film.pixels().len();
    while film.spp() < spp {
        let end = (film.slice_start() + len).min(pixels);
        assert!(backend.render_slice(job, film, end, NEVER).expect("slice"));
    }
}

#[test]
fn slices_of_any_size_give_the_image_of_whole_samples() {
    let (w, h) = (23, 17);
    let a = job("cornell-glass", w, h);
    for (name, mut backend) in backends() {
        let mut whole = Film::new(w, h);
        backend.render(&a, &mut whole, 5).expect("render");
        for len in [1, 37, 200, 391] {
            let mut sliced = Film::new(w, h);
            backend.render(&a, &mut sliced, 1).expect("render");
            slices(&mut backend, &a, &mut sliced, len, 4);
            backend.render(&a, &mut sliced, 1).expect("render");
            assert_eq!(sliced.spp(), 5, "{name}, slices of {len}");
            assert_eq!(whole.pixels(), sliced.pixels(), "{name}, slices of {len}");
            assert_eq!(whole.rejected(), sliced.rejected(), "{name}");
        }
    }
}

#[test]
fn another_job_between_slices_does_not_disturb_either() {
    // One device, two sessions taking turns slice by slice (the device
    // switches job state between every slice).
    let (w, h) = (16, 12);
    let (a, b) = (job("cornell", w, h), job("cornell-glass", w, h));
    for (name, mut backend) in backends() {
        let (mut fa, mut fb) = (Film::new(w, h), Film::new(w, h));
        while fa.spp() < 3 || fb.spp() < 3 {
            for (j, f, len) in [(&a, &mut fa, 50), (&b, &mut fb, 71)] {
                if f.spp() < 3 {
                    let end = (f.slice_start() + len).min(f.pixels().len());
                    assert!(backend.render_slice(j, f, end, NEVER).expect("slice"));
                }
            }
        }
        for (j, f) in [(&a, &fa), (&b, &fb)] {
            let mut alone = Film::new(w, h);
            backend.render(j, &mut alone, 3).expect("render");
            assert_eq!(
                alone.pixels(),
                f.pixels(),
                "{name}: taking turns changed the image"
            );
        }
    }
}

#[test]
fn mid_sample_each_pixel_is_divided_by_its_own_count() {
    let (w, h) = (20, 10);
    let a = job("cornell", w, h);
    for (name, mut backend) in backends() {
        let mut film = Film::new(w, h);
        backend.render(&a, &mut film, 4).expect("render");
        let (four_mean, four_err) = (film.mean(), film.error_estimate().expect("estimate"));
        let mut five = film.clone();
        backend.render(&a, &mut five, 1).expect("render");
        // Sample 4 in the first 60 pixels only.
        assert!(backend
            .render_slice(&a, &mut film, 60, NEVER)
            .expect("slice"));
        assert_eq!((film.spp(), film.slice_start()), (4, 60), "{name}");
        let mean = film.mean();
        assert_eq!(
            &mean[..60],
            &five.mean()[..60],
            "{name}: pixels with 5 samples"
        );
        assert_eq!(
            &mean[60..],
            &four_mean[60..],
            "{name}: pixels with 4 samples"
        );
        let err = film.error_estimate().expect("estimate");
        let five_err = five.error_estimate().expect("estimate");
        let (lo, hi) = (four_err.min(five_err), four_err.max(five_err));
        assert!(
            err >= lo * 0.999 && err <= hi * 1.001,
            "{name}: mid-sample estimate {err} outside [{lo}, {hi}]"
        );
    }
}

#[test]
fn a_device_failing_mid_sample_falls_back_and_finishes_the_sample() {
    let Ok(mut failing) = OpenClBackend::new(None) else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but there is no OpenCL device"
        );
        return;
    };
    let (w, h) = (12, 10);
    let a = job("cornell", w, h);
    let mut film = Film::new(w, h);
    failing
        .render_slice(&a, &mut film, 50)
        .expect("slice on the device");
    failing.fail_launches = true;
    let before = film.clone();
    // Asked for by name: an error, and the film as it was.
    let err = failing
        .render_slice(&a, &mut film, 90)
        .expect_err("injected failure");
    assert!(err.to_string().contains("kernel launch failed"), "{err}");
    assert_eq!((film.spp(), film.slice_start()), (0, 50));
    assert_eq!(film.pixels(), before.pixels());
    // Chosen by auto: rayon carries on from pixel 50 and completes the sample.
    let mut auto = Backend::OpenCl {
        backend: Box::new(failing),
        fallback: true,
    };
    assert!(auto
        .render_slice(&a, &mut film, 120, NEVER)
        .expect("falls back"));
    assert_eq!(auto.name(), "cpu");
    assert_eq!((film.spp(), film.slice_start()), (1, 0));
    let mut cpu = Film::new(w, h);
    Backend::choose(BackendChoice::Cpu)
        .expect("cpu")
        .render(&a, &mut cpu, 1)
        .expect("render");
    // The last 70 pixels are the CPU's own sample, bit for bit.
    assert_eq!(&film.pixels()[50..], &cpu.pixels()[50..]);
}

#[test]
fn a_cancelled_slice_says_so() {
    let (w, h) = (32, 32);
    let a = job("cornell", w, h);
    let mut cpu = Backend::choose(BackendChoice::Cpu).expect("cpu");
    let mut film = Film::new(w, h);
    assert!(!cpu
        .render_slice(&a, &mut film, 1024, &|| true)
        .expect("slice"));
    assert_eq!((film.spp(), film.slice_start()), (0, 0));
}

/// A device pass that a change makes useless gives up between launches:
/// the film stays as it was, and the next pass adds exactly the samples an
/// uninterrupted render adds (the device state was dropped and is rebuilt
/// from the host's film).
#[test]
fn a_device_pass_given_up_between_launches_leaves_the_film_as_it_was() {
    let Some(mut device) = common::opencl_device() else {
        return;
    };
    device.launch_target = std::time::Duration::from_nanos(1); // a sample a launch
    let (w, h) = (19, 13);
    let a = job("cornell", w, h);
    let mut film = Film::new(w, h);
    device.render(&a, &mut film, 2).expect("render");
    let before = film.pixels().to_vec();
    let launches = std::sync::atomic::AtomicUsize::new(0);
    let after_two = || launches.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= 2;
    let done = device
        .render_unless(&a, &mut film, 6, &after_two)
        .expect("pass");
    assert!(!done, "the pass was not given up");
    assert_eq!(launches.load(std::sync::atomic::Ordering::Relaxed), 3);
    assert_eq!(film.spp(), 2);
    assert_eq!(film.pixels(), &before[..]);
    device.render(&a, &mut film, 6).expect("render on");
    let mut whole = Film::new(w, h);
    common::opencl_device()
        .expect("device")
        .render(&a, &mut whole, 8)
        .expect("render");
    assert_eq!(film.spp(), 8);
    assert!(
        film.pixels() == whole.pixels(),
        "the pass after the cancelled one differs"
    );
}
