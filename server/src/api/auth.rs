//! The bearer token that `serve --token T` requires on every `/api` route:
//! `Authorization: Bearer T`, or `?token=T` (browsers cannot set headers on
//! WebSockets). The query is decoded as `application/x-www-form-urlencoded`
//! by `form_urlencoded` (`%XX` escapes, `+` for a space; malformed escapes
//! kept as they are, invalid UTF-8 replaced), so no input can make the check
//! fail other than by refusing it. Tokens are compared in constant time.

use crate::service::ApiError;
use crate::service::AppState;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, Uri};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::sync::Arc;
use subtle::ConstantTimeEq;

/// Middleware: passes the request on when no token is configured or the
/// right one is presented; otherwise 401 with a JSON error.
pub async fn require_token(
    State(state): State<Arc<AppState>>,
    req: Request,
    next: Next,
) -> Response {
    match &state.config.token {
        Some(expected) if !presents(req.headers(), req.uri(), expected) => {
            ApiError::Unauthorized.into_response()
        }
        _ => next.run(req).await,
    }
}

/// Whether the request carries `expected`, in its header or its query.
fn presents(headers: &HeaderMap, uri: &Uri, expected: &str) -> bool {
    let from_header = headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::to_owned);
    from_header
        .or_else(|| uri.query().and_then(query_token))
        .is_some_and(|given| bool::from(given.as_bytes().ct_eq(expected.as_bytes())))
}

/// The decoded value of the first `token` parameter of a query string.
pub fn query_token(query: &str) -> Option<String> {
    form_urlencoded::parse(query.as_bytes())
        .find(|(key, _)| key == "token")
        .map(|(_, value)| value.into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_tokens_are_percent_and_plus_decoded() {
        assert_eq!(query_token("token=s3cret").as_deref(), Some("s3cret"));
        assert_eq!(
            query_token("min_spp=4&token=a%2Bb%21+c").as_deref(),
            Some("a+b! c")
        );
        assert_eq!(
            query_token("tok%65n=x").as_deref(),
            Some("x"),
            "keys are decoded too"
        );
        assert_eq!(query_token("token=%C3%A9").as_deref(), Some("\u{e9}"));
        assert_eq!(
            query_token("token=first&token=second").as_deref(),
            Some("first")
        );
        assert_eq!(query_token("min_spp=4"), None);
        assert_eq!(
            query_token("token").as_deref(),
            Some(""),
            "a key alone has an empty value"
        );
    }

    #[test]
    fn malformed_escapes_and_non_ascii_bytes_are_values_not_panics() {
        // The hand-written decoder this replaces sliced "%a\u{e9}" inside the
        // two-byte character and panicked.
        assert_eq!(query_token("token=%a\u{e9}").as_deref(), Some("%a\u{e9}"));
        assert_eq!(query_token("token=%").as_deref(), Some("%"));
        assert_eq!(query_token("token=%zz%4").as_deref(), Some("%zz%4"));
        // A lone continuation byte decodes to U+FFFD, never to the token.
        assert_eq!(query_token("token=%80").as_deref(), Some("\u{fffd}"));
    }

    #[test]
    fn the_header_or_the_query_must_carry_the_exact_token() {
        let uri = |s: &str| s.parse::<Uri>().expect("uri");
        let bearer = |t: &str| {
            let mut h = HeaderMap::new();
            h.insert(
                header::AUTHORIZATION,
                format!("Bearer {t}").parse().expect("header"),
            );
            h
        };
        let none = HeaderMap::new();
        assert!(presents(&bearer("s3cret"), &uri("/api/sessions"), "s3cret"));
        assert!(presents(
            &none,
            &uri("/api/sessions?token=s3cret"),
            "s3cret"
        ));
        assert!(presents(&none, &uri("/api/x/ws?token=s3%63ret"), "s3cret"));
        assert!(!presents(&none, &uri("/api/sessions"), "s3cret"));
        assert!(
            !presents(&bearer("s3cre"), &uri("/api/sessions"), "s3cret"),
            "a prefix is not the token"
        );
        assert!(!presents(
            &none,
            &uri("/api/sessions?token=s3cretX"),
            "s3cret"
        ));
        assert!(!presents(&none, &uri("/api/sessions?token=%a"), "s3cret"));
        // A wrong header is not rescued by a right query (the header wins).
        assert!(!presents(
            &bearer("wrong"),
            &uri("/api/sessions?token=s3cret"),
            "s3cret"
        ));
    }
}
