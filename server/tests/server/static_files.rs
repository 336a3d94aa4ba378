//! The page's files, built in and from a folder.

use super::*;

/// Every file under `static/`, `/`-separated, relative to it, sorted.
fn static_files(dir: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("read_dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path
                    .strip_prefix(dir)
                    .expect("below")
                    .to_str()
                    .expect("utf-8")
                    .replace('\\', "/");
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_file_under_static_is_served_built_in_and_from_a_folder() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../static");
    let files = static_files(&dir);
    assert!(
        files.iter().any(|f| f.starts_with("js/")),
        "the page's modules live in static/js: {files:?}"
    );
    let mut embedded: Vec<String> = pathstream::api::embedded_static_files().collect();
    embedded.sort();
    assert_eq!(
        embedded, files,
        "the binary carries exactly the files under static/"
    );
    for static_dir in [None, Some(dir.clone())] {
        let from = if static_dir.is_some() {
            "--static-dir"
        } else {
            "built in"
        };
        let mut cfg = config();
        cfg.static_dir = static_dir;
        let (running, base) = server(cfg).await;
        let c = client();
        for file in files.iter().map(String::as_str).chain(["/"]) {
            let url = format!("{base}/{}", file.trim_start_matches('/'));
            let r = c.get(&url).send().await.expect("req");
            assert_eq!(r.status(), 200, "{from}: {url}");
            let headers = r.headers().clone();
            let on_disk = std::fs::read(dir.join(if file == "/" { "index.html" } else { file }))
                .expect("file");
            assert_eq!(
                r.bytes().await.expect("body").to_vec(),
                on_disk,
                "{from}: {url}"
            );
            let kind = headers["content-type"].to_str().expect("ascii").to_owned();
            let want = match file.rsplit('.').next() {
                Some("js") => "javascript",
                Some("css") => "text/css",
                _ => "text/html",
            };
            assert!(kind.contains(want), "{from}: {url} is {kind}");
            assert_eq!(headers["cache-control"], "no-cache", "{from}: {url}");
            // Revalidation: an unchanged file is not sent again.
            let (name, value) = match (headers.get("etag"), headers.get("last-modified")) {
                (Some(tag), _) => ("if-none-match", tag.clone()),
                (None, Some(date)) => ("if-modified-since", date.clone()),
                (None, None) => panic!("{from}: {url} has neither ETag nor Last-Modified"),
            };
            let again = c.get(&url).header(name, value).send().await.expect("req");
            assert_eq!(again.status(), 304, "{from}: {url} with {name}");
        }
        for (method, path, code) in [
            ("GET", "/nope.js", 404),
            ("GET", "/js/nope.js", 404),
            ("POST", "/app.js", 405),
        ] {
            let url = format!("{base}{path}");
            let r = if method == "GET" {
                c.get(&url)
            } else {
                c.post(&url)
            }
            .send()
            .await
            .expect("req");
            assert_eq!(r.status(), code, "{from}: {method} {path}");
            let v: Value = r
                .json()
                .await
                .unwrap_or_else(|e| panic!("{from}: {method} {path}: not JSON: {e}"));
            assert!(
                v["error"].as_str().is_some_and(|e| e.contains(path)),
                "{from}: {v}"
            );
        }
        running.shutdown().await.expect("shutdown");
    }
}
