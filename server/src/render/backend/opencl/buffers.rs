//! A job's scene on the device: one buffer per array of `layout::pack`,
//! listed once in [`SCENE_ARRAYS`], the host twin of
//! `kernels/scene_arrays.h`; and the `render` kernel's arguments, which are
//! those arrays in that order and then the launch's own ([`LAUNCH_PARAMS`]).
//!
//! Adding a scene array:
//! 1. a line `X(ElementType, name)` in `kernels/scene_arrays.h` (the
//!    kernel's `Scene` field and parameter follow; the routine checks in
//!    `kernels/checks.cl` name the fields they set);
//! 2. its data in [`Packed`] (`layout.rs`, or `meshes.rs` for meshes), and
//!    if the element type is a struct, its `#[repr(C)]` twin in `layout.rs`
//!    next to the C one in `kernels/types.h`;
//! 3. the entry in [`SCENE_ARRAYS`] at the same position: it is uploaded,
//!    counted by [`job_bytes`] and bound as an argument from there;
//!    `contract_tests.rs` fails until the names, order and element types
//!    agree (and, on a device, the element sizes).
//!
//! Adding a shared constant: see the checklist in `layout.rs`.

use super::layout::{self, Packed};
use super::meshes;
use super::textures;
use super::{call, Access, OpenClBackend, OpenClError};
use crate::render::bvh::BvhNode;
use crate::render::envmap::EnvMap;
use crate::render::shape::TriVerts;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem};
use opencl3::types::{cl_mem, cl_uint, cl_ulong};
use std::mem::size_of;
use std::sync::Arc;

/// One array of the scene as the kernel reads it.
pub(super) struct SceneArray {
    /// Its name in `kernels/scene_arrays.h`: the `Scene` field and the
    /// `render` kernel's parameter (read by the tests that hold the two
    /// lists equal).
    #[cfg_attr(not(test), allow(dead_code))]
    pub name: &'static str,
    /// Its element type there.
    #[cfg_attr(not(test), allow(dead_code))]
    pub c_type: &'static str,
    /// What a message about device memory calls it.
    pub label: &'static str,
    /// Bytes of one element on the host.
    pub elem_bytes: usize,
    /// The job's elements, as bytes.
    pub bytes: fn(&Packed) -> &[u8],
}

/// A [`SceneArray`] whose elements are `$t`, read from the packed job by
/// `$data` (so that the size and the data cannot name different types).
macro_rules! scene_array {
    ($name:literal: $c_type:literal, $label:literal, [$t:ty], |$p:ident| $data:expr) => {
        SceneArray {
            name: $name,
            c_type: $c_type,
            label: $label,
            elem_bytes: size_of::<$t>(),
            bytes: |$p| {
                let data: &[$t] = $data;
                bytemuck::cast_slice(data)
            },
        }
    };
}

/// The scene's arrays in the order of `kernels/scene_arrays.h`: the
/// `render` kernel's first parameters.
pub(super) const SCENE_ARRAYS: [SceneArray; 23] = [
    scene_array!("P": "Params", "params", [layout::Params], |p| {
        std::slice::from_ref(&p.params)
    }),
    scene_array!("objects": "Object", "objects", [layout::Object], |p| &p.objects),
    scene_array!("materials": "Material", "materials", [layout::Material], |p| {
        &p.materials
    }),
    scene_array!("lights": "Light", "lights", [layout::Light], |p| &p.lights),
    scene_array!("nodes": "BvhNode", "object BVH", [BvhNode], |p| &p.nodes),
    scene_array!("prims": "uint", "object BVH slots", [u32], |p| &p.prims),
    scene_array!("big": "uint", "large objects", [u32], |p| &p.big),
    scene_array!("instances": "Instance", "instances", [meshes::Instance], |p| {
        &p.meshes.instances
    }),
    scene_array!("mesh_nodes": "BvhNode", "mesh BVH", [BvhNode], |p| {
        &p.meshes.arrays().nodes
    }),
    scene_array!("tris": "TriVerts", "triangles", [TriVerts], |p| &p.meshes.arrays().tris),
    scene_array!("normals": "float4", "vertex normals", [[f32; 4]], |p| {
        &p.meshes.arrays().normals
    }),
    scene_array!("slots": "uint", "material slots", [u32], |p| &p.meshes.slots),
    scene_array!("ggx": "float", "GGX albedo tables", [f32], |p| &p.ggx),
    scene_array!("env_texels": "float", "environment map", [f32], |p| p.env_texels()),
    scene_array!("env_dist": "float", "environment map tables", [f32], |p| {
        p.env_dist()
    }),
    scene_array!("uvs": "float4", "texture coordinates", [[f32; 4]], |p| {
        &p.meshes.arrays().uvs
    }),
    scene_array!("tangents": "float4", "tangents", [[f32; 4]], |p| {
        &p.meshes.arrays().tangents
    }),
    scene_array!("colors": "float4", "vertex colours", [[f32; 4]], |p| {
        &p.meshes.arrays().colors
    }),
    scene_array!("maps": "MaterialMaps", "material maps", [textures::MaterialMaps], |p| {
        &p.textures.maps
    }),
    scene_array!("tex_images": "TexImage", "texture sizes", [textures::TexImage], |p| {
        &p.textures.images
    }),
    scene_array!("texels": "uint", "textures", [u32], |p| p.textures.texels()),
    scene_array!("srgb": "float", "sRGB table", [f32], |p| &p.textures.srgb),
    scene_array!("alpha": "AlphaTest", "alpha tests", [meshes::AlphaTest], |p| {
        &p.meshes.alpha
    }),
];

/// The `render` kernel's parameters after the scene's arrays, in order:
/// (C type, name) as kernels/render.cl declares them.
pub(super) const LAUNCH_PARAMS: [(&str, &str); 9] = [
    ("__global float *", "film"),
    ("__global float *", "guides"),
    ("__global uint *", "rejected"),
    ("ulong", "first"),
    ("uint", "count"),
    ("uint", "pixel_base"),
    ("uint", "pixel_end"),
    ("__global const uint4 *", "work"),
    ("uint", "mode"),
];

/// The job's scene on the device: one buffer per entry of [`SCENE_ARRAYS`],
/// in its order (an environment map's, textures' and meshes' shared with
/// other jobs of them).
pub(super) struct SceneBuffers(Vec<Arc<Buffer<u8>>>);

/// What jobs of one scene share on the device instead of uploading again.
#[derive(Default)]
pub(super) struct Shared {
    map: Option<MapBuffers>,
    textures: Option<TextureBuffer>,
    meshes: Option<MeshBuffers>,
}

/// The environment map last uploaded and its two buffers: the jobs of one
/// map (every camera move, edit or quality change under it) share them
/// instead of uploading its texels and tables again (100 MB for a 4k map).
/// Held by the map's `Arc`, so that its address cannot be another map's.
struct MapBuffers {
    map: Arc<EnvMap>,
    texels: Arc<Buffer<u8>>,
    dist: Arc<Buffer<u8>>,
}

/// The meshes last uploaded (held by their `Arc`s, in order, and whether
/// with their texture coordinates and tangents) and their arrays'
/// buffers, by name ([`meshes::MESH_ARRAYS`]): a camera move or a quality
/// change keeps the meshes, and their data is neither copied nor uploaded
/// again (a million triangles are ~150 MB); only the instances' transforms
/// are new.
struct MeshBuffers {
    meshes: Vec<Arc<crate::render::shape::Mesh>>,
    textured: bool,
    buffers: Vec<(&'static str, Arc<Buffer<u8>>)>,
}

/// The textures last uploaded (held by their `Arc`s, in order) and their
/// texels' buffer: the jobs of one scene's textures share it, and their
/// texels are neither copied nor uploaded again (a product model's maps
/// are hundreds of MB).
struct TextureBuffer {
    textures: Vec<Arc<crate::render::texture::Texture>>,
    texels: Arc<Buffer<u8>>,
}

/// Where one launch adds its samples.
pub(super) struct LaunchArgs<'a> {
    pub film: &'a Buffer<f32>,
    /// Feature sums (unread unless the program is built with FEATURES).
    pub guides: &'a Buffer<f32>,
    pub rejected: &'a Buffer<u32>,
    pub first: cl_ulong,
    pub count: cl_uint,
    pub pixel_base: cl_uint,
    pub pixel_end: cl_uint,
    /// Adaptive work entries (unread when `mode` is `WORK_UNIFORM`).
    pub work: &'a Buffer<[u32; 4]>,
    pub mode: cl_uint,
}

/// A kernel argument's value.
enum Arg {
    Mem(cl_mem),
    U32(cl_uint),
    U64(cl_ulong),
}

impl LaunchArgs<'_> {
    /// The values of [`LAUNCH_PARAMS`], in its order.
    fn values(&self) -> [Arg; LAUNCH_PARAMS.len()] {
        [
            Arg::Mem(self.film.get()),
            Arg::Mem(self.guides.get()),
            Arg::Mem(self.rejected.get()),
            Arg::U64(self.first),
            Arg::U32(self.count),
            Arg::U32(self.pixel_base),
            Arg::U32(self.pixel_end),
            Arg::Mem(self.work.get()),
            Arg::U32(self.mode),
        ]
    }
}

/// What a device can hold: the largest buffer, and all buffers together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLimits {
    pub max_alloc_bytes: u64,
    pub total_bytes: u64,
}

/// Bytes of each buffer a job needs on the device: a film of `film_bytes`
/// and its scene's arrays (each at least one element: OpenCL refuses empty
/// buffers).
pub(super) fn job_bytes(p: &Packed, film_bytes: usize) -> Vec<(&'static str, usize)> {
    let arrays = SCENE_ARRAYS.iter().map(|a| {
        // The texels and the meshes' arrays are sized without being
        // copied together.
        let bytes = match a.name {
            "texels" => p.textures.texel_bytes(),
            name => (p.meshes.array_bytes(name)).unwrap_or_else(|| (a.bytes)(p).len()),
        };
        (a.label, bytes.max(a.elem_bytes))
    });
    std::iter::once(("film", film_bytes))
        .chain(arrays)
        .collect()
}

/// Whether buffers of `bytes` fit `limits`, with `resident` bytes of other
/// jobs already on the device (which may be evicted); why not, naming the
/// largest buffer and the totals.
pub(super) fn check_fits(bytes: &[(&str, usize)], limits: MemoryLimits) -> Result<(), String> {
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    let (name, largest) = bytes
        .iter()
        .max_by_key(|(_, b)| *b)
        .map_or(("", 0), |&(n, b)| (n, b as u64));
    if largest > limits.max_alloc_bytes {
        return Err(format!(
            "its {name} need {:.1} MiB in one buffer, more than the device's largest allocation ({:.1} MiB)",
            mib(largest),
            mib(limits.max_alloc_bytes)
        ));
    }
    let total: u64 = bytes.iter().map(|(_, b)| *b as u64).sum();
    if total > limits.total_bytes {
        return Err(format!(
            "it needs {:.1} MiB of device memory (its {name} {:.1} MiB), more than the device's {:.1} MiB",
            mib(total),
            mib(largest),
            mib(limits.total_bytes)
        ));
    }
    Ok(())
}

/// Whether `a` and `b` hold the same objects in the same order.
fn same_arcs<T>(a: &[Arc<T>], b: &[Arc<T>]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| Arc::ptr_eq(x, y))
}

impl SceneBuffers {
    /// `p`'s arrays on the device, an environment map's, the textures' and
    /// the meshes' taken from `shared` where it holds those (else
    /// uploaded, and `shared` then holds them); and the bytes uploaded.
    pub(super) fn upload(
        cl: &OpenClBackend,
        p: &Packed,
        shared: &mut Shared,
    ) -> Result<(Self, usize), OpenClError> {
        let read = Access::ReadOnly;
        let held = match (&p.env_map, shared.map.as_ref()) {
            (Some(m), Some(held)) if Arc::ptr_eq(m, &held.map) => Some(held),
            _ => None,
        };
        let textures = &p.textures.textures;
        let held_texels = (shared.textures.as_ref())
            .filter(|h| !textures.is_empty() && same_arcs(&h.textures, textures))
            .map(|h| h.texels.clone());
        let meshes = &p.meshes;
        let held_meshes = (shared.meshes.as_ref()).filter(|h| {
            !meshes.meshes.is_empty()
                && h.textured == meshes.textured
                && same_arcs(&h.meshes, &meshes.meshes)
        });
        let mut uploaded = 0;
        let mut buffers = Vec::with_capacity(SCENE_ARRAYS.len());
        for a in &SCENE_ARRAYS {
            let shared = match (a.name, held) {
                ("env_texels", Some(h)) => Some(h.texels.clone()),
                ("env_dist", Some(h)) => Some(h.dist.clone()),
                ("texels", _) => held_texels.clone(),
                (name, _) => (held_meshes.and_then(|h| h.buffers.iter().find(|b| b.0 == name)))
                    .map(|b| b.1.clone()),
            };
            buffers.push(match (shared, (a.bytes)(p)) {
                (Some(b), _) => b,
                // One element the kernel never reads (the counts say none).
                (None, []) => Arc::new(cl.buffer(read, a.elem_bytes)?),
                (None, bytes) => {
                    uploaded += bytes.len();
                    Arc::new(cl.upload(read, bytes)?)
                }
            });
        }
        let at = |name: &str| SCENE_ARRAYS.iter().position(|a| a.name == name);
        if let (None, Some(map)) = (held, &p.env_map) {
            if let (Some(t), Some(d)) = (at("env_texels"), at("env_dist")) {
                shared.map = Some(MapBuffers {
                    map: map.clone(),
                    texels: buffers[t].clone(),
                    dist: buffers[d].clone(),
                });
            }
        }
        if held_meshes.is_none() && !meshes.meshes.is_empty() {
            let buffers = (meshes::MESH_ARRAYS.iter())
                .filter_map(|&name| Some((name, buffers[at(name)?].clone())))
                .collect();
            shared.meshes = Some(MeshBuffers {
                meshes: meshes.meshes.clone(),
                textured: meshes.textured,
                buffers,
            });
        }
        if let (None, false, Some(t)) = (held_texels, textures.is_empty(), at("texels")) {
            shared.textures = Some(TextureBuffer {
                textures: textures.clone(),
                texels: buffers[t].clone(),
            });
        }
        Ok((Self(buffers), uploaded))
    }

    /// Sets every argument of `kernel`: the scene's arrays, then `a`.
    ///
    /// # Safety
    /// `kernel` must be the `render` kernel of kernels/render.cl, whose
    /// parameters are the arrays of `kernels/scene_arrays.h` (`__global`
    /// pointers, in [`SCENE_ARRAYS`] order: a test holds the two lists
    /// equal) and then [`LAUNCH_PARAMS`]; each pointer argument gets the
    /// `cl_mem` of a buffer of that element type.
    #[allow(unsafe_code)]
    pub(super) unsafe fn set_args(
        &self,
        kernel: &Kernel,
        a: &LaunchArgs,
    ) -> Result<(), OpenClError> {
        let scene = self.0.iter().map(|b| Arg::Mem(b.get()));
        for (i, arg) in scene.chain(a.values()).enumerate() {
            let i = i as cl_uint;
            // SAFETY: per the contract above, argument i has the type the
            // kernel declares there: the buffers hold SCENE_ARRAYS' element
            // types (uploaded from the same table), and `values` gives
            // LAUNCH_PARAMS' types in its order.
            #[allow(unsafe_code)]
            unsafe {
                match arg {
                    Arg::Mem(m) => kernel.set_arg(i, &m),
                    Arg::U32(v) => kernel.set_arg(i, &v),
                    Arg::U64(v) => kernel.set_arg(i, &v),
                }
            }
            .map_err(call("set_arg"))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_too_large_for_the_device_is_named_and_sized() {
        let limits = MemoryLimits {
            max_alloc_bytes: 1 << 20,
            total_bytes: 3 << 20,
        };
        assert_eq!(
            check_fits(&[("film", 1 << 20), ("triangles", 1 << 19)], limits),
            Ok(())
        );
        let one =
            check_fits(&[("film", 1000), ("triangles", 3 << 19)], limits).expect_err("too big");
        assert!(
            one.contains("triangles need 1.5 MiB in one buffer") && one.contains("(1.0 MiB)"),
            "{one}"
        );
        let all = [
            ("film", 1 << 20),
            ("triangles", 1 << 20),
            ("mesh BVH", 1 << 20),
            ("objects", 1),
        ];
        let total = check_fits(&all, limits).expect_err("too much");
        assert!(
            total.contains("needs 3.0 MiB") && total.contains("device's 3.0 MiB"),
            "{total}"
        );
    }
}
