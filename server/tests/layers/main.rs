//! The library's layers import only downward, and the parts of a folder
//! never import each other in a circle: read from the source itself, every
//! `crate::`, `super::` and `self::` path of `server/src` (comments and
//! strings skipped), resolved through the `use` declarations it passes.
//!
//! - Top-level modules come in levels ([`LEVELS`]): a module imports only
//!   from lower levels, never from one beside it (`render` and `model`
//!   know nothing of each other; `api` and `bench` neither).
//! - In every folder, its files and subfolders import each other without a
//!   circle (an inline `mod tests` counts as part of its file; a folder's
//!   `mod.rs` is the folder itself, which its parts may use).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

mod paths;
use paths::{references, resolve};

/// Top-level modules by level, lowest first.
const LEVELS: &[&[&str]] = &[
    &["mesh_data", "material_maps"],
    &["render", "model"],
    &["resolve"],
    &["service"],
    &["api", "bench"],
];

type Module = Vec<String>;

/// One source file: its module path and what it refers to.
struct Source {
    module: Module,
    file: PathBuf,
    /// Paths it names (absolute, from the crate root), with the line.
    paths: Vec<(Module, usize)>,
    /// Names its `use` declarations bring in: name -> absolute path.
    uses: BTreeMap<String, Module>,
}

fn main_sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    collect(&root, &mut files);
    files
        .into_iter()
        .filter_map(|f| {
            let rel = f.strip_prefix(&root).ok()?.to_path_buf();
            let mut module: Module = rel
                .with_extension("")
                .iter()
                .map(|s| s.to_string_lossy().into_owned())
                .collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                module.pop();
            }
            // The binary (main.rs, cli/) uses the library as `pathstream::`.
            if rel == Path::new("main.rs") || rel.starts_with("cli") {
                return None;
            }
            let text = std::fs::read_to_string(&f).ok()?;
            let (paths, uses) = references(&module, &text);
            Some(Source {
                module,
                file: rel,
                paths,
                uses,
            })
        })
        .collect()
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// Every import between two modules: (from, to, file:line).
fn edges() -> Vec<(Module, Module, String)> {
    let sources = main_sources();
    assert!(
        sources.len() > 50,
        "read the sources ({} files)",
        sources.len()
    );
    let uses: BTreeMap<Module, &BTreeMap<String, Module>> = sources
        .iter()
        .map(|s| (s.module.clone(), &s.uses))
        .collect();
    let mut out = Vec::new();
    for s in &sources {
        for (path, line) in &s.paths {
            let to = resolve(path, &uses, 0);
            if to != s.module {
                out.push((s.module.clone(), to, format!("{}:{line}", s.file.display())));
            }
        }
    }
    out
}

fn level(top: &str) -> Option<usize> {
    LEVELS.iter().position(|l| l.contains(&top))
}

#[test]
fn top_level_modules_import_only_from_lower_levels() {
    let mut wrong = BTreeSet::new();
    for (from, to, at) in edges() {
        let (Some(a), Some(b)) = (from.first(), to.first()) else {
            continue; // the crate root
        };
        if a == b {
            continue;
        }
        let (la, lb) = (level(a), level(b));
        assert!(la.is_some(), "{at}: module {a} is in no level of LEVELS");
        if lb.is_none() || lb >= la {
            wrong.insert(format!(
                "{at}: {} imports {}",
                from.join("::"),
                to.join("::")
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layers:\n{}",
        join(&wrong)
    );
}

#[test]
fn no_folder_has_parts_that_import_each_other_in_a_circle() {
    let edges = edges();
    let mut folders: BTreeSet<Module> = BTreeSet::new();
    for (from, _, _) in &edges {
        for n in 0..from.len() {
            folders.insert(from[..n].to_vec());
        }
    }
    let mut circles = Vec::new();
    for folder in &folders {
        let d = folder.len();
        // Parts of the folder (its files and subfolders) and their imports.
        let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
        for (from, to, at) in &edges {
            if from.len() > d && to.len() > d && from[..d] == folder[..] && to[..d] == folder[..] {
                let (a, b) = (&from[d], &to[d]);
                if a != b {
                    graph
                        .entry(a.clone())
                        .or_default()
                        .entry(b.clone())
                        .or_insert_with(|| at.clone());
                }
            }
        }
        if let Some(cycle) = find_cycle(&graph) {
            let steps: Vec<String> = cycle
                .windows(2)
                .map(|w| format!("{} -> {} ({})", w[0], w[1], graph[&w[0]][&w[1]]))
                .collect();
            circles.push(format!("in {}: {}", show(folder), steps.join(", ")));
        }
    }
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

/// A cycle of `graph`, first node repeated at the end, if it has one.
fn find_cycle(graph: &BTreeMap<String, BTreeMap<String, String>>) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        n: &str,
        graph: &BTreeMap<String, BTreeMap<String, String>>,
        marks: &mut BTreeMap<String, Mark>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        marks.insert(n.to_owned(), Mark::Open);
        stack.push(n.to_owned());
        for next in graph.get(n).into_iter().flat_map(|m| m.keys()) {
            match marks.get(next) {
                Some(Mark::Open) => {
                    let at = stack.iter().position(|s| s == next).unwrap_or(0);
                    let mut cycle = stack[at..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Some(Mark::Done) => {}
                None => {
                    if let Some(c) = visit(next, graph, marks, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        marks.insert(n.to_owned(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for n in graph.keys() {
        if !marks.contains_key(n) {
            if let Some(c) = visit(n, graph, &mut marks, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

fn show(m: &Module) -> String {
    if m.is_empty() {
        "the crate".into()
    } else {
        m.join("/")
    }
}

fn join(lines: &BTreeSet<String>) -> String {
    lines.iter().cloned().collect::<Vec<_>>().join("\n")
}

#[test]
fn paths_resolve_through_uses_and_inline_modules() {
    let text = "//! crate::api in a comment\nuse super::{frame::Frame, lock as l};\nuse crate::render::{self, Film};\nfn f() { let s = \"crate::api\"; crate::service::create(); }\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use super::super::x::Y;\n}\n";
    let module = vec!["service".to_owned(), "session".to_owned()];
    let (paths, uses) = references(&module, text);
    let shown: Vec<String> = paths
        .iter()
        .map(|(p, l)| format!("{}@{l}", p.join("::")))
        .collect();
    assert_eq!(
        shown,
        [
            "service::frame::Frame@2",
            "service::lock@2",
            "render@3",
            "render::Film@3",
            "service::create@4",
            "service::session::*@7",
            "service::x::Y@8",
        ]
    );
    assert_eq!(
        uses.get("l").map(|p| p.join("::")).as_deref(),
        Some("service::lock")
    );
    assert_eq!(
        uses.get("Frame").map(|p| p.join("::")).as_deref(),
        Some("service::frame::Frame")
    );
    assert!(
        !uses.contains_key("Y"),
        "an inline module's uses are its own"
    );
    let mut graph = BTreeMap::new();
    graph.insert(
        "a".to_owned(),
        BTreeMap::from([("b".to_owned(), "x".to_owned())]),
    );
    graph.insert(
        "b".to_owned(),
        BTreeMap::from([("a".to_owned(), "y".to_owned())]),
    );
    assert_eq!(
        find_cycle(&graph),
        Some(vec!["a".into(), "b".into(), "a".into()])
    );
    graph.remove("b");
    assert_eq!(find_cycle(&graph), None);
}
