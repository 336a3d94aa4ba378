use super::*;
use serde_json::{json, Value};

#[test]
fn requests_are_checked_by_field() {
    let r = |f: Option<&str>, q: Option<u8>, w: Option<u32>| StreamRequest {
        format: f.map(str::to_owned),
        quality: q,
        width: w,
        progressive: None,
        raw: None,
        token: None,
    };
    assert_eq!(
        r(None, None, None).settings().expect("ok"),
        StreamSettings::default()
    );
    assert_eq!(
        r(Some("webp"), Some(60), None)
            .settings()
            .expect("ok")
            .format,
        StreamFormat::Webp { quality: 60 }
    );
    assert_eq!(
        r(Some("jpeg"), None, Some(64)).settings().expect("ok"),
        StreamSettings {
            format: StreamFormat::Jpeg { quality: 85 },
            width: Some(64),
            progressive: false,
            raw: false,
        }
    );
    for (req, needle) in [
        (r(Some("gif"), None, None), "stream.format"),
        (
            r(Some("jpeg"), Some(0), None),
            "stream.quality: must be between 1 and 100",
        ),
        (
            r(None, Some(50), None),
            "stream.quality: only for format jpeg or webp",
        ),
        (r(None, None, Some(0)), "stream.width"),
    ] {
        let e = req.settings().expect_err("bad").to_string();
        assert!(e.contains(needle), "{e}");
    }
}

#[test]
fn the_messages_are_exactly_todays() {
    // Clients match on these (and so do the server's own tests).
    let bad = |v: Value| {
        serde_json::from_value::<StreamRequest>(v)
            .expect("parses")
            .settings()
            .expect_err("refused")
            .to_string()
    };
    assert_eq!(
        bad(json!({"format": "gif"})),
        "stream.format: must be png, jpeg or webp (got 'gif')"
    );
    assert_eq!(
        bad(json!({"format": "webp", "quality": 101})),
        "stream.quality: must be between 1 and 100 (got 101)"
    );
    assert_eq!(
        bad(json!({"quality": 5})),
        "stream.quality: only for format jpeg or webp"
    );
    assert_eq!(bad(json!({"width": 0})), "stream.width: must be at least 1");
    // The token rides along; anything else unknown is refused.
    let with_token = json!({"format": "png", "token": "t", "progressive": true});
    let settings = serde_json::from_value::<StreamRequest>(with_token)
        .expect("parses")
        .settings()
        .expect("ok");
    assert!(settings.progressive);
    let e = serde_json::from_value::<StreamRequest>(json!({"fps": 3})).expect_err("unknown");
    assert!(e.to_string().contains("unknown field `fps`"), "{e}");
}

fn status() -> SessionStatus {
    serde_json::from_value(crate::status::tests::older_status()).expect("a status")
}

#[test]
fn stats_carry_the_status_at_the_top_level_and_round_trip() {
    let stats = Stats {
        status: status(),
        frame: 9,
        format: "jpeg".into(),
        frame_bytes: 1234,
        frame_width: 2,
        frame_height: 1,
        progressive: true,
        preview: Some(4),
        denoised: true,
        delivered_fps: 3,
        link_mbps: None,
        delivery_ms: Some(1.5),
    };
    let message = StreamMessage::Stats(Box::new(stats));
    let v = serde_json::to_value(&message).expect("serializes");
    assert_eq!(v["type"], "stats");
    assert_eq!(
        (v["id"].as_str(), v["frame"].as_u64()),
        (Some("s"), Some(9))
    );
    assert_eq!(v["link_mbps"], Value::Null, "null, not absent");
    let back: StreamMessage = serde_json::from_value(v).expect("reads back");
    assert_eq!(back, message);
}

#[test]
fn stats_of_an_older_server_and_errors_read() {
    // Before the stream said how it sent the frame: only the status.
    let mut old = serde_json::to_value(status()).expect("serializes");
    old["type"] = json!("stats");
    match serde_json::from_value::<StreamMessage>(old).expect("reads") {
        StreamMessage::Stats(s) => assert_eq!((s.status, s.frame, s.preview), (status(), 0, None)),
        other => panic!("{other:?}"),
    }
    let error = json!({"type": "error", "error": "ack: must be a frame number (got -1)"});
    assert_eq!(
        serde_json::from_value::<StreamMessage>(error).expect("reads"),
        StreamMessage::Error(ErrorBody::new("ack: must be a frame number (got -1)"))
    );
    let e = StreamMessage::Error(ErrorBody::new("x"));
    assert_eq!(
        serde_json::to_value(&e).expect("serializes"),
        json!({"type": "error", "error": "x"})
    );
}
