//! pathstream: a progressive path tracer (`render`) served over HTTP
//! (`service`). The renderer does not depend on the service.

pub mod render;
pub mod service;
