//! The body of every HTTP error, `{"error": "..."}` with a 4xx or 5xx
//! status: a 4xx says what was wrong with the request, naming the field; a
//! 5xx says little. On the stream's socket the same message comes as
//! `{"type": "error", "error": "..."}` ([`crate::StreamMessage::Error`]).

use serde::{Deserialize, Serialize};

/// An error's body.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorBody {
    /// What went wrong.
    pub error: String,
}

impl ErrorBody {
    /// The body carrying `message`.
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            error: message.into(),
        }
    }
}
