//! Where sessions render: on one worker (a device) or on every worker at
//! once, and what a worker renders with.

use crate::render::Backend;
use serde::Serialize;

/// Where a session renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// On this worker.
    One(usize),
    /// On every worker at once (`backend: "all"`).
    All,
}

/// What a worker renders with, as `/api/health` and `/api/devices` report it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BackendInfo {
    /// `cpu` or `opencl`.
    pub backend: String,
    pub device: String,
}

impl BackendInfo {
    pub fn of(backend: &Backend) -> Self {
        Self {
            backend: backend.name().to_owned(),
            device: backend.device(),
        }
    }
}
