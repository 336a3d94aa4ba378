//! Shapes in the hot path's form (camera-relative f32), one file each.

mod quad;
mod sphere;
mod sphere_batch;

pub use quad::Quad;
pub use sphere::{Roots, Sphere};
pub use sphere_batch::SphereBatch;
