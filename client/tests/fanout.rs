//! `pathstream-client render` on several real `pathstream` servers at once:
//! one image, merged from their frames (the workspace builds both binaries
//! into the same folder).

use pathstream_client::LinearImage;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{assert_fails, start_server, text};

/// `pathstream-client --server S1 --server S2 ... ARGS`.
fn client(servers: &[&str], args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pathstream-client"));
    c.env_remove("PATHSTREAM_URL");
    for s in servers {
        c.args(["--server", s]);
    }
    c.args(args);
    c
}

/// Renders cornell at `size` with `spp` and `seed` on `servers` to `out`;
/// the command's output (asserted successful).
///
/// Each sample clamped to 1: unclamped, the lamp's edge pixels (radiance 12
/// next to about 0.5) make a 48x48 image's RMS error heavy-tailed, about 15%
/// apart from seed to seed, so that a ratio of two errors misses 0.7-1.3
/// for one seed in six; clamped, 2% apart. Every render, the reference too,
/// estimates the same clamped image, so the comparison is unchanged.
fn render(servers: &[&str], size: u32, spp: u64, seed: u64, out: &Path) -> Output {
    let size = size.to_string();
    let (spp, seed) = (spp.to_string(), seed.to_string());
    let run = client(
        servers,
        &[
            "render",
            "--scene",
            "cornell",
            "--width",
            &size,
            "--height",
            &size,
            "--spp",
            &spp,
            "--seed",
            &seed,
            "--clamp",
            "1",
            "-o",
            out.to_str().expect("utf-8"),
        ],
    )
    .output()
    .expect("runs");
    assert!(
        run.status.success(),
        "{}{}",
        text(&run.stdout),
        text(&run.stderr)
    );
    run
}

fn pfm(path: &Path) -> LinearImage {
    LinearImage::decode_pfm(&std::fs::read(path).expect("file")).expect("a PFM")
}

/// Relative RMS error of `image` against `reference`, over all pixels and
/// channels.
fn error(image: &LinearImage, reference: &LinearImage) -> f64 {
    let d2: f64 = image
        .pixels
        .iter()
        .flatten()
        .zip(reference.pixels.iter().flatten())
        .map(|(&a, &r)| (f64::from(a) - f64::from(r)).powi(2))
        .sum();
    (d2 / reference.sum_of_squares()).sqrt()
}

/// The number after `key` in `line`.
fn number_after(line: &str, key: &str) -> f64 {
    let at = line
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in {line}"));
    let digits: String = line[at + key.len()..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    digits
        .parse()
        .unwrap_or_else(|_| panic!("'{key}' in {line}"))
}

#[test]
fn two_servers_render_one_image_with_the_error_of_their_summed_samples() {
    let (a, b) = (start_server(), start_server());
    let dir = tempfile::tempdir().expect("tempdir");
    let path = |name: &str| dir.path().join(name);
    let size = 48;

    let merged = render(&[&a.url, &b.url], size, 64, 5, &path("merged.pfm"));
    let line = text(&merged.stdout);
    // Each server rendered its half, and says so.
    let (spp_a, spp_b) = (
        number_after(&line, &format!("{}: ", a.url)),
        number_after(&line, &format!("{}: ", b.url)),
    );
    assert!(spp_a >= 16.0 && spp_b >= 16.0, "{line}");
    assert!(spp_a + spp_b >= 64.0, "{line}");
    assert!(line.contains(" spp from 2 servers ("), "{line}");
    let merged_estimate = number_after(&line, "error estimate ");
    assert!(line.contains("% (merged)"), "{line}");
    let merged = pfm(&path("merged.pfm"));
    assert_eq!((merged.width, merged.height), (size, size));

    // Against a long render: the merged image has the error of 64 samples,
    // below that of 32 (by 1/sqrt(2) in expectation).
    render(&[&a.url], size, 1024, 99, &path("reference.pfm"));
    let reference = pfm(&path("reference.pfm"));
    let mut e32 = 0.0;
    for (seed, server) in [(7, &a.url), (8, &b.url)] {
        let out = path(&format!("single32_{seed}.pfm"));
        render(&[server], size, 32, seed, &out);
        e32 += error(&pfm(&out), &reference).powi(2) / 2.0;
    }
    let e32 = e32.sqrt();
    let single64 = render(&[&b.url], size, 64, 9, &path("single64.pfm"));
    let e64 = error(&pfm(&path("single64.pfm")), &reference);
    let em = error(&merged, &reference);
    eprintln!("relative RMS error: merged {em:.4}, 64 spp {e64:.4}, 32 spp {e32:.4}");
    assert!(em < 0.85 * e32, "merged {em}, 32 spp {e32}");
    assert!(
        (0.7..1.3).contains(&(em / e64)),
        "merged {em}, 64 spp {e64}"
    );
    // The merged estimate says what one server's estimate at 64 spp says.
    let single_estimate = number_after(&text(&single64.stdout), "error estimate ");
    let ratio = merged_estimate / single_estimate;
    assert!(
        (0.75..1.33).contains(&ratio),
        "merged estimate {merged_estimate}%, 64 spp {single_estimate}%"
    );

    // Nothing left behind.
    for s in [&a, &b] {
        let list = client(&[&s.url], &["sessions"]).output().expect("runs");
        assert_eq!(text(&list.stdout).trim(), "", "{} kept a session", s.url);
    }
}

#[test]
fn an_unreachable_server_is_dropped_with_a_warning_and_the_png_is_the_servers() {
    let live = start_server();
    let dead = "http://127.0.0.1:9";
    let dir = tempfile::tempdir().expect("tempdir");
    let fanned = dir.path().join("fanned.png");
    let args = [
        "render", "--scene", "cornell", "--width", "24", "--height", "16", "--spp", "16", "--seed",
        "5", "-o",
    ];
    // Both named by PATHSTREAM_URL, comma-separated.
    let run = Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .env("PATHSTREAM_URL", format!("{},{dead}", live.url))
        .args(args)
        .arg(&fanned)
        .output()
        .expect("runs");
    let (stdout, stderr) = (text(&run.stdout), text(&run.stderr));
    assert!(run.status.success(), "{stdout}{stderr}");
    assert!(stderr.contains(&format!("warning: {dead}")), "{stderr}");
    assert!(
        stdout.contains(&format!("16 spp from 1 server ({}: 16 spp)", live.url)),
        "{stdout}"
    );
    // One server's frame (seed 5) merged alone is that frame: tone-mapped
    // here, it is the PNG the server makes of the same render.
    let single = dir.path().join("single.png");
    let run = client(&[&live.url], &args)
        .arg(&single)
        .output()
        .expect("runs");
    assert!(run.status.success(), "{}", text(&run.stderr));
    let here = image::open(&fanned).expect("a PNG").to_rgb8();
    let there = image::open(&single).expect("a PNG").to_rgb8();
    assert_eq!(here.dimensions(), (24, 16));
    assert!(
        here == there,
        "the client's tone map differs from the server's"
    );

    // No server at all: exit 4, as for one unreachable server.
    let run = client(&[dead, dead], &args)
        .arg(dir.path().join("never.png"))
        .output()
        .expect("runs");
    assert_fails(&run, 4, "no server left");
    // Several servers are for render only.
    let run = client(&[&live.url, dead], &["sessions"])
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(2), "{}", text(&run.stderr));
}

#[test]
fn a_server_lost_mid_render_is_dropped_and_the_others_render_its_share() {
    let a = start_server();
    let mut b = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("merged.pfm");
    let render = client(
        &[&a.url, &b.url],
        &[
            "render", "--scene", "cornell", "--width", "32", "--height", "32", "--spp", "2048",
            "-o",
        ],
    )
    .arg(&out)
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()
    .expect("runs");
    // Kill B once its session renders.
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let list = client(&[&b.url], &["sessions"]).output().expect("runs");
        if !text(&list.stdout).trim().is_empty() {
            break;
        }
        assert!(Instant::now() < deadline, "no session appeared on B");
        std::thread::sleep(Duration::from_millis(20));
    }
    b.kill();
    let run = render.wait_with_output().expect("exits");
    let (stdout, stderr) = (text(&run.stdout), text(&run.stderr));
    assert!(run.status.success(), "{stdout}{stderr}");
    assert!(stderr.contains(&format!("warning: {}", b.url)), "{stderr}");
    // A's half, and B's half again on A.
    assert!(
        stdout.contains(&format!("2048 spp from 1 server ({}: 2048 spp)", a.url)),
        "{stdout}"
    );
    assert_eq!(pfm(&out).width, 32);
}
