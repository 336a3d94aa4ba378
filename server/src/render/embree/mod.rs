//! Intel Embree 3, loaded at run time as OpenCL and Open Image Denoise
//! are, as the CPU backend's optional ray tracer for meshes:
//! `PATHSTREAM_EMBREE` names the library file or a folder holding it, or
//! `off`; else `libembree3.so.3` is looked up on the system's library path
//! (Debian: `apt-get install libembree3-3`). Without it the CPU traverses
//! its own BVH, as the OpenCL kernel always does.
//!
//! What this module holds: the library and one device (started once, on
//! first use, never released), a mesh as an Embree scene of one triangle
//! geometry, and the world's scene, which answers the queries: meshes
//! placed once as triangles of its own (one tree for a ray to walk), large
//! or shared ones as placed mesh scenes (instances). Both kinds of scene
//! are built robust
//! (`RTC_SCENE_FLAG_ROBUST`: watertight, as the CPU's own triangle test
//! is). A query may carry a filter that refuses hits (the triangle a ray
//! leaves, alpha-tested texels), called by Embree for each hit it finds.
//!
//! `unsafe` is allowed statement by statement, each with a `SAFETY:`
//! comment. What the C API leaves to its caller: handles are used only
//! while alive (each is owned by one Rust value that releases it on drop,
//! and the world's scene holds the mesh scenes it places), buffers are
//! written only within the counts asked for, and committed scenes are only
//! read (Embree allows queries on one scene from many threads at once).
#![allow(unsafe_code)]

pub mod ffi;
mod packet;

pub use packet::{Answers, Packet};

use std::ffi::c_void;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

/// The library's file name on Linux (Embree 3).
pub const LIBRARY: &str = "libembree3.so.3";

/// The loaded library and its device.
pub struct Embree {
    lib: ffi::Library,
    device: ffi::Handle,
    /// Embree's version, e.g. "3.13.5".
    pub version: String,
}

// SAFETY: the device handle is only passed to Embree's functions, which
// may be called for one device from any thread (Embree's API is thread
// safe but for writes to one scene or geometry, which are never shared
// before they are committed).
unsafe impl Send for Embree {}
// SAFETY: as above.
unsafe impl Sync for Embree {}

impl std::fmt::Debug for Embree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Embree {} ({})", self.version, self.lib.path.display())
    }
}

static STATE: OnceLock<Result<Embree, String>> = OnceLock::new();

/// The library if a world has loaded it already (loads nothing: for
/// reports, which should not start Embree's threads in a process that may
/// never trace a large mesh).
pub fn loaded() -> Option<&'static Embree> {
    STATE.get().and_then(|s| s.as_ref().ok())
}

/// The library, loaded and started on first use, or why it is not there.
pub fn embree() -> Result<&'static Embree, &'static str> {
    let state = STATE.get_or_init(|| {
        let state = start();
        match &state {
            Ok(e) => tracing::info!(
                library = %e.lib.path.display(),
                version = %e.version,
                "the CPU traces mesh rays with Embree"
            ),
            Err(why) => tracing::info!("the CPU traces its own BVH: {why}"),
        }
        state
    });
    state.as_ref().map_err(String::as_str)
}

/// Where to look for the library, in order; None: switched off.
fn candidates() -> Option<Vec<PathBuf>> {
    match std::env::var_os("PATHSTREAM_EMBREE").filter(|v| !v.is_empty()) {
        Some(v) if v == "off" || v == "0" => None,
        Some(p) => {
            let p = PathBuf::from(p);
            Some(match p.is_dir() {
                true => vec![p.join(LIBRARY), p.join("lib").join(LIBRARY)],
                false => vec![p],
            })
        }
        None => Some(vec![PathBuf::from(LIBRARY)]),
    }
}

fn start() -> Result<Embree, String> {
    let Some(paths) = candidates() else {
        return Err("Embree is switched off (PATHSTREAM_EMBREE=off)".into());
    };
    let mut tried = Vec::new();
    for path in paths {
        match ffi::Library::load(&path) {
            Ok(lib) => {
                // SAFETY: a NUL-terminated (empty) configuration string.
                let device = unsafe { (lib.api.new_device)(c"".as_ptr()) };
                if device.is_null() {
                    return Err(format!("{}: rtcNewDevice failed", path.display()));
                }
                // SAFETY: a live device.
                let v = unsafe { (lib.api.device_property)(device, ffi::DEVICE_PROPERTY_VERSION) };
                let version = format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100);
                if v / 10000 != 3 {
                    return Err(format!("{} is Embree {version}, not 3", path.display()));
                }
                return Ok(Embree {
                    lib,
                    device,
                    version,
                });
            }
            Err(e) => tried.push(e),
        }
    }
    Err(format!(
        "{} (install Embree 3, e.g. Debian's libembree3-3, or point PATHSTREAM_EMBREE at it)",
        tried.join("; ")
    ))
}

impl Embree {
    /// Embree's error for the calls since the last check, if any.
    fn check(&self, what: &str) -> Result<(), String> {
        // SAFETY: a live device.
        match unsafe { (self.lib.api.device_error)(self.device) } {
            ffi::ERROR_NONE => Ok(()),
            code => Err(format!("Embree error {code} in {what}")),
        }
    }

    /// A new scene with the flags every scene here has.
    fn new_scene(&self, quality: u32) -> Result<ffi::Handle, String> {
        let api = &self.lib.api;
        // SAFETY: a live device; the scene is configured before any use.
        let scene = unsafe { (api.new_scene)(self.device) };
        if scene.is_null() {
            self.check("rtcNewScene")?;
            return Err("rtcNewScene failed".into());
        }
        let flags = ffi::SCENE_FLAG_ROBUST | ffi::SCENE_FLAG_CONTEXT_FILTER_FUNCTION;
        // SAFETY: a new scene of ours.
        unsafe {
            (api.set_scene_flags)(scene, flags);
            (api.set_scene_build_quality)(scene, quality);
        }
        Ok(scene)
    }

    /// A mesh (object-space positions, triangles by vertex index) as a
    /// committed scene of its own, its triangles numbered as given; an
    /// index beyond the positions is refused before Embree reads it.
    pub fn mesh(
        &'static self,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<MeshScene, String> {
        let api = &self.lib.api;
        let scene = MeshScene {
            scene: self.new_scene(ffi::BUILD_QUALITY_HIGH)?,
            embree: self,
        };
        self.attach_triangles(scene.scene, 0, positions.iter().copied(), triangles)?;
        // SAFETY: a live scene of ours, fully attached.
        unsafe { (api.commit_scene)(scene.scene) };
        self.check("building a mesh")?;
        Ok(scene)
    }

    /// Triangles (positions, then index triples) as a geometry of `scene`
    /// with id `id`, or why not (an index beyond the positions).
    fn attach_triangles(
        &self,
        scene: ffi::Handle,
        id: u32,
        positions: impl ExactSizeIterator<Item = [f32; 3]>,
        triangles: &[[u32; 3]],
    ) -> Result<(), String> {
        let api = &self.lib.api;
        let n = positions.len();
        if let Some(t) = triangles.iter().flatten().find(|&&i| i as usize >= n) {
            return Err(format!("vertex index {t} of {n}"));
        }
        // SAFETY: a live device and scene of ours, not yet committed; the
        // buffers Embree returns have room for the counts asked (16-byte
        // vertices, the padding Embree wants for its SIMD loads; 12-byte
        // index triples) and are written only before the geometry is
        // committed. The scene keeps the geometry, ours is released after
        // attaching.
        unsafe {
            let geometry = (api.new_geometry)(self.device, ffi::GEOMETRY_TYPE_TRIANGLE);
            if geometry.is_null() {
                self.check("rtcNewGeometry")?;
                return Err("rtcNewGeometry failed".into());
            }
            (api.set_geometry_build_quality)(geometry, ffi::BUILD_QUALITY_HIGH);
            let buffer = |kind, format, stride, count| {
                (api.set_new_geometry_buffer)(geometry, kind, 0, format, stride, count)
            };
            let vertices =
                buffer(ffi::BUFFER_TYPE_VERTEX, ffi::FORMAT_FLOAT3, 16, n).cast::<[f32; 4]>();
            let indices = buffer(
                ffi::BUFFER_TYPE_INDEX,
                ffi::FORMAT_UINT3,
                12,
                triangles.len(),
            )
            .cast::<[u32; 3]>();
            if vertices.is_null() || indices.is_null() {
                (api.release_geometry)(geometry);
                self.check("rtcSetNewGeometryBuffer")?;
                return Err("rtcSetNewGeometryBuffer failed".into());
            }
            let vertices = std::slice::from_raw_parts_mut(vertices, n);
            for (v, p) in vertices.iter_mut().zip(positions) {
                *v = [p[0], p[1], p[2], 0.0];
            }
            std::slice::from_raw_parts_mut(indices, triangles.len()).copy_from_slice(triangles);
            (api.commit_geometry)(geometry);
            (api.attach_geometry_by_id)(scene, geometry, id);
            (api.release_geometry)(geometry);
        }
        self.check("adding triangles")
    }

    /// The world's meshes as one scene: each part either triangles of
    /// its own or a mesh scene placed by a matrix. A hit names the part by
    /// its id.
    pub fn scene(&'static self, parts: Vec<Part<'_>>) -> Result<WorldScene, String> {
        let api = &self.lib.api;
        let flat = parts.iter().any(|p| matches!(p, Part::Triangles { .. }));
        // A scene over triangles is worth the better build (it is the
        // tree most rays walk); one over placements alone is small.
        let quality = match flat {
            true => ffi::BUILD_QUALITY_HIGH,
            false => ffi::BUILD_QUALITY_MEDIUM,
        };
        let mut scene = WorldScene {
            scene: self.new_scene(quality)?,
            embree: self,
            _meshes: Vec::new(),
        };
        for part in parts {
            match part {
                Part::Triangles {
                    id,
                    positions,
                    triangles,
                } => {
                    self.attach_triangles(scene.scene, id, positions.into_iter(), triangles)?;
                }
                Part::Placed { id, mesh, matrix } => {
                    // SAFETY: live device, scenes (the mesh scene stays
                    // alive in `_meshes` as long as the world's scene) and
                    // a 12-float matrix read during the call.
                    unsafe {
                        let geometry = (api.new_geometry)(self.device, ffi::GEOMETRY_TYPE_INSTANCE);
                        if geometry.is_null() {
                            self.check("rtcNewGeometry")?;
                            return Err("rtcNewGeometry failed".into());
                        }
                        (api.set_geometry_instanced_scene)(geometry, mesh.scene);
                        let m = matrix.as_ptr().cast::<c_void>();
                        (api.set_geometry_transform)(
                            geometry,
                            0,
                            ffi::FORMAT_FLOAT3X4_COLUMN_MAJOR,
                            m,
                        );
                        (api.commit_geometry)(geometry);
                        (api.attach_geometry_by_id)(scene.scene, geometry, id);
                        (api.release_geometry)(geometry);
                    }
                    self.check("placing a mesh")?;
                    scene._meshes.push(mesh);
                }
            }
        }
        // SAFETY: a live scene of ours, fully attached.
        unsafe { (api.commit_scene)(scene.scene) };
        self.check("building the world's meshes")?;
        Ok(scene)
    }
}

/// A part of the world's scene ([`Embree::scene`]).
pub enum Part<'a> {
    /// A mesh's triangles, their vertices placed in the scene's frame.
    Triangles {
        id: u32,
        positions: Vec<[f32; 3]>,
        triangles: &'a [[u32; 3]],
    },
    /// A mesh's own scene (built once, kept with the mesh) placed by a
    /// 3x4 matrix by columns, its last column the translation.
    Placed {
        id: u32,
        mesh: Arc<MeshScene>,
        matrix: [f32; 12],
    },
}

/// A mesh as an Embree scene (one triangle geometry), released on drop.
pub struct MeshScene {
    scene: ffi::Handle,
    embree: &'static Embree,
}

/// The world's meshes as an Embree scene (triangles of its own and
/// placed mesh scenes), released on drop.
pub struct WorldScene {
    scene: ffi::Handle,
    embree: &'static Embree,
    _meshes: Vec<Arc<MeshScene>>,
}

macro_rules! scene_traits {
    ($t:ty, $what:literal) => {
        // SAFETY: a committed scene is only read, and Embree allows queries
        // on one scene from many threads at once; it may be released from
        // any thread.
        unsafe impl Send for $t {}
        // SAFETY: as above.
        unsafe impl Sync for $t {}

        impl Drop for $t {
            fn drop(&mut self) {
                // SAFETY: the scene is ours; no query runs (we hold it);
                // scenes that place it hold references of their own.
                unsafe { (self.embree.lib.api.release_scene)(self.scene) }
            }
        }

        impl std::fmt::Debug for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($what, " {:?}"), self.scene)
            }
        }
    };
}

scene_traits!(MeshScene, "Embree mesh scene");
scene_traits!(WorldScene, "Embree world scene");

/// A nearest hit: the distance, the placement's id, the triangle and its
/// barycentrics u, v (weights of its second and third vertex).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawHit {
    pub t: f32,
    pub id: u32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// The part a hit names: the placement it went through, else the
/// geometry (triangles of the world's scene itself).
#[inline(always)]
fn hit_id(inst: u32, geom: u32) -> u32 {
    match inst {
        ffi::INVALID_ID => geom,
        placed => placed,
    }
}

/// Which hits a query accepts (Embree goes on past a refused one).
pub trait HitFilter {
    /// Whether ray `lane` of the query (0 for a single ray) stops at
    /// triangle `prim` of placement `id` at barycentrics `u`, `v`. Must
    /// not panic (it runs inside Embree).
    fn accepts(&self, lane: u32, id: u32, prim: u32, u: f32, v: f32) -> bool;
}

/// The context a filtered query passes: Embree's, then the filter.
#[repr(C)]
struct Filtered<'a, F> {
    context: ffi::Context,
    filter: &'a F,
}

/// Embree's filter callback for `F`: refuses each hit `F` refuses. A
/// ray's lane is its `id` field, which the queries set (Embree may hand
/// the callback a packet's rays one at a time, or copies of them).
unsafe extern "C" fn run_filter<F: HitFilter>(args: *const ffi::FilterArgs) {
    // SAFETY: Embree passes valid arguments for N rays and hits; the
    // context is the `Filtered<F>` that a query of `WorldScene` made
    // (its first field is Embree's context, `repr(C)`) and which outlives
    // the query; `ray` and `hit` are N rays and N hits by field, 32-bit
    // values each (rtcore_ray.h's RTCRayN and RTCHitN).
    unsafe {
        let args = &*args;
        let filter = (*args.context.cast::<Filtered<'_, F>>()).filter;
        let n = args.n as usize;
        let floats = args.hit.cast::<f32>();
        let ints = args.hit.cast::<u32>();
        let rays = args.ray.cast::<u32>();
        for i in 0..n {
            let valid = args.valid.add(i);
            if *valid == 0 {
                continue;
            }
            let (u, v) = (*floats.add(3 * n + i), *floats.add(4 * n + i));
            let (prim, geom, inst) = (
                *ints.add(5 * n + i),
                *ints.add(6 * n + i),
                *ints.add(7 * n + i),
            );
            let id = hit_id(inst, geom);
            let lane = *rays.add(ffi::ray_id_word(n, i));
            if !filter.accepts(lane, id, prim, u, v) {
                *valid = 0;
            }
        }
    }
}

impl WorldScene {
    /// The nearest hit along `origin + t dir` with 0 <= t <= `tfar` that
    /// `filter` (if any) accepts.
    #[inline(always)]
    pub fn intersect<F: HitFilter>(
        &self,
        origin: [f32; 3],
        dir: [f32; 3],
        tfar: f32,
        filter: Option<&F>,
    ) -> Option<RawHit> {
        let mut rh = ffi::RayHit {
            ray: ffi::Ray {
                org: origin,
                tnear: 0.0,
                dir,
                time: 0.0,
                tfar,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: ffi::Hit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: ffi::INVALID_ID,
                geom_id: ffi::INVALID_ID,
                inst_id: [ffi::INVALID_ID],
            },
        };
        let api = &self.embree.lib.api;
        match filter {
            None => {
                let mut context = ffi::Context::new(None);
                // SAFETY: a committed, live scene; `context` and `rh` are
                // valid, aligned, and ours for the call.
                unsafe { (api.intersect1)(self.scene, &mut context, &mut rh) };
            }
            Some(filter) => {
                let mut context = Filtered {
                    context: ffi::Context::new(Some(run_filter::<F>)),
                    filter,
                };
                let c = (&mut context as *mut Filtered<'_, F>).cast::<ffi::Context>();
                // SAFETY: as above; `context` starts with Embree's context
                // and lives through the call, in which `run_filter::<F>`
                // reads it back as a `Filtered<F>`.
                unsafe { (api.intersect1)(self.scene, c, &mut rh) };
            }
        }
        (rh.hit.geom_id != ffi::INVALID_ID).then_some(RawHit {
            t: rh.ray.tfar,
            id: hit_id(rh.hit.inst_id[0], rh.hit.geom_id),
            prim: rh.hit.prim_id,
            u: rh.hit.u,
            v: rh.hit.v,
        })
    }
}
