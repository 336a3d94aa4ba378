//! Kernel sources, the scene features a program is specialised for, and the
//! build (with its log on failure). Specialisation is by compiler defines
//! generated in one place ([`Features::build_options`]), never by editing
//! the source.

use super::layout::{
    device_uses_bvh, kernel_light_count, shared_defines, KIND_QUAD, KIND_SPHERE, MAT_DIFFUSE,
    MAT_GLASS, MAT_MIRROR, MAT_PBR,
};
use crate::render::job::RenderJob;
use crate::render::light::EmitterShape;
use crate::render::material::{Bsdf, NO_MAPS};
use crate::render::math::Vec3A;
use crate::render::sampler::SamplerKind;
use crate::render::texture::Map;
use crate::render::world::Geometry;
use crate::render::Filter;
use opencl3::context::Context;
use opencl3::program::Program;

/// The kernel's sources in dependency order (`kernels/`, built into the binary).
pub const SOURCES: [&str; 16] = [
    include_str!("../../../../../kernels/scene_arrays.h"),
    include_str!("../../../../../kernels/types.h"),
    include_str!("../../../../../kernels/rng.h"),
    include_str!("../../../../../kernels/shapes.h"),
    include_str!("../../../../../kernels/bvh.h"),
    include_str!("../../../../../kernels/triangles.h"),
    include_str!("../../../../../kernels/world.h"),
    include_str!("../../../../../kernels/fresnel.h"),
    include_str!("../../../../../kernels/ggx.h"),
    include_str!("../../../../../kernels/maps.h"),
    include_str!("../../../../../kernels/materials.h"),
    include_str!("../../../../../kernels/envmap.h"),
    include_str!("../../../../../kernels/camera.h"),
    include_str!("../../../../../kernels/lights.h"),
    include_str!("../../../../../kernels/integrator.h"),
    include_str!("../../../../../kernels/render.cl"),
];

/// What a scene and its settings use; one program per distinct value.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Features {
    pub spheres: bool,
    pub quads: bool,
    pub diffuse: bool,
    pub mirror: bool,
    pub glass: bool,
    /// glTF's metallic-roughness model (`MAT_PBR`, kernels/ggx.h).
    pub ggx: bool,
    /// A `MAT_PBR` material transmits (rough glass).
    pub transmission: bool,
    /// A material absorbs inside (Beer-Lambert).
    pub volume: bool,
    /// A `MAT_PBR` material has a clear coat.
    pub coat: bool,
    /// A coated material's maps can give its coat a normal of its own.
    pub coat_normal: bool,
    /// A placed mesh has vertex colours.
    pub vertex_colors: bool,
    pub schlick: bool,
    pub exact: bool,
    pub sphere_lights: bool,
    pub quad_lights: bool,
    pub nee: bool,
    pub box_filter: bool,
    /// Sobol points (else independent random numbers).
    pub sobol: bool,
    pub num_objects: u32,
    pub num_lights: u32,
    pub max_depth: u32,
    /// Entries of the BVH traversal stack (three per level and four), or 0
    /// when the world is scanned (no BVH code is compiled in).
    pub bvh_stack: u32,
    /// Entries of the mesh BVHs' stack, or 0 without meshes (no triangle
    /// code is compiled in).
    pub mesh_stack: u32,
    /// Triangles of emissive meshes among the emitters.
    pub tri_lights: bool,
    /// A non-black environment (its light and its emitter).
    pub environment: bool,
    /// An environment map (its lookups, sampling and MIS at diffuse
    /// surfaces).
    pub env_map: bool,
    /// A computed sky's sun (its disc met by rays that leave the scene,
    /// and its emitter).
    pub sun: bool,
    /// A thin-lens camera (aperture > 0).
    pub lens: bool,
    /// The camera's projection (`PROJ_*`).
    pub projection: u32,
    /// The denoiser's feature sums beside the film (`render::features`).
    pub features: bool,
    /// Texture maps on some material (`kernels/maps.h`).
    pub textures: bool,
    /// Alpha-tested mesh slots (`render::alpha`, `kernels/triangles.h`).
    pub alpha: bool,
    /// Test hook: every n-th sample becomes NaN (checks the film's rejection).
    pub inject_nan_every: Option<u64>,
}

impl Features {
    pub fn of(job: &RenderJob) -> Self {
        let w = &job.world;
        let kind = |k: u32| {
            w.objects.iter().any(|o| match o.geometry {
                Geometry::Sphere(_) => k == KIND_SPHERE,
                Geometry::Quad(_) => k == KIND_QUAD,
                Geometry::Instance(_) => false,
            })
        };
        let used: Vec<_> = w
            .objects
            .iter()
            .filter(|o| !matches!(o.geometry, Geometry::Instance(_)))
            .map(|o| o.material)
            .chain(w.instances.iter().flat_map(|i| i.materials.iter().copied()))
            .map(|m| w.materials[m as usize])
            .collect();
        // What the kernel's emitters are, read off the world's (building
        // them, as `pack` does, costs O(emitters) every pass).
        let light_count = kernel_light_count(w);
        let emitters = &w.lights.emitters[..if light_count > 0 {
            w.lights.emitters.len()
        } else {
            0
        }];
        let mat = |k: u32| {
            used.iter().any(|m| match m.bsdf {
                Bsdf::Diffuse => k == MAT_DIFFUSE,
                Bsdf::Mirror => k == MAT_MIRROR,
                Bsdf::Glass { .. } => k == MAT_GLASS,
                Bsdf::Pbr(_) => k == MAT_PBR,
            })
        };
        let glass_with = |want: bool| {
            used.iter()
                .any(|m| matches!(m.bsdf, Bsdf::Glass { schlick, .. } if schlick == want))
        };
        let light_kind = |k: u32| {
            emitters.iter().any(|e| match e.shape {
                EmitterShape::Sphere(_) => k == KIND_SPHERE,
                EmitterShape::Quad(_) => k == KIND_QUAD,
                EmitterShape::Triangle(_)
                | EmitterShape::Environment
                | EmitterShape::Map(_)
                | EmitterShape::Sun(_) => false,
            })
        };
        Self {
            spheres: kind(KIND_SPHERE),
            quads: kind(KIND_QUAD),
            diffuse: mat(MAT_DIFFUSE),
            mirror: mat(MAT_MIRROR),
            glass: mat(MAT_GLASS),
            ggx: mat(MAT_PBR),
            transmission: used
                .iter()
                .any(|m| matches!(m.bsdf, Bsdf::Pbr(p) if p.transmission > 0.0)),
            volume: used.iter().any(|m| m.absorb != Vec3A::ZERO),
            coat: used
                .iter()
                .any(|m| matches!(m.bsdf, Bsdf::Pbr(p) if p.coat > 0.0)),
            coat_normal: used.iter().any(|m| {
                matches!(m.bsdf, Bsdf::Pbr(p) if p.coat > 0.0)
                    && m.maps != NO_MAPS
                    && [Map::Normal, Map::ClearcoatNormal]
                        .into_iter()
                        .any(|n| w.maps[m.maps as usize].has(n))
            }),
            vertex_colors: w.vertex_colors,
            schlick: glass_with(true),
            exact: glass_with(false),
            sphere_lights: job.settings.nee && light_kind(KIND_SPHERE),
            quad_lights: job.settings.nee && light_kind(KIND_QUAD),
            nee: job.settings.nee && light_count > 0,
            box_filter: job.filter == Filter::Box,
            sobol: job.sampler == SamplerKind::Sobol,
            num_objects: w.objects.len() as u32,
            num_lights: if job.settings.nee {
                light_count as u32
            } else {
                0
            },
            max_depth: job.settings.max_depth,
            bvh_stack: if device_uses_bvh(w) {
                bvh_stack(w.device_bvh().0.depth)
            } else {
                0
            },
            mesh_stack: w
                .instances
                .iter()
                .map(|i| bvh_stack(i.mesh.bvh.depth))
                .max()
                .unwrap_or(0),
            tri_lights: job.settings.nee
                && emitters
                    .iter()
                    .any(|e| matches!(e.shape, EmitterShape::Triangle(_))),
            environment: w.environment.max_element() > 0.0,
            env_map: w.env_map.is_some(),
            sun: w.sun.is_some(),
            lens: job.camera.has_lens(),
            projection: job.camera.projection as u32,
            features: job.settings.features,
            textures: used.iter().any(|m| m.maps != NO_MAPS),
            alpha: w.instances.iter().any(|i| i.alpha.is_some()),
            inject_nan_every: None,
        }
    }

    /// `-D` options that specialise the kernel to these features.
    pub fn build_options(&self) -> String {
        let b = |v: bool| u8::from(v);
        let mut o = format!(
            "-D SPECIALISED -D HAS_SPHERES={} -D HAS_QUADS={} -D HAS_DIFFUSE={} -D HAS_MIRROR={} \
             -D HAS_GLASS={} -D HAS_GGX={} -D HAS_SCHLICK={} -D HAS_EXACT={} -D HAS_SPHERE_LIGHTS={} -D HAS_QUAD_LIGHTS={} \
             -D NEE={} -D BOX_FILTER={} -D SOBOL={} -D NUM_OBJECTS={}u -D NUM_LIGHTS={}u -D MAX_DEPTH_VALUE={}u \
             -D HAS_BVH={} -D BVH_STACK={} -D HAS_MESHES={} -D MESH_STACK={} -D HAS_TRI_LIGHTS={} -D HAS_ENV={} -D HAS_ENV_MAP={} -D HAS_SUN={} -D HAS_LENS={} \
             -D PROJECTION={}u -D FEATURES={} -D HAS_TEXTURES={} -D HAS_ALPHA={} -D HAS_TRANSMISSION={} -D HAS_VOLUME={} -D HAS_COAT={} \
             -D HAS_COAT_NORMAL={} -D HAS_VERTEX_COLORS={}",
            b(self.spheres),
            b(self.quads),
            b(self.diffuse),
            b(self.mirror),
            b(self.glass),
            b(self.ggx),
            b(self.schlick),
            b(self.exact),
            b(self.sphere_lights),
            b(self.quad_lights),
            b(self.nee),
            b(self.box_filter),
            b(self.sobol),
            self.num_objects,
            self.num_lights,
            self.max_depth,
            b(self.bvh_stack > 0),
            self.bvh_stack.max(1),
            b(self.mesh_stack > 0),
            self.mesh_stack.max(1),
            b(self.tri_lights),
            b(self.environment),
            b(self.env_map),
            b(self.sun),
            b(self.lens),
            self.projection,
            b(self.features),
            b(self.textures),
            b(self.alpha),
            b(self.transmission),
            b(self.volume),
            b(self.coat),
            b(self.coat_normal),
            b(self.vertex_colors),
        );
        if let Some(n) = self.inject_nan_every {
            o.push_str(&format!(" -D INJECT_NAN_EVERY={n}UL"));
        }
        o
    }
}

/// Which program: specialised to features, or the generic one (every
/// feature compiled in, counts read at run time).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ProgramKey {
    Specialised(Features),
    Generic {
        inject_nan_every: Option<u64>,
        features: bool,
    },
}

/// Stack entries a traversal of a BVH `depth` levels deep needs: a node
/// pushes at most four children and pops one, per level.
pub fn bvh_stack(depth: u32) -> u32 {
    3 * depth + 4
}

/// Options every program is built with: the language version and the
/// constants shared with the host.
pub fn common_options() -> String {
    format!("-cl-std=CL1.2 {}", shared_defines())
}

/// The kernel sources followed by the routine checks (`kernels/checks.cl`),
/// which run single routines on the device against their Rust twins.
pub fn check_sources() -> Vec<&'static str> {
    let mut v = SOURCES.to_vec();
    v.push(include_str!("../../../../../kernels/checks.cl"));
    v
}

impl ProgramKey {
    pub fn build_options(&self) -> String {
        let common = common_options();
        let common = common.as_str();
        match self {
            ProgramKey::Specialised(f) => format!("{common} {}", f.build_options()),
            ProgramKey::Generic {
                inject_nan_every,
                features,
            } => {
                let mut o = format!("{common} -D FEATURES={}", u8::from(*features));
                if let Some(n) = inject_nan_every {
                    o.push_str(&format!(" -D INJECT_NAN_EVERY={n}UL"));
                }
                o
            }
        }
    }
}

/// Builds `sources` with `options`; the error carries the compiler's log.
/// The sources go to the compiler as one string: `cl3`'s multi-source call
/// passes Rust `&str`s where C expects `const char*`s, which crashes.
pub fn build(context: &Context, sources: &[&str], options: &str) -> Result<Program, String> {
    Program::create_and_build_from_source(context, &sources.concat(), options)
}
