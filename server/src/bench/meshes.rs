//! Meshes: BVH build time and memory, rays per second for camera rays and
//! diffuse-bounce rays, and paths per second, for generated meshes of a
//! given size (a closed, bumpy sphere: every camera ray near its middle
//! meets it, bounce rays leave it in all directions).
//!
//! The rays are made once and kept ([`RaySet`]), so that another tracer
//! (Embree, in `examples/embree_compare.rs`) can trace the very same ones.

use crate::model::generate::bumpy_sphere;
use crate::render::backend::nearest_hits;
use crate::render::camera::CameraRays;
use crate::render::material::cosine_hemisphere;
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::scene::{
    EnvironmentJson, ImportJson, MeshDataJson, ObjectJson, SceneJson, SurfaceJson,
};
use crate::render::world::{Hit, Origin, World};
use crate::render::{Backend, BackendChoice, BackendError, Film, Quality, RenderJob, Scene};
use std::collections::BTreeMap;
use std::time::Instant;

/// Image size of the camera rays (and the paths/s render).
pub const RAY_IMAGE: (u32, u32) = (512, 512);

/// One mesh size measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MeshRow {
    pub triangles: usize,
    pub build_seconds: f64,
    /// Bytes of the mesh: vertices, triangles (twice), BVH.
    pub memory_bytes: usize,
    pub bvh_nodes: usize,
    pub bvh_depth: u32,
    pub camera_rays_per_sec: f64,
    pub bounce_rays_per_sec: f64,
    /// Diffuse paths (max depth 4, NEE on, under a uniform sky) per second.
    pub paths_per_sec: f64,
    /// The same on the first OpenCL backend, if the benchmark has one.
    pub opencl_paths_per_sec: Option<f64>,
    /// Time to pack and upload the scene (BVHs, triangles, instances) and
    /// the film to that device, and the device memory they take.
    pub opencl_upload_seconds: Option<f64>,
    pub opencl_device_bytes: Option<u64>,
}

/// A mesh scene and the rays to time on it, in camera-relative space.
pub struct RaySet {
    pub scene: Scene,
    pub world: World,
    pub camera: Vec<(Ray, Origin)>,
    pub bounce: Vec<(Ray, Origin)>,
    pub build_seconds: f64,
}

/// The bumpy sphere of about `triangles` triangles, diffuse, under a
/// uniform sky, framed; built (timed) and its rays made.
pub fn ray_set(triangles: usize) -> RaySet {
    let mesh = bumpy_sphere(triangles);
    let data = MeshDataJson {
        positions: mesh.positions.iter().map(|p| p.map(f64::from)).collect(),
        triangles: mesh.triangles.clone(),
        normals: None,
    };
    let raw = SceneJson {
        camera: None,
        materials: BTreeMap::from([(
            "clay".to_owned(),
            crate::render::scene::MaterialJson::Diffuse(SurfaceJson {
                albedo: [0.7; 3].into(),
                emission: None,
                normal: None,
                alpha: None,
            }),
        )]),
        objects: vec![ObjectJson::Mesh(ImportJson {
            file: None,
            asset: None,
            data: Some(data),
            transform: None,
            material: Some("clay".into()),
        })],
        light: None,
        environment: Some(EnvironmentJson::Color([1.0; 3])),
    };
    let start = Instant::now();
    let scene = Scene::from_json(&raw).expect("a generated mesh is valid");
    let build_seconds = start.elapsed().as_secs_f64();
    let world = World::new(&scene, scene.camera.position);
    let cam = CameraRays::new(&scene.camera, RAY_IMAGE.0, RAY_IMAGE.1);
    let camera: Vec<(Ray, Origin)> = (0..RAY_IMAGE.1)
        .flat_map(|y| (0..RAY_IMAGE.0).map(move |x| (x, y)))
        .map(|(x, y)| (cam.ray(x as f32 + 0.5, y as f32 + 0.5), Origin::NONE))
        .collect();
    let hits = nearest_hits(&world, &camera);
    let bounce = camera
        .iter()
        .zip(&hits)
        .enumerate()
        .filter_map(|(i, ((ray, _), hit))| {
            let hit = hit.as_ref()?;
            let s = world.surface(hit, ray);
            let nl = if ray.dir.dot(s.ng) < 0.0 { s.ng } else { -s.ng };
            let (u1, u2) = Sampler::new(7, i as u64, 0).next_2d();
            let dir = cosine_hemisphere(nl, u1, u2);
            let from = Origin {
                object: hit.object,
                prim: hit.prim,
                entering: dir.dot(s.ng) < 0.0,
            };
            Some((world.spawn(&s, dir), from))
        })
        .collect();
    RaySet {
        scene,
        world,
        camera,
        bounce,
        build_seconds,
    }
}

/// Rays per second through the world, best of `repeats` passes over `rays`.
pub fn rays_per_sec(world: &World, rays: &[(Ray, Origin)], repeats: u32) -> f64 {
    rays_per_sec_with(world, rays, repeats, nearest_hits)
}

/// How a set of rays is traced: `nearest_hits` or `nearest_hits_packets`.
pub type Tracer = fn(&World, &[(Ray, Origin)]) -> Vec<Option<Hit>>;

/// [`rays_per_sec`] with the rays traced by `trace`.
pub fn rays_per_sec_with(
    world: &World,
    rays: &[(Ray, Origin)],
    repeats: u32,
    trace: Tracer,
) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        let hits = trace(world, rays);
        best = best.min(start.elapsed().as_secs_f64());
        std::hint::black_box(hits);
    }
    rays.len() as f64 / best.max(1e-9)
}

/// Measures one mesh size: build, memory, rays/s, and paths/s over
/// `seconds` of rendering, on the CPU and on `opencl` if given.
pub fn measure(
    triangles: usize,
    seconds: f64,
    opencl: Option<&mut Backend>,
) -> Result<MeshRow, BackendError> {
    let set = ray_set(triangles);
    let mesh = &set.scene.imports[0].instances[0].mesh;
    let repeats = if triangles > 2_000_000 { 2 } else { 3 };
    let camera = rays_per_sec(&set.world, &set.camera, repeats);
    let bounce = rays_per_sec(&set.world, &set.bounce, repeats);
    let quality = Quality {
        max_depth: 4,
        rr_depth: 5,
        time_ms: Some((seconds * 1000.0).max(1.0) as u64),
        ..Quality::default()
    };
    let (w, h) = (RAY_IMAGE.0 / 2, RAY_IMAGE.1 / 2);
    let job = RenderJob::new(&set.scene, w, h, &quality);
    let paths = |backend: &mut Backend| -> Result<f64, BackendError> {
        let mut film = Film::new(w, h);
        let done = crate::render::progressive::render(&job, backend, &mut film, &quality, |_| {})?;
        Ok(done.samples_per_sec)
    };
    let cpu_paths = paths(&mut Backend::choose(BackendChoice::Cpu)?)?;
    let (mut opencl_paths, mut upload, mut device_bytes) = (None, None, None);
    if let Some(b) = opencl {
        b.prepare(&job)?; // the compiler is not timed
        opencl_paths = Some(paths(b)?);
        if let Backend::OpenCl { backend, .. } = b {
            upload = backend.last_upload.map(|(d, _)| d.as_secs_f64());
            device_bytes = backend.last_upload.map(|(_, b)| b as u64);
        }
    }
    Ok(MeshRow {
        triangles: mesh.triangles.len(),
        build_seconds: set.build_seconds,
        memory_bytes: mesh.memory_bytes(),
        bvh_nodes: mesh.bvh.nodes.len(),
        bvh_depth: mesh.bvh.depth,
        camera_rays_per_sec: camera,
        bounce_rays_per_sec: bounce,
        paths_per_sec: cpu_paths,
        opencl_paths_per_sec: opencl_paths,
        opencl_upload_seconds: upload,
        opencl_device_bytes: device_bytes,
    })
}

/// Origin and direction of every ray as plain arrays (for other tracers).
pub fn plain(rays: &[(Ray, Origin)]) -> Vec<([f32; 3], [f32; 3])> {
    rays.iter()
        .map(|(r, _)| (r.origin.to_array(), r.dir.to_array()))
        .collect()
}
