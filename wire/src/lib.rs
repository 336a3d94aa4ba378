//! The JSON contract of the pathstream API: the bodies the server sends and
//! the client reads (a session's status, the health and device listings,
//! assets, the stream's settings and its stats, error bodies), as serde
//! types. Both the server (`pathstream`) and the client
//! (`pathstream-client`) depend on this crate, so the two cannot drift
//! apart, and the client needs nothing of the server.
//!
//! Besides the JSON, what both sides must compute alike: the linear PFM
//! body of `frame.pfm` ([`pfm`]), the sRGB tone map that makes `frame.png`
//! of it ([`tonemap`]), and the relative error measure that the status's
//! `error_estimate` reports ([`error_estimate`]).
//!
//! Types that the server also reads here (the stream settings) validate
//! themselves with the server's messages; the rest are plain data, with
//! `#[serde(default)]` where a field came later, so that a client still
//! reads an older server.
#![warn(missing_docs)]

pub mod asset;
pub mod error;
pub mod error_estimate;
pub mod health;
pub mod pfm;
pub mod sky;
pub mod status;
pub mod stream;
pub mod tonemap;

pub use asset::{is_environment_name, Asset, AssetList, Uploaded};
pub use error::ErrorBody;
pub use health::{
    BackendInfo, Denoiser, DenoiserDevice, Devices, Health, OpenClDevice, Scenes, WorkerLoad,
};
pub use sky::Sky;
pub use status::{
    Camera, Denoise, DeviceShare, Environment, EnvironmentMap, Light, Pick, Projection, Quality,
    SessionList, SessionStatus, SppSpread,
};
pub use stream::{Stats, StreamError, StreamFormat, StreamMessage, StreamRequest, StreamSettings};
