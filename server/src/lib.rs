//! pathstream: a progressive path tracer served over HTTP, in layers that
//! each import only from those below:
//!
//! - `mesh_data`: a triangle mesh's arrays, the one plain type the two
//!   layers above it share;
//! - `render`: the renderer (scene model, world, BVH, materials, lights,
//!   integrator, backends); it reads no files and knows no HTTP;
//! - `model`: model file loaders (OBJ, glTF, PLY) producing their own plain
//!   types; they know nothing of rendering;
//! - `resolve`: scenes from names and files, model files into the
//!   renderer's types;
//! - `service`: the render service's core: sessions, their workers and
//!   passes, frames, changes, assets;
//! - `api`: its transport: HTTP routes, the WebSocket stream and its
//!   encodings, auth, limits, the static browser client; `api::start`;
//! - `bench`, and the command line in the binary: tools on top of it all.

pub mod api;
pub mod bench;
pub mod material_maps;
pub mod mesh_data;
pub mod model;
pub mod render;
pub mod resolve;
pub mod service;
