//! The architecture page (`docs/architecture.md`) against the code: its layer table lists every
//! module of `src/` once, every `crate::` import goes to a lower layer, and no file is over 600
//! lines but those the page names.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The repository.
pub(crate) const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The binary's files and folder (its commands), which may use any layer.
const BINARY: [&str; 3] = ["lib.rs", "main.rs", "cli"];

/// Module → layer, from the page's table (`| 3 | `params` | … |`).
fn layers() -> BTreeMap<String, u32> {
    let page = std::fs::read_to_string(Path::new(ROOT).join("docs/architecture.md")).unwrap();
    let mut layers = BTreeMap::new();
    for row in page.lines().filter(|l| l.starts_with("| ")) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let Ok(layer) = cells[1].parse::<u32>() else { continue };
        for module in cells[2].split(',').map(|m| m.trim().trim_matches('`')) {
            assert!(layers.insert(module.to_string(), layer).is_none(), "{module} is listed twice");
        }
    }
    layers
}

/// The modules of `src/`: its folders and files other than the binary's.
fn modules() -> Vec<String> {
    let mut found: Vec<String> = std::fs::read_dir(Path::new(ROOT).join("src"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !BINARY.contains(&p.file_name().unwrap().to_str().unwrap()))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    found.sort();
    found
}

/// Every `.rs` file under `path`, into `out`.
pub(crate) fn rust_files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).unwrap() {
            rust_files(&entry.unwrap().path(), out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_path_buf());
    }
}

/// The top-level modules `source` names as `crate::<module>` (a `crate::name!` is a macro, which
/// lives at the crate's root, not a module).
fn imports(source: &str) -> Vec<String> {
    source
        .match_indices("crate::")
        .filter(|(at, _)| !source[..*at].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == '$'))
        .filter_map(|(at, _)| {
            let rest = &source[at + 7..];
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
            (end > 0 && !rest[end..].starts_with('!')).then(|| rest[..end].to_string())
        })
        .collect()
}

#[test]
fn the_layer_table_lists_every_module_of_src_once() {
    let listed: Vec<String> = layers().into_keys().collect();
    assert_eq!(listed, modules(), "docs/architecture.md's layer table and src/ disagree");
    let lib = std::fs::read_to_string(Path::new(ROOT).join("src/lib.rs")).unwrap();
    let mut declared: Vec<String> =
        lib.lines().filter_map(|l| l.strip_prefix("pub mod ")).map(|m| m.trim_end_matches(';').to_string()).collect();
    declared.sort();
    assert_eq!(declared, listed, "lib.rs declares other modules than the page lists");
}

#[test]
fn every_import_goes_to_a_lower_layer() {
    let layers = layers();
    let mut wrong = Vec::new();
    for (module, &layer) in &layers {
        let dir = Path::new(ROOT).join("src").join(module);
        let path = if dir.is_dir() { dir } else { dir.with_extension("rs") };
        let mut files = Vec::new();
        rust_files(&path, &mut files);
        // A technique's render tests sit in its folder but test it through the whole engine,
        // as the integration tests do (see lib.rs): they are exempt, as those are.
        for file in files.into_iter().filter(|f| !f.ends_with("render_tests.rs")) {
            let source = std::fs::read_to_string(&file).unwrap();
            for used in imports(&source).into_iter().filter(|u| u != module) {
                match layers.get(&used) {
                    Some(&other) if other < layer => {}
                    other => wrong.push(format!(
                        "{} (layer {layer}) uses crate::{used} (layer {other:?})",
                        file.strip_prefix(ROOT).unwrap().display()
                    )),
                }
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layers of docs/architecture.md:\n{}", wrong.join("\n"));
}

/// The most lines a file of `src/` may have unless the page names it as an exception.
const MAX_LINES: usize = 600;

#[test]
fn no_file_is_over_600_lines_but_the_exceptions_the_page_names() {
    let page = std::fs::read_to_string(Path::new(ROOT).join("docs/architecture.md")).unwrap();
    let section = page.split("## File sizes").nth(1).unwrap().split("\n## ").next().unwrap();
    let named: Vec<&str> =
        section.lines().filter_map(|l| l.strip_prefix("- `")).filter_map(|l| l.split('`').next()).collect();
    let mut files = Vec::new();
    rust_files(&Path::new(ROOT).join("src"), &mut files);
    let mut long = Vec::new();
    for file in files {
        let relative = file.strip_prefix(ROOT).unwrap().to_string_lossy().replace('\\', "/");
        let lines = std::fs::read_to_string(&file).unwrap().lines().count();
        if lines > MAX_LINES && !named.contains(&relative.as_str()) {
            long.push(format!("{relative}: {lines} lines"));
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines that docs/architecture.md does not name:\n{}",
        long.join("\n")
    );
    for name in named {
        assert!(Path::new(ROOT).join(name).is_file(), "docs/architecture.md names {name}, which is not a file");
    }
}

#[test]
fn the_import_scan_sees_what_it_must() {
    let source = "use crate::gpu::Gpu; $crate::no; my_crate::no; crate::a_macro! {} crate::params::ParamSet::new();";
    assert_eq!(imports(source), ["gpu", "params"]);
}

#[test]
fn every_technique_folder_is_registered_once_and_its_shaders_are_built_in() {
    let dir = Path::new(ROOT).join("src/techniques");
    let registry = std::fs::read_to_string(dir.join("mod.rs")).unwrap();
    let built_in = indra::assets::Assets::new(None);
    let mut folders: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    for name in &folders {
        assert!(registry.contains(&format!("pub mod {name};")), "src/techniques/{name}/ is not declared");
        assert_eq!(registry.matches(&format!("    {name}::INFO,")).count(), 1, "{name} is not in REGISTRY once");
        for shader in std::fs::read_dir(dir.join(name)).unwrap().map(|e| e.unwrap().path()) {
            if shader.extension().is_some_and(|e| e == "wgsl") {
                let file = shader.file_name().unwrap().to_string_lossy().into_owned();
                let asset = built_in.load(indra::assets::AssetKind::Shader, &file).unwrap();
                assert_eq!(asset.source, std::fs::read_to_string(&shader).unwrap(), "{file} is not the built-in copy");
            }
        }
    }
    assert_eq!(indra::techniques::REGISTRY.len(), folders.len(), "REGISTRY has entries without a folder");
}
