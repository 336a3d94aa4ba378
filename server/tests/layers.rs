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

/// Top-level modules by level, lowest first.
const LEVELS: &[&[&str]] = &[
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

/// The code of `text` with comments, strings and character literals blanked
/// (newlines kept, so that lines still count).
fn code_only(text: &str) -> Vec<char> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::with_capacity(c.len());
    let mut i = 0;
    let blank = |ch: char| if ch == '\n' { '\n' } else { ' ' };
    let at = |k: usize| c.get(k).copied().unwrap_or('\0');
    while i < c.len() {
        if c[i] == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c[i] == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    out.extend([' ', ' ']);
                    i += 2;
                    continue;
                }
                if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    out.extend([' ', ' ']);
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                    continue;
                }
                out.push(blank(c[i]));
                i += 1;
            }
        } else if c[i] == 'r' && (at(i + 1) == '"' || (at(i + 1) == '#' && !is_ident(at(i + 2)))) {
            // Raw string r"..." or r#"..."#.
            let mut hashes = 0;
            let mut j = i + 1;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') || (i > 0 && is_ident(c[i - 1])) {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let close: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            out.extend(std::iter::repeat_n(' ', j + 1 - i));
            i = j + 1;
            while i < c.len() && !c[i..].starts_with(&close) {
                out.push(blank(c[i]));
                i += 1;
            }
            out.extend(std::iter::repeat_n(' ', close.len()));
            i += close.len();
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < c.len() {
                    out.push(blank(c[i]));
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{..}'); else a lifetime.
            let end = if at(i + 1) == '\\' {
                (i + 3..c.len()).find(|&j| c[j] == '\'')
            } else if at(i + 2) == '\'' {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    out.extend(std::iter::repeat_n(' ', e + 1 - i));
                    i = e + 1;
                }
                None => {
                    out.push(c[i]);
                    i += 1;
                }
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Every path `text` (the file of `module`) names through `crate::`,
/// `super::` or `self::`, made absolute; and the names its `use`
/// declarations bring in. Paths inside an inline `mod x { }` are resolved
/// from that module but belong to the file.
fn references(module: &Module, text: &str) -> (Vec<(Module, usize)>, BTreeMap<String, Module>) {
    let c = code_only(text);
    let mut paths = Vec::new();
    let mut uses = BTreeMap::new();
    // Inline modules open in this file: (name, brace depth inside it).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let (mut depth, mut line) = (0usize, 1usize);
    let mut i = 0;
    while i < c.len() {
        match c[i] {
            '\n' => line += 1,
            '{' => depth += 1,
            '}' => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            _ => {}
        }
        if !is_ident(c[i]) || (i > 0 && (is_ident(c[i - 1]) || c[i - 1] == ':')) {
            i += 1;
            continue;
        }
        let word_end = (i..c.len()).find(|&j| !is_ident(c[j])).unwrap_or(c.len());
        let word: String = c[i..word_end].iter().collect();
        let here: Module = module
            .iter()
            .cloned()
            .chain(inline.iter().map(|(n, _)| n.clone()))
            .collect();
        if word == "mod" {
            let (name, after) = ident_after(&c, word_end);
            if let Some(name) = name {
                if next_non_space(&c, after) == Some('{') {
                    inline.push((name, depth + 1));
                }
            }
            i = word_end;
            continue;
        }
        let is_use = word == "use";
        let start = if is_use {
            skip_space(&c, word_end)
        } else if matches!(word.as_str(), "crate" | "super" | "self")
            && c.get(word_end..word_end + 2) == Some(&[':', ':'])
        {
            i
        } else {
            i = word_end;
            continue;
        };
        let (tree, end) = parse_tree(&c, start);
        let lines_in = c[i..end.min(c.len())]
            .iter()
            .filter(|&&ch| ch == '\n')
            .count();
        let mut leaves = Vec::new();
        flatten(&tree, &mut Vec::new(), &mut leaves);
        for (segments, alias) in leaves {
            let Some(abs) = absolute(&here, &segments) else {
                continue; // an external crate's path
            };
            if is_use {
                let name = alias.or_else(|| abs.last().cloned());
                if let Some(name) = name.filter(|n| n != "*" && n != "self") {
                    // Only the file's own scope: inline modules' uses stay theirs.
                    if inline.is_empty() {
                        uses.insert(name, abs.clone());
                    }
                }
            }
            paths.push((abs, line));
        }
        // Braces inside the path were counted as depth: they are balanced.
        line += lines_in;
        i = end;
    }
    (paths, uses)
}

fn skip_space(c: &[char], mut i: usize) -> usize {
    while i < c.len() && c[i].is_whitespace() {
        i += 1;
    }
    i
}

fn next_non_space(c: &[char], i: usize) -> Option<char> {
    c.get(skip_space(c, i)).copied()
}

fn ident_after(c: &[char], i: usize) -> (Option<String>, usize) {
    let s = skip_space(c, i);
    let e = (s..c.len()).find(|&j| !is_ident(c[j])).unwrap_or(c.len());
    ((e > s).then(|| c[s..e].iter().collect()), e)
}

/// A use tree: a path, then optionally a group or `as` alias.
#[derive(Debug)]
struct Tree {
    segments: Vec<String>,
    group: Vec<Tree>,
    alias: Option<String>,
}

/// Parses `a::b::{c, d::e as f}` from `i`; the tree and where it ends.
fn parse_tree(c: &[char], mut i: usize) -> (Tree, usize) {
    let mut t = Tree {
        segments: Vec::new(),
        group: Vec::new(),
        alias: None,
    };
    loop {
        i = skip_space(c, i);
        match c.get(i) {
            Some('{') => {
                i += 1;
                loop {
                    i = skip_space(c, i);
                    match c.get(i) {
                        Some('}') => {
                            i += 1;
                            break;
                        }
                        Some(',') => i += 1,
                        None => break,
                        _ => {
                            let (sub, e) = parse_tree(c, i);
                            if e == i {
                                i += 1; // not a path: skip the character
                            } else {
                                i = e;
                            }
                            t.group.push(sub);
                        }
                    }
                }
                return (t, i);
            }
            Some('*') => {
                t.segments.push("*".into());
                return (t, i + 1);
            }
            Some(&ch) if is_ident(ch) => {
                let e = (i..c.len()).find(|&j| !is_ident(c[j])).unwrap_or(c.len());
                let seg: String = c[i..e].iter().collect();
                if seg == "as" && !t.segments.is_empty() {
                    let (alias, after) = ident_after(c, e);
                    t.alias = alias;
                    return (t, after);
                }
                t.segments.push(seg);
                i = e;
                let j = skip_space(c, i);
                if c.get(j..j + 2) == Some(&[':', ':']) {
                    i = j + 2;
                } else {
                    let k = skip_space(c, i);
                    if c.get(k..k + 2) == Some(&['a', 's'])
                        && c.get(k + 2).is_some_and(|ch| !is_ident(*ch))
                    {
                        i = k;
                        continue;
                    }
                    return (t, i);
                }
            }
            _ => return (t, i),
        }
    }
}

/// The leaves of a use tree: full segment lists and their aliases.
fn flatten(t: &Tree, prefix: &mut Vec<String>, out: &mut Vec<(Vec<String>, Option<String>)>) {
    let n = prefix.len();
    prefix.extend(t.segments.iter().cloned());
    if t.group.is_empty() {
        out.push((prefix.clone(), t.alias.clone()));
    } else {
        for sub in &t.group {
            if sub.segments.first().is_some_and(|s| s == "self") && sub.segments.len() == 1 {
                out.push((prefix.clone(), sub.alias.clone()));
            } else {
                flatten(sub, prefix, out);
            }
        }
    }
    prefix.truncate(n);
}

/// `segments` (starting `crate`, `super` or `self`) from module `here`,
/// as a path from the crate root; None for other roots.
fn absolute(here: &Module, segments: &[String]) -> Option<Module> {
    let mut path = match segments.first().map(String::as_str) {
        Some("crate") => Vec::new(),
        Some("self") => here.clone(),
        Some("super") => here.clone(),
        _ => return None,
    };
    let mut rest = &segments[1..];
    if segments[0] == "super" {
        path.pop();
        while rest.first().is_some_and(|s| s == "super") {
            path.pop();
            rest = &rest[1..];
        }
    }
    path.extend(rest.iter().cloned());
    Some(path)
}

/// The module `path` refers to: its longest prefix that is a module, and
/// when the next name was brought into that module by a `use`, wherever
/// that leads.
fn resolve(
    path: &[String],
    uses: &BTreeMap<Module, &BTreeMap<String, Module>>,
    depth: u32,
) -> Module {
    let mut n = path.len();
    while n > 0 && !uses.contains_key(&path[..n].to_vec()) {
        n -= 1;
    }
    let module = path[..n].to_vec();
    if depth < 16 {
        if let Some(next) = path.get(n) {
            if let Some(target) = uses.get(&module).and_then(|u| u.get(next)) {
                let mut full = target.clone();
                full.extend(path[n + 1..].iter().cloned());
                if full != path {
                    return resolve(&full, uses, depth + 1);
                }
            }
        }
    }
    module
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
