//! The same client for code without an async runtime: every call blocks.

use crate::error::{ClientError, Result};
use crate::types::*;
use pathstream_wire::{Asset, AssetList, Devices, Health, SessionStatus, Uploaded};
use std::time::Duration;

/// A blocking client (it owns a small single-threaded runtime).
pub struct Client {
    inner: crate::Client,
    runtime: tokio::runtime::Runtime,
}

impl Client {
    pub fn new(base: &str) -> Result<Self> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| ClientError::Input(e.to_string()))?;
        Ok(Self {
            inner: crate::Client::new(base)?,
            runtime,
        })
    }

    pub fn token(mut self, token: Option<String>) -> Self {
        self.inner = self.inner.token(token);
        self
    }

    pub fn health(&self) -> Result<Health> {
        self.runtime.block_on(self.inner.health())
    }

    pub fn devices(&self) -> Result<Devices> {
        self.runtime.block_on(self.inner.devices())
    }

    pub fn scenes(&self) -> Result<Vec<String>> {
        self.runtime.block_on(self.inner.scenes())
    }

    pub fn create_session(&self, req: &CreateSession) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.create_session(req))
    }

    pub fn sessions(&self) -> Result<Vec<SessionStatus>> {
        self.runtime.block_on(self.inner.sessions())
    }

    pub fn session(&self, id: &str) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.session(id))
    }

    pub fn set_camera(&self, id: &str, patch: &CameraPatch) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.set_camera(id, patch))
    }

    /// The surface under pixel (`x`, `y`) of the session's image.
    pub fn pick(&self, id: &str, x: f64, y: f64) -> Result<crate::Pick> {
        self.runtime.block_on(self.inner.pick(id, x, y))
    }

    /// Replaces the session's environment.
    pub fn set_environment(
        &self,
        id: &str,
        environment: &crate::Environment,
    ) -> Result<SessionStatus> {
        self.runtime
            .block_on(self.inner.set_environment(id, environment))
    }

    pub fn set_light(&self, id: &str, patch: &LightPatch) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.set_light(id, patch))
    }

    pub fn set_quality(&self, id: &str, patch: &QualityPatch) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.set_quality(id, patch))
    }

    pub fn set_scene(&self, id: &str, scene: &SceneSpec) -> Result<SessionStatus> {
        self.runtime.block_on(self.inner.set_scene(id, scene))
    }

    pub fn frame_png(
        &self,
        id: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        self.runtime
            .block_on(self.inner.frame_png(id, min_spp, timeout))
    }

    pub fn frame_pfm(
        &self,
        id: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        self.runtime
            .block_on(self.inner.frame_pfm(id, min_spp, timeout))
    }

    pub fn delete_session(&self, id: &str) -> Result<()> {
        self.runtime.block_on(self.inner.delete_session(id))
    }

    pub fn upload_asset(&self, name: &str, bytes: Vec<u8>) -> Result<Uploaded> {
        self.runtime.block_on(self.inner.upload_asset(name, bytes))
    }

    pub fn assets(&self) -> Result<AssetList> {
        self.runtime.block_on(self.inner.assets())
    }

    pub fn asset(&self, id: &str) -> Result<Asset> {
        self.runtime.block_on(self.inner.asset(id))
    }

    pub fn delete_asset(&self, id: &str) -> Result<()> {
        self.runtime.block_on(self.inner.delete_asset(id))
    }
}
