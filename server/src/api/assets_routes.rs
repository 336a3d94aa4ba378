//! `/api/assets`: upload model files once, refer to them from scenes.
//!
//! ```text
//! POST   /api/assets?name=bunny.ply   body: the file's bytes
//!          -> 201 {"id": "<sha-256>", "name", "format", "bytes", "memory_bytes",
//!                  "triangles", "meshes", "instances", "materials", "has_camera",
//!                  "warnings": [...], "deduplicated": false}
//!             (200 and "deduplicated": true when these bytes were uploaded before)
//! GET    /api/assets                  {"assets": [...], "memory_bytes", "memory_limit_bytes"}
//! GET    /api/assets/{id}             one asset
//! DELETE /api/assets/{id}             204; sessions using it keep rendering it
//! GET    /api/environments            {"maps": [{"id", "name"}]}: the maps built
//!                                     into the server, usable as "environment":
//!                                     {"map": ID or NAME} without an upload
//! ```
//! An upload larger than `--max-asset-bytes` is refused from its
//! `Content-Length` before the body is read (413). A file that is not a
//! model, or a malformed one, is a 400 whose message names the file and
//! the problem; a full store is a 507.

use crate::service::assets::{AssetError, AssetInfo};
use crate::service::ApiError;
use crate::service::AppState;
use axum::extract::rejection::QueryRejection;
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{header, StatusCode};
use axum::routing::get;
use axum::{Json, Router};
use pathstream_wire::{AssetList, Uploaded};
use serde::Deserialize;
use std::sync::Arc;

type AppResult<T> = Result<T, ApiError>;

/// The routes, with the body limit of uploads (`max_bytes`) on `POST`.
pub fn router(max_bytes: usize) -> Router<Arc<AppState>> {
    Router::new()
        .route(
            "/assets",
            get(list)
                .post(upload)
                .layer(DefaultBodyLimit::max(max_bytes.saturating_add(1))),
        )
        .route("/assets/{id}", get(one).delete(remove))
        .route("/environments", get(environments))
}

/// The environment maps built into the server.
async fn environments() -> Json<serde_json::Value> {
    let maps: Vec<_> = crate::resolve::builtin_maps()
        .iter()
        .map(|m| serde_json::json!({"id": m.id, "name": m.name}))
        .collect();
    Json(serde_json::json!({"maps": maps}))
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct UploadQuery {
    /// The file's name (its extension tells the format when the bytes do not).
    name: Option<String>,
}

async fn upload(
    State(state): State<Arc<AppState>>,
    query: Result<Query<UploadQuery>, QueryRejection>,
    request: Request,
) -> AppResult<(StatusCode, Json<Uploaded>)> {
    let Query(query) =
        query.map_err(|e| ApiError::BadRequest(format!("query: {}", e.body_text())))?;
    let limit = state.assets.limits.max_asset_bytes;
    let declared = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    if declared.is_some_and(|n| n > limit as u64) {
        return Err(ApiError::TooLarge(limit));
    }
    let bytes = axum::body::to_bytes(request.into_body(), limit)
        .await
        .map_err(|_| ApiError::TooLarge(limit))?;
    if bytes.is_empty() {
        return Err(ApiError::BadRequest(
            "body: empty; send the model file's bytes".into(),
        ));
    }
    let name = query.name.unwrap_or_default();
    let worker = state.clone();
    // Reading a model and building its BVH takes a while: off the runtime.
    let added = tokio::task::spawn_blocking(move || worker.assets.add(&name, &bytes))
        .await
        .map_err(|e| ApiError::Internal(format!("asset upload task: {e}")))?;
    let (asset, new) = added.map_err(|e| match e {
        AssetError::Invalid(why) => ApiError::BadRequest(why),
        AssetError::TooLarge(_, limit) => ApiError::TooLarge(limit),
        full @ AssetError::Full { .. } => ApiError::Full(full.to_string()),
    })?;
    if new {
        tracing::info!(asset = %asset.id, name = %asset.name, triangles = asset.triangles(), "asset uploaded");
    }
    let status = if new {
        StatusCode::CREATED
    } else {
        StatusCode::OK
    };
    Ok((
        status,
        Json(Uploaded {
            asset: asset.info(),
            deduplicated: !new,
        }),
    ))
}

async fn list(State(state): State<Arc<AppState>>) -> Json<AssetList> {
    Json(AssetList {
        assets: state.assets.list().iter().map(|a| a.info()).collect(),
        memory_bytes: state.assets.memory() as u64,
        memory_limit_bytes: state.assets.limits.max_total_bytes as u64,
    })
}

fn unknown(id: &str) -> ApiError {
    ApiError::NotFound(format!("no asset '{id}'"))
}

async fn one(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
) -> AppResult<Json<AssetInfo>> {
    state
        .assets
        .get(&id)
        .map(|a| Json(a.info()))
        .ok_or_else(|| unknown(&id))
}

async fn remove(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
) -> AppResult<StatusCode> {
    if state.assets.remove(&id) {
        tracing::info!(asset = %id, "asset deleted");
        Ok(StatusCode::NO_CONTENT)
    } else {
        Err(unknown(&id))
    }
}
