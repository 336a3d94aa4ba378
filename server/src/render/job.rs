//! Everything one pass of rendering needs, prepared once per change of
//! scene, camera, size or quality.

use crate::render::camera::CameraRays;
use crate::render::filter::Filter;
use crate::render::integrator::{self, Path, PathSettings};
use crate::render::isa::Isa;
use crate::render::math::Vec3A;
use crate::render::quality::Quality;
use crate::render::sampler::SamplerKind;
use crate::render::scene::Scene;
use crate::render::world::World;
use std::sync::atomic::{AtomicU64, Ordering};

/// Longest image side accepted.
pub const MAX_SIDE: u32 = 65_536;
/// Most pixels in one image (the film holds 48 bytes per pixel).
pub const MAX_PIXELS: u64 = 4096 * 4096;

/// Checks an image size; the message names the offending dimension.
pub fn check_size(width: u32, height: u32) -> Result<(), String> {
    for (name, v) in [("width", width), ("height", height)] {
        if !(1..=MAX_SIDE).contains(&v) {
            return Err(format!(
                "{name}: must be between 1 and {MAX_SIDE} (got {v})"
            ));
        }
    }
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(format!(
            "width x height: {pixels} pixels is more than the limit of {MAX_PIXELS}"
        ));
    }
    Ok(())
}

fn next_id() -> u64 {
    static NEXT_ID: AtomicU64 = AtomicU64::new(1);
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Unique per `RenderJob::new` (clones share it): lets a device know
    /// whether the job it holds buffers for is still the current one.
    pub id: u64,
    pub world: World,
    pub camera: CameraRays,
    pub settings: PathSettings,
    pub filter: Filter,
    pub sampler: SamplerKind,
    pub seed: u64,
}

impl RenderJob {
    /// `scene` and `quality` are already validated; width and height >= 1.
    pub fn new(scene: &Scene, width: u32, height: u32, quality: &Quality) -> Self {
        Self::with_sky_probe(scene, width, height, quality, true)
    }

    /// [`RenderJob::new`], with the sky probe or without it (light selection
    /// by power alone: what the benchmark compares the probe with).
    pub fn with_sky_probe(
        scene: &Scene,
        width: u32,
        height: u32,
        quality: &Quality,
        sky_probe: bool,
    ) -> Self {
        let camera = CameraRays::new(&scene.camera, width, height);
        let mut world = World::new(scene, scene.camera.position);
        // A sky that walls hide gets few shadow rays (`sky_probe`).
        if quality.nee && sky_probe {
            crate::render::sky_probe::weigh_sky(&mut world, &camera);
        }
        Self {
            id: next_id(),
            world,
            camera,
            settings: quality.path_settings(),
            filter: quality.filter,
            sampler: quality.sampler,
            seed: quality.seed,
        }
    }

    /// A copy that devices treat as another job (its own state on a device:
    /// a caller then changes what the id stands for, such as the camera).
    pub fn with_new_id(&self) -> Self {
        Self {
            id: next_id(),
            ..self.clone()
        }
    }

    pub fn width(&self) -> u32 {
        self.camera.width
    }

    pub fn height(&self) -> u32 {
        self.camera.height
    }

    /// Sample `sample` of pixel (x, y) as a path about to start.
    #[inline(always)]
    pub fn camera_path(&self, x: u32, y: u32, sample: u64) -> Path {
        integrator::camera_path(
            &self.camera,
            self.filter,
            (self.sampler, self.seed),
            (x, y),
            sample,
        )
    }

    /// Radiance of sample `sample` of pixel (x, y), computed with `isa`'s
    /// kernels (the same number whichever it is).
    #[inline(always)]
    pub fn sample<I: Isa>(&self, isa: I, x: u32, y: u32, sample: u64) -> Vec3A {
        self.camera_path(x, y, sample)
            .trace(isa, &self.world, &self.settings)
    }
}
