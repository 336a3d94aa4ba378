//! pathstream: a progressive path tracer served over HTTP, in layers that
//! each import only from those below:
//!
//! - `render`: the renderer (scene model, world, BVH, materials, lights,
//!   integrator, backends); it reads no files and knows no HTTP;
//! - `model`: model file loaders (OBJ, glTF, PLY) producing their own plain
//!   types; they know nothing of rendering;
//! - `resolve`: scenes from names and files, model files into the
//!   renderer's types;
//! - `service`: the render service (sessions and their workers, then the
//!   HTTP and WebSocket transport on top);
//! - `bench`, and the command line in the binary: tools on top of it all.

pub mod bench;
pub mod model;
pub mod render;
pub mod resolve;
pub mod service;
