//! What can go wrong talking to a server.

/// Client errors; each says which kind of failure it is, so that a command
/// line can map them to exit codes.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The server answered with an error status and this message.
    #[error("server error {status}: {message}")]
    Server { status: u16, message: String },
    /// The server could not be reached (connection refused, timeout, DNS).
    #[error("cannot reach the server: {0}")]
    Unreachable(String),
    /// The server answered something this client does not understand.
    #[error("unexpected answer from the server: {0}")]
    Protocol(String),
    /// Bad input on this side (a URL, a file).
    #[error("{0}")]
    Input(String),
}

impl ClientError {
    pub(crate) fn from_reqwest(e: reqwest::Error) -> Self {
        if e.is_connect() || e.is_timeout() {
            ClientError::Unreachable(e.to_string())
        } else if e.is_decode() {
            ClientError::Protocol(e.to_string())
        } else {
            ClientError::Unreachable(e.to_string())
        }
    }
}

pub type Result<T> = std::result::Result<T, ClientError>;

/// The message of an error body (`{"error": "..."}`), if `body` is one.
pub(crate) fn message_of(body: &[u8]) -> Option<String> {
    serde_json::from_slice::<pathstream_wire::ErrorBody>(body)
        .ok()
        .map(|b| b.error)
}
