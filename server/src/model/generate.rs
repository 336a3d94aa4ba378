//! Meshes made in code, for tests and benchmarks: closed, indexed (every
//! edge shared by exactly two triangles, consistently wound outwards),
//! except [`uv_sphere`], which is made for textures.

use super::MeshData;
use std::collections::HashMap;

/// A unit icosahedron subdivided `levels` times (20 * 4^levels triangles),
/// its vertices on the unit sphere, with the sphere's normals.
pub fn icosphere(levels: u32) -> MeshData {
    let t = (1.0 + 5.0f64.sqrt()) / 2.0;
    let mut positions: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalized(p))
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push(normalized([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions: Vec<[f32; 3]> = positions.iter().map(|p| p.map(|x| x as f32)).collect();
    MeshData {
        name: format!("icosphere-{levels}"),
        normals: Some(positions.clone()),
        materials: vec![0; triangles.len()],
        positions,
        triangles,
        ..MeshData::default()
    }
}

/// A closed, bumpy sphere of about `triangles` triangles (a UV sphere whose
/// radius varies smoothly with latitude and longitude), without normals:
/// a stand-in for a scanned model in benchmarks.
pub fn bumpy_sphere(triangles: usize) -> MeshData {
    // A UV grid of n x 2n quads, 2 triangles each, minus the poles' halves.
    let n = ((triangles as f64 / 4.0).sqrt().round() as usize).max(3);
    let (rings, segments) = (n, 2 * n);
    let radius = |theta: f64, phi: f64| {
        1.0 + 0.15 * (5.0 * theta).sin() * (7.0 * phi).cos()
            + 0.05 * (23.0 * phi + 3.0 * theta).sin()
    };
    let mut positions = vec![[0.0f32, 1.0 * radius(0.0, 0.0) as f32, 0.0]];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let r = radius(theta, phi);
            positions.push([
                (r * theta.sin() * phi.cos()) as f32,
                (r * theta.cos()) as f32,
                (r * theta.sin() * phi.sin()) as f32,
            ]);
        }
    }
    positions.push([0.0, -(radius(std::f64::consts::PI, 0.0) as f32), 0.0]);
    let south = positions.len() as u32 - 1;
    let at = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let mut tris = Vec::new();
    for j in 0..segments {
        tris.push([0, at(1, j + 1), at(1, j)]);
        tris.push([south, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    MeshData {
        name: format!("bumpy-sphere-{}", tris.len()),
        positions,
        normals: None,
        materials: vec![0; tris.len()],
        triangles: tris,
        ..MeshData::default()
    }
}

/// A unit sphere of `rows` latitude bands and `cols` longitude segments
/// with a sphere object's texture mapping (u = 0.5 facing +z, v = 0 at the
/// top, as `World::texcoords` maps one), its normals, and tangents along
/// +u (sign +1): a textured ball. Not closed in the index sense: the seam's
/// vertices are doubled (u = 0 and u = 1), each pole is a row of vertices,
/// and the triangles that would be degenerate there are left out.
pub fn uv_sphere(rows: u32, cols: u32) -> MeshData {
    let (rows, cols) = (rows.max(2), cols.max(3));
    let (mut positions, mut uvs, mut tangents) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=rows {
        let v = f64::from(i) / f64::from(rows);
        let (st, ct) = (std::f64::consts::PI * v).sin_cos();
        for j in 0..=cols {
            let u = f64::from(j) / f64::from(cols);
            let (sp, cp) = (std::f64::consts::TAU * (u - 0.5)).sin_cos();
            positions.push([st * sp, ct, st * cp].map(|x| x as f32));
            uvs.push([u as f32, v as f32]);
            tangents.push([cp as f32, 0.0, -sp as f32, 1.0]);
        }
    }
    let at = |i: u32, j: u32| i * (cols + 1) + j;
    let mut triangles = Vec::new();
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            if i + 1 < rows {
                triangles.push([a, d, c]);
            }
            if i > 0 {
                triangles.push([a, c, b]);
            }
        }
    }
    MeshData {
        name: "uv-sphere".into(),
        normals: Some(positions.clone()),
        positions,
        uvs: [Some(uvs), None],
        tangents: Some(tangents),
        colors: None,
        materials: vec![0; triangles.len()],
        triangles,
    }
}

fn normalized(p: [f64; 3]) -> [f64; 3] {
    let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    p.map(|x| x / l)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The (unnormalised) normal of triangle `t` by its winding.
    fn face_normal(m: &MeshData, t: &[u32; 3]) -> [f64; 3] {
        let [a, b, c] = t.map(|i| m.positions[i as usize].map(f64::from));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    }

    /// Every edge is shared by exactly two triangles, in opposite directions.
    fn assert_closed(m: &MeshData) {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                assert_ne!(a, b, "degenerate triangle {t:?}");
                *edges.entry((a, b)).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    #[test]
    fn icosphere_is_closed_and_on_the_unit_sphere() {
        let m = icosphere(3);
        assert_eq!(m.triangles.len(), 20 * 64);
        assert_eq!(m.positions.len(), 10 * 64 + 2);
        assert_closed(&m);
        for p in &m.positions {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((l - 1.0).abs() < 1e-6);
        }
        // Wound outwards: each face normal points away from the centre.
        for t in &m.triangles {
            let (n, a) = (
                face_normal(&m, t),
                m.positions[t[0] as usize].map(f64::from),
            );
            assert!(n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0.0);
        }
    }

    #[test]
    fn uv_sphere_maps_as_a_sphere_object_and_faces_out() {
        let m = uv_sphere(8, 16);
        assert_eq!(m.triangles.len(), 2 * 16 * (8 - 1));
        let uv = m.uvs[0].as_ref().expect("uvs");
        let t = m.tangents.as_ref().expect("tangents");
        for (k, p) in m.positions.iter().enumerate() {
            let p = p.map(f64::from);
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((l - 1.0).abs() < 1e-6);
            // World::texcoords' sphere mapping, away from the seam and poles.
            let [u, v] = uv[k].map(f64::from);
            if p[1].abs() < 0.999 && u > 1e-6 && u < 1.0 - 1e-6 {
                let want_u = 0.5 + p[0].atan2(p[2]) / std::f64::consts::TAU;
                assert!((u - want_u).abs() < 1e-6, "u {u} vs {want_u}");
            }
            assert!((v - p[1].clamp(-1.0, 1.0).acos() / std::f64::consts::PI).abs() < 1e-6);
            // The tangent is along +u: perpendicular to the normal, (z, 0, -x).
            let dot = t[k][0] as f64 * p[0] + t[k][2] as f64 * p[2];
            assert!(dot.abs() < 1e-6 && t[k][1] == 0.0);
        }
        for tri in &m.triangles {
            let n = face_normal(&m, tri);
            let [a, b, c] = tri.map(|i| m.positions[i as usize].map(f64::from));
            let centre = [0, 1, 2].map(|k| a[k] + b[k] + c[k]);
            assert!(
                n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] > 0.0,
                "{tri:?}"
            );
        }
    }

    #[test]
    fn bumpy_sphere_is_closed_and_about_the_size_asked() {
        let m = bumpy_sphere(10_000);
        assert_closed(&m);
        assert!(
            (9_000..11_000).contains(&m.triangles.len()),
            "{}",
            m.triangles.len()
        );
    }
}
