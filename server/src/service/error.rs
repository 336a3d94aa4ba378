//! One error type for the whole service: each kind is what a request did
//! wrong (or `Internal`), and its message names the field. The transport
//! (`crate::api`) answers each kind with its status: a 4xx says what was
//! wrong with the request; a 5xx says little and the detail is logged.

use pathstream_wire::StreamError;

#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    #[error("{0}")]
    BadRequest(String),
    #[error("{0}")]
    NotFound(String),
    /// It existed and was deleted meanwhile (a request that was waiting).
    #[error("{0}")]
    Gone(String),
    #[error("{0}")]
    MethodNotAllowed(String),
    #[error("missing or wrong bearer token")]
    Unauthorized,
    #[error("request body is larger than the limit of {0} bytes")]
    TooLarge(usize),
    #[error("{0}")]
    TooMany(String),
    /// Out of room for what the request would store (assets).
    #[error("{0}")]
    Full(String),
    /// A body of a type the route does not take (see `guard`).
    #[error("{0}")]
    UnsupportedMediaType(String),
    #[error("internal error")]
    Internal(String),
}

impl ApiError {
    pub fn unknown_session(id: &str) -> Self {
        ApiError::NotFound(format!("no session '{id}'"))
    }
}

/// A refused scene edit is the client's mistake; its message names the field.
impl From<crate::render::scene::EditError> for ApiError {
    fn from(e: crate::render::scene::EditError) -> Self {
        ApiError::BadRequest(e.to_string())
    }
}

/// A stream request that cannot be honoured; its message names the field.
impl From<StreamError> for ApiError {
    fn from(e: StreamError) -> Self {
        ApiError::BadRequest(e.to_string())
    }
}

/// Parses a JSON body into `T`; errors name the JSON path of the field.
pub fn parse_json<T: serde::de::DeserializeOwned>(body: &[u8]) -> Result<T, ApiError> {
    let de = &mut serde_json::Deserializer::from_slice(body);
    serde_path_to_error::deserialize(de).map_err(|e| path_error(e, "invalid JSON", ""))
}

/// Reads an already parsed JSON `value` (the field `key` of a message) as
/// `T`; errors name the path below `key`, as in `camera.position: ...`.
pub fn parse_field<T: serde::de::DeserializeOwned>(
    key: &str,
    value: serde_json::Value,
) -> Result<T, ApiError> {
    serde_path_to_error::deserialize(value).map_err(|e| path_error(e, key, &format!("{key}.")))
}

/// A 400 naming where the error is: `whole` when it is the whole document,
/// else `prefix` and the path.
fn path_error<E: std::fmt::Display>(
    e: serde_path_to_error::Error<E>,
    whole: &str,
    prefix: &str,
) -> ApiError {
    let path = e.path().to_string();
    let inner = e.into_inner();
    if path == "." {
        ApiError::BadRequest(format!("{whole}: {inner}"))
    } else {
        ApiError::BadRequest(format!("{prefix}{path}: {inner}"))
    }
}
