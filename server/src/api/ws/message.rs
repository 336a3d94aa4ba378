//! A client's WebSocket message, parsed once into what it asks:
//!
//! ```json
//! {"ack": 41}
//! {"stream": {"format": "jpeg", "quality": 80, "width": 640}}
//! {"camera": {"position": [50, 52, 250]}, "quality": {"spp": 256}}
//! {"ack": 42, "light": {"intensity": 20}}
//! ```
//!
//! An acknowledgement counts even when the rest of its message is refused;
//! the stream settings and the changes apply together or not at all.
//! Errors name the field, as the HTTP routes' do.

use super::super::stream::{StreamRequest, StreamSettings};
use crate::service::change::{Change, SceneRules};
use crate::service::error::parse_json;
use crate::service::ApiError;
use serde_json::Value;

/// What one client message asks.
#[derive(Debug)]
pub struct ClientMessage {
    /// `"ack": FRAME`: the client has frame FRAME.
    pub ack: Option<u64>,
    /// The stream settings and changes it asks for, or why they are refused.
    pub request: Result<Request, ApiError>,
}

/// A message's stream settings and changes (none, for a bare ack).
#[derive(Debug, Default)]
pub struct Request {
    pub stream: Option<StreamSettings>,
    /// In the order they apply: scene, camera, light, quality.
    pub changes: Vec<Change>,
}

impl ClientMessage {
    /// The message `text`; scenes in it may use what `rules` allow.
    pub fn parse(text: &str, rules: &SceneRules<'_>) -> ClientMessage {
        let refused = |e: ApiError| ClientMessage {
            ack: None,
            request: Err(e),
        };
        let mut fields = match parse_json::<Value>(text.as_bytes()) {
            Ok(Value::Object(fields)) => fields,
            Ok(_) => {
                return refused(ApiError::BadRequest(
                    "message: must be a JSON object".into(),
                ))
            }
            Err(e) => return refused(e),
        };
        let ack = match fields.remove("ack") {
            None => None,
            Some(v) => match v.as_u64() {
                Some(seq) => Some(seq),
                None => {
                    return refused(ApiError::BadRequest(format!(
                        "ack: must be a frame number (got {v})"
                    )))
                }
            },
        };
        let request = stream(fields.remove("stream")).and_then(|stream| {
            Ok(Request {
                stream,
                changes: Change::from_fields(fields, rules)?,
            })
        });
        ClientMessage { ack, request }
    }
}

/// The settings a `stream` field asks for.
fn stream(field: Option<Value>) -> Result<Option<StreamSettings>, ApiError> {
    let Some(field) = field else {
        return Ok(None);
    };
    let request = serde_json::from_value::<StreamRequest>(field)
        .map_err(|e| ApiError::BadRequest(format!("stream: {e}")))?;
    Ok(Some(request.settings()?))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use pathstream_wire::StreamFormat;

    fn parse(text: &str) -> ClientMessage {
        ClientMessage::parse(text, &SceneRules::INLINE_ONLY)
    }

    fn refusal(text: &str) -> String {
        parse(text).request.expect_err(text).to_string()
    }

    #[test]
    fn an_ack_stream_settings_and_changes_come_out_of_one_message() {
        let m = parse(
            r#"{"ack": 7, "stream": {"format": "jpeg"}, "quality": {"spp": 4}, "scene": "cornell"}"#,
        );
        assert_eq!(m.ack, Some(7));
        let r = m.request.unwrap();
        assert_eq!(
            r.stream.map(|s| s.format),
            Some(StreamFormat::Jpeg { quality: 85 })
        );
        let kinds: Vec<&str> = (r.changes.iter())
            .map(|c| match c {
                Change::Scene { .. } => "scene",
                Change::Quality(_) => "quality",
                _ => "other",
            })
            .collect();
        assert_eq!(kinds, ["scene", "quality"]);
        let bare = parse(r#"{"ack": 3}"#);
        assert_eq!(bare.ack, Some(3));
        let r = bare.request.unwrap();
        assert!(r.stream.is_none() && r.changes.is_empty());
    }

    #[test]
    fn an_ack_counts_when_the_rest_is_refused_and_nothing_else_applies() {
        let m = parse(r#"{"ack": 9, "stream": {"format": "jpeg"}, "camera": {"zoom": 2}}"#);
        assert_eq!(m.ack, Some(9));
        let e = m.request.unwrap_err().to_string();
        assert!(e.starts_with("camera.zoom: unknown field `zoom`"), "{e}");
    }

    #[test]
    fn refusals_name_the_field_as_before() {
        for (text, want) in [
            ("not json", "invalid JSON: expected ident"),
            ("{", "?: EOF while parsing an object"),
            ("[1, 2]", "message: must be a JSON object"),
            (r#"{"ack": -1}"#, "ack: must be a frame number (got -1)"),
            (
                r#"{"ack": "x", "camera": {}}"#,
                "ack: must be a frame number (got \"x\")",
            ),
            (
                r#"{"stream": {"format": "gif"}}"#,
                "stream.format: must be png, jpeg or webp (got 'gif')",
            ),
            (r#"{"stream": {"fps": 3}}"#, "stream: unknown field `fps`"),
            (
                r#"{"ack": 1, "bogus": 1}"#,
                "message: unknown key 'bogus' (expected camera, environment, light, quality or scene)",
            ),
            (r#"{"scene": "nowhere"}"#, "scene: unknown scene 'nowhere'"),
        ] {
            let e = refusal(text);
            assert!(e.starts_with(want), "{text}: {e}");
        }
        assert_eq!(parse(r#"{"ack": "x"}"#).ack, None, "a bad ack is no ack");
    }
}
