//! Scene buffers are checked against the device's memory before upload: a
//! scene that does not fit is refused with an error that names what is too
//! large, `auto` renders it with rayon instead (the device keeps serving
//! the scenes that fit), and jobs taking turns on a device with room for one
//! evict each other without losing a sample.

mod common;

use common::{opencl_device as device, scene};
use pathstream::render::backend::opencl::MemoryLimits;
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob};

fn cpu_film(job: &RenderJob, spp: u64) -> Film {
    let mut film = Film::new(job.width(), job.height());
    Backend::choose(BackendChoice::Cpu)
        .expect("cpu")
        .render(job, &mut film, spp)
        .expect("render");
    film
}

#[test]
fn a_scene_larger_than_the_device_is_refused_by_name_and_auto_uses_rayon() {
    let Some(mut small) = device() else { return };
    // 64x64: a film of 64 x 64 x 48 bytes = 192 KiB, more than this device's
    // largest buffer.
    small.memory_limits = MemoryLimits {
        max_alloc_bytes: 100 << 10,
        total_bytes: 1 << 30,
    };
    let big = RenderJob::new(&scene("cornell"), 64, 64, &Quality::default());
    let fits = RenderJob::new(&scene("cornell"), 16, 16, &Quality::default());
    let mut named = Backend::OpenCl {
        backend: Box::new(small),
        fallback: false,
    };
    let mut film = Film::new(64, 64);
    let err = named.render(&big, &mut film, 1).expect_err("too large");
    let text = err.to_string();
    assert!(
        text.contains("its film need 0.2 MiB in one buffer"),
        "{text}"
    );
    assert!(text.contains("largest allocation"), "{text}");
    assert_eq!(film.spp(), 0, "the film is untouched");
    // Chosen by auto: this scene on rayon (the same bits as the CPU's), the
    // device still there for the next.
    let Backend::OpenCl { backend, .. } = named else {
        unreachable!()
    };
    let mut auto = Backend::OpenCl {
        backend,
        fallback: true,
    };
    auto.render(&big, &mut film, 2).expect("falls back");
    assert_eq!(auto.name(), "opencl", "one scene does not cost the device");
    assert_eq!(film.pixels(), cpu_film(&big, 2).pixels());
    let mut small_film = Film::new(16, 16);
    auto.render(&fits, &mut small_film, 2).expect("fits");
    assert_eq!(small_film.spp(), 2);
}

#[test]
fn jobs_too_large_to_share_the_device_evict_each_other_and_lose_nothing() {
    let Some(mut tight) = device() else { return };
    let (a, b) = (
        RenderJob::new(&scene("cornell"), 40, 30, &Quality::default()),
        RenderJob::new(&scene("cornell-glass"), 40, 30, &Quality::default()),
    );
    // Room for one job's film and scene, not two.
    tight.memory_limits = MemoryLimits {
        max_alloc_bytes: 1 << 30,
        total_bytes: 40 * 30 * 48 + (16 << 10),
    };
    let (mut fa, mut fb) = (Film::new(40, 30), Film::new(40, 30));
    for n in [2, 3] {
        tight.render(&a, &mut fa, n).expect("a");
        tight.render(&b, &mut fb, n).expect("b");
    }
    let mut alone = device().expect("device");
    for (job, film) in [(&a, &fa), (&b, &fb)] {
        let mut f = Film::new(40, 30);
        alone.render(job, &mut f, 5).expect("render");
        assert_eq!(f.pixels(), film.pixels(), "evictions changed the image");
    }
}

/// The device keeps a scene's textures and meshes between jobs: a camera
/// move (a new job of the same textures and meshes) uploads neither, and
/// the same job again renders the same samples; another scene's are
/// uploaded.
#[test]
fn textures_and_meshes_are_uploaded_once_for_the_jobs_that_share_them() {
    let Some(mut d) = device() else { return };
    let textured = pathstream::bench::textured::cornell_mesh_textured().expect("scene");
    let side = u64::from(pathstream::bench::textured::MAP_SIDE);
    let texel_bytes = 6 * side * side * 4;
    let mut render = |s: &pathstream::render::Scene| {
        let before = d.scene_bytes_uploaded;
        let job = RenderJob::new(s, 16, 16, &Quality::default());
        let mut film = Film::new(16, 16);
        d.render(&job, &mut film, 2).expect("render");
        (film, d.scene_bytes_uploaded - before)
    };
    let (first, all) = render(&textured);
    assert!(all >= texel_bytes, "first job: {all} bytes");
    let mut moved = textured.clone();
    moved.camera.position.x += 5.0;
    // Neither the texels nor the meshes' arrays: the objects and the
    // instances' transforms only.
    let (_, uploaded) = render(&moved);
    assert!(
        uploaded * 20 < all,
        "a camera move: {uploaded} of {all} bytes"
    );
    let (again, _) = render(&textured);
    assert!(
        first.mean() == again.mean(),
        "the shared texels render the same samples"
    );
    let rebuilt = pathstream::bench::textured::cornell_mesh_textured().expect("scene");
    let (_, uploaded) = render(&rebuilt);
    assert!(uploaded >= texel_bytes, "other textures: {uploaded} bytes");
}
