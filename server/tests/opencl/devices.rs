//! Choosing, failing and sharing devices: the fallback to rayon, a bad
//! device number, a device failing mid-render, launches split into pixel
//! ranges and sessions taking turns.

use super::*;

#[test]
fn auto_falls_back_to_rayon_and_says_so_when_there_is_no_platform() {
    let empty = tempfile::tempdir().expect("tempdir");
    let out = empty.path().join("x.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args([
            "render",
            "--scene",
            "furnace",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "--backend",
            "auto",
            "--out",
        ])
        .arg(&out)
        .env("OCL_ICD_VENDORS", empty.path())
        .output()
        .expect("runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains("backend cpu (rayon"), "{summary}");
    assert!(
        summary.contains("no OpenCL platform found"),
        "says why: {summary}"
    );
    let devices = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .arg("devices")
        .env("OCL_ICD_VENDORS", empty.path())
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&devices.stdout);
    assert!(text.contains("auto picks: rayon on the CPU"), "{text}");
}

#[test]
fn explicit_opencl_with_a_bad_device_number_is_a_clear_error() {
    let Some(_) = device() else { return };
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args([
            "render",
            "--scene",
            "furnace",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "--device",
            "99",
            "--out",
            "/tmp/x.png",
        ])
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("--device 99"), "{err}");
}

#[test]
fn a_device_that_fails_mid_render_loses_no_samples() {
    let Some(first) = device() else { return };
    let s = scene("cornell");
    let job = RenderJob::new(&s, 8, 8, &Quality::default());
    // Asked for by name: the error comes back and the film is untouched.
    let mut named = Backend::OpenCl {
        backend: Box::new(first),
        fallback: false,
    };
    let mut film = Film::new(8, 8);
    named.render(&job, &mut film, 4).expect("render");
    let before = film.pixels().to_vec();
    if let Backend::OpenCl { backend, .. } = &mut named {
        backend.fail_launches = true;
    }
    let err = named
        .render(&job, &mut film, 4)
        .expect_err("injected failure");
    assert!(err.to_string().contains("kernel launch failed"), "{err}");
    assert_eq!(film.spp(), 4);
    assert_eq!(film.pixels(), &before[..]);
    // Chosen by auto: a logged fall back to rayon that carries on from sample 4.
    let mut failing = OpenClBackend::new(None).expect("device");
    failing.fail_launches = true;
    let mut auto = Backend::OpenCl {
        backend: Box::new(failing),
        fallback: true,
    };
    auto.render(&job, &mut film, 4).expect("falls back");
    assert_eq!(auto.name(), "cpu");
    assert!(auto.device().contains("OpenCL failed"), "{}", auto.device());
    assert_eq!(film.spp(), 8);
    // Samples 4..8 are the CPU's own: what the fallback added to each pixel
    // is exactly what a CPU render adds after its own first four samples.
    let mut cpu = Backend::choose(BackendChoice::Cpu).expect("cpu");
    let (mut first4, mut all8) = (Film::new(8, 8), Film::new(8, 8));
    cpu.render(&job, &mut first4, 4).expect("render");
    cpu.render(&job, &mut all8, 8).expect("render");
    for (i, ((after, opencl), (c8, c4))) in film
        .pixels()
        .iter()
        .zip(&before)
        .zip(all8.pixels().iter().zip(first4.pixels()))
        .enumerate()
    {
        for c in 0..3 {
            for (added, cpu_added, scale) in [
                (
                    after.even[c] - opencl.even[c],
                    c8.even[c] - c4.even[c],
                    after.even[c].abs() + c8.even[c].abs(),
                ),
                (
                    after.odd[c] - opencl.odd[c],
                    c8.odd[c] - c4.odd[c],
                    after.odd[c].abs() + c8.odd[c].abs(),
                ),
            ] {
                assert!(
                    (added - cpu_added).abs() <= 1e-12 * scale,
                    "pixel {i} channel {c}: fallback added {added}, the CPU adds {cpu_added}"
                );
            }
        }
    }
}

#[test]
fn launches_split_into_pixel_ranges_give_the_same_image() {
    let Some(mut whole) = device() else { return };
    let mut tiled = OpenClBackend::new(None).expect("device");
    // A target no launch can meet: one sample per launch.
    tiled.launch_target = std::time::Duration::from_nanos(1);
    // Taller than one launch's worth of pixels: several launches per sample.
    tiled.launch_pixels = 4096;
    let (w, h) = (64, (tiled.launch_pixels / 64 + 3) as u32);
    let s = scene("cornell-glass");
    let job = RenderJob::new(
        &s,
        w,
        h,
        &Quality {
            seed: 3,
            max_depth: 2,
            ..Quality::default()
        },
    );
    let (mut a, mut b) = (Film::new(w, h), Film::new(w, h));
    whole.render(&job, &mut a, 3).expect("render");
    for n in [1, 2] {
        tiled.render(&job, &mut b, n).expect("render");
    }
    assert_eq!(b.spp(), 3);
    assert_eq!(a.pixels(), b.pixels());
}

#[test]
fn sessions_taking_turns_on_one_device_keep_their_films() {
    let Some(mut shared) = device() else { return };
    let (a, b) = (scene("cornell"), scene("cornell-glass"));
    let (ja, jb) = (
        RenderJob::new(&a, 16, 12, &Quality::default()),
        RenderJob::new(&b, 16, 12, &Quality::default()),
    );
    let (mut fa, mut fb) = (Film::new(16, 12), Film::new(16, 12));
    for n in [3, 5] {
        shared.render(&ja, &mut fa, n).expect("render");
        shared.render(&jb, &mut fb, n).expect("render");
    }
    for (job, film) in [(&ja, &fa), (&jb, &fb)] {
        let mut alone = OpenClBackend::new(None).expect("device");
        let mut f = Film::new(16, 12);
        alone.render(job, &mut f, 8).expect("render");
        assert_eq!(f.pixels(), film.pixels(), "taking turns changed the image");
    }
}
