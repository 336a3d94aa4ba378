//! pathstream's CPU traversal next to Embree 3, on the same mesh and the
//! same rays, in one run (the meshes issue's "within 2x of Embree").
//!
//! ```text
//! apt-get install -y libembree-dev        # Debian 12: Embree 3.13.5
//! cargo run --release -p pathstream --features embree --example embree_compare -- \
//!     [TRIANGLES...] [--out FILE.csv] [--repeats N] [--quality] [--verbose]
//! ```
//!
//! For each size (default 10k, 100k, 1M, 4M triangles) `bench::meshes`
//! makes the bumpy sphere, its pathstream scene and world, 512x512 camera
//! rays and one diffuse bounce per camera hit. Embree gets the mesh's own
//! f32 vertices and indices (object space, as pathstream's BVH holds them)
//! and every ray mapped into object space by the instance's
//! `obj_from_cam`, exactly as pathstream maps it before its traversal (the
//! map is done inside Embree's timed loop too). So both trace the same
//! f32 triangles with the same f32 rays; the agreement check compares hit
//! or miss, triangle and distance of every ray.
//!
//! Embree traces single rays (`rtcIntersect1`) on rayon's threads (the
//! same pool as pathstream), tnear = 0 for every ray: camera rays start at
//! the camera; bounce rays start where pathstream spawned them, already
//! moved off the surface by its error bound (pathstream also skips the
//! triangle a ray leaves; Embree cannot, and self-hits are counted). Rays
//! per second are the best of `--repeats` passes (default 3), the tracers
//! taking turns pass by pass, so that load from elsewhere hits all alike.
//! "Embree robust" is `RTC_SCENE_FLAG_ROBUST` (watertight, like
//! pathstream's test). `--quality` adds Embree with `RTC_BUILD_QUALITY_HIGH`
//! (the default is MEDIUM). `--verbose` turns on Embree's own report
//! (`verbose=3`: its ISA, the BVH it builds, the intersectors it picks).
//!
//! Embree is bound by the small `extern "C"` block below (Embree 3's C API,
//! `libembree3`); only this example uses it, behind the `embree` feature.

use pathstream::bench::meshes::{ray_set, rays_per_sec, RaySet};
use pathstream::model::generate::bumpy_sphere;
use pathstream::render::backend::nearest_hits;
use pathstream::render::math::Affine3A;
use pathstream::render::ray::Ray;
use pathstream::render::shape::Mesh;
use pathstream::render::world::{Hit, Origin};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

/// The part of Embree 3's C API (rtcore.h, 3.13) that this example needs.
#[allow(unsafe_code, non_camel_case_types, dead_code)]
mod ffi {
    use std::ffi::{c_char, c_uint, c_void};

    pub type RTCDevice = *mut c_void;
    pub type RTCScene = *mut c_void;
    pub type RTCGeometry = *mut c_void;

    pub const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
    pub const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
    pub const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
    pub const RTC_FORMAT_UINT3: c_uint = 0x5003;
    pub const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
    pub const RTC_SCENE_FLAG_NONE: c_uint = 0;
    pub const RTC_SCENE_FLAG_ROBUST: c_uint = 1 << 2;
    pub const RTC_BUILD_QUALITY_MEDIUM: c_uint = 1;
    pub const RTC_BUILD_QUALITY_HIGH: c_uint = 2;
    pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
    pub const RTC_INVALID_GEOMETRY_ID: c_uint = c_uint::MAX;
    pub const RTC_DEVICE_PROPERTY_VERSION: c_uint = 0;
    pub const RTC_ERROR_NONE: c_uint = 0;

    /// `struct RTCRay` (16-byte aligned, 48 bytes).
    #[repr(C, align(16))]
    #[derive(Clone, Copy, Debug)]
    pub struct RTCRay {
        pub org_x: f32,
        pub org_y: f32,
        pub org_z: f32,
        pub tnear: f32,
        pub dir_x: f32,
        pub dir_y: f32,
        pub dir_z: f32,
        pub time: f32,
        pub tfar: f32,
        pub mask: c_uint,
        pub id: c_uint,
        pub flags: c_uint,
    }

    /// `struct RTCHit` with RTC_MAX_INSTANCE_LEVEL_COUNT = 1 (as Debian
    /// builds it).
    #[repr(C, align(16))]
    #[derive(Clone, Copy, Debug)]
    pub struct RTCHit {
        pub ng_x: f32,
        pub ng_y: f32,
        pub ng_z: f32,
        pub u: f32,
        pub v: f32,
        pub prim_id: c_uint,
        pub geom_id: c_uint,
        pub inst_id: [c_uint; 1],
    }

    #[repr(C)]
    #[derive(Clone, Copy, Debug)]
    pub struct RTCRayHit {
        pub ray: RTCRay,
        pub hit: RTCHit,
    }

    /// `struct RTCIntersectContext` (RTC_MAX_INSTANCE_LEVEL_COUNT = 1,
    /// RTC_MIN_WIDTH = 0).
    #[repr(C)]
    pub struct RTCIntersectContext {
        pub flags: c_uint,
        pub filter: Option<unsafe extern "C" fn(*const c_void)>,
        pub inst_id: [c_uint; 1],
    }

    const _: () = assert!(std::mem::size_of::<RTCRay>() == 48);
    const _: () = assert!(std::mem::size_of::<RTCHit>() == 32);
    const _: () = assert!(std::mem::size_of::<RTCRayHit>() == 80);
    const _: () = assert!(std::mem::size_of::<RTCIntersectContext>() == 24);

    impl RTCIntersectContext {
        /// What the header's inline `rtcInitIntersectContext` does.
        pub fn new() -> Self {
            Self {
                flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
                filter: None,
                inst_id: [RTC_INVALID_GEOMETRY_ID],
            }
        }
    }

    #[link(name = "embree3")]
    extern "C" {
        pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
        pub fn rtcReleaseDevice(device: RTCDevice);
        pub fn rtcGetDeviceError(device: RTCDevice) -> c_uint;
        pub fn rtcGetDeviceProperty(device: RTCDevice, prop: c_uint) -> isize;
        pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
        pub fn rtcSetSceneFlags(scene: RTCScene, flags: c_uint);
        pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_uint);
        pub fn rtcNewGeometry(device: RTCDevice, kind: c_uint) -> RTCGeometry;
        pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: c_uint);
        pub fn rtcSetNewGeometryBuffer(
            geometry: RTCGeometry,
            kind: c_uint,
            slot: c_uint,
            format: c_uint,
            byte_stride: usize,
            item_count: usize,
        ) -> *mut c_void;
        pub fn rtcCommitGeometry(geometry: RTCGeometry);
        pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
        pub fn rtcReleaseGeometry(geometry: RTCGeometry);
        pub fn rtcCommitScene(scene: RTCScene);
        pub fn rtcReleaseScene(scene: RTCScene);
        pub fn rtcIntersect1(
            scene: RTCScene,
            context: *mut RTCIntersectContext,
            rayhit: *mut RTCRayHit,
        );
    }
}

/// An Embree device, released on drop.
struct Device(ffi::RTCDevice);

impl Device {
    fn new(config: &str) -> Device {
        let config = std::ffi::CString::new(config).expect("no NUL in the config");
        // SAFETY: `config` is a NUL-terminated string that outlives the call.
        #[allow(unsafe_code)]
        let device = unsafe { ffi::rtcNewDevice(config.as_ptr()) };
        assert!(!device.is_null(), "rtcNewDevice failed");
        Device(device)
    }

    /// Panics with Embree's error code if the last calls failed.
    fn check(&self, what: &str) {
        // SAFETY: the device is live (released only on drop).
        #[allow(unsafe_code)]
        let error = unsafe { ffi::rtcGetDeviceError(self.0) };
        assert_eq!(error, ffi::RTC_ERROR_NONE, "Embree error {error} in {what}");
    }

    /// Embree's version, e.g. 31305 for 3.13.5.
    fn version(&self) -> isize {
        // SAFETY: the device is live.
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcGetDeviceProperty(self.0, ffi::RTC_DEVICE_PROPERTY_VERSION)
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every scene holds a reference of its own (Embree counts
        // them), so releasing ours here is valid whatever order drops run.
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcReleaseDevice(self.0)
        }
    }
}

/// A committed Embree scene of one triangle mesh, released on drop.
struct EmbreeScene {
    scene: ffi::RTCScene,
    build_seconds: f64,
}

// SAFETY: a committed Embree scene is read-only and Embree documents
// rtcIntersect1 on one scene as safe to call from many threads at once.
#[allow(unsafe_code)]
unsafe impl Sync for EmbreeScene {}
// SAFETY: as above; the handle may be used and released from any thread.
#[allow(unsafe_code)]
unsafe impl Send for EmbreeScene {}

impl EmbreeScene {
    /// Copies the mesh into Embree's buffers and commits the scene; the
    /// commit (the BVH build) is timed.
    fn build(
        device: &Device,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        flags: u32,
        quality: u32,
    ) -> EmbreeScene {
        // SAFETY: the device is live; the buffers Embree returns have room
        // for `count` items of the stride asked (16-byte vertices, the
        // padding Embree wants for its SIMD loads; 12-byte index triples),
        // and are written only before the geometry is committed. The
        // geometry is released after attaching (the scene keeps it).
        #[allow(unsafe_code)]
        let (scene, build_seconds) = unsafe {
            let scene = ffi::rtcNewScene(device.0);
            ffi::rtcSetSceneFlags(scene, flags);
            ffi::rtcSetSceneBuildQuality(scene, quality);
            let geometry = ffi::rtcNewGeometry(device.0, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
            ffi::rtcSetGeometryBuildQuality(geometry, quality);
            let vertices = ffi::rtcSetNewGeometryBuffer(
                geometry,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT3,
                16,
                positions.len(),
            )
            .cast::<[f32; 4]>();
            let indices = ffi::rtcSetNewGeometryBuffer(
                geometry,
                ffi::RTC_BUFFER_TYPE_INDEX,
                0,
                ffi::RTC_FORMAT_UINT3,
                12,
                triangles.len(),
            )
            .cast::<[u32; 3]>();
            device.check("rtcSetNewGeometryBuffer");
            assert!(!vertices.is_null() && !indices.is_null());
            let vertices = std::slice::from_raw_parts_mut(vertices, positions.len());
            for (v, p) in vertices.iter_mut().zip(positions) {
                *v = [p[0], p[1], p[2], 0.0];
            }
            std::slice::from_raw_parts_mut(indices, triangles.len()).copy_from_slice(triangles);
            ffi::rtcCommitGeometry(geometry);
            ffi::rtcAttachGeometry(scene, geometry);
            ffi::rtcReleaseGeometry(geometry);
            let start = Instant::now();
            ffi::rtcCommitScene(scene);
            (scene, start.elapsed().as_secs_f64())
        };
        device.check("rtcCommitScene");
        EmbreeScene {
            scene,
            build_seconds,
        }
    }

    /// Nearest hit of `ray`, mapped by `map` first, as pathstream reports
    /// one (the same type, so that collecting the results costs both
    /// tracers the same): object 0 (the mesh is the world's only
    /// object), the triangle, and barycentrics from Embree's u, v.
    #[inline(always)]
    fn intersect(&self, map: &Affine3A, ray: &Ray) -> Option<Hit> {
        let o = map.transform_point3a(ray.origin);
        let d = map.transform_vector3a(ray.dir);
        let mut rh = ffi::RTCRayHit {
            ray: ffi::RTCRay {
                org_x: o.x,
                org_y: o.y,
                org_z: o.z,
                tnear: 0.0,
                dir_x: d.x,
                dir_y: d.y,
                dir_z: d.z,
                time: 0.0,
                tfar: f32::INFINITY,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: ffi::RTCHit {
                ng_x: 0.0,
                ng_y: 0.0,
                ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                prim_id: ffi::RTC_INVALID_GEOMETRY_ID,
                geom_id: ffi::RTC_INVALID_GEOMETRY_ID,
                inst_id: [ffi::RTC_INVALID_GEOMETRY_ID],
            },
        };
        let mut context = ffi::RTCIntersectContext::new();
        // SAFETY: the scene is committed and live; `context` and `rh` are
        // valid, aligned, and exclusively ours for the call.
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcIntersect1(self.scene, &mut context, &mut rh)
        };
        (rh.hit.geom_id != ffi::RTC_INVALID_GEOMETRY_ID).then_some(Hit {
            t: rh.ray.tfar,
            object: 0,
            prim: rh.hit.prim_id,
            bary: [1.0 - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v],
        })
    }

    /// Every ray's nearest hit, on rayon's threads, in chunks as
    /// `nearest_hits` does.
    fn hits(&self, map: &Affine3A, rays: &[(Ray, Origin)]) -> Vec<Option<Hit>> {
        rays.par_chunks(4096)
            .flat_map_iter(|chunk| chunk.iter().map(|(r, _)| self.intersect(map, r)))
            .collect()
    }

    /// Rays per second of one pass.
    fn rays_per_sec(&self, map: &Affine3A, rays: &[(Ray, Origin)]) -> f64 {
        let start = Instant::now();
        let hits = self.hits(map, rays);
        let seconds = start.elapsed().as_secs_f64();
        std::hint::black_box(hits);
        rays.len() as f64 / seconds.max(1e-9)
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: the scene is ours and no trace is running (we hold it).
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcReleaseScene(self.scene)
        }
    }
}

/// How far Embree's hits agree with pathstream's on one ray kind.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    hits_pathstream: usize,
    hits_embree: usize,
    /// One hit, the other missed.
    hit_miss: usize,
    same_triangle: usize,
    /// Both hit, different triangles (ties on shared edges, or a different
    /// surface).
    other_triangle: usize,
    /// Of those, where the distances differ by more than 1e-4 relative.
    other_surface: usize,
    /// Largest |t_embree - t_pathstream| / t_pathstream where both hit the
    /// same triangle.
    max_rel_dt: f64,
    /// Embree hits on the triangle the ray leaves (pathstream skips it).
    self_hits: usize,
}

impl Agreement {
    fn of(rays: &[(Ray, Origin)], ours: &[Option<Hit>], theirs: &[Option<Hit>]) -> Agreement {
        let mut a = Agreement {
            rays: rays.len(),
            ..Agreement::default()
        };
        for (((_, from), p), e) in rays.iter().zip(ours).zip(theirs) {
            a.hits_pathstream += usize::from(p.is_some());
            a.hits_embree += usize::from(e.is_some());
            if let Some(e) = e {
                a.self_hits += usize::from(e.prim == from.prim);
            }
            match (p, e) {
                (Some(p), Some(e)) => {
                    let rel = f64::from((e.t - p.t).abs()) / f64::from(p.t);
                    if e.prim == p.prim {
                        a.same_triangle += 1;
                        a.max_rel_dt = a.max_rel_dt.max(rel);
                    } else {
                        a.other_triangle += 1;
                        a.other_surface += usize::from(rel > 1e-4);
                    }
                }
                (None, None) => {}
                _ => a.hit_miss += 1,
            }
        }
        a
    }

    fn summary(&self) -> String {
        format!(
            "{} rays: hits {} (pathstream) / {} (Embree), hit-vs-miss {}, same triangle {} ({:.4}%), other triangle {} (of which {} at a distance >1e-4 rel. off), max rel. |dt| on the same triangle {:.2e}, Embree self-hits {}",
            self.rays,
            self.hits_pathstream,
            self.hits_embree,
            self.hit_miss,
            self.same_triangle,
            100.0 * self.same_triangle as f64 / self.hits_pathstream.max(1) as f64,
            self.other_triangle,
            self.other_surface,
            self.max_rel_dt,
            self.self_hits,
        )
    }
}

/// One size's results.
struct Row {
    triangles: usize,
    build_scene: f64,
    build_mesh: f64,
    build_embree: f64,
    build_robust: f64,
    build_high: Option<f64>,
    /// Rays/s: [pathstream, Embree, Embree robust, Embree high quality].
    camera: [f64; 4],
    bounce: [f64; 4],
    camera_rays: usize,
    bounce_rays: usize,
    /// Share of the machine's CPU time that other processes took while the
    /// passes were timed (from /proc; None where it cannot be read).
    others: Option<f64>,
    agree_camera: Agreement,
    agree_bounce: Agreement,
    agree_camera_robust: Agreement,
    agree_bounce_robust: Agreement,
}

struct Args {
    sizes: Vec<usize>,
    out: Option<String>,
    repeats: u32,
    quality: bool,
    verbose: bool,
}

fn parse_args() -> Args {
    let mut args = Args {
        sizes: Vec::new(),
        out: None,
        repeats: 3,
        quality: false,
        verbose: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => args.out = Some(it.next().expect("--out FILE")),
            "--repeats" => {
                args.repeats = it.next().and_then(|n| n.parse().ok()).expect("--repeats N")
            }
            "--quality" => args.quality = true,
            "--verbose" => args.verbose = true,
            "-h" | "--help" => {
                println!("embree_compare [TRIANGLES...] [--out FILE.csv] [--repeats N] [--quality] [--verbose]");
                std::process::exit(0);
            }
            n => args
                .sizes
                .push(parse_size(n).unwrap_or_else(|| panic!("not a size or an option: {n}"))),
        }
    }
    if args.sizes.is_empty() {
        args.sizes = vec![10_000, 100_000, 1_000_000, 4_000_000];
    }
    args
}

/// "4000000", "4M", "100k".
fn parse_size(s: &str) -> Option<usize> {
    let (digits, scale) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 1_000.0),
        'm' | 'M' => (&s[..s.len() - 1], 1_000_000.0),
        _ => (s, 1.0),
    };
    digits.parse::<f64>().ok().map(|x| (x * scale) as usize)
}

fn measure(device: &Device, n: usize, args: &Args) -> Row {
    let RaySet {
        scene,
        world,
        camera,
        bounce,
        build_seconds,
    } = ray_set(n);
    let mesh = &scene.imports[0].instances[0];
    assert_eq!(
        mesh.world_from_object,
        pathstream::render::math::DAffine3::IDENTITY
    );
    assert_eq!((world.objects.len(), world.instances.len()), (1, 1));
    let map = world.instances[0].obj_from_cam;
    let (positions, triangles) = (&mesh.mesh.positions, &mesh.mesh.triangles);

    // pathstream's BVH build alone (the scene's build also converts and
    // checks the JSON mesh data).
    let data = bumpy_sphere(n);
    let start = Instant::now();
    let again = Mesh::new(data).expect("a valid mesh");
    let build_mesh = start.elapsed().as_secs_f64();
    assert_eq!(again.triangles.len(), triangles.len());
    drop(again);

    let medium = EmbreeScene::build(
        device,
        positions,
        triangles,
        ffi::RTC_SCENE_FLAG_NONE,
        ffi::RTC_BUILD_QUALITY_MEDIUM,
    );
    let robust = EmbreeScene::build(
        device,
        positions,
        triangles,
        ffi::RTC_SCENE_FLAG_ROBUST,
        ffi::RTC_BUILD_QUALITY_MEDIUM,
    );
    let high = args.quality.then(|| {
        EmbreeScene::build(
            device,
            positions,
            triangles,
            ffi::RTC_SCENE_FLAG_NONE,
            ffi::RTC_BUILD_QUALITY_HIGH,
        )
    });

    // Agreement: every ray, both kinds.
    let ours_camera = nearest_hits(&world, &camera);
    let ours_bounce = nearest_hits(&world, &bounce);
    let agree_camera = Agreement::of(&camera, &ours_camera, &medium.hits(&map, &camera));
    let agree_bounce = Agreement::of(&bounce, &ours_bounce, &medium.hits(&map, &bounce));
    let agree_camera_robust = Agreement::of(&camera, &ours_camera, &robust.hits(&map, &camera));
    let agree_bounce_robust = Agreement::of(&bounce, &ours_bounce, &robust.hits(&map, &bounce));
    drop((ours_camera, ours_bounce));

    // Speed: the tracers take turns, pass by pass; best pass of each.
    let time = |rays: &[(Ray, Origin)]| {
        let mut best = [0.0f64; 4];
        for _ in 0..args.repeats.max(1) {
            let mut pass = [
                rays_per_sec(&world, rays, 1),
                medium.rays_per_sec(&map, rays),
                robust.rays_per_sec(&map, rays),
                high.as_ref().map_or(0.0, |h| h.rays_per_sec(&map, rays)),
            ];
            for (b, p) in best.iter_mut().zip(&mut pass) {
                *b = b.max(*p);
            }
        }
        best
    };
    let before = CpuTicks::now();
    let camera_speed = time(&camera);
    let bounce_speed = time(&bounce);
    let others = CpuTicks::now()
        .zip(before)
        .map(|(after, before)| after.others_share(&before));
    Row {
        triangles: triangles.len(),
        build_scene: build_seconds,
        build_mesh,
        build_embree: medium.build_seconds,
        build_robust: robust.build_seconds,
        build_high: high.as_ref().map(|h| h.build_seconds),
        camera: camera_speed,
        bounce: bounce_speed,
        camera_rays: camera.len(),
        bounce_rays: bounce.len(),
        others,
        agree_camera,
        agree_bounce,
        agree_camera_robust,
        agree_bounce_robust,
    }
}

/// CPU time so far (Linux clock ticks): the machine's in all and idle,
/// and this process's.
#[derive(Clone, Copy)]
struct CpuTicks {
    total: u64,
    idle: u64,
    ours: u64,
}

impl CpuTicks {
    fn now() -> Option<CpuTicks> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let cpu: Vec<u64> = stat
            .lines()
            .next()?
            .split_whitespace()
            .skip(1)
            .map_while(|x| x.parse().ok())
            .collect();
        // user nice system idle iowait irq softirq steal (guest time is
        // already in user).
        let total = cpu.iter().take(8).sum();
        let idle = cpu.get(3)? + cpu.get(4)?;
        let own = std::fs::read_to_string("/proc/self/stat").ok()?;
        let fields: Vec<&str> = own.rsplit_once(')')?.1.split_whitespace().collect();
        // utime and stime: fields 14 and 15 of the line, 12 and 13 after
        // the command name.
        let ours = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
        Some(CpuTicks { total, idle, ours })
    }

    /// Share of all CPU time since `before` that neither idled nor was ours.
    fn others_share(&self, before: &CpuTicks) -> f64 {
        let total = self.total.saturating_sub(before.total).max(1) as f64;
        let busy = self
            .total
            .saturating_sub(before.total)
            .saturating_sub(self.idle.saturating_sub(before.idle));
        busy.saturating_sub(self.ours.saturating_sub(before.ours)) as f64 / total
    }
}

fn mrays(x: f64) -> String {
    format!("{:.2}", x / 1e6)
}

fn table(rows: &[Row], quality: bool) -> String {
    let mut s = String::new();
    s.push_str("| triangles | build s: pathstream scene / mesh BVH | build s: Embree / robust | camera Mrays/s: pathstream | Embree | Embree robust | ratio Embree/ps (robust/ps) | bounce Mrays/s: pathstream | Embree | Embree robust | ratio Embree/ps (robust/ps) |\n");
    s.push_str("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for r in rows {
        let ratio = |x: &[f64; 4]| format!("{:.2} ({:.2})", x[1] / x[0], x[2] / x[0]);
        let _ = writeln!(
            s,
            "| {} | {:.3} / {:.3} | {:.3} / {:.3} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.triangles,
            r.build_scene,
            r.build_mesh,
            r.build_embree,
            r.build_robust,
            mrays(r.camera[0]),
            mrays(r.camera[1]),
            mrays(r.camera[2]),
            ratio(&r.camera),
            mrays(r.bounce[0]),
            mrays(r.bounce[1]),
            mrays(r.bounce[2]),
            ratio(&r.bounce),
        );
    }
    if quality {
        s.push_str("\nEmbree build quality MEDIUM (default) vs HIGH:\n\n");
        s.push_str("| triangles | build s: MEDIUM / HIGH | camera Mrays/s: MEDIUM / HIGH | bounce Mrays/s: MEDIUM / HIGH |\n");
        s.push_str("| ---: | ---: | ---: | ---: |\n");
        for r in rows {
            let _ = writeln!(
                s,
                "| {} | {:.3} / {:.3} | {} / {} | {} / {} |",
                r.triangles,
                r.build_embree,
                r.build_high.unwrap_or(f64::NAN),
                mrays(r.camera[1]),
                mrays(r.camera[3]),
                mrays(r.bounce[1]),
                mrays(r.bounce[3]),
            );
        }
    }
    s
}

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "triangles,camera_rays,bounce_rays,build_s_pathstream_scene,build_s_pathstream_mesh,build_s_embree,build_s_embree_robust,build_s_embree_high,\
camera_rays_per_s_pathstream,camera_rays_per_s_embree,camera_rays_per_s_embree_robust,camera_rays_per_s_embree_high,\
bounce_rays_per_s_pathstream,bounce_rays_per_s_embree,bounce_rays_per_s_embree_robust,bounce_rays_per_s_embree_high,\
camera_hit_miss,camera_other_triangle,bounce_hit_miss,bounce_other_triangle,bounce_embree_self_hits,others_cpu_share\n",
    );
    for r in rows {
        let opt = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6}"));
        let rate = |x: f64| {
            if x > 0.0 {
                format!("{x:.0}")
            } else {
                String::new()
            }
        };
        let _ = writeln!(
            s,
            "{},{},{},{:.6},{:.6},{:.6},{:.6},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.triangles,
            r.camera_rays,
            r.bounce_rays,
            r.build_scene,
            r.build_mesh,
            r.build_embree,
            r.build_robust,
            opt(r.build_high),
            rate(r.camera[0]),
            rate(r.camera[1]),
            rate(r.camera[2]),
            rate(r.camera[3]),
            rate(r.bounce[0]),
            rate(r.bounce[1]),
            rate(r.bounce[2]),
            rate(r.bounce[3]),
            r.agree_camera.hit_miss,
            r.agree_camera.other_triangle,
            r.agree_bounce.hit_miss,
            r.agree_bounce.other_triangle,
            r.agree_bounce.self_hits,
            r.others.map_or(String::new(), |x| format!("{x:.3}")),
        );
    }
    s
}

fn main() {
    let args = parse_args();
    let threads = rayon::current_num_threads();
    let mut config = format!("threads={threads}");
    if args.verbose {
        config.push_str(",verbose=3");
    }
    let device = Device::new(&config);
    let v = device.version();
    eprintln!(
        "Embree {}.{}.{} (device \"{config}\"), rayon threads {threads}, best of {} passes",
        v / 10000,
        v / 100 % 100,
        v % 100,
        args.repeats
    );
    let mut rows = Vec::new();
    for &n in &args.sizes {
        eprintln!("{n} triangles ...");
        let row = measure(&device, n, &args);
        eprintln!("  camera, Embree:        {}", row.agree_camera.summary());
        eprintln!(
            "  camera, Embree robust: {}",
            row.agree_camera_robust.summary()
        );
        eprintln!("  bounce, Embree:        {}", row.agree_bounce.summary());
        eprintln!(
            "  bounce, Embree robust: {}",
            row.agree_bounce_robust.summary()
        );
        if let Some(others) = row.others {
            eprintln!("  other processes took {:.0}% of the machine's CPU time while the passes were timed", 100.0 * others);
        }
        rows.push(row);
    }
    println!("{}", table(&rows, args.quality));
    if let Some(out) = &args.out {
        std::fs::write(out, csv(&rows)).unwrap_or_else(|e| panic!("writing {out}: {e}"));
        eprintln!("wrote {out}");
    }
}
