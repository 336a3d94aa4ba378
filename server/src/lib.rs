//! pathstream: a progressive path tracer (`render`) served over HTTP.

pub mod render;
