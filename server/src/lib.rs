//! pathstream: a progressive path tracer (`render`) served over HTTP
//! (`service`), and measured (`bench`); `model` reads model files (OBJ, glTF,
//! PLY). The renderer depends on neither `service` nor `bench`.

pub mod bench;
pub mod model;
pub mod render;
pub mod service;
