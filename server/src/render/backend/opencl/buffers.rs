//! A job's scene on the device: one buffer per array of `layout::pack`,
//! and the `render` kernel's arguments in the order kernels/render.cl
//! declares them.

use super::layout::{self, Packed};
use super::meshes;
use super::{call, Access, OpenClBackend, OpenClError};
use crate::render::bvh::BvhNode;
use crate::render::shape::TriVerts;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem};
use opencl3::types::{cl_uint, cl_ulong};
use std::mem::size_of;

pub(super) struct SceneBuffers {
    params: Buffer<layout::Params>,
    objects: Buffer<layout::Object>,
    materials: Buffer<layout::Material>,
    lights: Buffer<layout::Light>,
    nodes: Buffer<BvhNode>,
    prims: Buffer<u32>,
    big: Buffer<u32>,
    instances: Buffer<meshes::Instance>,
    mesh_nodes: Buffer<BvhNode>,
    tris: Buffer<TriVerts>,
    normals: Buffer<[f32; 4]>,
    slots: Buffer<u32>,
}

/// Where one launch adds its samples.
pub(super) struct LaunchArgs<'a> {
    pub film: &'a Buffer<f32>,
    pub rejected: &'a Buffer<u32>,
    pub first: cl_ulong,
    pub count: cl_uint,
    pub pixel_base: cl_uint,
    pub pixel_end: cl_uint,
    /// Adaptive work entries (unread when `mode` is `WORK_UNIFORM`).
    pub work: &'a Buffer<[u32; 4]>,
    pub mode: cl_uint,
}

/// What a device can hold: the largest buffer, and all buffers together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLimits {
    pub max_alloc_bytes: u64,
    pub total_bytes: u64,
}

/// Bytes of each buffer a job needs on the device: its scene and a film
/// of `film_bytes`.
pub(super) fn job_bytes(p: &Packed, film_bytes: usize) -> [(&'static str, usize); 13] {
    let b = |n: usize, size: usize| n.max(1) * size;
    let m = &p.meshes;
    [
        ("film", film_bytes),
        ("objects", b(p.objects.len(), size_of::<layout::Object>())),
        (
            "materials",
            b(p.materials.len(), size_of::<layout::Material>()),
        ),
        ("lights", b(p.lights.len(), size_of::<layout::Light>())),
        ("object BVH", b(p.nodes.len(), size_of::<BvhNode>())),
        ("object BVH slots", b(p.prims.len(), 4)),
        ("large objects", b(p.big.len(), 4)),
        (
            "instances",
            b(m.instances.len(), size_of::<meshes::Instance>()),
        ),
        ("mesh BVH", b(m.nodes.len(), size_of::<BvhNode>())),
        ("triangles", b(m.tris.len(), size_of::<TriVerts>())),
        ("vertex normals", b(m.normals.len(), 16)),
        ("material slots", b(m.slots.len(), 4)),
        ("params", size_of::<layout::Params>()),
    ]
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

impl SceneBuffers {
    pub(super) fn upload(cl: &OpenClBackend, p: &Packed) -> Result<Self, OpenClError> {
        let read = Access::ReadOnly;
        let m = &p.meshes;
        Ok(Self {
            params: cl.upload(read, std::slice::from_ref(&p.params))?,
            objects: cl.upload(read, &p.objects)?,
            materials: cl.upload(read, &p.materials)?,
            lights: cl.upload(read, &p.lights)?,
            nodes: cl.upload(read, &p.nodes)?,
            prims: cl.upload(read, &p.prims)?,
            big: cl.upload(read, &p.big)?,
            instances: cl.upload(read, &m.instances)?,
            mesh_nodes: cl.upload(read, &m.nodes)?,
            tris: cl.upload(read, &m.tris)?,
            normals: cl.upload(read, &m.normals)?,
            slots: cl.upload(read, &m.slots)?,
        })
    }

    /// Sets every argument of `kernel`.
    ///
    /// # Safety
    /// `kernel` must be the `render` kernel of kernels/render.cl, whose
    /// parameters are, in order: the params, objects, materials and lights
    /// (`__global` pointers), the film and the rejection counter, `ulong
    /// first`, `uint count`, `uint pixel_base`, `uint pixel_end`, then the
    /// BVH's nodes, prims and big objects and the meshes' instances, nodes,
    /// triangles, normals and slots (`__global` pointers); each pointer
    /// argument gets the `cl_mem` of a buffer of that element type.
    #[allow(unsafe_code)]
    pub(super) unsafe fn set_args(
        &self,
        kernel: &Kernel,
        a: &LaunchArgs,
    ) -> Result<(), OpenClError> {
        let mems = [
            (0, self.params.get()),
            (1, self.objects.get()),
            (2, self.materials.get()),
            (3, self.lights.get()),
            (4, a.film.get()),
            (5, a.rejected.get()),
            (10, self.nodes.get()),
            (11, self.prims.get()),
            (12, self.big.get()),
            (13, self.instances.get()),
            (14, self.mesh_nodes.get()),
            (15, self.tris.get()),
            (16, self.normals.get()),
            (17, self.slots.get()),
            (18, a.work.get()),
        ];
        // SAFETY: per the contract above, every index gets the type the
        // kernel declares there.
        #[allow(unsafe_code)]
        unsafe {
            for (i, mem) in mems {
                kernel.set_arg(i, &mem).map_err(call("set_arg"))?;
            }
            kernel.set_arg(6, &a.first).map_err(call("set_arg"))?;
            kernel.set_arg(7, &a.count).map_err(call("set_arg"))?;
            kernel.set_arg(8, &a.pixel_base).map_err(call("set_arg"))?;
            kernel.set_arg(9, &a.pixel_end).map_err(call("set_arg"))?;
            kernel.set_arg(19, &a.mode).map_err(call("set_arg"))?;
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
