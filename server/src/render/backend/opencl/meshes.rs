//! Mesh instances in the kernel's layout (`kernels/types.h`, `Instance`;
//! `kernels/triangles.h` reads them): every distinct mesh's BVH nodes and
//! leaf-ordered triangles once, whatever number of instances place it, and
//! per instance its transforms, the round-trip bound its ray offsets need,
//! and where its mesh and material slots start in the shared buffers.

use crate::render::alpha as render_alpha;
use crate::render::bvh::BvhNode;
use crate::render::maps::{Slot, NO_TEXTURE};
use crate::render::shape::{Mesh, TriVerts};
use crate::render::world::World;
use bytemuck::{Pod, Zeroable};
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// `normal_base` of an instance whose mesh has no vertex normals.
pub const NO_NORMALS: u32 = u32::MAX;

/// A placed mesh as the kernel reads it. Matrices are glam's `Affine3A`
/// columns (x, y, z axes, then the translation), applied as the CPU does:
/// `x * p.x + y * p.y + z * p.z + t`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Instance {
    pub obj_from_cam: [[f32; 4]; 4],
    pub cam_from_obj: [[f32; 4]; 4],
    /// Inverse transpose of `cam_from_obj`'s matrix (columns).
    pub normal_from_obj: [[f32; 4]; 3],
    /// |obj_from_cam(cam_from_obj(p)) - p| <= rt_a max|p| + rt_b.
    pub rt_a: f32,
    pub rt_b: f32,
    /// Where the mesh's nodes and triangles start in the shared buffers.
    pub node_base: u32,
    pub tri_base: u32,
    /// Where this instance's material of each mesh slot starts (`slots`).
    pub slot_base: u32,
    /// Where the mesh's per-slot vertex normals start (3 per triangle), or
    /// [`NO_NORMALS`].
    pub normal_base: u32,
    /// Where its per-slot texture coordinates start (3 per triangle: u0,
    /// v0, u1, v1 of each corner), or [`NO_NORMALS`].
    pub uv_base: u32,
    /// Where its per-slot tangents start (3 per triangle, w the sign), or
    /// [`NO_NORMALS`].
    pub tangent_base: u32,
    /// Where its mesh slots' alpha tests start (`alpha`), or [`NO_NORMALS`]
    /// where every slot is opaque.
    pub alpha_base: u32,
    /// Where its per-slot vertex colours start (3 per triangle, w unused),
    /// or [`NO_NORMALS`].
    pub color_base: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<Instance>() == 224);

/// A mesh slot's alpha test (`render::alpha::AlphaTest`): the base colour
/// texture's slot (texture `NO_TEXTURE`: none), cutoff, factor, mode (0
/// opaque, 1 mask, 2 blend).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct AlphaTest {
    pub tex: super::textures::MapSlot,
    pub cutoff: f32,
    pub factor: f32,
    pub mode: u32,
    pub pad0: u32,
}

const _: () = assert!(std::mem::size_of::<AlphaTest>() == 64);

/// Every instance of a world, and the buffers they point into.
#[derive(Debug, Default)]
pub struct PackedMeshes {
    pub instances: Vec<Instance>,
    /// World material of each instance's mesh slots.
    pub slots: Vec<u32>,
    /// Alpha tests of the mesh slots of instances that have any.
    pub alpha: Vec<AlphaTest>,
    /// Deepest mesh BVH.
    pub depth: u32,
    /// The distinct meshes, in the order their data lies in
    /// [`MeshArrays`], and whether that holds their texture coordinates and
    /// tangents (some material reads maps): what a device keys the arrays
    /// it keeps by.
    pub meshes: Vec<Arc<Mesh>>,
    pub textured: bool,
    arrays: OnceLock<MeshArrays>,
}

/// The distinct meshes' data, one mesh after another.
#[derive(Debug, Default)]
pub struct MeshArrays {
    pub nodes: Vec<BvhNode>,
    /// Triangles in leaf order; `v1[3]` holds the triangle's material slot
    /// (as bits), `v0[3]` its index in the mesh, as on the CPU.
    pub tris: Vec<TriVerts>,
    /// Three unit vertex normals per triangle slot (w unused), for meshes
    /// that have them.
    pub normals: Vec<[f32; 4]>,
    /// Texture coordinates (both sets) of each triangle slot's corners,
    /// for meshes that have them and are placed where a material has maps.
    pub uvs: Vec<[f32; 4]>,
    /// Tangents likewise (w: the bitangent's sign).
    pub tangents: Vec<[f32; 4]>,
    /// Vertex colours of each triangle slot's corners (w unused), for
    /// meshes that have them.
    pub colors: Vec<[f32; 4]>,
}

/// The kernel's names of [`MeshArrays`]' fields, in [`counts`]' order.
pub const MESH_ARRAYS: [&str; 6] = ["mesh_nodes", "tris", "normals", "uvs", "tangents", "colors"];

/// Elements `mesh` adds to each of [`MeshArrays`]' fields ([`MESH_ARRAYS`]
/// order): what [`pack`] places by and [`MeshArrays`] is built by.
fn counts(mesh: &Mesh, textured: bool) -> [usize; 6] {
    let corners = |has: bool| if has { 3 * mesh.tris.len() } else { 0 };
    [
        mesh.bvh.nodes.len(),
        mesh.tris.len(),
        corners(mesh.normals.is_some()),
        corners(textured && mesh.uvs.iter().any(Option::is_some)),
        corners(textured && mesh.tangents.is_some()),
        corners(mesh.colors.is_some()),
    ]
}

impl PackedMeshes {
    /// The meshes' data: copied together on first use only, so that a
    /// device already holding these meshes (the jobs of one scene: every
    /// camera move) never has them copied.
    pub fn arrays(&self) -> &MeshArrays {
        self.arrays
            .get_or_init(|| build(&self.meshes, self.textured))
    }

    /// Bytes of the field of [`MeshArrays`] the kernel calls `name`, without
    /// building them; None for another name.
    pub fn array_bytes(&self, name: &str) -> Option<usize> {
        let k = MESH_ARRAYS.iter().position(|n| *n == name)?;
        let elem = [
            std::mem::size_of::<BvhNode>(),
            std::mem::size_of::<TriVerts>(),
            16,
            16,
            16,
            16,
        ][k];
        Some(
            elem * (self.meshes.iter())
                .map(|m| counts(m, self.textured)[k])
                .sum::<usize>(),
        )
    }
}

fn build(meshes: &[Arc<Mesh>], textured: bool) -> MeshArrays {
    let mut out = MeshArrays::default();
    for mesh in meshes {
        let c = counts(mesh, textured);
        out.nodes.extend_from_slice(&mesh.bvh.nodes);
        out.tris.extend(mesh.tris.iter().map(|t| {
            let mut t = *t;
            t.v1[3] = f32::from_bits(mesh.materials[t.index() as usize]);
            t
        }));
        let xyz = |[x, y, z]: [f32; 3]| [x, y, z, 0.0];
        if let (Some(n), true) = (&mesh.normals, c[2] > 0) {
            corners(&mut out.normals, mesh, |v| xyz(n[v]));
        }
        if c[3] > 0 {
            let set = |k: usize, v: usize| mesh.uvs[k].as_ref().map_or([0.0; 2], |u| u[v]);
            corners(&mut out.uvs, mesh, |v| {
                let ([a, b], [c, d]) = (set(0, v), set(1, v));
                [a, b, c, d]
            });
        }
        if let (Some(tangents), true) = (&mesh.tangents, c[4] > 0) {
            corners(&mut out.tangents, mesh, |v| tangents[v]);
        }
        if let (Some(colors), true) = (&mesh.colors, c[5] > 0) {
            corners(&mut out.colors, mesh, |v| xyz(colors[v]));
        }
    }
    out
}

fn cols3(m: &crate::render::math::Mat3A) -> [[f32; 4]; 3] {
    [m.x_axis, m.y_axis, m.z_axis].map(|c| [c.x, c.y, c.z, 0.0])
}

fn affine(a: &crate::render::math::Affine3A) -> [[f32; 4]; 4] {
    let [x, y, z] = cols3(&a.matrix3);
    let t = a.translation;
    [x, y, z, [t.x, t.y, t.z, 0.0]]
}

pub fn pack(w: &World) -> PackedMeshes {
    let mut out = PackedMeshes {
        // Texture coordinates and tangents only where some material reads maps.
        textured: !w.maps.is_empty(),
        ..PackedMeshes::default()
    };
    // Elements placed so far in each of the arrays, and (node_base,
    // tri_base, normal_base, uv_base, tangent_base, color_base) of each
    // distinct mesh (per-corner arrays count in triangles).
    let mut placed_so_far = [0usize; 6];
    let mut placed: HashMap<*const Mesh, [u32; 6]> = HashMap::new();
    for inst in &w.instances {
        let [node_base, tri_base, normal_base, uv_base, tangent_base, color_base] =
            *placed.entry(Arc::as_ptr(&inst.mesh)).or_insert_with(|| {
                let c = counts(&inst.mesh, out.textured);
                let bases: [u32; 6] = std::array::from_fn(|k| match k {
                    0 | 1 => placed_so_far[k] as u32,
                    _ if c[k] > 0 => (placed_so_far[k] / 3) as u32,
                    _ => NO_NORMALS,
                });
                for (sum, n) in placed_so_far.iter_mut().zip(c) {
                    *sum += n;
                }
                out.depth = out.depth.max(inst.mesh.bvh.depth);
                out.meshes.push(inst.mesh.clone());
                bases
            });
        let slot_base = out.slots.len() as u32;
        out.slots.extend_from_slice(&inst.materials);
        let alpha_base = match &inst.alpha {
            None => NO_NORMALS,
            Some(tests) => {
                let base = out.alpha.len() as u32;
                out.alpha.extend(tests.iter().map(|t| alpha_test(w, t)));
                base
            }
        };
        out.instances.push(Instance {
            obj_from_cam: affine(&inst.obj_from_cam),
            cam_from_obj: affine(&inst.cam_from_obj),
            normal_from_obj: cols3(&inst.normal_from_obj),
            rt_a: inst.rt_a,
            rt_b: inst.rt_b,
            node_base,
            tri_base,
            slot_base,
            normal_base,
            uv_base,
            tangent_base,
            alpha_base,
            color_base,
            pad: [0; 2],
        });
    }
    out
}

/// Appends `mesh`'s per-vertex attribute `at(vertex)` for the three
/// corners of each triangle in leaf order.
fn corners(out: &mut Vec<[f32; 4]>, mesh: &Mesh, at: impl Fn(usize) -> [f32; 4]) {
    for t in &mesh.tris {
        for v in mesh.triangles[t.index() as usize] {
            out.push(at(v as usize));
        }
    }
}

/// One slot's alpha test in the kernel's layout; its texture is the
/// world's (the base colour texture, which `World::textures` holds).
fn alpha_test(w: &World, t: &render_alpha::AlphaTest) -> AlphaTest {
    let (mode, cutoff) = match t.mode {
        render_alpha::AlphaMode::Opaque => (0, 0.0),
        render_alpha::AlphaMode::Mask(c) => (1, c),
        render_alpha::AlphaMode::Blend => (2, 0.0),
    };
    let slot = match &t.texture {
        None => Slot::NONE,
        Some((tex, sampling)) => Slot {
            texture: (w.textures.iter())
                .position(|x| Arc::ptr_eq(x, tex))
                .map_or(NO_TEXTURE, |i| i as u32),
            sampling: *sampling,
        },
    };
    AlphaTest {
        tex: super::textures::slot(&slot),
        cutoff,
        factor: t.factor,
        mode,
        pad0: 0,
    }
}
