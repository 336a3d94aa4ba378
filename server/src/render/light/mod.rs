//! Emitters as next-event estimation sees them: each samples a direction
//! towards itself from a receiving point, with its pdf; [`Lights`] lists
//! them with a table that picks one in proportion to its power.
//! Lights know nothing of the scene's intersection: the integrator traces
//! the shadow rays (`render::integrator::nee`). An environment map as a
//! light is in `sky` (its image and tables in `render::envmap`).

mod emitter;
pub mod pick;
pub mod points;
pub mod sky;

pub use emitter::{Emitter, EmitterShape, LightTri, Lights, Receiver, SunLight};
pub use pick::PickTable;
pub use sky::EnvLight;
