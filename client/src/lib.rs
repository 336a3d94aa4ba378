//! A client for the pathstream render service: typed requests and responses
//! for every route, the frame stream as a `Stream`, and a blocking wrapper;
//! linear frames ([`Client::linear_frame`]) and the merge of several renders
//! of one image into one ([`merge`]).
//!
//! ```no_run
//! # async fn demo() -> pathstream_client::Result<()> {
//! use pathstream_client::{Client, CreateSession, SceneSpec};
//! let client = Client::new("http://127.0.0.1:8080")?;
//! let session = client
//!     .create_session(&CreateSession { scene: Some(SceneSpec::Name("cornell".into())), ..Default::default() })
//!     .await?;
//! let png = client.frame_png(&session.id, Some(64), None).await?;
//! client.delete_session(&session.id).await?;
//! # Ok(()) }
//! ```

pub mod blocking;
mod error;
mod linear;
pub mod merge;
mod stream;
mod types;

pub use error::{ClientError, Result};
pub use linear::{ImageError, LinearFrame, LinearImage};
/// The whole contract, for what the names above leave out (the stream's
/// stats and settings, error bodies).
pub use pathstream_wire as wire;
/// Linear radiance to the 8-bit sRGB of the server's `frame.png`.
pub use pathstream_wire::tonemap::srgb8;
/// What the server answers: the contract's types, shared with the server.
pub use pathstream_wire::{
    Asset, AssetList, BackendInfo, Camera, Denoise, Denoiser, DenoiserDevice, DeviceShare, Devices,
    Environment, EnvironmentMap, Health, Light, OpenClDevice, Pick, Projection, Quality, Scenes,
    SessionList, SessionStatus, SppSpread, Uploaded, WorkerLoad,
};
pub use stream::FrameStream;
pub use types::*;

use reqwest::{Method, RequestBuilder, Response};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::time::Duration;

/// An async client for one server.
#[derive(Clone, Debug)]
pub struct Client {
    base: String,
    token: Option<String>,
    http: reqwest::Client,
}

impl Client {
    /// A client for the server at `base` (e.g. `http://127.0.0.1:8080`), with
    /// a 60 s timeout per request (frame requests add their own wait).
    pub fn new(base: &str) -> Result<Self> {
        Self::with_timeout(base, Duration::from_secs(60))
    }

    pub fn with_timeout(base: &str, timeout: Duration) -> Result<Self> {
        let base = base.trim_end_matches('/').to_owned();
        if !(base.starts_with("http://") || base.starts_with("https://")) {
            return Err(ClientError::Input(format!(
                "server URL '{base}' must start with http:// or https://"
            )));
        }
        let http = reqwest::Client::builder()
            .timeout(timeout)
            .connect_timeout(Duration::from_secs(5))
            .build()
            .map_err(|e| ClientError::Input(e.to_string()))?;
        Ok(Self {
            base,
            token: None,
            http,
        })
    }

    /// Sends `Authorization: Bearer token` with every request.
    pub fn token(mut self, token: Option<String>) -> Self {
        self.token = token.filter(|t| !t.is_empty());
        self
    }

    pub fn base_url(&self) -> &str {
        &self.base
    }

    fn request(&self, method: Method, path: &str) -> RequestBuilder {
        let r = self.http.request(method, format!("{}{path}", self.base));
        match &self.token {
            Some(t) => r.bearer_auth(t),
            None => r,
        }
    }

    async fn send(&self, r: RequestBuilder) -> Result<Response> {
        let response = r.send().await.map_err(ClientError::from_reqwest)?;
        if response.status().is_success() {
            return Ok(response);
        }
        let status = response.status().as_u16();
        let text = response.text().await.unwrap_or_default();
        let message = error::message_of(text.as_bytes()).unwrap_or(text);
        Err(ClientError::Server { status, message })
    }

    async fn json<T: DeserializeOwned>(&self, r: RequestBuilder) -> Result<T> {
        let response = self.send(r).await?;
        let bytes = response.bytes().await.map_err(ClientError::from_reqwest)?;
        serde_json::from_slice(&bytes).map_err(|e| ClientError::Protocol(e.to_string()))
    }

    /// The raw JSON of a GET (the contract tests compare it with the types).
    pub async fn get_json(&self, path: &str) -> Result<serde_json::Value> {
        self.json(self.request(Method::GET, path)).await
    }

    pub async fn health(&self) -> Result<Health> {
        self.json(self.request(Method::GET, "/api/health")).await
    }

    pub async fn devices(&self) -> Result<Devices> {
        self.json(self.request(Method::GET, "/api/devices")).await
    }

    pub async fn scenes(&self) -> Result<Vec<String>> {
        Ok(self
            .json::<Scenes>(self.request(Method::GET, "/api/scenes"))
            .await?
            .scenes)
    }

    pub async fn create_session(&self, req: &CreateSession) -> Result<SessionStatus> {
        self.json(self.request(Method::POST, "/api/sessions").json(req))
            .await
    }

    pub async fn sessions(&self) -> Result<Vec<SessionStatus>> {
        Ok(self
            .json::<SessionList>(self.request(Method::GET, "/api/sessions"))
            .await?
            .sessions)
    }

    pub async fn session(&self, id: &str) -> Result<SessionStatus> {
        self.json(self.request(Method::GET, &format!("/api/sessions/{id}")))
            .await
    }

    async fn patch<B: Serialize>(&self, id: &str, what: &str, body: &B) -> Result<SessionStatus> {
        self.json(
            self.request(Method::PATCH, &format!("/api/sessions/{id}/{what}"))
                .json(body),
        )
        .await
    }

    pub async fn set_camera(&self, id: &str, patch: &CameraPatch) -> Result<SessionStatus> {
        self.patch(id, "camera", patch).await
    }

    /// The surface under pixel (`x`, `y`) of the session's image.
    pub async fn pick(&self, id: &str, x: f64, y: f64) -> Result<Pick> {
        self.json(self.request(Method::GET, &format!("/api/sessions/{id}/pick?x={x}&y={y}")))
            .await
    }

    pub async fn set_light(&self, id: &str, patch: &LightPatch) -> Result<SessionStatus> {
        self.patch(id, "light", patch).await
    }

    pub async fn set_quality(&self, id: &str, patch: &QualityPatch) -> Result<SessionStatus> {
        self.patch(id, "quality", patch).await
    }

    pub async fn set_scene(&self, id: &str, scene: &SceneSpec) -> Result<SessionStatus> {
        self.json(
            self.request(Method::PUT, &format!("/api/sessions/{id}/scene"))
                .json(scene),
        )
        .await
    }

    /// Replaces the session's environment (a colour, or a map: an uploaded
    /// asset's id or a built-in map's name).
    pub async fn set_environment(
        &self,
        id: &str,
        environment: &Environment,
    ) -> Result<SessionStatus> {
        self.json(
            self.request(Method::PUT, &format!("/api/sessions/{id}/environment"))
                .json(environment),
        )
        .await
    }

    async fn frame_response(
        &self,
        id: &str,
        kind: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Response> {
        self.frame_response_as(id, kind, (min_spp, timeout), None)
            .await
    }

    /// The frame route's response; `denoise` asks for the denoised (true)
    /// or the raw (false) image, None for what the session shows.
    async fn frame_response_as(
        &self,
        id: &str,
        kind: &str,
        (min_spp, timeout): (Option<u64>, Option<Duration>),
        denoise: Option<bool>,
    ) -> Result<Response> {
        let wait = timeout.unwrap_or(Duration::from_secs(30));
        let mut path = format!(
            "/api/sessions/{id}/frame.{kind}?timeout_ms={}",
            wait.as_millis()
        );
        if let Some(n) = min_spp {
            path.push_str(&format!("&min_spp={n}"));
        }
        if let Some(d) = denoise {
            path.push_str(if d { "&denoise=1" } else { "&denoise=0" });
        }
        let r = self
            .request(Method::GET, &path)
            .timeout(wait + Duration::from_secs(30));
        self.send(r).await
    }

    async fn frame(
        &self,
        id: &str,
        kind: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        let response = self.frame_response(id, kind, min_spp, timeout).await?;
        Ok(response
            .bytes()
            .await
            .map_err(ClientError::from_reqwest)?
            .to_vec())
    }

    /// The current image as PNG; with `min_spp`, once it has that many
    /// samples per pixel (waiting at most `timeout`, default 30 s).
    pub async fn frame_png(
        &self,
        id: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        self.frame(id, "png", min_spp, timeout).await
    }

    /// A frame as `kind` (`png` or `pfm`), denoised (`Some(true)`; a 400
    /// where the server has no denoiser), raw (`Some(false)`) or as the
    /// session's `quality.denoise` says (None).
    pub async fn frame_as(
        &self,
        id: &str,
        kind: &str,
        min_spp: Option<u64>,
        denoise: Option<bool>,
    ) -> Result<Vec<u8>> {
        let response = (self.frame_response_as(id, kind, (min_spp, None), denoise)).await?;
        let bytes = response.bytes().await.map_err(ClientError::from_reqwest)?;
        Ok(bytes.to_vec())
    }

    /// The same as linear PFM.
    pub async fn frame_pfm(
        &self,
        id: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        self.frame(id, "pfm", min_spp, timeout).await
    }

    /// The same decoded, with the samples per pixel and error estimate the
    /// server sent with it.
    pub async fn linear_frame(
        &self,
        id: &str,
        min_spp: Option<u64>,
        timeout: Option<Duration>,
    ) -> Result<LinearFrame> {
        let response = self.frame_response(id, "pfm", min_spp, timeout).await?;
        let header = |name: &str| -> Result<String> {
            let value = response.headers().get(name).and_then(|v| v.to_str().ok());
            value
                .map(str::to_owned)
                .ok_or_else(|| ClientError::Protocol(format!("frame.pfm without {name}")))
        };
        let number = |name: &str, text: &str| {
            ClientError::Protocol(format!("frame.pfm: {name} '{text}' is not a number"))
        };
        let spp_text = header("x-pathstream-spp")?;
        let spp = spp_text
            .parse()
            .map_err(|_| number("x-pathstream-spp", &spp_text))?;
        let gen_text = header("x-pathstream-generation")?;
        let generation = gen_text
            .parse()
            .map_err(|_| number("x-pathstream-generation", &gen_text))?;
        let error_text = header("x-pathstream-error-estimate")?;
        let error_estimate = match error_text.as_str() {
            "null" => None,
            t => Some(
                t.parse()
                    .map_err(|_| number("x-pathstream-error-estimate", t))?,
            ),
        };
        let bytes = response.bytes().await.map_err(ClientError::from_reqwest)?;
        let image =
            LinearImage::decode_pfm(&bytes).map_err(|e| ClientError::Protocol(e.to_string()))?;
        Ok(LinearFrame {
            image,
            spp,
            error_estimate,
            generation,
        })
    }

    /// `POST /api/assets`: uploads a model file's bytes under `name` (its
    /// extension tells the format where the bytes do not). The same bytes
    /// uploaded twice are one asset.
    pub async fn upload_asset(&self, name: &str, bytes: Vec<u8>) -> Result<Uploaded> {
        let query: String = form_urlencoded::Serializer::new(String::new())
            .append_pair("name", name)
            .finish();
        let r = self
            .request(Method::POST, &format!("/api/assets?{query}"))
            .header(reqwest::header::CONTENT_TYPE, "application/octet-stream")
            .body(bytes)
            .timeout(Duration::from_secs(600));
        self.json(r).await
    }

    pub async fn assets(&self) -> Result<AssetList> {
        self.json(self.request(Method::GET, "/api/assets")).await
    }

    pub async fn asset(&self, id: &str) -> Result<Asset> {
        self.json(self.request(Method::GET, &format!("/api/assets/{id}")))
            .await
    }

    pub async fn delete_asset(&self, id: &str) -> Result<()> {
        self.send(self.request(Method::DELETE, &format!("/api/assets/{id}")))
            .await?;
        Ok(())
    }

    pub async fn delete_session(&self, id: &str) -> Result<()> {
        self.send(self.request(Method::DELETE, &format!("/api/sessions/{id}")))
            .await?;
        Ok(())
    }

    /// The session's frame stream over its WebSocket.
    pub async fn stream(&self, id: &str) -> Result<FrameStream> {
        let ws = self.base.replacen("http", "ws", 1);
        let mut url = format!("{ws}/api/sessions/{id}/ws");
        if let Some(t) = &self.token {
            url.push_str(&format!("?token={t}"));
        }
        FrameStream::connect(&url).await
    }
}
