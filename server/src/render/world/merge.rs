//! Small meshes merged into one: one BVH over their triangles instead of a
//! BVH over instances that each hold their own.
//!
//! A ray that meets a two-level world pays per instance it enters: the map
//! into object space, the watertight test's setup (three divisions) and a
//! second traversal from that BVH's root. In a room of walls and a few
//! models nearly every ray enters several. So the placements of small
//! meshes (smallest first, up to a budget of triangles: a mesh placed
//! twice is copied twice, and a forest of instanced trees must stay
//! instances), turned the right way round (a mirroring placement would
//! flip their triangles' faces), become one mesh in
//! a scene frame (world space moved to the centre of their boxes, so that
//! f32 keeps the scene's own precision wherever it sits), placed by a
//! translation alone: the ray's triangle setup is then shared
//! (`Instance::translation_only`). Meshes with and without vertex normals
//! merge separately (a flat mesh has no normals to fill in); missing texture
//! coordinates, tangents and colours are filled with what reads as their
//! absence ((0, 0), a zero tangent, white).
//!
//! The merged mesh depends on the meshes and their placements only, not on
//! the camera, so a camera move reuses it: the last few merges are cached
//! (`world::reuse`).
//!
//! The image differs from the unmerged world's by rounding only (vertices
//! are placed in f64 once and rounded, instead of rays being mapped in f32).

use super::reuse::Reuse;
use crate::render::math::{DAffine3, DVec3};
use crate::render::shape::{Mesh, MeshData};
use std::sync::Arc;

/// Meshes of more triangles than this keep their own instance: their own
/// traversal outweighs the instance's setup, and merging would copy them.
pub const MERGE_MESH_MAX: usize = 1 << 16;
/// At most this many triangles are merged in all (the smallest meshes
/// first). An edit that moves one merged mesh (the `light` verb on a
/// glowing mesh, a moved object) rebuilds the whole merge: at this size
/// about 70 ms on two cores (the BVH builds 99,224 triangles in 0.05 s,
/// docs/BENCHMARKS.md), and about 25 MB of copies.
pub const MERGE_MAX: usize = 1 << 17;
/// Merges kept for reuse (one per scene rendered lately).
const CACHED: usize = 4;

/// A mesh as the scene places it.
pub(super) struct Placement<'a> {
    pub mesh: &'a Arc<Mesh>,
    pub world_from_object: DAffine3,
    /// World material of each of the mesh's slots.
    pub materials: &'a [u32],
}

/// Meshes merged into one.
pub(super) struct Merged {
    pub mesh: Arc<Mesh>,
    /// World-space position of the merged mesh's origin.
    pub frame: DVec3,
    /// The placements merged, ascending.
    pub members: Vec<usize>,
    /// World material of each of the merged mesh's slots (the members'
    /// slots in turn).
    pub materials: Arc<[u32]>,
}

/// The groups of `placements` worth merging (none where fewer than two
/// meshes qualify).
pub(super) fn merge(placements: &[Placement<'_>]) -> Vec<Merged> {
    let mut total = 0;
    let mut groups = Vec::new();
    for smooth in [false, true] {
        let mut members: Vec<usize> = (0..placements.len())
            .filter(|&i| {
                let p = &placements[i];
                let det = p.world_from_object.matrix3.determinant();
                p.mesh.normals.is_some() == smooth
                    && det.is_finite()
                    && det > 0.0
                    && p.mesh.triangles.len() <= MERGE_MESH_MAX
            })
            .collect();
        members.sort_by_key(|&i| (placements[i].mesh.triangles.len(), i));
        members.retain(|&i| {
            let n = placements[i].mesh.triangles.len();
            let fits = total + n <= MERGE_MAX;
            total += if fits { n } else { 0 };
            fits
        });
        members.sort_unstable();
        if members.len() < 2 {
            continue;
        }
        let parts: Vec<&Placement<'_>> = members.iter().map(|&i| &placements[i]).collect();
        let Some((mesh, frame)) = cached_or_built(&parts) else {
            continue;
        };
        let materials = parts
            .iter()
            .flat_map(|p| (0..p.mesh.material_slots as usize).map(|s| p.materials[s]))
            .collect();
        groups.push(Merged {
            mesh,
            frame,
            members,
            materials,
        });
    }
    groups
}

/// Merges of the last scenes rendered.
static CACHE: Reuse<(Arc<Mesh>, DVec3)> = Reuse::new(CACHED);

fn cached_or_built(parts: &[&Placement<'_>]) -> Option<(Arc<Mesh>, DVec3)> {
    let placed: Vec<_> = (parts.iter())
        .map(|p| (0, p.mesh, &p.world_from_object))
        .collect();
    CACHE
        .get_or_build(&placed, || {
            build(parts).map(|(m, f)| (Arc::new(m), f)).ok_or(())
        })
        .ok()
}

/// The parts' triangles in one mesh, relative to the centre of their
/// world-space boxes; None where the placed data is not a valid mesh
/// (coordinates beyond f32).
fn build(parts: &[&Placement<'_>]) -> Option<(Mesh, DVec3)> {
    let (lo, hi) = parts
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            let (a, b) = p.mesh.bounds().transformed(&p.world_from_object);
            (lo.min(a), hi.max(b))
        });
    let frame = (lo + hi) * 0.5;
    let has = |f: fn(&Mesh) -> bool| parts.iter().any(|p| f(p.mesh));
    let uv_sets = [0, 1].map(|s| parts.iter().any(|p| p.mesh.uvs[s].is_some()));
    let mut data = MeshData {
        name: format!("{} small meshes, merged", parts.len()),
        positions: Vec::new(),
        normals: has(|m| m.normals.is_some()).then(Vec::new),
        uvs: uv_sets.map(|any| any.then(Vec::new)),
        tangents: has(|m| m.tangents.is_some()).then(Vec::new),
        colors: has(|m| m.colors.is_some()).then(Vec::new),
        triangles: Vec::new(),
        materials: Vec::new(),
    };
    let mut slot_base = 0;
    for p in parts {
        let m: &Mesh = p.mesh;
        let a = DAffine3 {
            matrix3: p.world_from_object.matrix3,
            translation: p.world_from_object.translation - frame,
        };
        // Normals by the inverse transpose, scaled back to about unit
        // length (a constant factor: they are normalised after
        // interpolation, as the instance's mapped ones are).
        let det = a.matrix3.determinant();
        let normal_from_obj = a.matrix3.inverse().transpose() * det.cbrt();
        let f32s = |v: DVec3| v.as_vec3().to_array();
        let base = data.positions.len() as u32;
        (data.positions).extend(m.positions.iter().map(|&q| f32s(a.transform_point3(d3(q)))));
        if let (Some(out), Some(normals)) = (&mut data.normals, &m.normals) {
            out.extend(normals.iter().map(|&n| f32s(normal_from_obj * d3(n))));
        }
        for (out, set) in data.uvs.iter_mut().zip(&m.uvs) {
            if let Some(out) = out {
                match set {
                    Some(uv) => out.extend_from_slice(uv),
                    None => out.resize(out.len() + m.positions.len(), [0.0; 2]),
                }
            }
        }
        if let Some(out) = &mut data.tangents {
            match &m.tangents {
                Some(t) => out.extend(t.iter().map(|&[x, y, z, w]| {
                    let [x, y, z] = f32s(a.matrix3 * DVec3::new(x.into(), y.into(), z.into()));
                    [x, y, z, w]
                })),
                None => out.resize(out.len() + m.positions.len(), [0.0, 0.0, 0.0, 1.0]),
            }
        }
        if let Some(out) = &mut data.colors {
            match &m.colors {
                Some(c) => out.extend_from_slice(c),
                None => out.resize(out.len() + m.positions.len(), [1.0; 3]),
            }
        }
        (data.triangles).extend(m.triangles.iter().map(|t| t.map(|v| v + base)));
        (data.materials).extend(m.materials.iter().map(|s| s + slot_base));
        slot_base += m.material_slots;
    }
    Some((Mesh::new(data).ok()?, frame))
}

fn d3(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::math::Vec3A;
    use glam::DQuat;

    fn triangle(attributes: bool) -> Arc<Mesh> {
        let data = MeshData {
            name: "t".into(),
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
            uvs: [
                attributes.then(|| vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                None,
            ],
            tangents: attributes.then(|| vec![[1.0, 0.0, 0.0, -1.0]; 3]),
            colors: attributes.then(|| vec![[0.2, 0.4, 0.6], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
            triangles: vec![[0, 1, 2], [0, 2, 1]],
            materials: if attributes { vec![0, 1] } else { vec![] },
            ..Default::default()
        };
        Arc::new(Mesh::new(data).expect("mesh"))
    }

    #[test]
    fn merged_meshes_keep_every_attribute_where_it_was_and_fill_the_rest() {
        let (a, b) = (triangle(true), triangle(false));
        let turn = DAffine3::from_scale_rotation_translation(
            DVec3::new(2.0, 3.0, 0.5),
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
            DVec3::new(1e4, -20.0, 5.0),
        );
        let moved = DAffine3::from_translation(DVec3::new(1e4 + 3.0, -20.0, 5.0));
        let placements = [
            Placement {
                mesh: &a,
                world_from_object: turn,
                materials: &[7, 8],
            },
            Placement {
                mesh: &b,
                world_from_object: moved,
                materials: &[9],
            },
        ];
        let merged = merge(&placements);
        assert_eq!(merged.len(), 1);
        let m = &merged[0];
        assert_eq!(m.members, [0, 1]);
        assert_eq!(*m.materials, [7, 8, 9]);
        let mesh = &*m.mesh;
        assert_eq!(mesh.materials, [0, 1, 2, 2]);
        assert_eq!(mesh.triangles[2..], [[3, 4, 5], [3, 5, 4]]);
        // Positions placed, relative to the frame, in f32 of the scene's
        // own size (the frame is the boxes' centre, near 1e4).
        let originals = (placements.iter()).flat_map(|p| {
            p.mesh
                .positions
                .iter()
                .map(|&q| p.world_from_object.transform_point3(d3(q)))
        });
        for (&p, world) in mesh.positions.iter().zip(originals) {
            let want = world - m.frame;
            assert!((d3(p) - want).abs().max_element() < 1e-5, "{p:?} vs {want}");
        }
        assert!(m.frame.x > 9e3);
        // Attributes at a point of each triangle, as the placed original's.
        let bary = [0.2, 0.3, 0.5];
        assert_eq!(mesh.uv(0, 1, bary), a.uv(0, 1, bary));
        assert_eq!(mesh.uv(0, 2, bary), [0.0; 2], "filled: no coordinates");
        assert_eq!(mesh.color(0, bary), a.color(0, bary));
        assert_eq!(mesh.color(3, bary), Some(Vec3A::ONE), "filled: white");
        let (t, sign) = mesh.tangent(0, bary).expect("tangent");
        let (t0, s0) = a.tangent(0, bary).expect("tangent");
        let want = turn.matrix3 * t0.as_dvec3();
        assert!((t.as_dvec3() - want).length() < 1e-5 && sign == s0);
        assert_eq!(mesh.tangent(2, bary), Some((Vec3A::ZERO, 1.0)), "filled");
    }

    #[test]
    fn mirrored_or_lone_meshes_keep_their_instance_and_merges_are_reused() {
        let (a, b, c) = (triangle(false), triangle(false), triangle(false));
        let at = |x: f64| DAffine3::from_translation(DVec3::new(x, 0.0, 0.0));
        let mirror = DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        let place = |mesh, world_from_object| Placement {
            mesh,
            world_from_object,
            materials: &[0],
        };
        // `c` mirrored: only `b` qualifies, alone.
        let list = [place(&b, at(1.0)), place(&c, mirror)];
        assert!(merge(&list).is_empty());
        // A mesh placed twice is copied twice.
        let list = [
            place(&a, at(0.0)),
            place(&b, at(1.0)),
            place(&a, at(2.0)),
            place(&c, mirror),
        ];
        let merged = merge(&list);
        assert_eq!(merged.len(), 1);
        assert_eq!(merged[0].members, [0, 1, 2]);
        assert_eq!(merged[0].mesh.triangles.len(), 6);
        // The same placements again: the same merged mesh, not a new one.
        let again = merge(&list);
        assert!(Arc::ptr_eq(&again[0].mesh, &merged[0].mesh));
        // Moved: a new one.
        let list = [place(&b, at(1.0)), place(&c, at(3.5))];
        assert!(!Arc::ptr_eq(&merge(&list)[0].mesh, &merged[0].mesh));
    }

    #[test]
    fn large_meshes_and_those_beyond_the_budget_keep_their_instance() {
        let big = |n: usize| {
            let data = MeshData {
                name: "big".into(),
                positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                triangles: vec![[0, 1, 2]; n],
                ..Default::default()
            };
            Arc::new(Mesh::new(data).expect("mesh"))
        };
        let at = |mesh, x: f64| Placement {
            mesh,
            world_from_object: DAffine3::from_translation(DVec3::new(x, 3.0, 0.0)),
            materials: &[0],
        };
        let (a, b, c) = (triangle(false), big(MERGE_MESH_MAX + 1), triangle(false));
        let merged = merge(&[at(&a, 0.0), at(&b, 1.0), at(&c, 2.0)]);
        assert_eq!(merged[0].members, [0, 2], "too large to merge");
        // Two meshes of the largest size fill the budget; the third stays.
        let (d, e, f) = (
            big(MERGE_MESH_MAX),
            big(MERGE_MESH_MAX),
            big(MERGE_MESH_MAX),
        );
        assert_eq!(2 * MERGE_MESH_MAX, MERGE_MAX);
        let merged = merge(&[at(&d, 0.0), at(&e, 1.0), at(&f, 2.0)]);
        assert_eq!(merged[0].members, [0, 1]);
        assert_eq!(merged[0].mesh.triangles.len(), MERGE_MAX);
    }

    #[test]
    fn a_merge_is_let_go_once_its_meshes_are() {
        fn at(mesh: &Arc<Mesh>, x: f64, y: f64) -> Placement<'_> {
            Placement {
                mesh,
                world_from_object: DAffine3::from_translation(DVec3::new(x, y, 0.0)),
                materials: &[0],
            }
        }
        let (c, d) = (triangle(false), triangle(false));
        let reused = [at(&c, 0.0, -7.0), at(&d, 1.0, -7.0)];
        merge(&reused);
        let kept = {
            let (a, b) = (triangle(false), triangle(false));
            merge(&[at(&a, 0.0, 7.0), at(&b, 1.0, 7.0)])[0].mesh.clone()
        };
        // A merge found in the cache: the entry whose meshes are gone goes.
        merge(&reused);
        assert_eq!(Arc::strong_count(&kept), 1, "only this test holds it");
    }
}
