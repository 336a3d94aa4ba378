//! Embree 3 through a small `extern "C"` block (rtcore.h, 3.13): a device,
//! a scene of one triangle mesh, and single-ray queries on rayon's threads.

use pathstream::render::math::{Affine3A, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::world::{Hit, Origin};
use rayon::prelude::*;
use std::time::Instant;

/// Embree 3's C API (rtcore.h, 3.13): the structures and constants the
/// library's run-time binding defines, and the functions this example
/// links (the service resolves its own at run time instead).
#[allow(unsafe_code, non_camel_case_types, dead_code)]
pub mod ffi {
    pub use pathstream::render::embree::ffi::{
        Context as RTCIntersectContext, Hit as RTCHit, Ray as RTCRay, RayHit as RTCRayHit,
        BUFFER_TYPE_INDEX as RTC_BUFFER_TYPE_INDEX, BUFFER_TYPE_VERTEX as RTC_BUFFER_TYPE_VERTEX,
        BUILD_QUALITY_HIGH as RTC_BUILD_QUALITY_HIGH,
        BUILD_QUALITY_MEDIUM as RTC_BUILD_QUALITY_MEDIUM,
        DEVICE_PROPERTY_VERSION as RTC_DEVICE_PROPERTY_VERSION, ERROR_NONE as RTC_ERROR_NONE,
        FORMAT_FLOAT3 as RTC_FORMAT_FLOAT3, FORMAT_UINT3 as RTC_FORMAT_UINT3,
        GEOMETRY_TYPE_TRIANGLE as RTC_GEOMETRY_TYPE_TRIANGLE,
        INVALID_ID as RTC_INVALID_GEOMETRY_ID, SCENE_FLAG_ROBUST as RTC_SCENE_FLAG_ROBUST,
    };
    use std::ffi::{c_char, c_uint, c_void};

    pub type RTCDevice = *mut c_void;
    pub type RTCScene = *mut c_void;
    pub type RTCGeometry = *mut c_void;
    pub const RTC_SCENE_FLAG_NONE: c_uint = 0;
    pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;

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
        pub fn rtcIntersect16(
            valid: *const i32,
            scene: RTCScene,
            context: *mut RTCIntersectContext,
            rayhit: *mut RTCRayHit16,
        );
        /// Reads and writes only the rays (`RTCRay16`, the first part of
        /// an `RTCRayHit16`): tfar becomes -inf where something blocks.
        pub fn rtcOccluded16(
            valid: *const i32,
            scene: RTCScene,
            context: *mut RTCIntersectContext,
            ray: *mut RTCRayHit16,
        );
    }

    /// `RTCRayHit16`: sixteen rays and their hits, a field at a time
    /// (`RTCRay16` then `RTCHit16`, one instance level).
    #[repr(C, align(64))]
    #[derive(Clone, Copy)]
    pub struct RTCRayHit16 {
        pub org: [[f32; 16]; 3],
        pub tnear: [f32; 16],
        pub dir: [[f32; 16]; 3],
        pub time: [f32; 16],
        pub tfar: [f32; 16],
        pub mask: [u32; 16],
        pub id: [u32; 16],
        pub flags: [u32; 16],
        pub ng: [[f32; 16]; 3],
        pub u: [f32; 16],
        pub v: [f32; 16],
        pub prim_id: [u32; 16],
        pub geom_id: [u32; 16],
        pub inst_id: [u32; 16],
    }

    const _: () = assert!(std::mem::size_of::<RTCRayHit16>() == 20 * 64);

    /// The `valid` mask `rtcIntersect16` reads: -1 for a ray, 0 for none.
    #[repr(C, align(64))]
    pub struct Valid16(pub [i32; 16]);
}

/// An Embree device, released on drop.
pub struct Device(ffi::RTCDevice);

impl Device {
    pub fn new(config: &str) -> Device {
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
    pub fn version(&self) -> isize {
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

/// How a pass asks Embree: one ray at a time (`rtcIntersect1`), or
/// packets of sixteen (`rtcIntersect16`), told they are incoherent (the
/// default) or coherent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    Single,
    Packets,
    Coherent,
}

/// A committed Embree scene of one triangle mesh, released on drop.
pub struct EmbreeScene {
    scene: ffi::RTCScene,
    pub build_seconds: f64,
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
    pub fn build(
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
    pub fn intersect(&self, map: &Affine3A, ray: &Ray) -> Option<Hit> {
        let o = map.transform_point3a(ray.origin);
        let d = map.transform_vector3a(ray.dir);
        let mut rh = ffi::RTCRayHit {
            ray: ffi::RTCRay {
                org: o.to_array(),
                tnear: 0.0,
                dir: d.to_array(),
                time: 0.0,
                tfar: f32::INFINITY,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: ffi::RTCHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: ffi::RTC_INVALID_GEOMETRY_ID,
                geom_id: ffi::RTC_INVALID_GEOMETRY_ID,
                inst_id: [ffi::RTC_INVALID_GEOMETRY_ID],
            },
        };
        let mut context = ffi::RTCIntersectContext::new(None);
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

    /// Up to sixteen rays' nearest hits in one packet (`rtcIntersect16`),
    /// mapped by `map` first, appended to `out` as `intersect` reports them.
    #[inline(always)]
    pub fn intersect16(
        &self,
        map: &Affine3A,
        rays: &[(Ray, Origin)],
        coherent: bool,
        out: &mut Vec<Option<Hit>>,
    ) {
        let n = rays.len().min(16);
        let (mut o, mut d) = ([Vec3A::ZERO; 16], [Vec3A::ZERO; 16]);
        for (k, (ray, _)) in rays.iter().take(16).enumerate() {
            o[k] = map.transform_point3a(ray.origin);
            d[k] = map.transform_vector3a(ray.dir);
        }
        let live = std::array::from_fn(|k| k < n);
        let hits = self.nearest16(&o, &d, &live, coherent);
        out.extend_from_slice(&hits[..n]);
    }

    /// The nearest hits of sixteen rays in one packet, lane `k` live where
    /// `live[k]`; hits as `intersect` reports them.
    #[inline(always)]
    pub fn nearest16(
        &self,
        o: &[Vec3A; 16],
        d: &[Vec3A; 16],
        live: &[bool; 16],
        coherent: bool,
    ) -> [Option<Hit>; 16] {
        let (valid, mut rh) = packet16(o, d, &[f32::INFINITY; 16], live);
        let mut context = ffi::RTCIntersectContext::new(None);
        if coherent {
            context.flags = ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        }
        // SAFETY: the scene is committed and live; the mask, context and
        // packet are valid, 64-byte aligned and exclusively ours.
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcIntersect16(valid.0.as_ptr(), self.scene, &mut context, &mut rh)
        };
        std::array::from_fn(|k| {
            (live[k] && rh.geom_id[k] != ffi::RTC_INVALID_GEOMETRY_ID).then_some(Hit {
                t: rh.tfar[k],
                object: 0,
                prim: rh.prim_id[k],
                bary: [1.0 - rh.u[k] - rh.v[k], rh.u[k], rh.v[k]],
            })
        })
    }

    /// Whether anything blocks each live lane's ray before its `tfar`
    /// (`rtcOccluded16`; for `wide_paths`).
    #[allow(dead_code)]
    #[inline(always)]
    pub fn occluded16(
        &self,
        o: &[Vec3A; 16],
        d: &[Vec3A; 16],
        tfar: &[f32; 16],
        live: &[bool; 16],
    ) -> [bool; 16] {
        let (valid, mut rh) = packet16(o, d, tfar, live);
        let mut context = ffi::RTCIntersectContext::new(None);
        // SAFETY: as in `nearest16`; Embree touches only the rays.
        #[allow(unsafe_code)]
        unsafe {
            ffi::rtcOccluded16(valid.0.as_ptr(), self.scene, &mut context, &mut rh)
        };
        std::array::from_fn(|k| live[k] && rh.tfar[k] == f32::NEG_INFINITY)
    }

    /// Every ray's nearest hit in packets of sixteen neighbouring rays,
    /// on rayon's threads in chunks as `hits` does; `coherent` tells
    /// Embree the rays of a packet are alike (Mitsuba's camera rays).
    pub fn hits16(
        &self,
        map: &Affine3A,
        rays: &[(Ray, Origin)],
        coherent: bool,
    ) -> Vec<Option<Hit>> {
        rays.par_chunks(4096)
            .flat_map_iter(|chunk| {
                let mut out = Vec::with_capacity(chunk.len());
                for packet in chunk.chunks(16) {
                    self.intersect16(map, packet, coherent, &mut out);
                }
                out
            })
            .collect()
    }

    /// Every ray's nearest hit, on rayon's threads, in chunks as
    /// `nearest_hits` does.
    pub fn hits(&self, map: &Affine3A, rays: &[(Ray, Origin)]) -> Vec<Option<Hit>> {
        rays.par_chunks(4096)
            .flat_map_iter(|chunk| chunk.iter().map(|(r, _)| self.intersect(map, r)))
            .collect()
    }

    /// Rays per second of one pass, asked as `query` says.
    pub fn rays_per_sec(&self, map: &Affine3A, rays: &[(Ray, Origin)], query: Query) -> f64 {
        let start = Instant::now();
        let hits = match query {
            Query::Single => self.hits(map, rays),
            Query::Packets => self.hits16(map, rays, false),
            Query::Coherent => self.hits16(map, rays, true),
        };
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

/// A packet of sixteen rays (origin `o`, direction `d`, from 0 to `tfar`),
/// lane `k` live where `live[k]`, and its `valid` mask.
#[inline(always)]
fn packet16(
    o: &[Vec3A; 16],
    d: &[Vec3A; 16],
    tfar: &[f32; 16],
    live: &[bool; 16],
) -> (ffi::Valid16, ffi::RTCRayHit16) {
    let mut valid = ffi::Valid16([0; 16]);
    // SAFETY: an all-zero packet is a valid value of this plain-data
    // struct; the fields the lanes use are set below.
    #[allow(unsafe_code)]
    let mut rh: ffi::RTCRayHit16 = unsafe { std::mem::zeroed() };
    for k in 0..16 {
        for axis in 0..3 {
            rh.org[axis][k] = o[k][axis];
            rh.dir[axis][k] = d[k][axis];
        }
        rh.tfar[k] = tfar[k];
        rh.mask[k] = u32::MAX;
        rh.geom_id[k] = ffi::RTC_INVALID_GEOMETRY_ID;
        rh.prim_id[k] = ffi::RTC_INVALID_GEOMETRY_ID;
        rh.inst_id[k] = ffi::RTC_INVALID_GEOMETRY_ID;
        valid.0[k] = if live[k] { -1 } else { 0 };
    }
    (valid, rh)
}
