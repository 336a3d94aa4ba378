//! HTTP routes (contract in ../shared/design.md): `app(state)` builds the
//! whole service. Handlers parse requests into validated values at the edge
//! and hand them to the session ([`Session::apply`] for changes).

use super::auth::require_token;
use super::{assets_routes, static_files, ws};
use crate::render::backend::opencl::DeviceInfo;
use crate::render::scene::{CameraEdit, LightEdit, BUILTIN_NAMES};
use crate::render::{Preset, Quality};
use crate::service::change::Change;
use crate::service::error::{parse_json, ApiError};
use crate::service::session::{Frame, Status};
use crate::service::AppState;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{header, HeaderName, HeaderValue, StatusCode};
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, patch, put};
use axum::{Json, Router};
use pathstream_wire::{Devices, Health, OpenClDevice, Scenes};
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;
use std::time::Duration;
use tower_http::catch_panic::CatchPanicLayer;
use tower_http::cors::CorsLayer;
use tower_http::set_header::SetResponseHeaderLayer;
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
        .route("/sessions/{id}/quality", patch(patch_quality_route))
        .route("/sessions/{id}/scene", put(put_scene))
        .route("/sessions/{id}/pick", get(pick))
        .route("/sessions/{id}/environment", put(put_environment))
        .route("/sessions/{id}/frame.png", get(frame_png))
        .route("/sessions/{id}/frame.pfm", get(frame_pfm))
        .route("/sessions/{id}/samples.png", get(samples_png))
        .route("/sessions/{id}/ws", get(ws::upgrade))
        .merge(assets_routes::router(state.config.assets.max_asset_bytes))
        .fallback(api_not_found)
        .route_layer(middleware::from_fn_with_state(state.clone(), require_token))
        .layer(middleware::from_fn(super::guard::api_guard));
    let router = Router::new()
        .nest("/api", api)
        .route("/metrics", get(metrics))
        .fallback_service(static_files::router(state.config.static_dir.as_deref()));
    with_layers(router, &state).with_state(state)
}

/// The header naming the box that answered (`serve --node-name`).
pub const NODE_HEADER: &str = "x-pathstream-node";

/// The layers around every route: the body limit, handler panics answered
/// as 500 JSON (logged, counted), request traces, CORS when asked for, and
/// outermost the node's name on every response when it has one.
fn with_layers(router: Router<Arc<AppState>>, state: &Arc<AppState>) -> Router<Arc<AppState>> {
    let metrics = state.metrics.clone();
    let router = router
        .layer(DefaultBodyLimit::max(state.config.max_body_bytes))
        .layer(CatchPanicLayer::custom(move |panic| {
            super::guard::panic_response(&metrics, panic)
        }))
        .layer(TraceLayer::new_for_http());
    let router = if state.config.cors {
        router.layer(CorsLayer::permissive())
    } else {
        router
    };
    let node = state.config.node_name.as_deref().map(HeaderValue::from_str);
    match node {
        Some(Ok(value)) => router.layer(SetResponseHeaderLayer::overriding(
            HeaderName::from_static(NODE_HEADER),
            value,
        )),
        Some(Err(e)) => {
            // `AppState::new` refuses such names; `with_device` does not check.
            tracing::error!(error = %e, "the node name is not a header value; no {NODE_HEADER}");
            router
        }
        None => router,
    }
}

async fn api_not_found(req: Request) -> ApiError {
    ApiError::NotFound(format!(
        "no route for {} {}",
        req.method(),
        req.uri().path()
    ))
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

/// Liveness and load: this box's node name (null without `--node-name`),
/// its sessions, and per worker its sessions and the fraction of the last
/// 5 s it spent rendering (`"load"`, in the order of `"backends"`).
async fn health(State(state): State<Arc<AppState>>) -> Json<Health> {
    Json(Health {
        status: "ok".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        node: state.config.node_name.clone(),
        sessions: state.session_count(),
        backends: state.backends(),
        load: state.load(),
    })
}

/// The workers as they render now (after an OpenCL device failed, rayon)
/// and the OpenCL devices this machine lists.
async fn devices(State(state): State<Arc<AppState>>) -> Json<Devices> {
    let listed = crate::render::backend::opencl::list_devices();
    // The first call loads the library (off the async threads).
    let denoiser = tokio::task::spawn_blocking(crate::render::denoise::status).await;
    Json(Devices {
        backends: state.backends(),
        default: state.default_backend().backend,
        opencl_devices: (listed.as_ref().ok()).map(|l| l.iter().map(opencl_device).collect()),
        opencl_error: listed.err(),
        denoiser: denoiser.ok(),
    })
}

/// An OpenCL device as the API lists it (without the handle the renderer
/// keeps). Taken apart field by field: a field added to the renderer's
/// listing fails to compile here until the contract has it too.
fn opencl_device(d: &DeviceInfo) -> OpenClDevice {
    let DeviceInfo {
        index,
        platform,
        name,
        vendor,
        kind,
        compute_units,
        global_mem_bytes,
        max_alloc_bytes,
        fp64,
        opencl_c_version,
        correctly_rounded_divide_sqrt: _,
        device: _,
    } = d.clone();
    OpenClDevice {
        index,
        platform,
        name,
        vendor,
        kind: kind.to_owned(),
        compute_units,
        global_mem_bytes,
        max_alloc_bytes,
        fp64,
        opencl_c_version,
    }
}

async fn scenes() -> Json<Scenes> {
    Json(Scenes {
        scenes: BUILTIN_NAMES.iter().map(|&n| n.to_owned()).collect(),
    })
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
                            "filter": q.filter, "sampler": q.sampler, "clamp": q.clamp,
                            "adaptive": q.adaptive},
            })
        })
        .collect();
    Json(json!({"presets": list}))
}

async fn metrics(State(state): State<Arc<AppState>>) -> impl IntoResponse {
    let mut text = state.metrics.render(state.session_count());
    text.push_str(&crate::service::load::prometheus(&state.load()));
    ([(header::CONTENT_TYPE, "text/plain; version=0.0.4")], text)
}

async fn create_session(
    State(state): State<Arc<AppState>>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<(StatusCode, Json<Status>)> {
    let body = body_bytes(body, state.config.max_body_bytes)?;
    let session = state.create_session(parse_json(&body)?)?;
    Ok((StatusCode::CREATED, Json(session.status())))
}

async fn list_sessions(State(state): State<Arc<AppState>>) -> Json<Value> {
    let list: Vec<Status> = state.sessions().iter().map(|s| s.status()).collect();
    Json(json!({"sessions": list}))
}

async fn get_session(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
) -> AppResult<Json<Status>> {
    Ok(Json(state.session(&id)?.status()))
}

async fn delete_session(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
) -> AppResult<StatusCode> {
    state.remove_session(&id)?;
    tracing::info!(session = %id, "session deleted");
    Ok(StatusCode::NO_CONTENT)
}

/// The body of a change request parsed as `T`, made a change and applied.
async fn change<T: serde::de::DeserializeOwned>(
    state: Arc<AppState>,
    id: String,
    body: Result<Bytes, BytesRejection>,
    make: fn(T, &AppState) -> Result<Change, ApiError>,
) -> AppResult<Json<Status>> {
    let session = state.session(&id)?;
    let parsed: T = parse_json(&body_bytes(body, state.config.max_body_bytes)?)?;
    Ok(Json(session.apply(make(parsed, &state)?)?))
}

async fn patch_camera(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, |edit: CameraEdit, _| {
        Ok(Change::Camera(edit))
    })
    .await
}

async fn put_environment(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, |v: Value, state| {
        Change::environment(v, &state.scene_rules())
    })
    .await
}

async fn patch_light(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, |edit: LightEdit, _| {
        Ok(Change::Light(edit))
    })
    .await
}

async fn patch_quality_route(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, |patch: Value, _| {
        Ok(Change::Quality(patch))
    })
    .await
}

async fn put_scene(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> AppResult<Json<Status>> {
    change(state, id, body, |v, state| {
        Change::scene(v, &state.scene_rules())
    })
    .await
}

/// `?x=&y=` of `GET .../pick`: a point of the image, in pixels.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PickQuery {
    x: f64,
    y: f64,
    /// Accepted here so that `?token=` works on every route.
    #[allow(dead_code)]
    token: Option<String>,
}

/// The surface under a point of the image: `{"hit": false}`, or `{"hit":
/// true, "point": [x, y, z], "distance": d, "focus_distance": f}`.
async fn pick(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<PickQuery>, QueryRejection>,
) -> AppResult<Json<Value>> {
    let Query(q) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let session = state.session(&id)?;
    session.touch();
    Ok(Json(match session.pick(q.x, q.y)? {
        Some(p) => {
            let mut v = json!(p);
            v["hit"] = json!(true);
            v
        }
        None => json!({"hit": false}),
    }))
}

/// `?min_spp=N&timeout_ms=T` on the frame routes.
#[derive(Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameQuery {
    /// Wait until the image has at least this many samples per pixel.
    min_spp: Option<u64>,
    /// ... but no longer than this (default 30 s, at most 10 min).
    timeout_ms: Option<u64>,
    /// `1`: the denoised image, `0`: the raw one (default: as the
    /// session's `quality.denoise` says for this frame).
    denoise: Option<String>,
    /// Accepted here so that `?token=` works on every route.
    #[allow(dead_code)]
    token: Option<String>,
}

impl FrameQuery {
    const DEFAULT_TIMEOUT: Duration = Duration::from_secs(30);
    const MAX_TIMEOUT: Duration = Duration::from_secs(600);

    fn parse(query: Result<Query<FrameQuery>, QueryRejection>) -> AppResult<FrameQuery> {
        query
            .map(|Query(q)| q)
            .map_err(|e| ApiError::BadRequest(e.body_text()))
    }

    /// (samples per pixel to wait for, longest wait).
    fn wait(&self) -> (u64, Duration) {
        let timeout = self
            .timeout_ms
            .map_or(Self::DEFAULT_TIMEOUT, Duration::from_millis);
        (self.min_spp.unwrap_or(0), timeout.min(Self::MAX_TIMEOUT))
    }
}

async fn wait_frame(
    state: &AppState,
    id: &str,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<(Arc<Frame>, bool)> {
    let query = FrameQuery::parse(query)?;
    let asked = match query.denoise.as_deref() {
        None => None,
        Some("1" | "true") => Some(true),
        Some("0" | "false") => Some(false),
        Some(other) => {
            return Err(ApiError::BadRequest(format!(
                "denoise: must be 1 or 0 (got '{other}')"
            )))
        }
    };
    if asked == Some(true) {
        tokio::task::spawn_blocking(crate::render::denoise::available)
            .await
            .map_err(|e| ApiError::Internal(e.to_string()))?
            .map_err(|e| ApiError::BadRequest(format!("denoise: {e}")))?;
    }
    let (min_spp, timeout) = query.wait();
    let session = state.session(id)?;
    let frame = session.frame_with(min_spp, timeout).await?;
    let denoised = asked.unwrap_or_else(|| frame.shows_denoised());
    Ok((frame, denoised))
}

fn frame_headers(f: &Frame, denoised: bool) -> [(&'static str, String); 4] {
    [
        ("x-pathstream-denoised", denoised.to_string()),
        ("x-pathstream-spp", f.spp.to_string()),
        (
            "x-pathstream-error-estimate",
            f.error_estimate.map_or("null".into(), |e| e.to_string()),
        ),
        ("x-pathstream-generation", f.generation.to_string()),
    ]
}

async fn frame_png(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Response> {
    let (frame, denoised) = wait_frame(&state, &id, query).await?;
    let f = frame.clone();
    let png = tokio::task::spawn_blocking(move || f.png(denoised))
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))??;
    Ok((
        [(header::CONTENT_TYPE.as_str(), "image/png".to_owned())],
        frame_headers(&frame, png.denoised),
        png.bytes.to_vec(),
    )
        .into_response())
}

async fn frame_pfm(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Response> {
    let (frame, denoised) = wait_frame(&state, &id, query).await?;
    let denoised = denoised && frame.can_denoise();
    let f = frame.clone();
    let pfm = tokio::task::spawn_blocking(move || f.pfm(denoised))
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))?
        .map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok((
        [(
            header::CONTENT_TYPE.as_str(),
            "image/x-portable-floatmap".to_owned(),
        )],
        frame_headers(&frame, denoised),
        pfm,
    )
        .into_response())
}

/// Where the frame's samples went: one pixel per tile, from the fewest
/// (dark blue) to the most (yellow) on a log scale, tiles at their share of
/// the target error green (the page's overlay). Takes the frame routes'
/// `?min_spp=N&timeout_ms=T`.
async fn samples_png(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    query: Result<Query<FrameQuery>, QueryRejection>,
) -> AppResult<Response> {
    let (frame, _) = wait_frame(&state, &id, query).await?;
    // Before the first pass: every tile at 0 samples.
    let density = frame.density.clone().unwrap_or_else(|| {
        Arc::new(crate::service::density::Density::empty(
            frame.width,
            frame.height,
        ))
    });
    let png = tokio::task::spawn_blocking(move || density.png())
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))?
        .map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok((
        [(header::CONTENT_TYPE.as_str(), "image/png".to_owned())],
        frame_headers(&frame, false),
        png,
    )
        .into_response())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {

    #[tokio::test]
    async fn a_handler_panic_answers_500_json_is_counted_and_the_server_lives_on() {
        let state = AppState::with_device(crate::service::ServeConfig::default(), None);
        let router = Router::new()
            .route(
                "/api/boom",
                get(|| async { panic!("boom from input") as &'static str }),
            )
            .route("/metrics", get(metrics));
        let app = with_layers(router, &state).with_state(state.clone());
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
            .await
            .expect("bind");
        let addr = listener.local_addr().expect("addr");
        let server = tokio::spawn(async move { axum::serve(listener, app).await });
        let client = reqwest::Client::new();
        for _ in 0..2 {
            let r = client
                .get(format!("http://{addr}/api/boom"))
                .send()
                .await
                .expect("an answer, not a reset");
            assert_eq!(r.status().as_u16(), 500);
            let body: Value = r.json().await.expect("JSON");
            assert_eq!(
                body["error"], "internal error",
                "the panic's text stays in the log"
            );
        }
        let m = client
            .get(format!("http://{addr}/metrics"))
            .send()
            .await
            .expect("metrics")
            .text()
            .await
            .expect("text");
        assert!(m.contains("pathstream_handler_panics_total 2"), "{m}");
        server.abort();
        state.stop();
    }
    use super::*;
    use axum::http::Uri;

    fn query(q: &str) -> AppResult<FrameQuery> {
        let uri: Uri = format!("/api/sessions/x/frame.png{q}").parse().unwrap();
        FrameQuery::parse(Query::try_from_uri(&uri))
    }

    #[test]
    fn frame_queries_decode_with_defaults_and_a_cap() {
        assert_eq!(query("").unwrap().wait(), (0, Duration::from_secs(30)));
        assert_eq!(
            query("?min_spp=64&timeout_ms=1500").unwrap().wait(),
            (64, Duration::from_millis(1500))
        );
        assert_eq!(
            query("?timeout_ms=99999999").unwrap().wait().1,
            Duration::from_secs(600),
            "at most 10 min"
        );
        let q = query("?token=a%2Bb+c&min_spp=%31%36").unwrap();
        assert_eq!(
            (q.token.as_deref(), q.min_spp),
            (Some("a+b c"), Some(16)),
            "percent and plus decoded"
        );
    }

    #[test]
    fn bad_frame_queries_name_the_parameter() {
        for (q, needle) in [
            ("?min_spp=abc", "min_spp: invalid digit"),
            ("?min_spp=-1", "min_spp: invalid digit"),
            ("?timeout_ms=1e3", "timeout_ms: invalid digit"),
            ("?zoom=2", "unknown field `zoom`"),
        ] {
            let e = query(q).expect_err(q).to_string();
            assert!(e.contains(needle), "{q}: {e}");
        }
    }
}
