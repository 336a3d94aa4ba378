//! Alpha-tested quads: a quad whose material cuts it out (its `alpha`)
//! becomes an instance of one shared two-triangle mesh, the unit square
//! placed by the quad's corner and edges, so that the alpha test of mesh
//! instances (`render::alpha`, the kernel's `alpha_passes`) serves it on
//! every backend. Its UVs and tangent are the quad's own (u along
//! `edge_u`, the image upright along `edge_v`, as `World::texcoords` maps
//! a quad), so a cut-out quad shows what the quad would, minus the holes.

use crate::render::math::{DAffine3, DMat3, DVec3};
use crate::render::shape::{Mesh, MeshData};
use std::sync::{Arc, OnceLock};

/// The unit square in z = 0, (0, 0) to (1, 1), as two triangles facing +z,
/// with the quad's UVs (u = a, v = 1 - b) in both sets and +x tangents.
pub fn unit_square() -> Arc<Mesh> {
    static SQUARE: OnceLock<Arc<Mesh>> = OnceLock::new();
    SQUARE
        .get_or_init(|| {
            let ab: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            let uv: Vec<[f32; 2]> = ab.iter().map(|&[a, b]| [a, 1.0 - b]).collect();
            let data = MeshData {
                name: "quad".into(),
                positions: ab.iter().map(|&[a, b]| [a, b, 0.0]).collect(),
                normals: None,
                uvs: [Some(uv.clone()), Some(uv)],
                tangents: Some(vec![[1.0, 0.0, 0.0, 1.0]; 4]),
                colors: None,
                triangles: vec![[0, 1, 2], [0, 2, 3]],
                materials: vec![0, 0],
            };
            Arc::new(Mesh::new(data).expect("the unit square is a valid mesh"))
        })
        .clone()
}

/// world_from_object for [`unit_square`] spanning corner + s u + t v: the
/// edges as its x and y axes, their unit normal as z (a quad is never
/// degenerate, validation saw to it; the determinant is |u x v| > 0).
pub fn square_placement(corner: DVec3, edge_u: DVec3, edge_v: DVec3) -> DAffine3 {
    let normal = edge_u.cross(edge_v).normalize();
    DAffine3 {
        matrix3: DMat3::from_cols(edge_u, edge_v, normal),
        translation: corner,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_square_lands_on_the_quad_facing_its_way() {
        let (c, u, v) = (
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(0.5, 1.0, 0.0),
        );
        let m = square_placement(c, u, v);
        assert!(m.matrix3.determinant() > 0.0, "not mirrored");
        let mesh = unit_square();
        let corners: Vec<DVec3> = (mesh.positions.iter())
            .map(|p| m.transform_point3(DVec3::from_array(p.map(f64::from))))
            .collect();
        for (got, want) in corners.iter().zip([c, c + u, c + u + v, c + v]) {
            assert!((*got - want).length() < 1e-12, "{got} vs {want}");
        }
        // The first triangle's normal is the quad's (u x v).
        let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        assert!(n.normalize().dot(u.cross(v).normalize()) > 0.999_999);
        // UVs: (a, 1 - b) at each corner, both sets.
        let uv = mesh.uvs[0].as_ref().expect("uv");
        assert_eq!(uv, &vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
        assert_eq!(mesh.uvs[0], mesh.uvs[1]);
    }
}
