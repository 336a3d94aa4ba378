//! Reading a source file's module paths: comments and strings blanked, the
//! `use` trees parsed, each path made absolute and followed through the
//! `use` declarations it passes.

use super::Module;
use std::collections::BTreeMap;

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
pub(super) fn references(
    module: &Module,
    text: &str,
) -> (Vec<(Module, usize)>, BTreeMap<String, Module>) {
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
pub(super) fn resolve(
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
