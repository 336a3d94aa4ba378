//! `pathstream-client` with adaptive sampling, against a real server.

mod common;

use common::{client, start_server, text, Server};
use std::time::{Duration, Instant};

/// Polls `status ID` until the session halts in `generation` or a later
/// one; its status.
fn halted(server: &Server, id: &str, generation: u64) -> pathstream_client::SessionStatus {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let run = client(server, &["status", id]);
        assert!(run.status.success(), "{}", text(&run.stderr));
        let s: pathstream_client::SessionStatus =
            serde_json::from_slice(&run.stdout).expect("status JSON");
        if s.halted() && s.generation >= generation {
            return s;
        }
        assert!(Instant::now() < deadline, "{id} never halted: {s:?}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn adaptive_render_spreads_its_samples_and_says_so() {
    let server = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("a.png");
    let settings = [
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "32",
        "--adaptive",
        "on",
    ];
    let run = client(
        &server,
        &[
            &["render"][..],
            &settings,
            &["-o", out.to_str().expect("utf-8")],
        ]
        .concat(),
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    // "32 spp (mean; min A, median B, max C)": after the uniform warm-up
    // (16 spp), the noisiest tiles got more samples than the rest.
    let stdout = text(&run.stdout);
    let count = |key: &str| -> u64 {
        let at = stdout
            .find(key)
            .unwrap_or_else(|| panic!("no '{key}' in {stdout}"));
        let digits: String = stdout[at + key.len()..]
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        digits
            .parse()
            .unwrap_or_else(|_| panic!("'{key}' in {stdout}"))
    };
    assert!(stdout.contains("32 spp (mean; "), "{stdout}");
    let (min, max) = (count("min "), count("max "));
    assert!(min >= 16 && max > min, "{stdout}");

    // The session's own status says the same.
    let created = client(&server, &[&["create"][..], &settings].concat());
    assert!(created.status.success(), "{}", text(&created.stderr));
    let s: pathstream_client::SessionStatus =
        serde_json::from_slice(&created.stdout).expect("status JSON");
    assert!(s.quality.adaptive);
    let s = halted(&server, &s.id, s.generation);
    assert!(s.quality.adaptive);
    assert!(s.spp >= 32, "{s:?}");
    let p = s.spp_spread;
    assert!(p.min <= p.median && p.median <= p.max, "{p:?}");
    assert!(p.min >= 16 && p.max > 16 && p.max > p.min, "{p:?}");
    let t = u64::from(s.tile_size);
    assert!(t >= 1, "{s:?}");
    assert_eq!(s.tiles, 32u64.div_ceil(t).pow(2), "32x32 in {t}x{t} tiles");

    // Off again: every pixel gets the same samples.
    let off = client(&server, &["quality", &s.id, "--adaptive", "off"]);
    assert!(off.status.success(), "{}", text(&off.stderr));
    let changed: pathstream_client::SessionStatus =
        serde_json::from_slice(&off.stdout).expect("status JSON");
    assert!(
        changed.generation > s.generation,
        "the change restarted the film"
    );
    let s = halted(&server, &s.id, changed.generation);
    assert!(!s.quality.adaptive);
    let p = s.spp_spread;
    assert_eq!((p.min, p.median, p.max), (32, 32, 32), "{s:?}");
    assert!(client(&server, &["delete", &s.id]).status.success());
}
