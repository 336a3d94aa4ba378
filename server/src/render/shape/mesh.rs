//! Indexed triangle meshes in their own (object) space, with their BVH.
//!
//! A mesh is built once per model file (or inline data) and shared, behind
//! an `Arc`, by every placement (instance) and by every job: moving the
//! camera or a light never rebuilds it. Its triangles are stored a second
//! time in the BVH's leaf order ([`TriVerts`], 48 bytes each, the layout the
//! OpenCL kernel reads too), so that a leaf reads its triangles in sequence;
//! the indexed form stays for shading normals and materials.

pub use crate::mesh_data::MeshData;
use crate::render::bvh::{Aabb, Bvh, WideBvh, MAX_LEAF};
use crate::render::embree::{Embree, MeshScene};
use crate::render::math::Vec3A;
use crate::render::shape::{TriPack, TriVerts};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// A checked [`MeshData`] (read through `Deref`: `mesh.positions`) and
/// what is built from it once. Its `materials` has an entry per triangle
/// (the data's empty list becomes slot 0 everywhere); an instance maps the
/// slots to scene materials.
#[derive(Debug)]
pub struct Mesh {
    data: MeshData,
    /// Number of material slots (one more than the largest in `materials`).
    pub material_slots: u32,
    pub bvh: Bvh,
    /// The same hierarchy eight wide, which the CPU traverses (the kernel
    /// reads `bvh`).
    pub wide: WideBvh,
    /// The triangles in leaf-slot order.
    pub tris: Vec<TriVerts>,
    /// Each leaf's triangles packed for the CPU's four-wide test: the
    /// leaf at slot `first` is pack `first / 4` (the BVH's leaves are
    /// aligned, [`Bvh::aligned_leaves`]).
    pub packs: Vec<TriPack>,
    /// Each triangle's unit normal in object space, (v1 - v0) x (v2 - v0)
    /// normalised (zero where that has no length): what a hit's surface
    /// computed from the vertices, the same bits, one load away instead
    /// of three and a square root.
    face_normals: Vec<Vec3A>,
    /// The mesh as an Embree scene, built on first use by a CPU that
    /// traces with Embree (None: Embree refused it).
    embree: OnceLock<Option<Arc<MeshScene>>>,
}

/// Why mesh data cannot be used; the caller adds where it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("vertex {0}: position is not finite")]
    Position(usize),
    #[error("vertex {0}: normal is not finite")]
    Normal(usize),
    #[error("{0} normals for {1} vertices")]
    NormalCount(usize, usize),
    #[error("{what} of vertex {index} is not finite")]
    Attribute { what: &'static str, index: usize },
    #[error("COLOR_0 of vertex {0} is outside [0, 1]")]
    Color(usize),
    #[error("{count} {what} for {vertices} vertices")]
    AttributeCount {
        what: &'static str,
        count: usize,
        vertices: usize,
    },
    #[error("triangle {0}: vertex index {1} is out of range ({2} vertices)")]
    Index(usize, u32, usize),
    #[error("{0} material indices for {1} triangles")]
    MaterialCount(usize, usize),
    #[error("{0} triangles are more than one mesh can hold")]
    TooMany(usize),
}

impl std::ops::Deref for Mesh {
    type Target = MeshData;

    #[inline(always)]
    fn deref(&self) -> &MeshData {
        &self.data
    }
}

impl Mesh {
    /// Checks the data and builds the BVH (in parallel).
    pub fn new(mut data: MeshData) -> Result<Mesh, MeshError> {
        let MeshData {
            positions,
            normals,
            uvs,
            tangents,
            colors,
            triangles,
            ..
        } = &data;
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(i) = positions
            .iter()
            .position(|p| !p.iter().all(|x| x.is_finite()))
        {
            return Err(MeshError::Position(i));
        }
        if let Some(n) = normals {
            if n.len() != positions.len() {
                return Err(MeshError::NormalCount(n.len(), positions.len()));
            }
            if let Some(i) = n.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
                return Err(MeshError::Normal(i));
            }
        }
        let n = positions.len();
        for (what, set) in ["TEXCOORD_0", "TEXCOORD_1"].into_iter().zip(uvs) {
            if let Some(v) = set {
                attribute(what, v, n)?;
            }
        }
        if let Some(t) = tangents {
            attribute("TANGENT", t, n)?;
        }
        if let Some(c) = colors {
            attribute("COLOR_0", c, n)?;
            if let Some(index) = c
                .iter()
                .position(|c| c.iter().any(|x| !(0.0..=1.0).contains(x)))
            {
                return Err(MeshError::Color(index));
            }
        }
        for (i, t) in triangles.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&v| v as usize >= positions.len()) {
                return Err(MeshError::Index(i, bad, positions.len()));
            }
        }
        if data.materials.is_empty() {
            data.materials = vec![0; data.triangles.len()];
        }
        let (positions, triangles, materials) = (&data.positions, &data.triangles, &data.materials);
        if materials.len() != triangles.len() {
            return Err(MeshError::MaterialCount(materials.len(), triangles.len()));
        }
        let material_slots = materials.iter().copied().max().unwrap_or(0) + 1;
        let verts = |i: usize| -> [[f32; 3]; 3] { triangles[i].map(|v| positions[v as usize]) };
        let boxes: Vec<Aabb> = (0..triangles.len())
            .into_par_iter()
            .map(|i| Aabb::of_points(verts(i).map(Vec3A::from)))
            .collect();
        if boxes.len() > Bvh::MAX_PRIMS / MAX_LEAF {
            return Err(MeshError::TooMany(boxes.len()));
        }
        let (bvh, wide) = Bvh::build_pair(&boxes);
        let tris: Vec<TriVerts> = bvh
            .prims
            .par_iter()
            .map(|&p| TriVerts::new(p, verts(p as usize)))
            .collect();
        let packs = (leaf_counts(&bvh).into_par_iter().enumerate())
            .map(|(k, count)| TriPack::new(&tris, (k * MAX_LEAF) as u32, count))
            .collect();
        let face_normals = (0..triangles.len())
            .into_par_iter()
            .map(|i| {
                let v = verts(i).map(Vec3A::from);
                (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero()
            })
            .collect();
        Ok(Mesh {
            data,
            material_slots,
            bvh,
            wide,
            tris,
            packs,
            face_normals,
            embree: OnceLock::new(),
        })
    }

    /// The mesh as a scene of `embree`'s, built on first use.
    pub fn embree_scene(&self, embree: &'static Embree) -> Result<Arc<MeshScene>, String> {
        let built = self.embree.get_or_init(|| {
            embree
                .mesh(&self.positions, &self.triangles)
                .map_err(|e| tracing::warn!(mesh = %self.name, "Embree refused the mesh: {e}"))
                .ok()
                .map(Arc::new)
        });
        built
            .clone()
            .ok_or_else(|| format!("Embree refused mesh {}", self.name))
    }

    /// Asks the processor to start loading what shading triangle `i`
    /// reads (its vertices, normals and material slot), without waiting
    /// for it: a caller with a second path to shade first hides the loads'
    /// latency behind that work.
    #[inline(always)]
    pub fn prefetch_surface(&self, i: u32) {
        let Some(tri) = self.triangles.get(i as usize) else {
            return;
        };
        prefetch(self.materials.as_ptr().wrapping_add(i as usize));
        prefetch(self.face_normals.as_ptr().wrapping_add(i as usize));
        for &v in tri {
            prefetch(self.positions.as_ptr().wrapping_add(v as usize));
            if let Some(n) = &self.normals {
                prefetch(n.as_ptr().wrapping_add(v as usize));
            }
        }
    }

    /// Triangle `i`'s unit normal in object space (zero if degenerate).
    #[inline(always)]
    pub fn face_normal(&self, i: u32) -> Vec3A {
        self.face_normals[i as usize]
    }

    /// The vertices of triangle `i`.
    #[inline(always)]
    pub fn vertices(&self, i: u32) -> [Vec3A; 3] {
        self.triangles[i as usize].map(|v| Vec3A::from(self.positions[v as usize]))
    }

    /// The interpolated shading normal (not normalised) at barycentrics
    /// `b` of triangle `i`, if the mesh has normals.
    #[inline(always)]
    pub fn shading_normal(&self, i: u32, b: [f32; 3]) -> Option<Vec3A> {
        let normals = self.normals.as_ref()?;
        let [a, c, d] = self.triangles[i as usize].map(|v| Vec3A::from(normals[v as usize]));
        Some(a * b[0] + c * b[1] + d * b[2])
    }

    /// UV set `set` at barycentrics `b` of triangle `i` ((0, 0) where the
    /// mesh has no such set).
    #[inline(always)]
    pub fn uv(&self, set: usize, i: u32, b: [f32; 3]) -> [f32; 2] {
        let Some(uvs) = &self.uvs[set] else {
            return [0.0; 2];
        };
        let [p, q, r] = self.triangles[i as usize].map(|v| uvs[v as usize]);
        [
            p[0] * b[0] + q[0] * b[1] + r[0] * b[2],
            p[1] * b[0] + q[1] * b[1] + r[1] * b[2],
        ]
    }

    /// The interpolated tangent (object space, not normalised) and the sign
    /// of the first vertex's bitangent, if the mesh has tangents.
    #[inline(always)]
    pub fn tangent(&self, i: u32, b: [f32; 3]) -> Option<(Vec3A, f32)> {
        let tangents = self.tangents.as_ref()?;
        let [p, q, r] = self.triangles[i as usize].map(|v| tangents[v as usize]);
        let t = Vec3A::new(p[0], p[1], p[2]) * b[0]
            + Vec3A::new(q[0], q[1], q[2]) * b[1]
            + Vec3A::new(r[0], r[1], r[2]) * b[2];
        Some((t, if p[3] < 0.0 { -1.0 } else { 1.0 }))
    }

    /// The interpolated colour at barycentrics `b` of triangle `i`, if the
    /// mesh has colours.
    #[inline(always)]
    pub fn color(&self, i: u32, b: [f32; 3]) -> Option<Vec3A> {
        let colors = self.colors.as_ref()?;
        let [p, q, r] = self.triangles[i as usize].map(|v| Vec3A::from(colors[v as usize]));
        Some(p * b[0] + q * b[1] + r * b[2])
    }

    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds
    }

    /// Bytes held: vertices, normals, triangles, materials, the BVH and the
    /// leaf-ordered triangles.
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * 12
            + self.normals.as_ref().map_or(0, |n| n.len() * 12)
            + self
                .uvs
                .iter()
                .flatten()
                .map(|u| u.len() * 8)
                .sum::<usize>()
            + self.tangents.as_ref().map_or(0, |t| t.len() * 16)
            + self.colors.as_ref().map_or(0, |c| c.len() * 12)
            + self.triangles.len() * 16
            + self.bvh.memory_bytes()
            + self.wide.memory_bytes()
            + self.tris.len() * std::mem::size_of::<TriVerts>()
            + self.packs.len() * std::mem::size_of::<TriPack>()
            + self.face_normals.len() * std::mem::size_of::<Vec3A>()
    }
}

/// A per-vertex attribute: one finite value per vertex.
fn attribute<const N: usize>(
    what: &'static str,
    values: &[[f32; N]],
    vertices: usize,
) -> Result<(), MeshError> {
    if values.len() != vertices {
        return Err(MeshError::AttributeCount {
            what,
            count: values.len(),
            vertices,
        });
    }
    match values.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
        Some(index) => Err(MeshError::Attribute { what, index }),
        None => Ok(()),
    }
}

/// Triangles in each leaf of an aligned BVH, by leaf number.
fn leaf_counts(bvh: &Bvh) -> Vec<u32> {
    let mut counts = vec![0; bvh.prims.len() / MAX_LEAF];
    for node in &bvh.nodes {
        for (&first, &count) in node.child.iter().zip(&node.count) {
            if count > 0 {
                counts[first as usize / MAX_LEAF] = count;
            }
        }
    }
    counts
}

/// Starts loading the cache line at `p` into every level of cache (a hint:
/// no fault, whatever `p` is).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing and cannot fault.
    #[allow(unsafe_code, unused_unsafe)]
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
