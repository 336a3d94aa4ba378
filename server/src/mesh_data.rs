//! A triangle mesh's arrays as they arrive, from a model file or inline
//! scene JSON: what the loaders (`model`) produce and the renderer
//! (`render::shape::Mesh::new`, which checks them) consumes, written once
//! below both.

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex unit shading normals (same length as `positions`), if any.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per-vertex texture coordinates, sets 0 and 1 (glTF's TEXCOORD_n; UV
    /// origin top left).
    pub uvs: [Option<Vec<[f32; 2]>>; 2],
    /// Per-vertex tangents, w the bitangent's sign (glTF's TANGENT), given
    /// or generated.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// Per-vertex linear RGB colours in [0, 1] (glTF's COLOR_0, PLY's
    /// red/green/blue), which multiply the material's base colour.
    pub colors: Option<Vec<[f32; 3]>>,
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: the mesh's material slot, an index into the model's
    /// materials (empty: slot 0 everywhere).
    pub materials: Vec<u32>,
}
