//! pathstream: a progressive path tracer (`render`) served over HTTP
//! (`service`), and measured (`bench`). The renderer depends on neither.

pub mod bench;
pub mod render;
pub mod service;
