//! `pathstream-client render --backend all` against `pathstream serve
//! --backend all`: one image on every device of the server (PoCL and rayon
//! here; PoCL is required where CI is set), with each device's share.

mod common;

use common::{client, start_server_with, text};

#[test]
fn a_render_on_every_device_prints_each_devices_share() {
    let server = start_server_with("all");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("a.png");
    let run = client(
        &server,
        &[
            "render",
            "--scene",
            "cornell",
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "64",
            "--backend",
            "all",
            "-o",
            out.to_str().expect("utf-8"),
        ],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    let stdout = text(&run.stdout);
    assert!(
        stdout.contains("64 spp") && stdout.contains(" on all ("),
        "{stdout}"
    );
    let devices: Vec<&str> = stdout.lines().skip(1).collect();
    if std::env::var_os("CI").is_some() {
        assert_eq!(devices.len(), 2, "PoCL and rayon: {stdout}");
    }
    for line in &devices {
        assert!(
            line.contains(" M paths/s, ") && line.ends_with(" paths"),
            "{stdout}"
        );
    }
    assert!(image::open(&out).is_ok(), "a PNG");
}
