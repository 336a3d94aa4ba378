//! The loaders tested on generated files (no model files are committed):
//! a cube with per-face normals and two materials, written as OBJ + MTL, PLY
//! (ASCII, binary little and big endian) and glTF (`data:` URI, external
//! `.bin`, `.glb`), read back and compared exactly; malformed files; and
//! mutated files that must fail cleanly, never panic.

mod gltf;
mod gltf_variants;
mod obj;
mod ply;
mod robust;
mod textures;

use super::{detect, Format, Maps, Material, MeshData, Model};

/// Named materials without maps, as a model lists them.
pub(super) fn untextured<const N: usize>(
    m: [(&str, Material); N],
) -> Vec<(String, Material, Maps)> {
    m.into_iter()
        .map(|(n, m)| (n.to_owned(), m, Maps::default()))
        .collect()
}

/// A generated polygon mesh: positions, normals, faces with a material.
pub(super) struct Gen {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub faces: Vec<(Vec<u32>, u32)>,
}

/// A cube centred on (1, 2, 3) with edge 1: 24 vertices (4 per face, with
/// the face's normal), 6 quads counter-clockwise from outside; the four
/// side faces (±x, ±z) have material 0, top and bottom (±y) material 1.
pub(super) fn cube() -> Gen {
    let frames: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    let centre = [1.0f32, 2.0, 3.0];
    let mut g = Gen {
        positions: Vec::new(),
        normals: Vec::new(),
        faces: Vec::new(),
    };
    for (f, (n, u, v)) in frames.iter().enumerate() {
        let first = g.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            g.positions
                .push([0, 1, 2].map(|k| centre[k] + 0.5 * (n[k] + su * u[k] + sv * v[k])));
            g.normals.push(*n);
        }
        g.faces
            .push(((first..first + 4).collect(), u32::from(f >= 4)));
    }
    g
}

impl Gen {
    /// The faces fan-triangulated, with their materials.
    pub fn triangles(&self) -> (Vec<[u32; 3]>, Vec<u32>) {
        let mut tris = Vec::new();
        let mut mats = Vec::new();
        for (poly, m) in &self.faces {
            for k in 1..poly.len() - 1 {
                tris.push([poly[0], poly[k], poly[k + 1]]);
                mats.push(*m);
            }
        }
        (tris, mats)
    }

    /// The mesh a loader must return for this (vertex order kept).
    pub fn mesh(&self, name: &str, materials: &[u32]) -> MeshData {
        let (triangles, mats) = self.triangles();
        MeshData {
            name: name.to_owned(),
            positions: self.positions.clone(),
            normals: Some(self.normals.clone()),
            triangles,
            materials: mats.iter().map(|&m| materials[m as usize]).collect(),
            ..MeshData::default()
        }
    }
}

/// Checks the guarantees of the module doc on a loaded model.
pub(super) fn assert_guarantees(m: &Model) {
    assert!(!m.meshes.is_empty() && !m.instances.is_empty());
    for mesh in &m.meshes {
        assert!(
            !mesh.triangles.is_empty(),
            "mesh {} has no triangles",
            mesh.name
        );
        assert!(mesh.positions.iter().flatten().all(|x| x.is_finite()));
        assert!(mesh
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < mesh.positions.len()));
        assert_eq!(mesh.materials.len(), mesh.triangles.len());
        assert!(mesh
            .materials
            .iter()
            .all(|&i| (i as usize) < m.materials.len()));
        if let Some(n) = &mesh.normals {
            assert_eq!(n.len(), mesh.positions.len());
            for v in n {
                let l: f32 = v.iter().map(|x| x * x).sum();
                assert!((l - 1.0).abs() < 1e-5, "normal {v:?}");
            }
        }
    }
    for i in &m.instances {
        assert!(i.mesh < m.meshes.len());
        assert!(i.transform.iter().flatten().all(|x| x.is_finite()));
    }
    let names: std::collections::HashSet<_> = m.materials.iter().map(|(n, _, _)| n).collect();
    assert_eq!(names.len(), m.materials.len(), "material names are unique");
    let warnings: std::collections::HashSet<_> = m.warnings.iter().collect();
    assert_eq!(
        warnings.len(),
        m.warnings.len(),
        "warnings are deduplicated"
    );
}

/// A tiny deterministic generator (xorshift64*).
pub(super) struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn detect_reads_magic_then_extension() {
    assert_eq!(detect("a.obj", b"glTF\x02\0\0\0"), Some(Format::Glb));
    assert_eq!(detect("x", b"ply\nformat ascii 1.0\n"), Some(Format::Ply));
    assert_eq!(
        detect("x", b"ply\r\nformat ascii 1.0\r\n"),
        Some(Format::Ply)
    );
    assert_eq!(
        detect("upload", b" \n{\"asset\": {\"version\": \"2.0\"}}"),
        Some(Format::Gltf)
    );
    assert_eq!(
        detect("upload", b"\xEF\xBB\xBF{\"asset\": {}}"),
        Some(Format::Gltf)
    );
    assert_eq!(detect("M.OBJ", b"v 0 0 0"), Some(Format::Obj));
    assert_eq!(detect("m.GlTf", b"{}"), Some(Format::Gltf));
    assert_eq!(detect("m.Glb", b""), Some(Format::Glb));
    assert_eq!(detect("dir.v2/m.PLY", b""), Some(Format::Ply));
    assert_eq!(detect("m.stl", b"solid x"), None);
    assert_eq!(detect("noext", b"{\"scene\": 0}"), None);
    assert_eq!(detect("plywood", b"plywood"), None);
}

#[test]
fn unknown_and_unreadable_files_are_errors() {
    let limits = super::Limits::default();
    let e = super::load_bytes(b"solid cube\nendsolid\n", "cube.stl", &limits).expect_err("stl");
    assert_eq!(
        e.to_string(),
        "cube.stl: unknown format: expected an .obj, .gltf, .glb or .ply file"
    );
    let e =
        super::load_file(std::path::Path::new("/nonexistent/x.obj"), &limits).expect_err("missing");
    assert!(
        e.to_string()
            .starts_with("/nonexistent/x.obj: cannot read: "),
        "{e}"
    );
}
