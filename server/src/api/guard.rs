//! What stands between a hostile client and the handlers, for everything
//! under `/api`:
//! - bodies: a JSON body must say `Content-Type: application/json`, and an
//!   upload must not claim one of the types a browser sends cross-site
//!   without asking (`text/plain`, forms): so no web page a user visits can
//!   create or change sessions behind their back (415 otherwise);
//! - errors: whatever answers 4xx or 5xx (a path that is not UTF-8, a
//!   method a route does not take) answers `{"error": ...}`, 405 with its
//!   `Allow` header;
//! - panics: a handler that panics answers a 500 JSON error, is logged and
//!   is counted in `/metrics`, and the connection lives on.

use crate::service::ApiError;
use crate::service::Metrics;
use axum::body::{to_bytes, Body};
use axum::extract::{OriginalUri, Request};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::any::Any;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// The content types a browser sends cross-site without a preflight.
const CORS_SAFELISTED: [&str; 3] = [
    "text/plain",
    "application/x-www-form-urlencoded",
    "multipart/form-data",
];

/// A content type's `type/subtype`, lower case, without parameters.
fn essence(headers: &HeaderMap) -> Option<String> {
    let value = headers.get(header::CONTENT_TYPE)?.to_str().ok()?;
    Some(
        value
            .split(';')
            .next()
            .unwrap_or("")
            .trim()
            .to_ascii_lowercase(),
    )
}

/// Why a request with a body is refused (415), if it is: `path` is the full
/// path (`/api/...`).
pub fn content_type_refusal(method: &Method, path: &str, headers: &HeaderMap) -> Option<String> {
    if !matches!(*method, Method::POST | Method::PUT | Method::PATCH) {
        return None;
    }
    let given = essence(headers);
    let shown = given.as_deref().unwrap_or("none");
    if path == "/api/assets" {
        return match given.as_deref() {
            Some(t) if !t.is_empty() && !CORS_SAFELISTED.contains(&t) => None,
            _ => Some(format!(
                "{method} {path} takes the model file's bytes with a Content-Type such as \
                 application/octet-stream (got {shown})"
            )),
        };
    }
    match given.as_deref() {
        Some("application/json") => None,
        _ => Some(format!("{method} {path}: the body must be JSON with Content-Type: application/json (got {shown})")),
    }
}

/// The `/api` middleware: content types checked before the handler, and
/// any error answer that is not JSON made JSON.
pub async fn api_guard(req: Request, next: Next) -> Response {
    let method = req.method().clone();
    let path = req
        .extensions()
        .get::<OriginalUri>()
        .map_or_else(|| req.uri().path().to_owned(), |u| u.path().to_owned());
    if let Some(why) = content_type_refusal(&method, &path, req.headers()) {
        return ApiError::UnsupportedMediaType(why).into_response();
    }
    json_errors(next.run(req).await, &method, &path).await
}

/// `response` as is, or, for a 4xx/5xx whose body is not JSON, the same
/// status and headers with `{"error": ...}`.
async fn json_errors(response: Response, method: &Method, path: &str) -> Response {
    let status = response.status();
    let is_json = essence(response.headers()).is_some_and(|t| t == "application/json");
    if !(status.is_client_error() || status.is_server_error()) || is_json {
        return response;
    }
    let (mut parts, body) = response.into_parts();
    let text = to_bytes(body, 4096)
        .await
        .map(|b| String::from_utf8_lossy(&b).trim().to_owned())
        .unwrap_or_default();
    let message = if status == StatusCode::METHOD_NOT_ALLOWED {
        // The router adds the Allow header after this layer.
        format!("method {method} is not allowed on {path} (the Allow header lists those that are)")
    } else if text.is_empty() {
        status.canonical_reason().unwrap_or("error").to_owned()
    } else {
        text
    };
    let body = serde_json::json!({ "error": message }).to_string();
    parts.headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    parts.headers.remove(header::CONTENT_LENGTH);
    Response::from_parts(parts, Body::from(body))
}

/// The answer to a handler's panic: logged, counted, a 500 JSON error.
pub fn panic_response(metrics: &Arc<Metrics>, panic: Box<dyn Any + Send + 'static>) -> Response {
    let what = panic
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| panic.downcast_ref::<&str>().copied())
        .unwrap_or("(no message)");
    tracing::error!(panic = %what, "a request handler panicked");
    metrics.handler_panics.fetch_add(1, Ordering::Relaxed);
    ApiError::Internal(format!("handler panic: {what}")).into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_type(t: Option<&str>) -> HeaderMap {
        let mut h = HeaderMap::new();
        if let Some(t) = t {
            h.insert(
                header::CONTENT_TYPE,
                HeaderValue::from_str(t).expect("header"),
            );
        }
        h
    }

    #[test]
    fn json_bodies_need_the_json_content_type() {
        let post = Method::POST;
        assert_eq!(
            content_type_refusal(&post, "/api/sessions", &with_type(Some("application/json"))),
            None
        );
        assert_eq!(
            content_type_refusal(
                &post,
                "/api/sessions",
                &with_type(Some("Application/JSON; charset=utf-8"))
            ),
            None
        );
        for t in [
            None,
            Some("text/plain"),
            Some("application/x-www-form-urlencoded"),
            Some("text/json"),
        ] {
            let why = content_type_refusal(&post, "/api/sessions", &with_type(t)).expect("refused");
            assert!(why.contains("application/json"), "{why}");
        }
        assert!(content_type_refusal(
            &Method::PATCH,
            "/api/sessions/x/camera",
            &with_type(Some("text/plain"))
        )
        .is_some());
        // No body, no rule.
        assert_eq!(
            content_type_refusal(&Method::GET, "/api/sessions", &with_type(None)),
            None
        );
        assert_eq!(
            content_type_refusal(
                &Method::DELETE,
                "/api/sessions/x",
                &with_type(Some("text/plain"))
            ),
            None
        );
    }

    #[test]
    fn uploads_take_any_type_but_the_cross_site_ones() {
        let post = Method::POST;
        for t in [
            "application/octet-stream",
            "model/gltf-binary",
            "model/obj",
            "application/json",
        ] {
            assert_eq!(
                content_type_refusal(&post, "/api/assets", &with_type(Some(t))),
                None,
                "{t}"
            );
        }
        for t in [
            None,
            Some("text/plain"),
            Some("multipart/form-data; boundary=x"),
            Some("application/x-www-form-urlencoded"),
        ] {
            assert!(
                content_type_refusal(&post, "/api/assets", &with_type(t)).is_some(),
                "{t:?}"
            );
        }
    }
}
