//! The browser client: every file under `static/` at its path below `/`
//! (`/` itself is `index.html`), with no token. Release builds carry the
//! folder inside the binary (`rust-embed`; `build.rs` rebuilds when a file is
//! added), so the binary serves the page from anywhere; `serve --static-dir
//! DIR` serves a folder from disk instead (tower-http's `ServeDir`), which
//! shows edits to the page without rebuilding. Either way responses say
//! `Cache-Control: no-cache`, so a browser revalidates (ETag or
//! Last-Modified) and never runs a stale module beside a fresh one.

use crate::service::ApiError;
use axum::body::Body;
use axum::handler::HandlerWithoutStateExt;
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, get_service};
use axum::Router;
use std::path::Path;
use tower_http::services::ServeDir;
use tower_http::set_header::SetResponseHeaderLayer;

#[derive(rust_embed::Embed)]
#[folder = "../static/"]
struct Embedded;

const NO_CACHE: HeaderValue = HeaderValue::from_static("no-cache");

/// A router that answers every path with the client's file there, or a
/// JSON 404 (405 for methods other than GET and HEAD): the service's
/// fallback.
pub fn router(static_dir: Option<&Path>) -> Router {
    let files = match static_dir {
        Some(dir) => {
            let dir = ServeDir::new(dir)
                .append_index_html_on_directories(true)
                .not_found_service(not_found.into_service());
            get_service(dir).fallback(wrong_method)
        }
        None => get(embedded).fallback(wrong_method),
    };
    Router::new()
        .fallback_service(files)
        .layer(SetResponseHeaderLayer::overriding(
            header::CACHE_CONTROL,
            NO_CACHE,
        ))
}

/// Names of the files built into this binary, `/`-separated.
pub fn embedded_names() -> impl Iterator<Item = String> {
    Embedded::iter().map(|name| name.into_owned())
}

async fn not_found(uri: Uri) -> ApiError {
    ApiError::NotFound(format!("no file or route at {}", uri.path()))
}

async fn wrong_method(method: Method, uri: Uri) -> ApiError {
    ApiError::MethodNotAllowed(format!(
        "{method} {}: only GET serves files here",
        uri.path()
    ))
}

async fn embedded(uri: Uri, headers: HeaderMap) -> Response {
    let path = uri.path().trim_start_matches('/');
    let name = if path.is_empty() || path.ends_with('/') {
        format!("{path}index.html")
    } else {
        path.to_owned()
    };
    let Some(file) = Embedded::get(&name) else {
        return not_found(uri).await.into_response();
    };
    let etag = format!("\"{}\"", hex(&file.metadata.sha256_hash()));
    let fresh = headers
        .get(header::IF_NONE_MATCH)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|tags| tags.split(',').any(|t| t.trim() == etag));
    let mut response = if fresh {
        StatusCode::NOT_MODIFIED.into_response()
    } else {
        let mime = file.metadata.mimetype();
        // Browsers refuse ES modules served without a JavaScript type.
        let mime = if mime == "application/javascript" {
            "text/javascript"
        } else {
            mime
        };
        let content_type = if mime.starts_with("text/") {
            format!("{mime}; charset=utf-8")
        } else {
            mime.to_owned()
        };
        (
            [(header::CONTENT_TYPE, content_type)],
            Body::from(file.data.into_owned()),
        )
            .into_response()
    };
    if let Ok(v) = HeaderValue::from_str(&etag) {
        response.headers_mut().insert(header::ETAG, v);
    }
    response
}

fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    bytes
        .iter()
        .fold(String::with_capacity(bytes.len() * 2), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}
