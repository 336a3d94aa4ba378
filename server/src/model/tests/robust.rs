//! Garbage and mutated files: every one must load or fail with an error,
//! never panic; and a timing run for large files (ignored by default).

use super::{assert_guarantees, cube, Rng};
use crate::model::write::{write_obj, write_ply_binary};
use crate::model::{load_bytes, load_file, Limits, MeshData};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Valid files of every format, generated.
fn samples() -> Vec<(&'static str, Vec<u8>)> {
    let g = cube();
    let (triangles, materials) = g.triangles();
    let mesh = MeshData {
        name: "cube".into(),
        positions: g.positions.clone(),
        normals: Some(g.normals.clone()),
        triangles,
        materials,
        ..MeshData::default()
    };
    let mut ply = Vec::new();
    write_ply_binary(&mesh, &mut ply).expect("write");
    let mut obj = Vec::new();
    write_obj(&mesh, &mut obj).expect("write");
    let ascii = String::from(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
           element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    let gltf = br#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "translation": [1, 2, 3]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}]}"#;
    let mut glb = b"glTF".to_vec();
    let json = br#"{"asset":{"version":"2.0"},"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}],"bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]}"#;
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    let mut be = ply.clone();
    // The same header with big endian data is still readable (as garbage).
    if let Some(p) = be.windows(20).position(|w| w == b"binary_little_endian") {
        be[p..p + 20].copy_from_slice(b"binary_big_endian   ");
    }
    vec![
        ("m.ply", ply),
        ("be.ply", be),
        ("m.obj", obj),
        ("a.ply", ascii.into_bytes()),
        ("m.gltf", gltf.to_vec()),
        ("m.glb", glb),
    ]
}

#[test]
fn samples_load() {
    for (name, bytes) in samples() {
        if name == "be.ply" {
            continue;
        }
        let m =
            load_bytes(&bytes, name, &Limits::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_guarantees(&m);
    }
}

/// One random change: flip bytes, cut, splice a run, replace a number, or
/// insert garbage.
fn mutate(rng: &mut Rng, bytes: &[u8]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    match rng.below(6) {
        0 => {
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
        }
        1 => b.truncate(rng.below(b.len())),
        2 => {
            let (i, j) = (rng.below(b.len()), rng.below(b.len()));
            let (i, j) = (i.min(j), i.max(j));
            b.drain(i..j);
        }
        3 => {
            // A run of digits replaced by an extreme number.
            let starts: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
            if let Some(&s) = starts.get(rng.below(starts.len())) {
                let e = (s..b.len())
                    .find(|&i| !b[i].is_ascii_digit())
                    .unwrap_or(b.len());
                let pick = [
                    "0",
                    "4294967295",
                    "4294967296",
                    "18446744073709551615",
                    "99999999999999999999",
                    "-1",
                    "1e39",
                    "nan",
                ];
                b.splice(s..e, pick[rng.below(pick.len())].bytes());
            }
        }
        4 => {
            let i = rng.below(b.len());
            let junk: Vec<u8> = (0..rng.below(16)).map(|_| rng.next() as u8).collect();
            b.splice(i..i, junk);
        }
        _ => {
            // A 4-byte little-endian field set to an extreme value.
            let i = rng.below(b.len().saturating_sub(4));
            let v = [0u32, 1, 0x7fff_ffff, 0xffff_ffff, 0x8000_0000][rng.below(5)];
            if let Some(w) = b.get_mut(i..i + 4) {
                w.copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    b
}

#[test]
fn mutated_files_never_panic() {
    let limits = Limits {
        max_triangles: 100_000,
        max_vertices: 100_000,
        ..Limits::default()
    };
    // MODEL_FUZZ_ROUNDS=100000 (and MODEL_FUZZ_SEED) for a longer run.
    let rounds = std::env::var("MODEL_FUZZ_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(400);
    let seed = std::env::var("MODEL_FUZZ_SEED")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(0x5eed_1234_abcd_0001);
    let mut rng = Rng(seed);
    let (mut ok, mut failed) = (0, 0);
    for (name, bytes) in samples() {
        for round in 0..rounds {
            let m = mutate(&mut rng, &bytes);
            let r = catch_unwind(AssertUnwindSafe(|| load_bytes(&m, name, &limits)));
            match r {
                Ok(Ok(model)) => {
                    assert_guarantees(&model);
                    ok += 1;
                }
                Ok(Err(e)) => {
                    assert!(!e.reason.is_empty());
                    failed += 1;
                }
                Err(_) => panic!(
                    "{name} round {round} panics on {:?}",
                    String::from_utf8_lossy(&m)
                ),
            }
        }
    }
    // Both outcomes happen (the mutations are neither all fatal nor all benign).
    assert!(ok > 100 && failed > 500, "ok {ok}, failed {failed}");
}

#[test]
fn garbage_is_an_error() {
    let mut rng = Rng(99);
    for name in ["g.obj", "g.ply", "g.gltf", "g.glb", "g"] {
        for len in [0, 1, 7, 100, 5000] {
            let bytes: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
            assert!(
                load_bytes(&bytes, name, &Limits::default()).is_err(),
                "{name} {len}"
            );
            let mut magic = match name {
                "g.ply" => b"ply\n".to_vec(),
                "g.glb" => b"glTF".to_vec(),
                _ => b"{\"asset\": ".to_vec(),
            };
            magic.extend(&bytes);
            assert!(
                load_bytes(&magic, name, &Limits::default()).is_err(),
                "{name} {len} after magic"
            );
        }
    }
    let e = load_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n", "big.ply", &Limits::default())
        .expect_err("absurd");
    assert_eq!(
        e.to_string(),
        "big.ply: header: element vertex: 4000000000 vertices, more than the limit of 16000000"
    );
    let e = load_bytes(b"\x00\x01garbage", "g.bin", &Limits::default()).expect_err("unknown");
    assert!(e.reason.starts_with("unknown format"));
}

/// A grid of `n` x `n` quads (2 n^2 triangles) with normals.
fn grid(n: u32) -> MeshData {
    let mut m = MeshData {
        name: "grid".into(),
        normals: Some(Vec::new()),
        ..Default::default()
    };
    for y in 0..=n {
        for x in 0..=n {
            m.positions.push([
                x as f32 / n as f32,
                y as f32 / n as f32,
                ((x * y) % 7) as f32 * 1e-3,
            ]);
            if let Some(v) = m.normals.as_mut() {
                v.push([0.0, 0.0, 1.0]);
            }
        }
    }
    for y in 0..n {
        for x in 0..n {
            let i = y * (n + 1) + x;
            m.triangles.push([i, i + 1, i + n + 2]);
            m.triangles.push([i, i + n + 2, i + n + 1]);
        }
    }
    m.materials = vec![0; m.triangles.len()];
    m
}

/// Times `load_file` of a 1M-triangle binary PLY and OBJ:
/// `cargo test --release -p pathstream --lib model::tests::robust::time_large_files -- --ignored --nocapture`
#[test]
#[ignore = "a timing run: prints load times of 1M-triangle files"]
fn time_large_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = grid(708);
    println!(
        "{} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for (name, write) in [
        (
            "grid.ply",
            write_ply_binary as fn(&MeshData, &mut std::fs::File) -> std::io::Result<()>,
        ),
        ("grid.obj", write_obj),
    ] {
        let path = dir.path().join(name);
        let mut f = std::fs::File::create(&path).expect("create");
        write(&mesh, &mut f).expect("write");
        drop(f);
        let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        for run in 0..3 {
            let t = std::time::Instant::now();
            let m = load_file(&path, &Limits::default()).expect("loads");
            let s = t.elapsed().as_secs_f64();
            assert_eq!(m.meshes[0].triangles.len(), mesh.triangles.len());
            if name.ends_with(".ply") {
                assert_eq!(m.meshes[0], mesh);
            }
            println!(
                "{name} ({:.1} MB) run {run}: load_file {:.3} s",
                size as f64 / 1e6,
                s
            );
        }
    }
}
