//! Tests that the host's tables and the kernel sources say the same thing:
//! the scene's arrays (`buffers.rs`, `SCENE_ARRAYS`, against
//! `kernels/scene_arrays.h`) and the `render` kernel's parameters, and the
//! shared constants (`layout.rs`, `SHARED_CONSTANTS`), which `kernels/`
//! must use and never define.

use super::buffers::{LAUNCH_PARAMS, SCENE_ARRAYS};
use super::layout::SHARED_CONSTANTS;
use super::program::{Features, ProgramKey};
use std::collections::BTreeSet;

const SCENE_ARRAYS_H: &str = include_str!("../../../../../kernels/scene_arrays.h");
const TYPES_H: &str = include_str!("../../../../../kernels/types.h");
const RENDER_CL: &str = include_str!("../../../../../kernels/render.cl");

/// Every file of `kernels/` (not only the program's sources: the routine
/// checks, and any file added later), as (file name, text).
fn kernel_files() -> Vec<(String, String)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../kernels");
    let mut files: Vec<(String, String)> = std::fs::read_dir(dir)
        .expect("kernels/")
        .map(|e| e.expect("kernels/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "h" || x == "cl"))
        .map(|p| {
            let name = p
                .file_name()
                .expect("a file")
                .to_string_lossy()
                .into_owned();
            (name, std::fs::read_to_string(&p).expect("kernel source"))
        })
        .collect();
    files.sort();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names.contains(&"render.cl") && names.contains(&"checks.cl"),
        "{names:?}"
    );
    files
}

/// `source` without its comments (kernels/ has no string literals).
fn strip_comments(source: &str) -> String {
    let mut out = String::with_capacity(source.len());
    let mut rest = source;
    while let Some(i) = rest.find('/') {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        if let Some(after) = tail.strip_prefix("/*") {
            let end = after.find("*/").expect("closed comment");
            out.push(' ');
            rest = &after[end + 2..];
        } else if tail.starts_with("//") {
            rest = &tail[tail.find('\n').unwrap_or(tail.len())..];
        } else {
            out.push('/');
            rest = &tail[1..];
        }
    }
    out.push_str(rest);
    out
}

/// The `(element type, name)` entries of `#define SCENE_ARRAYS(X)`.
fn header_arrays() -> Vec<(String, String)> {
    let text = strip_comments(SCENE_ARRAYS_H);
    let body = text
        .split_once("#define SCENE_ARRAYS(X)")
        .expect("scene_arrays.h defines SCENE_ARRAYS(X)")
        .1;
    body.split("X(")
        .skip(1)
        .map(|entry| {
            let inner = entry.split_once(')').expect("X(type, name)").0;
            let (ty, name) = inner.split_once(',').expect("X(type, name)");
            (ty.trim().to_owned(), name.trim().to_owned())
        })
        .collect()
}

/// The text between the parentheses that follow `open` in `source`.
fn parenthesised<'a>(source: &'a str, open: &str) -> &'a str {
    let start = source.find(open).expect("present") + open.len();
    let mut depth = 1;
    for (i, c) in source[start..].char_indices() {
        depth += match c {
            '(' => 1,
            ')' => -1,
            _ => 0,
        };
        if depth == 0 {
            return &source[start..start + i];
        }
    }
    panic!("unclosed parenthesis after {open}");
}

/// `decl` as tokens, `*` one of them: "__global float *film" and
/// "__global float* film" read the same.
fn tokens(decl: &str) -> Vec<String> {
    decl.replace('*', " * ")
        .split_whitespace()
        .map(str::to_owned)
        .collect()
}

#[test]
fn the_scene_arrays_are_the_headers_in_order() {
    let host: Vec<(String, String)> = SCENE_ARRAYS
        .iter()
        .map(|a| (a.c_type.to_owned(), a.name.to_owned()))
        .collect();
    assert_eq!(
        host,
        header_arrays(),
        "buffers.rs SCENE_ARRAYS (left) and kernels/scene_arrays.h (right) must list the same \
         (element type, name) in the same order"
    );
    let labels: BTreeSet<&str> = SCENE_ARRAYS.iter().map(|a| a.label).collect();
    assert_eq!(
        labels.len(),
        SCENE_ARRAYS.len(),
        "memory messages tell them apart"
    );
    assert!(!labels.contains("film"), "the film is not a scene array");
}

#[test]
fn the_render_kernel_takes_the_scene_arrays_then_the_launch_arguments() {
    // The kernel's Scene and its parameters are expansions of the one list.
    let types = strip_comments(TYPES_H);
    let render = strip_comments(RENDER_CL);
    assert!(types.contains("#define SCENE_FIELD(T, name) __global const T *name;"));
    assert!(types.contains("SCENE_ARRAYS(SCENE_FIELD)\n} Scene;"));
    assert!(render.contains("#define SCENE_PARAM(T, name) __global const T *name,"));
    assert!(render.contains("#define SCENE_NAME(T, name) name,"));
    assert!(render.contains("Scene sc = {SCENE_ARRAYS(SCENE_NAME)};"));
    let params = parenthesised(&render, "__kernel void render(");
    let launch = params
        .trim()
        .strip_prefix("SCENE_ARRAYS(SCENE_PARAM)")
        .expect("the scene's arrays come first");
    let kernel: Vec<Vec<String>> = launch.split(',').map(tokens).collect();
    let host: Vec<Vec<String>> = LAUNCH_PARAMS
        .iter()
        .map(|(ty, name)| tokens(&format!("{ty} {name}")))
        .collect();
    assert_eq!(
        host, kernel,
        "buffers.rs LAUNCH_PARAMS (left) and render's parameters after the scene arrays (right)"
    );
    // Elsewhere a Scene is built field by field, by name: a positional
    // initialiser would be the list written again, in an order that can rot.
    for (file, text) in kernel_files() {
        for (i, _) in text.match_indices("Scene sc = {") {
            let init = text[i + "Scene sc = {".len()..].trim_start();
            assert!(
                init.starts_with("SCENE_ARRAYS(") || init.starts_with('.'),
                "{file}: a Scene built by position: {}",
                &text[i..text[i..].find(';').map_or(text.len(), |e| i + e)]
            );
        }
    }
}

#[test]
fn the_device_sees_the_element_sizes_the_host_uploads() {
    let device = match super::OpenClBackend::new(None) {
        Ok(d) => d,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => {
            eprintln!("skipping OpenCL: {e}");
            return;
        }
    };
    let checks = device.checks("").expect("check program");
    let sizes: Vec<u32> = checks
        .run("check_scene_array_sizes", 1, SCENE_ARRAYS.len(), &[])
        .expect("sizes");
    let host: Vec<(&str, u32)> = SCENE_ARRAYS
        .iter()
        .map(|a| (a.name, a.elem_bytes as u32))
        .collect();
    let device: Vec<(&str, u32)> = SCENE_ARRAYS.iter().map(|a| a.name).zip(sizes).collect();
    assert_eq!(
        host, device,
        "bytes per element: host (left), device's sizeof (right)"
    );
}

/// `text` as a number if it is a C integer literal (decimal or hex, with
/// any u/l suffix).
fn int_literal(text: &str) -> Option<u64> {
    let t = text.trim_end_matches(['u', 'U', 'l', 'L']);
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => t.parse().ok(),
    }
}

/// `text` as an f32 if it is a C floating literal (`0.99f`, `1e-3`).
fn float_literal(text: &str) -> Option<f32> {
    let t = text.trim_end_matches(['f', 'F']);
    (t.contains(['.', 'e', 'E']) && !t.starts_with("0x"))
        .then(|| t.parse().ok())
        .flatten()
}

#[test]
fn no_shared_constant_is_defined_in_the_kernels() {
    let names: BTreeSet<&str> = SHARED_CONSTANTS.iter().map(|(n, _)| *n).collect();
    assert_eq!(names.len(), SHARED_CONSTANTS.len(), "no name twice");
    let mut wrong = Vec::new();
    for (file, text) in kernel_files() {
        let code = strip_comments(&text);
        for line in code.lines() {
            let Some(define) = line.trim_start().strip_prefix("#define") else {
                continue;
            };
            let define = define.trim_start();
            let end = define
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(define.len());
            let (name, value) = (&define[..end], define[end..].trim());
            // By name: the constant itself, or a float's decimal twin.
            if names.contains(name) || names.contains(format!("{name}_BITS").as_str()) {
                wrong.push(format!("{file}: #define {name} (a shared constant)"));
            }
            // By value, under another name: integers from 8 (below, values
            // such as 0, 1 and 2 are every flag's) and floats.
            for (shared, v) in SHARED_CONSTANTS {
                let same_int = v >= 8 && int_literal(value) == Some(u64::from(v));
                let same_float = shared.ends_with("_BITS")
                    && float_literal(value).is_some_and(|f| f.to_bits() == v);
                if same_int || same_float {
                    wrong.push(format!("{file}: #define {name} {value} is {shared}"));
                }
            }
        }
        // A float goes by its bits, and is read back as a float.
        for (shared, _) in SHARED_CONSTANTS
            .iter()
            .filter(|(n, _)| n.ends_with("_BITS"))
        {
            for (i, _) in code.match_indices(shared) {
                if !code[..i].ends_with("as_float(") {
                    wrong.push(format!(
                        "{file}: {shared} read other than as as_float({shared})"
                    ));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "kernels/ must take these from layout.rs SHARED_CONSTANTS:\n{}",
        wrong.join("\n")
    );
}

/// The `-D` names of `options`.
fn defined_by(options: &str) -> impl Iterator<Item = String> + '_ {
    options
        .split("-D ")
        .skip(1)
        .map(|d| d.split(['=', ' ']).next().unwrap_or("").to_owned())
}

#[test]
fn every_upper_case_name_in_the_kernels_is_defined_somewhere() {
    // What the host defines: the shared constants and the specialisation
    // (every option on, so that every name appears).
    let all = Features {
        spheres: true,
        quads: true,
        diffuse: true,
        mirror: true,
        glass: true,
        ggx: true,
        transmission: true,
        volume: true,
        coat: true,
        coat_normal: true,
        vertex_colors: true,
        schlick: true,
        exact: true,
        sphere_lights: true,
        quad_lights: true,
        nee: true,
        box_filter: true,
        sobol: true,
        num_objects: 1,
        num_lights: 1,
        max_depth: 1,
        bvh_stack: 1,
        mesh_stack: 1,
        tri_lights: true,
        environment: true,
        env_map: true,
        sun: true,
        lens: true,
        projection: 0,
        features: true,
        textures: true,
        alpha: true,
        inject_nan_every: Some(1),
    };
    let mut known: BTreeSet<String> =
        defined_by(&ProgramKey::Specialised(all).build_options()).collect();
    assert!(SHARED_CONSTANTS.iter().all(|(n, _)| known.contains(*n)));
    // OpenCL's own (pragma words, math constants), and a switch one may
    // pass in PATHSTREAM_OPENCL_OPTIONS (types.h).
    let outside = "OPENCL EXTENSION FP_CONTRACT OFF NAN INFINITY M_PI_F M_1_PI_F ALLOW_CONTRACTION";
    known.extend(outside.split(' ').map(String::from));
    let code: String = kernel_files()
        .iter()
        .map(|(_, t)| strip_comments(t))
        .collect();
    // What the kernels define, and their macros' parameters.
    let is_word = |c: char| c.is_ascii_alphanumeric() || c == '_';
    for line in code.lines() {
        if let Some(define) = line.trim_start().strip_prefix("#define ") {
            let end = define.find(|c| !is_word(c)).unwrap_or(define.len());
            known.insert(define[..end].to_owned());
            if let Some(params) = define[end..].strip_prefix('(') {
                let params = params.split_once(')').map_or("", |(p, _)| p);
                known.extend(params.split(',').map(|p| p.trim().to_owned()));
            }
        }
    }
    let unknown: BTreeSet<&str> = code
        .split(|c: char| !is_word(c))
        .filter(|w| w.len() > 1 && w.starts_with(|c: char| c.is_ascii_uppercase()))
        .filter(|w| {
            w.chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        })
        .filter(|w| !known.contains(*w))
        .collect();
    assert!(
        unknown.is_empty(),
        "kernels/ uses {unknown:?}, which neither kernels/ nor the build options define \
         (a shared constant belongs in layout.rs SHARED_CONSTANTS)"
    );
}
