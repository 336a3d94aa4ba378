//! Shapes in the hot path's form (camera-relative f32; meshes in their own
//! object space), one file each, and the sphere batches that test several
//! spheres at once.

mod mesh;
mod quad;
mod sphere;
mod sphere_batch;
#[cfg(target_arch = "x86_64")]
mod sphere_batch_avx2;
mod tri_pack;
mod triangle;

pub use mesh::{Mesh, MeshData, MeshError};
pub use quad::Quad;
pub use sphere::{Roots, Sphere};
pub use sphere_batch::{Leaving, SphereBatch, LANES as SPHERE_BATCH_LANES};
#[cfg(target_arch = "x86_64")]
pub use sphere_batch_avx2::nearest as nearest_sphere_avx2;
pub use tri_pack::{PackHits, TriPack};
pub use triangle::{hit_point, TriRay, TriVerts};
