//! Host twins of the kernel's shared structs (`kernels/types.h`): same field
//! names, `#[repr(C)]`, 16-byte aligned, sizes asserted here and checked
//! against the device's own `sizeof` by the `check_layout_sizes` kernel;
//! and the constants host and kernel share ([`SHARED_CONSTANTS`]), which
//! every program build receives as `-D NAME=VALUEu`.
//!
//! Adding a shared constant:
//! 1. define it once on the host (here, or as a `pub(crate) const` where
//!    the Rust code that uses it lives) and add it to [`SHARED_CONSTANTS`]:
//!    an integer as itself, an `f32` as its bits under `NAME_BITS`;
//! 2. in `kernels/`, use the name (a float as `as_float(NAME_BITS)`), never
//!    a `#define` of it or of its value (`contract_tests.rs` scans
//!    `kernels/` for both, and for upper-case names that nothing defines);
//! 3. nothing else: `shared_defines` passes the table to every build,
//!    the routine checks' included.
//!
//! Adding a scene array (a device buffer the kernel reads): see the
//! checklist in `buffers.rs`.

use crate::render::bvh::BvhNode;
use crate::render::camera::RayProjection;
use crate::render::job::RenderJob;
use crate::render::light::EmitterShape;
use crate::render::material::Bsdf;
use crate::render::math::Vec3A;
use crate::render::sampler::SamplerKind;
use crate::render::texture::{Map, MAP_SLOTS};
use crate::render::world::{AccelChoice, Geometry, World};
use crate::render::Filter;
use bytemuck::{Pod, Zeroable};

pub const KIND_SPHERE: u32 = 0;
pub const KIND_QUAD: u32 = 1;
/// A mesh instance: `Object::pad0` is its index in the instances buffer.
pub const KIND_INSTANCE: u32 = 2;
/// Emitter kinds (`Light::kind`).
pub const LIGHT_OBJECT: u32 = 0;
pub const LIGHT_TRIANGLE: u32 = 1;
pub const LIGHT_ENVIRONMENT: u32 = 2;
/// An environment map (`HAS_ENV_MAP`; the map's tables are scene arrays).
pub const LIGHT_ENV_MAP: u32 = 3;
/// A computed sky's sun (`HAS_SUN`; its disc is `Params::sun`).
pub const LIGHT_SUN: u32 = 4;
pub const MAT_DIFFUSE: u32 = 0;
pub const MAT_MIRROR: u32 = 1;
pub const MAT_GLASS: u32 = 2;
pub const MAT_PBR: u32 = 3;
/// No object hit (an object index).
pub const NO_OBJECT: u32 = u32::MAX;

/// The constants host and kernel share, written once: every program is
/// built with them as `-D NAME=VALUEu` (kernels/ defines none). An `f32`
/// goes as its bits, named `NAME_BITS`, and the kernel reads it with
/// `as_float`, so both sides hold the same float bit for bit (a decimal
/// literal in C would be a second definition, rounded by another compiler).
pub const SHARED_CONSTANTS: [(&str, u32); 51] = [
    ("KIND_SPHERE", KIND_SPHERE),
    ("KIND_QUAD", KIND_QUAD),
    ("KIND_INSTANCE", KIND_INSTANCE),
    ("LIGHT_OBJECT", LIGHT_OBJECT),
    ("LIGHT_TRIANGLE", LIGHT_TRIANGLE),
    ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
    ("LIGHT_ENV_MAP", LIGHT_ENV_MAP),
    ("LIGHT_SUN", LIGHT_SUN),
    ("NO_NORMALS", super::meshes::NO_NORMALS),
    ("NO_PRIM", crate::render::world::NO_PRIM),
    ("MAT_DIFFUSE", MAT_DIFFUSE),
    ("MAT_MIRROR", MAT_MIRROR),
    ("MAT_GLASS", MAT_GLASS),
    ("MAT_PBR", MAT_PBR),
    ("GGX_TABLE_N", crate::render::ggx::TABLE_N as u32),
    ("GGX_TABLE_LEN", crate::render::ggx::TABLE_LEN as u32),
    ("GLASS_IOR_N", crate::render::ggx::glass::IOR_N as u32),
    (
        "GLASS_IOR_SCALE_BITS",
        crate::render::ggx::glass::IOR_SCALE.to_bits(),
    ),
    (
        "GLASS_MATCHED_BITS",
        crate::render::ggx::glass::MATCHED.to_bits(),
    ),
    ("NO_OBJECT", NO_OBJECT),
    ("BVH_ROBUST_BITS", crate::render::bvh::ROBUST.to_bits()),
    ("GAMMA7_BITS", crate::render::math::gamma(7).to_bits()),
    (
        "MAX_SURVIVAL_BITS",
        crate::render::integrator::MAX_SURVIVAL.to_bits(),
    ),
    ("ADAPTIVE_TILE", crate::render::adaptive::TILE_SIZE),
    ("SOBOL_VERTICES", crate::render::sampler::SOBOL_VERTICES),
    (
        "LENS_DIMENSION_HI",
        crate::render::sampler::LENS_DIMENSION_HI,
    ),
    ("WORK_LIST", WORK_LIST),
    ("WORK_DENSE", WORK_DENSE),
    // The generic program's traversal stacks (specialised ones are sized
    // to the scene's trees, `program::bvh_stack`).
    ("MAX_BVH_STACK", crate::render::bvh::STACK as u32),
    ("FILM_FLOATS", super::FILM_FLOATS as u32),
    ("GUIDE_FLOATS", super::guides::GUIDE_FLOATS as u32),
    ("ONE_BELOW_BITS", crate::render::math::ONE_BELOW.to_bits()),
    ("TWO_PI2_BITS", crate::render::envmap::TWO_PI2.to_bits()),
    ("PROJ_PERSPECTIVE", RayProjection::Perspective as u32),
    ("PROJ_ORTHOGRAPHIC", RayProjection::Orthographic as u32),
    ("PROJ_PANORAMA", RayProjection::Panorama as u32),
    ("NO_MAPS", crate::render::material::NO_MAPS),
    ("NO_TEXTURE", crate::render::maps::NO_TEXTURE),
    ("ALPHA_MIN_BITS", crate::render::ggx::ALPHA_MIN.to_bits()),
    ("MAP_SLOTS", MAP_SLOTS as u32),
    ("MAP_BASE_COLOR", Map::BaseColor as u32),
    ("MAP_METALLIC", Map::Metallic as u32),
    ("MAP_ROUGHNESS", Map::Roughness as u32),
    ("MAP_NORMAL", Map::Normal as u32),
    ("MAP_EMISSION", Map::Emission as u32),
    ("MAP_TRANSMISSION", Map::Transmission as u32),
    ("MAP_CLEARCOAT", Map::Clearcoat as u32),
    ("MAP_CLEARCOAT_ROUGHNESS", Map::ClearcoatRoughness as u32),
    ("MAP_SPECULAR", Map::Specular as u32),
    ("MAP_SPECULAR_COLOR", Map::SpecularColor as u32),
    ("MAP_CLEARCOAT_NORMAL", Map::ClearcoatNormal as u32),
];

/// The metallic-roughness albedo tables where a material uses the model,
/// followed by the rough glass's where one transmits (`kernels/ggx.h`).
pub fn ggx_tables(w: &crate::render::world::World) -> Vec<f32> {
    let pbr: Vec<_> = w
        .materials
        .iter()
        .filter_map(|m| match m.bsdf {
            Bsdf::Pbr(p) => Some(p),
            _ => None,
        })
        .collect();
    let mut out = Vec::new();
    if !pbr.is_empty() {
        out.extend_from_slice(&crate::render::ggx::tables().data);
    }
    if pbr.iter().any(|p| p.transmission > 0.0) {
        out.extend_from_slice(&crate::render::ggx::glass::table().data);
    }
    out
}

/// How a launch finds its pixels and samples (the kernel's `mode`): every
/// pixel of a range, samples `first..first + count`.
pub const WORK_UNIFORM: u32 = 0;
/// Adaptive work as a compacted list: work-item i renders pixel i mod T^2 of
/// the tile named by entry i / T^2 (T: [`crate::render::adaptive::TILE_SIZE`]).
pub const WORK_LIST: u32 = 1;
/// Adaptive work per tile of the image: work-item i renders pixel i, with
/// the samples its tile's entry gives (none: it returns at once).
pub const WORK_DENSE: u32 = 2;

/// [`SHARED_CONSTANTS`] as compiler options.
pub fn shared_defines() -> String {
    SHARED_CONSTANTS
        .iter()
        .map(|(name, value)| format!("-D {name}={value}u"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Object {
    pub p0: [f32; 4],
    pub p1: [f32; 4],
    pub p2: [f32; 4],
    pub p3: [f32; 4],
    pub p4: [f32; 4],
    pub kind: u32,
    pub material: u32,
    pub pad0: u32,
    pub pad1: u32,
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Material {
    /// w: index of refraction (glass).
    pub albedo: [f32; 4],
    pub emission: [f32; 4],
    pub kind: u32,
    pub schlick: u32,
    pub emissive: u32,
    /// Its maps in the `maps` array, or `NO_MAPS`.
    pub maps: u32,
    /// pbr: metallic, alpha, roughness, f0 (`ggx::Pbr`).
    pub pbr: [f32; 4],
    /// pbr: transmission, ior, 1 for a thin wall.
    pub glass: [f32; 4],
    /// The absorption coefficient inside (w unused).
    pub absorb: [f32; 4],
    /// pbr: clear coat weight, alpha, roughness.
    pub coat: [f32; 4],
    /// pbr: the dielectric's Schlick F0 (rgb) and F90.
    pub spec: [f32; 4],
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Params {
    /// w: near_clip.
    pub forward: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub nee: u32,
    pub filter: u32,
    pub clamp: f32,
    pub num_objects: u32,
    pub num_lights: u32,
    /// 0 = random, 1 = sobol.
    pub sampler: u32,
    /// 1 when nearest hits are found through the BVH (nodes, prims, big).
    pub use_bvh: u32,
    /// Objects tested one by one before the BVH (`big`).
    pub num_big: u32,
    /// A thin lens: its radius over |right| and over |up| (`CameraRays`;
    /// 0: a pinhole); `right.w` is the focus distance.
    pub lens_x: f32,
    pub lens_y: f32,
    /// Radiance of rays that leave the scene (w unused); with a map, what
    /// camera rays see where it is hidden (w: 1 where it is visible).
    pub environment: [f32; 4],
    /// An environment map: its rotation's cos and sin, its intensity.
    pub env: [f32; 4],
    /// The map's width and height (0: no map).
    pub env_size: [u32; 4],
    /// x: the camera's projection (`RayProjection`, `PROJ_*`).
    pub camera: [u32; 4],
    /// A computed sky's sun: the unit direction towards it, w: 1 - cos of
    /// its angular radius (`SunLight`).
    pub sun: [f32; 4],
    /// Its radiance (w: 1 where there is a sun, else all 0).
    pub sun_radiance: [f32; 4],
}

/// An emitter for next-event estimation and its entries of the power pick
/// table (render/light/pick.rs): the kernel picks one as the CPU does.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// The object a shadow ray must hit to see it (not for the environment).
    pub object: u32,
    /// The triangle of that object, or `NO_PRIM`.
    pub prim: u32,
    /// The 31-bit x it owns, [lower, upper).
    pub lower: u32,
    pub upper: u32,
    pub pmf: f32,
    /// `LIGHT_OBJECT` (a sphere or quad: its `Object`), `LIGHT_TRIANGLE`
    /// (below), `LIGHT_ENVIRONMENT`.
    pub kind: u32,
    /// Its material's maps where they have an emission map, else `NO_MAPS`.
    pub maps: u32,
    /// The pick's guide entry i (not this emitter's own: the table's row i).
    pub guide: u32,
    pub emission: [f32; 4],
    /// A triangle in camera space: p0 + e1 b1 + e2 b2; n.w its area.
    pub p0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
    pub n: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<Light>() == 112);
const _: () = assert!(std::mem::size_of::<Object>() == 96);
const _: () = assert!(std::mem::size_of::<Material>() == 128);
const _: () = assert!(std::mem::size_of::<Params>() == 208);

fn v4(v: Vec3A, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// The object loop's cost per ray on a device, in units of one sphere
/// test: a quad costs two.
pub fn device_scan_cost(spheres: usize, quads: usize) -> usize {
    spheres + 2 * quads
}

/// Scenes whose loop costs more than this are searched through the BVH on
/// a device. Measured on PoCL (`cargo run --release --example
/// accel_crossover -- opencl`, docs/OPENCL.md): the BVH wins from about 17
/// spheres, or 9 spheres and 4 quads, far sooner than on the CPU, whose
/// scan tests eight spheres at once.
pub const DEVICE_SCAN_MAX_COST: usize = 16;

/// Whether the kernel searches `w` through a BVH: the device's own
/// measurement, unless the world was built with a fixed choice.
pub fn device_uses_bvh(w: &World) -> bool {
    if !w.instances.is_empty() {
        return true; // as on the CPU: meshes are only ever searched by BVH
    }
    match w.accel_choice {
        AccelChoice::Bvh => true,
        AccelChoice::Scan => false,
        AccelChoice::Auto => {
            let quads = w
                .objects
                .iter()
                .filter(|o| matches!(o.geometry, Geometry::Quad(_)))
                .count();
            device_scan_cost(w.objects.len() - quads, quads) > DEVICE_SCAN_MAX_COST
        }
    }
}

/// What the kernel's next-event estimation aims at: every emitter (sphere,
/// quad, triangle of an emissive mesh, the environment), with the CPU's
/// power alias table (one shadow ray to one emitter per shading point).
/// Empty when the CPU would aim at none either.
pub fn kernel_lights(w: &World) -> Vec<Light> {
    let lights = &w.lights;
    if kernel_light_count(w) == 0 {
        return Vec::new();
    }
    let table = lights.table.as_ref().filter(|_| lights.emitters.len() > 1);
    lights
        .emitters
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let (lower, upper, guide, pmf) = table.map_or((0, 1 << 31, 0, 1.0), |t| t.column(i));
            let mut l = Light {
                object: e.object,
                prim: e.prim,
                lower,
                upper,
                pmf,
                guide,
                kind: LIGHT_OBJECT,
                maps: e.maps,
                emission: v4(e.emission, 0.0),
                ..Light::default()
            };
            match &e.shape {
                EmitterShape::Sphere(_) | EmitterShape::Quad(_) => {}
                EmitterShape::Triangle(t) => {
                    l.kind = LIGHT_TRIANGLE;
                    (l.p0, l.e1, l.e2, l.n) =
                        (v4(t.p0, 0.0), v4(t.e1, 0.0), v4(t.e2, 0.0), v4(t.n, t.area));
                }
                EmitterShape::Environment => l.kind = LIGHT_ENVIRONMENT,
                EmitterShape::Map(_) => l.kind = LIGHT_ENV_MAP,
                EmitterShape::Sun(_) => l.kind = LIGHT_SUN,
            }
            l
        })
        .collect()
}

/// How many emitters [`kernel_lights`] gives, without building them (a
/// program key is made every pass; a mesh may have a million emitters).
pub fn kernel_light_count(w: &World) -> usize {
    match w.lights.emitters.len() {
        n if n > 1 && w.lights.table.is_none() => 0,
        n => n,
    }
}

/// The job's scene and settings in the kernel's layout.
pub struct Packed {
    pub params: Params,
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// The objects' BVH as the CPU traverses it (empty for a scanned world):
    /// its nodes, the object of each leaf slot, and the objects tested one
    /// by one before it.
    pub nodes: Vec<BvhNode>,
    pub prims: Vec<u32>,
    pub big: Vec<u32>,
    pub meshes: super::meshes::PackedMeshes,
    /// Texture maps and their texels, where a material has maps.
    pub textures: super::textures::PackedTextures,
    /// The metallic-roughness BSDF's albedo tables (`ggx::Tables`), where
    /// a material uses it.
    pub ggx: Vec<f32>,
    /// The environment map, whose texels and tables the kernel reads as
    /// they are (no copy: `buffers.rs` uploads their bytes).
    pub env_map: Option<std::sync::Arc<crate::render::envmap::EnvMap>>,
}

impl Packed {
    /// The map's texels as floats (RGB per texel), or none.
    pub fn env_texels(&self) -> &[f32] {
        self.env_map
            .as_deref()
            .map_or(&[], |m| bytemuck::cast_slice(&m.texels))
    }

    /// The map's sampling tables (`Distribution2D::data`), or none.
    pub fn env_dist(&self) -> &[f32] {
        self.env_map.as_deref().map_or(&[], |m| &m.dist.data)
    }
}

pub fn pack(job: &RenderJob) -> Packed {
    let w = &job.world;
    let objects = w
        .objects
        .iter()
        .map(|o| match &o.geometry {
            Geometry::Sphere(s) => Object {
                p0: v4(s.center, s.radius),
                p1: [s.k, s.inv_radius, 0.0, 0.0],
                kind: KIND_SPHERE,
                material: o.material,
                ..Object::default()
            },
            Geometry::Quad(q) => Object {
                p0: v4(q.corner, q.area),
                p1: v4(q.edge_u, 0.0),
                p2: v4(q.edge_v, 0.0),
                p3: v4(q.normal, 0.0),
                p4: v4(q.w, 0.0),
                kind: KIND_QUAD,
                material: o.material,
                ..Object::default()
            },
            Geometry::Instance(i) => Object {
                kind: KIND_INSTANCE,
                material: o.material,
                pad0: *i,
                ..Object::default()
            },
        })
        .collect();
    let materials = w
        .materials
        .iter()
        .map(|m| {
            let (kind, ior, schlick) = match m.bsdf {
                Bsdf::Diffuse => (MAT_DIFFUSE, 1.0, false),
                Bsdf::Mirror => (MAT_MIRROR, 1.0, false),
                Bsdf::Glass { ior, schlick } => (MAT_GLASS, ior, schlick),
                Bsdf::Pbr(_) => (MAT_PBR, 1.0, false),
            };
            let (pbr, glass, coat, spec) = match m.bsdf {
                Bsdf::Pbr(p) => (
                    [p.metallic, p.alpha, p.roughness, p.f0],
                    [p.transmission, p.ior, f32::from(u8::from(p.thin)), 0.0],
                    [p.coat, p.coat_alpha, p.coat_roughness, 0.0],
                    v4(p.spec_f0, p.spec_f90),
                ),
                _ => ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]),
            };
            Material {
                albedo: v4(m.albedo, ior),
                emission: v4(m.emission, 0.0),
                kind,
                schlick: u32::from(schlick),
                emissive: u32::from(m.emissive),
                maps: m.maps,
                pbr,
                glass,
                absorb: v4(m.absorb, 0.0),
                coat,
                spec,
            }
        })
        .collect();
    let c = &job.camera;
    let s = &job.settings;
    let params = Params {
        forward: v4(c.forward, c.near_clip),
        right: v4(c.right, c.focus),
        up: v4(c.up, 0.0),
        seed: job.seed,
        width: c.width,
        height: c.height,
        max_depth: s.max_depth,
        rr_depth: s.rr_depth,
        nee: u32::from(s.nee),
        filter: u32::from(job.filter == Filter::Box),
        clamp: s.clamp,
        num_objects: w.objects.len() as u32,
        num_lights: kernel_light_count(w) as u32,
        sampler: u32::from(job.sampler == SamplerKind::Sobol),
        use_bvh: 0,
        num_big: 0,
        lens_x: c.lens_x,
        lens_y: c.lens_y,
        environment: match &w.env_map {
            Some(m) => v4(m.background, if m.visible { 1.0 } else { 0.0 }),
            None => v4(w.environment, 0.0),
        },
        env: w
            .env_map
            .as_ref()
            .map_or([0.0; 4], |m| [m.cos_rot, m.sin_rot, m.intensity, 0.0]),
        env_size: w
            .env_map
            .as_ref()
            .map_or([0; 4], |m| [m.map.width, m.map.height, 0, 0]),
        camera: [c.projection as u32, 0, 0, 0],
        sun: w.sun.map_or([0.0; 4], |(s, _)| v4(s.dir, s.one_minus_cos)),
        sun_radiance: w.sun.map_or([0.0; 4], |(_, le)| v4(le, 1.0)),
    };
    let mut packed = Packed {
        params,
        objects,
        materials,
        lights: kernel_lights(w),
        nodes: Vec::new(),
        prims: Vec::new(),
        big: Vec::new(),
        meshes: super::meshes::pack(w),
        textures: super::textures::pack(w),
        env_map: w.env_map.as_ref().map(|m| m.map.clone()),
        ggx: ggx_tables(w),
    };
    if device_uses_bvh(w) {
        let (bvh, big) = w.device_bvh();
        packed.nodes = bvh.nodes.clone();
        packed.prims = bvh.prims.clone();
        packed.params.use_bvh = 1;
        packed.params.num_big = big.len() as u32;
        packed.big = big;
    }
    packed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::builtin;
    use crate::render::world::World;

    #[test]
    fn the_device_searches_by_bvh_from_its_own_crossover() {
        let world = |name: &str, choice| {
            let s = builtin(name).expect("built-in");
            World::with_accel(&s, s.camera.position, choice)
        };
        for name in [
            "cornell",
            "cornell-glass",
            "cornell-quads",
            "smallpt",
            "furnace",
        ] {
            assert!(
                !device_uses_bvh(&world(name, AccelChoice::Auto)),
                "{name} is looped over"
            );
        }
        assert!(
            device_uses_bvh(&world("cornell", AccelChoice::Bvh)),
            "a forced choice holds"
        );
        assert!(
            device_scan_cost(16, 0) <= DEVICE_SCAN_MAX_COST
                && device_scan_cost(17, 0) > DEVICE_SCAN_MAX_COST
        );
        assert!(device_scan_cost(9, 4) > DEVICE_SCAN_MAX_COST);
        // A BVH built for the device where the CPU scans: every object once.
        let w = world("cornell-quads", AccelChoice::Auto);
        let (bvh, big) = w.device_bvh();
        let mut all: Vec<u32> = bvh.prims.iter().copied().chain(big).collect();
        all.sort_unstable();
        assert_eq!(all, (0..w.objects.len() as u32).collect::<Vec<_>>());
    }
}
