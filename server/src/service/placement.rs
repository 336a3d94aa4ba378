//! Where sessions render: on one worker (a device) or on every worker at
//! once, and what a worker renders with.

use crate::render::Backend;

/// Where a session renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// On this worker.
    One(usize),
    /// On every worker at once (`backend: "all"`).
    All,
}

/// What a worker renders with, as `/api/health` and `/api/devices` report it.
pub use pathstream_wire::BackendInfo;

/// What `backend` renders with, as the API names it.
pub fn backend_info(backend: &Backend) -> BackendInfo {
    BackendInfo {
        backend: backend.name().to_owned(),
        device: backend.device(),
    }
}
