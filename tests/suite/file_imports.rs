//! The files of `src/` against each other: no two files import each other, directly or round a
//! longer circle (a module and the modules it declares aside: a folder's `mod.rs` names its
//! files and they use what it declares, as Rust has it).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::architecture::{ROOT, rust_files};

/// The module path of each library file: `src/media/clip.rs` → `media::clip`,
/// `src/scene/mod.rs` → `scene`. The binary's files (`main.rs`, `cli/`) are not the library's.
fn library_files() -> BTreeMap<Vec<String>, PathBuf> {
    let src = Path::new(ROOT).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let binary = [src.join("main.rs"), src.join("lib.rs"), src.join("cli")];
    files
        .into_iter()
        .filter(|f| !binary.iter().any(|b| f.starts_with(b)))
        .map(|f| {
            let relative = f.strip_prefix(&src).unwrap().with_extension("");
            let mut path: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if path.last().is_some_and(|l| l == "mod") {
                path.pop();
            }
            (path, f)
        })
        .collect()
}

/// The paths `source` names from `crate::`, `super::` and `self::`, made absolute for a file
/// whose module is `module`; `use a::{b, c::D}` gives `a::b` and `a::c::D`. A file's tests
/// (`#[cfg(test)]` to its end) are left out, their `super::` being the file itself, and so are
/// comments: a doc link is not an import.
fn named_paths(source: &str, module: &[String]) -> Vec<Vec<String>> {
    let code: String = source
        .split("#[cfg(test)]\nmod tests")
        .next()
        .unwrap()
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let code = code.as_str();
    let mut found = Vec::new();
    for (at, _) in code.match_indices("::") {
        let before = &code[..at];
        let word_start = before.rfind(|c: char| !(c.is_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
        let first = &before[word_start..];
        // Only a path's first segment, and not `$crate` or `my_crate`.
        if code[..word_start].ends_with([':', '$']) {
            continue;
        }
        let mut base: Vec<String> = match first {
            "crate" => Vec::new(),
            "self" => module.to_vec(),
            "super" => module[..module.len().saturating_sub(1)].to_vec(),
            _ => continue,
        };
        let mut rest = &code[at + 2..];
        // Further `super::` climb on.
        while let Some(r) = rest.strip_prefix("super::") {
            base.pop();
            rest = r;
        }
        expand(rest, base, &mut found);
    }
    found
}

/// Appends the paths of `rest` (what follows a `::`) to `base`, opening one level of braces.
fn expand(rest: &str, mut base: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut rest = rest;
    loop {
        let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
        if end == 0 {
            if let Some(inner) = rest.strip_prefix('{') {
                let close = matching_brace(inner);
                for item in split_top_level(&inner[..close]) {
                    let item = item.trim();
                    if !item.is_empty() && item != "self" && !item.starts_with("self ") {
                        expand(item, base.clone(), out);
                    }
                }
                return;
            }
            break;
        }
        base.push(rest[..end].to_string());
        match rest[end..].strip_prefix("::") {
            Some(r) => rest = r,
            None => break,
        }
    }
    out.push(base);
}

fn matching_brace(s: &str) -> usize {
    let mut depth = 0;
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => return i,
            '}' => depth -= 1,
            _ => {}
        }
    }
    s.len()
}

fn split_top_level(s: &str) -> Vec<&str> {
    let (mut parts, mut depth, mut from) = (Vec::new(), 0, 0);
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&s[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[from..]);
    parts
}

/// File → the files it imports: each named path goes to the longest prefix that is a file.
fn import_graph() -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let files = library_files();
    let mut graph = BTreeMap::new();
    for (module, file) in &files {
        let source = std::fs::read_to_string(file).unwrap();
        let mut targets = BTreeSet::new();
        for path in named_paths(&source, module) {
            let Some(target) = (1..=path.len()).rev().map(|n| &path[..n]).find(|p| files.contains_key(*p)) else {
                continue;
            };
            // A module and the modules inside it use each other by nature.
            if !module.starts_with(target) && !target.starts_with(module) {
                targets.insert(target.to_vec());
            }
        }
        graph.insert(module.clone(), targets);
    }
    graph
}

/// One circle through `start` if there is one, as the files on it.
fn circle_through(graph: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>, start: &Vec<String>) -> Option<Vec<String>> {
    let mut stack = vec![(start.clone(), vec![start.join("::")])];
    let mut seen = BTreeSet::new();
    while let Some((node, trail)) = stack.pop() {
        for next in graph.get(&node).into_iter().flatten() {
            if next == start {
                return Some(trail.iter().cloned().chain([start.join("::")]).collect());
            }
            if seen.insert(next.clone()) {
                let mut longer = trail.clone();
                longer.push(next.join("::"));
                stack.push((next.clone(), longer));
            }
        }
    }
    None
}

#[test]
fn no_two_files_import_each_other_round_any_circle() {
    let graph = import_graph();
    let circles: BTreeSet<String> =
        graph.keys().filter_map(|f| circle_through(&graph, f)).map(|c| c.join(" → ")).collect();
    assert!(
        circles.is_empty(),
        "files that import each other:\n{}",
        circles.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn the_file_import_scan_sees_what_it_must() {
    let module: Vec<String> = ["media", "still"].map(String::from).to_vec();
    let source = "use super::picture::Picture;\nuse crate::gpu::{Gpu, blit::{self, Blit}};\n/// [`super::clip`]\n\
                  let x = $crate::no::Thing; my_crate::no();\n#[cfg(test)]\nmod tests { use super::*; }";
    let paths: Vec<String> = named_paths(source, &module).iter().map(|p| p.join("::")).collect();
    assert_eq!(paths, ["media::picture::Picture", "gpu::Gpu", "gpu::blit::Blit"]);
}
