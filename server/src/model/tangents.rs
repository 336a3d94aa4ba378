//! Tangents for normal maps where a file gives none: MikkTSpace (the
//! `mikktspace` crate), as glTF requires, from the mesh's positions, its
//! normals (the face's where it has none) and one UV set. MikkTSpace
//! answers per triangle corner; a vertex whose corners get different
//! tangents (a UV seam, a mirrored half) is split so that every corner keeps
//! its own.

use super::MeshData;
use std::collections::HashMap;

struct Corners<'a> {
    mesh: &'a MeshData,
    uvs: &'a [[f32; 2]],
    out: Vec<[f32; 4]>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.triangles[face][vert] as usize
    }
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)]
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match &self.mesh.normals {
            Some(n) => n[self.vertex(face, vert)],
            None => {
                let [a, b, c] = self.mesh.triangles[face].map(|v| self.mesh.positions[v as usize]);
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                if l > 0.0 {
                    n.map(|x| x / l)
                } else {
                    [0.0, 0.0, 1.0]
                }
            }
        }
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // MikkTSpace works in OpenGL's UV convention (v up); glTF's v runs
        // down, so the bitangent it finds then points up the image, as the
        // map's green channel does.
        let [u, v] = self.uvs[self.vertex(face, vert)];
        [u, 1.0 - v]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.out[face * 3 + vert] = tangent;
    }
}

/// Gives `mesh` MikkTSpace tangents from UV set `set`; false (and the mesh
/// unchanged) where it has no such set or the algorithm fails.
pub(super) fn generate(mesh: &mut MeshData, set: usize) -> bool {
    let Some(uvs) = mesh.uvs[set].clone() else {
        return false;
    };
    let mut corners = Corners {
        mesh,
        uvs: &uvs,
        out: vec![[0.0; 4]; mesh.triangles.len() * 3],
    };
    if !mikktspace::generate_tangents(&mut corners) {
        return false;
    }
    let per_corner = corners.out;
    let clean = |t: [f32; 4]| -> [f32; 4] {
        if t.iter().all(|x| x.is_finite()) {
            [t[0], t[1], t[2], if t[3] < 0.0 { -1.0 } else { 1.0 }]
        } else {
            [0.0, 0.0, 0.0, 1.0]
        }
    };
    let n = mesh.positions.len();
    let mut tangents: Vec<Option<[f32; 4]>> = vec![None; n];
    // Extra copies of split vertices: (original vertex, tangent bits) -> index.
    let mut copies: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    let mut extra: Vec<(u32, [f32; 4])> = Vec::new();
    for (f, tri) in mesh.triangles.iter_mut().enumerate() {
        for (k, v) in tri.iter_mut().enumerate() {
            let t = clean(per_corner[f * 3 + k]);
            match tangents[*v as usize] {
                None => tangents[*v as usize] = Some(t),
                Some(have) if have == t => {}
                Some(_) => {
                    let key = (*v, t.map(f32::to_bits));
                    let next = (n + extra.len()) as u32;
                    let copy = *copies.entry(key).or_insert_with(|| {
                        extra.push((key.0, t));
                        next
                    });
                    *v = copy;
                }
            }
        }
    }
    let mut out: Vec<[f32; 4]> = tangents
        .into_iter()
        .map(|t| t.unwrap_or([0.0, 0.0, 0.0, 1.0]))
        .collect();
    for &(v, t) in &extra {
        let v = v as usize;
        mesh.positions.push(mesh.positions[v]);
        if let Some(normals) = &mut mesh.normals {
            normals.push(normals[v]);
        }
        if let Some(colors) = &mut mesh.colors {
            colors.push(colors[v]);
        }
        for set in mesh.uvs.iter_mut().flatten() {
            set.push(set[v]);
        }
        out.push(t);
    }
    mesh.tangents = Some(out);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_gets_its_u_axis_and_a_seam_splits() {
        // A unit quad in the xy plane facing +z, u along +x, v down (-y).
        let mut mesh = MeshData {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            uvs: [
                Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
                None,
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            materials: vec![0, 0],
            ..Default::default()
        };
        assert!(generate(&mut mesh, 0));
        let t = mesh.tangents.as_ref().expect("tangents");
        assert_eq!(t.len(), 4);
        for v in t {
            assert!((v[0] - 1.0).abs() < 1e-5 && v[1].abs() < 1e-5, "{v:?}");
            // B = w (N x T) = w (+y): up the image, where v decreases.
            assert_eq!(v[3], 1.0, "{v:?}");
        }
        // The second triangle's u runs along -x (v3 at u = 2): the corners
        // it shares with the first need other tangents.
        mesh.tangents = None;
        mesh.uvs[0] = Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [2.0, 0.0]]);
        assert!(generate(&mut mesh, 0));
        assert!(mesh.positions.len() > 4, "no vertex was split");
        assert_eq!(
            mesh.positions.len(),
            mesh.tangents.as_ref().map_or(0, Vec::len)
        );
        assert_eq!(
            mesh.positions.len(),
            mesh.uvs[0].as_ref().map_or(0, Vec::len)
        );
    }

    #[test]
    fn no_uvs_no_tangents() {
        let mut mesh = MeshData {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            materials: vec![0],
            ..Default::default()
        };
        assert!(!generate(&mut mesh, 0));
        assert!(mesh.tangents.is_none());
    }
}
