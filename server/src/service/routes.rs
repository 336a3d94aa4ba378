//! HTTP routes (contract in ../shared/design.md) and the token check.

use super::error::{parse_json, ApiError};
use super::session::{Session, Status};
use super::updates::{apply_camera, apply_light, apply_quality, parse_scene, CameraPatch, LightPatch};
use super::{ws, AppState};
use crate::render::job::check_size;
use crate::render::scene::BUILTIN_NAMES;
use crate::render::{Preset, Quality};
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, patch, put};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;
use std::time::Duration;
use subtle::ConstantTimeEq;
use tower_http::cors::CorsLayer;
use tower_http::trace::TraceLayer;

type AppResult<T> = Result<T, ApiError>;

/// The whole service: API, WebSocket, metrics and the browser client.
pub fn app(state: Arc<AppState>) -> Router {
    let api = Router::new()
        .route("/health", get(health))
        .route("/devices", get(devices))
        .route("/scenes", get(scenes))
        .route("/presets", get(presets))
        .route("/sessions", get(list_sessions).post(create_session))
        .route("/sessions/{id}", get(get_session).delete(delete_session))
        .route("/sessions/{id}/camera", patch(patch_camera))
        .route("/sessions/{id}/light", patch(patch_light))
        .route("/sessions/{id}/quality", patch(patch_quality))
        .route("/sessions/{id}/scene", put(put_scene))
        .route("/sessions/{id}/frame.png", get(frame_png))
        .route("/sessions/{id}/frame.pfm", get(frame_pfm))
        .route("/sessions/{id}/ws", get(ws::upgrade))
        .fallback(api_not_found)
        .route_layer(middleware::from_fn_with_state(state.clone(), require_token));
    let mut router = Router::new()
        .nest("/api", api)
        .route("/metrics", get(metrics))
        .route("/", get(|State(s): State<Arc<AppState>>| static_file(s, "index.html")))
        .route("/app.js", get(|State(s): State<Arc<AppState>>| static_file(s, "app.js")))
        .route("/style.css", get(|State(s): State<Arc<AppState>>| static_file(s, "style.css")))
        .fallback(api_not_found)
        .layer(DefaultBodyLimit::max(state.config.max_body_bytes))
        .layer(TraceLayer::new_for_http());
    if state.config.cors {
        router = router.layer(CorsLayer::permissive());
    }
    router.with_state(state)
}

/// One of the client's three files: built in, or read from `static_dir`.
async fn static_file(state: Arc<AppState>, name: &'static str) -> Response {
    let (built_in, mime) = match name {
        "index.html" => (include_str!("../../../static/index.html"), "text/html; charset=utf-8"),
        "app.js" => (include_str!("../../../static/app.js"), "text/javascript; charset=utf-8"),
        _ => (include_str!("../../../static/style.css"), "text/css; charset=utf-8"),
    };
    let body = match &state.config.static_dir {
        Some(dir) => match tokio::fs::read_to_string(dir.join(name)).await {
            Ok(text) => text,
            Err(e) => return ApiError::NotFound(format!("{name}: {e}")).into_response(),
        },
        None => built_in.to_owned(),
    };
    ([(header::CONTENT_TYPE, mime), (header::CACHE_CONTROL, "no-cache")], body).into_response()
}

async fn api_not_found(req: Request) -> ApiError {
    ApiError::NotFound(format!("no route for {} {}", req.method(), req.uri().path()))
}

/// Bearer token on every /api route: `Authorization: Bearer T`, or `?token=T`
/// (browsers cannot set headers on WebSockets). Compared in constant time.
async fn require_token(State(state): State<Arc<AppState>>, req: Request, next: Next) -> Response {
    let Some(expected) = &state.config.token else {
        return next.run(req).await;
    };
    let from_header = req
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::to_owned);
    let from_query = req.uri().query().and_then(|q| {
        form_pairs(q).find(|(k, _)| k == "token").map(|(_, v)| v)
    });
    let ok = from_header
        .or(from_query)
        .is_some_and(|given| bool::from(given.as_bytes().ct_eq(expected.as_bytes())));
    if ok {
        next.run(req).await
    } else {
        ApiError::Unauthorized.into_response()
    }
}

fn form_pairs(query: &str) -> impl Iterator<Item = (String, String)> + '_ {
    query.split('&').filter_map(|pair| {
        let (k, v) = pair.split_once('=')?;
        Some((k.to_owned(), percent_decode(v)))
    })
}

fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' if i + 2 < bytes.len() => {
                match u8::from_str_radix(&s[i + 1..i + 3], 16) {
                    Ok(b) => {
                        out.push(b);
                        i += 3;
                        continue;
                    }
                    Err(_) => out.push(b'%'),
                }
            }
            b'+' => out.push(b' '),
            b => out.push(b),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn body_bytes(body: Result<Bytes, BytesRejection>, limit: usize) -> AppResult<Bytes> {
    body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::TooLarge(limit)
        } else {
            ApiError::BadRequest(e.body_text())
        }
    })
}

async fn health(State(state): State<Arc<AppState>>) -> Json<Value> {
    Json(json!({
        "status": "ok",
        "version": env!("CARGO_PKG_VERSION"),
        "sessions": state.session_count(),
        "backends": state.worker_info.iter().map(|(b, d)| json!({"backend": b, "device": d})).collect::<Vec<_>>(),
    }))
}

async fn devices(State(state): State<Arc<AppState>>) -> Json<Value> {
    let listed = crate::render::backend::opencl::list_devices();
    Json(json!({
        "backends": state.worker_info.iter().map(|(b, d)| json!({"backend": b, "device": d})).collect::<Vec<_>>(),
        "default": state.worker_info[state.default_worker].0,
        "opencl_devices": listed.as_ref().ok(),
        "opencl_error": listed.as_ref().err(),
    }))
}

async fn scenes() -> Json<Value> {
    Json(json!({"scenes": BUILTIN_NAMES}))
}

/// The quality presets: name, what it is for, and the settings it applies.
async fn presets() -> Json<Value> {
    let list: Vec<Value> = Preset::ALL
        .iter()
        .map(|p| {
            let q = p.apply(Quality::default());
            json!({
                "name": p.name(),
                "description": p.description(),
                "quality": {"max_depth": q.max_depth, "rr_depth": q.rr_depth, "nee": q.nee,
                            "filter": q.filter, "clamp": q.clamp},
            })
        })
        .collect();
    Json(json!({"presets": list}))
}

async fn metrics(State(state): State<Arc<AppState>>) -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "text/plain; version=0.0.4")],
        state.metrics.render(state.session_count()),
    )
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CreateSession {
    #[serde(default = "default_scene")]
    scene: Value,
    #[serde(default = "default_side")]
    width: u64,
    #[serde(default = "default_side")]
    height: u64,
    #[serde(default)]
    quality: Option<Value>,
    #[serde(default)]
    backend: Option<String>,
}

fn default_scene() -> Value {
    Value::String("cornell-glass".into())
}

fn default_side() -> u64 {
    512
}

fn new_id() -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let id = crate::render::sampler::mix64(nanos ^ crate::render::sampler::mix64(n ^ u64::from(std::process::id())));
    format!("{id:016x}")
}

async fn create_session(
    State(state): State<Arc<AppState>>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<(StatusCode, Json<Status>)> {
    let body = body_bytes(body, state.config.max_body_bytes)?;
    let req: CreateSession = parse_json(&body)?;
    let (width, height) = (
        u32::try_from(req.width).map_err(|_| ApiError::BadRequest(format!("width: {} is too large", req.width)))?,
        u32::try_from(req.height).map_err(|_| ApiError::BadRequest(format!("height: {} is too large", req.height)))?,
    );
    check_size(width, height).map_err(ApiError::BadRequest)?;
    let pixels = u64::from(width) * u64::from(height);
    if pixels > state.config.max_pixels {
        return Err(ApiError::BadRequest(format!(
            "width x height: {pixels} pixels is more than this server's limit of {}",
            state.config.max_pixels
        )));
    }
    let quality = match &req.quality {
        Some(q) => apply_quality(&Quality::default(), q)?,
        None => Quality::default(),
    };
    let (name, scene) = parse_scene(req.scene)?;
    let worker = state.worker_for(req.backend.as_deref())?;
    let session = Arc::new(Session::new(new_id(), name, scene, width, height, quality, state.worker_info(worker)));
    state.add_session(session.clone(), worker)?;
    tracing::info!(session = %session.id, width, height, "session created");
    Ok((StatusCode::CREATED, Json(session.status())))
}

async fn list_sessions(State(state): State<Arc<AppState>>) -> Json<Value> {
    let list: Vec<Status> = state.sessions().iter().map(|s| s.status()).collect();
    Json(json!({"sessions": list}))
}

async fn get_session(State(state): State<Arc<AppState>>, Path(id): Path<String>) -> AppResult<Json<Status>> {
    Ok(Json(state.session(&id)?.status()))
}

async fn delete_session(State(state): State<Arc<AppState>>, Path(id): Path<String>) -> AppResult<StatusCode> {
    state.remove_session(&id)?;
    tracing::info!(session = %id, "session deleted");
    Ok(StatusCode::NO_CONTENT)
}

/// The changes a client can make, over HTTP or the WebSocket.
pub enum Change {
    Camera(CameraPatch),
    Light(LightPatch),
    Quality(Value),
    Scene(Value),
}

/// Applies a change and wakes the session's worker; the status after it.
pub fn apply_change(state: &AppState, session: &Session, change: Change) -> AppResult<Status> {
    session.change(|st| match change {
        Change::Camera(p) => Ok((Some((st.scene_name.clone(), apply_camera(&st.scene, &p)?)), None)),
        Change::Light(p) => Ok((Some((st.scene_name.clone(), apply_light(&st.scene, &p)?)), None)),
        Change::Quality(q) => Ok((None, Some(apply_quality(&st.quality, &q)?))),
        Change::Scene(v) => Ok((Some(parse_scene(v)?), None)),
    })?;
    state.wake(&session.id);
    Ok(session.status())
}

/// The body of a change request parsed as `T`, turned into a change and applied.
async fn change<T: serde::de::DeserializeOwned>(
    state: Arc<AppState>,
    id: String,
    body: Result<Bytes, BytesRejection>,
    make: fn(T) -> Change,
) -> AppResult<Json<Status>> {
    let session = state.session(&id)?;
    let parsed: T = parse_json(&body_bytes(body, state.config.max_body_bytes)?)?;
    Ok(Json(apply_change(&state, &session, make(parsed))?))
}

async fn patch_camera(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, Change::Camera).await
}

async fn patch_light(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, Change::Light).await
}

async fn patch_quality(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, Change::Quality).await
}

async fn put_scene(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, Change::Scene).await
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameQuery {
    /// Wait until the image has at least this many samples per pixel.
    min_spp: Option<u64>,
    /// ... but no longer than this (default 30 s, at most 10 min).
    timeout_ms: Option<u64>,
    /// Accepted here so that `?token=` works on every route.
    #[allow(dead_code)]
    token: Option<String>,
}

async fn wait_frame(
    state: &AppState,
    id: &str,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Arc<super::session::Frame>> {
    let Query(q) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let session = state.session(id)?;
    let timeout = Duration::from_millis(q.timeout_ms.unwrap_or(30_000).min(600_000));
    Ok(session.frame_with(q.min_spp.unwrap_or(0), timeout).await)
}

fn frame_headers(f: &super::session::Frame) -> [(&'static str, String); 3] {
    [
        ("x-pathstream-spp", f.spp.to_string()),
        ("x-pathstream-error-estimate", f.error_estimate.map_or("null".into(), |e| e.to_string())),
        ("x-pathstream-generation", f.generation.to_string()),
    ]
}

async fn frame_png(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Response> {
    let frame = wait_frame(&state, &id, query).await?;
    let f = frame.clone();
    let png = tokio::task::spawn_blocking(move || f.png().map(<[u8]>::to_vec))
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))??;
    Ok(([(header::CONTENT_TYPE.as_str(), "image/png".to_owned())], frame_headers(&frame), png).into_response())
}

async fn frame_pfm(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Response> {
    let frame = wait_frame(&state, &id, query).await?;
    let f = frame.clone();
    let pfm = tokio::task::spawn_blocking(move || f.pfm())
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok((
        [(header::CONTENT_TYPE.as_str(), "image/x-portable-floatmap".to_owned())],
        frame_headers(&frame),
        pfm,
    )
        .into_response())
}
