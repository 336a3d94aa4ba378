//! The renderer. It knows nothing of HTTP and reads no files: a scene, an
//! image size and quality settings go in; a film that converges comes out.
//!
//! - `scene`: validated scene model, JSON, built-in scenes
//! - `world`, `shape`, `bvh`, `ray`: the scene as the hot path sees it
//! - `camera`, `filter`, `sampler`: where camera samples go and their randomness
//! - `material`, `fresnel`, `ggx`, `light`: how surfaces scatter, what emits
//! - `texture`, `maps`: image textures and the material maps that read them
//! - `integrator`: the path tracer, next-event estimation included
//! - `adaptive`: where an adaptive render's samples go
//! - `film`, `features`, `tonemap`, `output`: accumulation, error estimate,
//!   what a denoiser is guided by, image files
//! - `denoise`: Open Image Denoise, loaded at run time
//! - `embree`: Intel Embree, loaded at run time: the CPU's mesh rays
//! - `native`: how those two libraries are loaded
//! - `quality`, `preset`, `job`, `pass`, `progressive`, `backend`: what to
//!   render, in which passes, and where
//! - `split`: one render on several devices at once
//! - `isa`: the instruction sets the CPU hot path is compiled for

pub mod adaptive;
pub mod alpha;
pub mod backend;
pub mod bvh;
pub mod camera;
pub mod denoise;
pub mod embree;
pub mod envmap;
pub mod features;
pub mod film;
pub mod filter;
pub mod fresnel;
pub mod ggx;
pub mod integrator;
pub mod isa;
pub mod job;
pub mod jpeg_strips;
pub mod lanes;
pub mod light;
pub mod maps;
pub mod material;
pub mod math;
pub mod native;
pub mod output;
pub mod pass;
pub mod pick;
pub mod png_strips;
pub mod preset;
pub mod progressive;
pub mod quality;
pub mod ray;
pub mod sampler;
pub mod scene;
pub mod shape;
pub mod sky_probe;
pub mod split;
pub mod texture;
pub mod tonemap;
pub mod world;

pub use backend::{Backend, BackendChoice, BackendError};
pub use film::Film;
pub use filter::Filter;
pub use job::RenderJob;
pub use preset::Preset;
pub use progressive::Progress;
pub use quality::Quality;
pub use scene::{Scene, SceneError};
