//! PLY: ASCII, binary little and big endian.

use super::{assert_guarantees, cube, Gen};
use crate::model::Material;
use crate::model::{load_bytes, load_file, Instance, Limits, Model};
use std::fmt::Write as _;

const ASCII_HEADER_LINES: usize = 15;

/// The cube as ASCII PLY, with `u v` properties the loader ignores.
fn ply_ascii(g: &Gen) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment generated cube\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        g.positions.len(),
        g.faces.len()
    );
    for (p, n) in g.positions.iter().zip(&g.normals) {
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} 0.5 0.25",
            p[0], p[1], p[2], n[0], n[1], n[2]
        );
    }
    for (poly, _) in &g.faces {
        let _ = write!(s, "{}", poly.len());
        for i in poly {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    s
}

macro_rules! put {
    ($out:expr, $v:expr, $big:expr) => {
        if $big {
            $out.extend($v.to_be_bytes())
        } else {
            $out.extend($v.to_le_bytes())
        }
    };
}

/// The cube as binary PLY. Little endian: double positions, float normals,
/// a `uchar red` property, `uchar`/`uint` index lists and an `edge` element
/// (both ignored). Big endian: float positions, double normals,
/// `ushort`/`ushort` `vertex_index` lists. Returns (bytes, header length).
fn ply_binary(g: &Gen, big: bool) -> (Vec<u8>, usize) {
    let (format, pos, nor, list, name) = if big {
        (
            "binary_big_endian",
            "float",
            "double",
            "ushort ushort",
            "vertex_index",
        )
    } else {
        (
            "binary_little_endian",
            "double",
            "float",
            "uchar uint",
            "vertex_indices",
        )
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty {pos} x\nproperty {pos} y\nproperty {pos} z\n\
         property {nor} nx\nproperty {nor} ny\nproperty {nor} nz\n{}element face {}\nproperty list {list} {name}\n{}end_header\n",
        g.positions.len(),
        if big { "" } else { "property uchar red\n" },
        g.faces.len(),
        if big { "" } else { "element edge 2\nproperty int vertex1\nproperty int vertex2\n" },
    )
    .into_bytes();
    let header = out.len();
    for (p, n) in g.positions.iter().zip(&g.normals) {
        for &x in p {
            if big {
                put!(out, x, true);
            } else {
                put!(out, f64::from(x), false);
            }
        }
        for &x in n {
            if big {
                put!(out, f64::from(x), true);
            } else {
                put!(out, x, false);
            }
        }
        if !big {
            out.push(200);
        }
    }
    for (poly, _) in &g.faces {
        if big {
            put!(out, poly.len() as u16, true);
        } else {
            out.push(poly.len() as u8);
        }
        for &i in poly {
            if big {
                put!(out, i as u16, true);
            } else {
                put!(out, i, false);
            }
        }
    }
    if !big {
        for e in [[0i32, 1], [1, 2]] {
            put!(out, e[0], false);
            put!(out, e[1], false);
        }
    }
    (out, header)
}

fn expected(g: &Gen, warnings: &[&str]) -> Model {
    Model {
        meshes: vec![g.mesh("cube", &[0, 0])],
        materials: vec![(
            "default".into(),
            Material::Diffuse {
                albedo: [0.8; 3],
                emission: None,
            },
            Default::default(),
        )],
        images: Vec::new(),
        instances: vec![Instance {
            mesh: 0,
            transform: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
        }],
        camera: None,
        warnings: warnings.iter().map(|w| w.to_string()).collect(),
    }
}

const NO_MATERIALS: &str = "no materials: default diffuse (albedo 0.8)";

fn err(bytes: &[u8]) -> String {
    match load_bytes(bytes, "c.ply", &Limits::default()) {
        Ok(_) => panic!("loads"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn ascii_loads_exactly() {
    let g = cube();
    let text = ply_ascii(&g);
    assert_eq!(
        text.lines().position(|l| l == "end_header"),
        Some(ASCII_HEADER_LINES - 1)
    );
    let m = load_bytes(text.as_bytes(), "cube.ply", &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(
        m,
        expected(&g, &["vertex properties ignored: u, v", NO_MATERIALS])
    );
    // CRLF line ends read the same.
    let crlf = text.replace('\n', "\r\n");
    let m2 = load_bytes(crlf.as_bytes(), "cube.ply", &Limits::default()).expect("loads");
    assert_eq!(m2, m);
}

#[test]
fn binary_little_and_big_endian_load_exactly() {
    let g = cube();
    let dir = tempfile::tempdir().expect("tempdir");
    let (le, _) = ply_binary(&g, false);
    let path = dir.path().join("cube.ply");
    std::fs::write(&path, &le).expect("write");
    let m = load_file(&path, &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(
        m,
        expected(
            &g,
            &[
                "vertex properties ignored: red",
                "element edge (2 entries) ignored",
                NO_MATERIALS
            ]
        )
    );
    let (be, _) = ply_binary(&g, true);
    let m = load_bytes(&be, "cube.ply", &Limits::default()).expect("loads");
    assert_eq!(m, expected(&g, &[NO_MATERIALS]));
}

#[test]
fn binary_nan_is_an_error() {
    let g = cube();
    let (mut le, header) = ply_binary(&g, false);
    le[header + 3 * 37..header + 3 * 37 + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    assert_eq!(
        err(&le),
        format!(
            "c.ply: byte {}: vertex 3: position [NaN, 1.5, 3.5] is not finite",
            header + 3 * 37
        )
    );
}

#[test]
fn truncated_binary_files() {
    let g = cube();
    let (le, header) = ply_binary(&g, false);
    // Cut in vertex 12 (37 bytes a vertex): the header's counts need more.
    let cut = &le[..header + 12 * 37 + 5];
    assert_eq!(
        err(cut),
        format!(
            "c.ply: byte {header}: truncated (or a wrong count): element vertex with 24 entries needs at least 888 bytes after the header, the file has 449"
        )
    );
    // Cut in the last face (whose list is longer than the minimum).
    let (be, header) = ply_binary(&g, true);
    let cut = &be[..be.len() - 3];
    assert_eq!(
        err(cut),
        format!(
            "c.ply: byte {}: truncated: the file ends in face 5 of 6",
            header + 24 * 36 + 5 * 10
        )
    );
}

#[test]
fn ascii_errors_name_the_line() {
    let g = cube();
    let text = ply_ascii(&g);
    let lines: Vec<&str> = text.lines().collect();
    let with = |line: usize, new: &str| {
        let mut l = lines.clone();
        l[line - 1] = new;
        l.join("\n") + "\n"
    };
    let v3 = ASCII_HEADER_LINES + 4;
    assert_eq!(
        err(with(v3, "1e39 1.5 3.5 1 0 0 0 0").as_bytes()),
        format!("c.ply: line {v3}: vertex 3: position [inf, 1.5, 3.5] is not finite")
    );
    let f2 = ASCII_HEADER_LINES + 24 + 3;
    assert_eq!(
        err(with(f2, "4 8 9 10 99").as_bytes()),
        format!("c.ply: line {f2}: face 2: vertex index 99 out of range (24 vertices)")
    );
    assert_eq!(
        err(with(f2, "3 8 -1 10").as_bytes()),
        format!("c.ply: line {f2}: face 2: vertex index -1 out of range")
    );
    assert_eq!(
        err(with(v3, "1.5 abc 3.5 1 0 0 0 0").as_bytes()),
        format!("c.ply: line {v3}: vertex 3: cannot read \"1.5 abc 3.5 1 0 0 0 0\" (error at 1:5: expected one of \"\\r\\n\", EOF, [' '|'\\t'], ['-'|'+'], ['0'..='9'], ['\\n'|'\\r'])")
    );
    let e = err(with(v3, "nan 1.5 3.5 1 0 0 0 0").as_bytes());
    assert!(
        e.starts_with(&format!(
            "c.ply: line {v3}: vertex 3: cannot read \"nan 1.5"
        )),
        "{e}"
    );
    let short = lines[..ASCII_HEADER_LINES + 29].join("\n") + "\n";
    assert_eq!(
        err(short.as_bytes()),
        format!(
            "c.ply: line {}: truncated: the file ends in face 5 of 6",
            ASCII_HEADER_LINES + 30
        )
    );
}

#[test]
fn header_problems() {
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let ply = |header: &str| format!("ply\nformat ascii 1.0\n{header}end_header\n{body}");
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    assert_eq!(
        err(ply(&format!("element vertex 4000000000\n{xyz}{face}")).as_bytes()),
        "c.ply: header: element vertex: 4000000000 vertices, more than the limit of 16000000"
    );
    let big = ply(&format!("element vertex 1000000\n{xyz}{face}"));
    let header = big.find("end_header\n").map(|i| i + 11).expect("header");
    assert_eq!(
        err(big.as_bytes()),
        format!("c.ply: byte {header}: truncated (or a wrong count): element vertex with 1000000 entries needs at least 6000000 bytes after the header, the file has 26")
    );
    // The last line without its newline: still enough bytes.
    let m = load_bytes(
        ply(&format!("element vertex 3\n{xyz}{face}"))
            .trim_end()
            .as_bytes(),
        "c.ply",
        &Limits::default(),
    );
    assert_eq!(
        m.map(|m| m.meshes[0].triangles.clone()),
        Ok(vec![[0, 1, 2]])
    );
    assert_eq!(
        err(ply(&format!(
            "element vertex 3\n{xyz}element face 0\nproperty list uchar int vertex_indices\n"
        ))
        .as_bytes()),
        "c.ply: no triangles"
    );
    assert_eq!(
        err(ply(&format!("element vertex 3\n{xyz}")).as_bytes()),
        "c.ply: no triangles (the file needs a vertex and a face element)"
    );
    assert_eq!(
        err(ply(&format!(
            "element vertex 3\nproperty float x\nproperty float y\n{face}"
        ))
        .as_bytes()),
        "c.ply: header: element vertex has no x, y and z properties"
    );
    assert_eq!(
        err(ply(&format!(
            "element vertex 3\n{xyz}element face 1\nproperty list uchar float vertex_indices\n"
        ))
        .as_bytes()),
        "c.ply: header: face property vertex_indices is not a list of integers"
    );
    let e = err(ply(&format!("elemnt vertex 3\n{xyz}{face}")).as_bytes());
    assert!(e.starts_with("c.ply: line 3: bad header: "), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 3\n");
    assert!(e.starts_with("c.ply: line 4: bad header: "), "{e}");
    // A polygon's triangles count against the limit.
    let limits = Limits {
        max_vertices: 100,
        max_triangles: 2,
        ..Limits::default()
    };
    let quad = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\n{xyz}{face}end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n5 0 1 2 3 0\n"
    );
    let e = load_bytes(quad.as_bytes(), "q.ply", &limits).expect_err("over");
    assert_eq!(
        e.to_string(),
        "q.ply: line 14: 3 triangles, more than the limit of 2"
    );
}

#[test]
fn vertex_colours_are_the_base_colour() {
    // uchar colours (sRGB bytes), and float ones under their other name.
    let text = "ply\nformat ascii 1.0\nelement vertex 3\n\
        property float x\nproperty float y\nproperty float z\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 255 128 0 255\n1 0 0 0 0 0 255\n0 1 0 10 20 30 255\n3 0 1 2\n";
    let m = load_bytes(text.as_bytes(), "c.ply", &Limits::default()).expect("loads");
    assert_guarantees(&m);
    let decode = |b: u8| {
        let c = f64::from(b) / 255.0;
        let l = if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        l as f32
    };
    let want = [[255, 128, 0], [0, 0, 0], [10, 20, 30]].map(|c: [u8; 3]| c.map(decode));
    assert_eq!(m.meshes[0].colors.as_deref(), Some(&want[..]));
    assert_eq!(
        m.materials[0].1,
        Material::Diffuse {
            albedo: [1.0; 3],
            emission: None
        }
    );
    assert_eq!(
        m.warnings,
        [
            "vertex properties ignored: alpha",
            "no materials: white diffuse, coloured by the vertex colours"
        ]
    );
    let floats = "ply\nformat ascii 1.0\nelement vertex 3\n\
        property float x\nproperty float y\nproperty float z\n\
        property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 1 0.5 2\n1 0 0 0 0 -1\n0 1 0 0.2 0.2 0.2\n3 0 1 2\n";
    let m = load_bytes(floats.as_bytes(), "c.ply", &Limits::default()).expect("loads");
    let c = m.meshes[0].colors.as_ref().expect("colours");
    // Clamped to [0, 1] and decoded: 1 stays 1, 0.5 is 0.214.
    assert_eq!((c[0][0], c[0][2], c[1][2]), (1.0, 1.0, 0.0));
    assert!((c[0][1] - 0.214_041_14).abs() < 1e-6, "{c:?}");
    // A colour that is not finite is an error naming the vertex.
    let nan = floats.replace("0 0 0 1 0.5 2", "0 0 0 1 1e999 2");
    let e = err(nan.as_bytes());
    assert!(e.contains("vertex 0: colour"), "{e}");
}
