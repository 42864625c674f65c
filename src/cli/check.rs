//! `indra check`: validates scenes, shows and shaders, printing every located error.

use std::path::{Path, PathBuf};

use indra::assets::{AssetKind, Assets};
use indra::gpu::validate_as_used;
use indra::scene::load_scene;

/// Validates scenes and shaders; prints every located error.
pub fn check(assets: &Assets, files: &[PathBuf]) -> Result<(), String> {
    let mut targets: Vec<(AssetKind, String)> = Vec::new();
    // ISF shaders (.fs, with a .vs beside them) are checked as the isf node compiles them.
    let mut isf_files: Vec<String> = Vec::new();
    // A file named on the command line may be anywhere.
    let assets = &if files.is_empty() { assets.clone() } else { assets.allowing("/") };
    if files.is_empty() {
        targets.extend(assets.names(AssetKind::Shader).into_iter().map(|n| (AssetKind::Shader, n)));
        targets.extend(assets.names(AssetKind::Scene).into_iter().map(|n| (AssetKind::Scene, n)));
        targets.extend(assets.names(AssetKind::Show).into_iter().map(|n| (AssetKind::Show, format!("shows/{n}"))));
        isf_files.extend(indra::techniques::isf::shader_names(assets));
    } else {
        for f in files {
            let name = f.display().to_string();
            if f.extension().is_some_and(|e| e == "fs" || e == "glsl") {
                isf_files.push(name);
                continue;
            }
            let kind = if f.extension().is_some_and(|e| e == "wgsl") {
                AssetKind::Shader
            } else if indra::scene::names_a_show(&name) {
                AssetKind::Show
            } else {
                AssetKind::Scene
            };
            targets.push((kind, name));
        }
    }
    let shaders = assets.names(AssetKind::Shader);
    let mut failures = 0;
    for (kind, name) in &targets {
        let result = match kind {
            AssetKind::Scene | AssetKind::Show => load_scene(assets, name).map(|_| ()).map_err(|e| e.to_string()),
            AssetKind::Shader => read_shader(assets, name).and_then(|(origin, source)| {
                // A base is looked for beside the file first, then among the project's shaders;
                // a file they extend is checked through them.
                let beside = |base: &str| Path::new(name).with_file_name(base).display().to_string();
                let file = Path::new(name).file_name().map_or(name.clone(), |f| f.to_string_lossy().into_owned());
                validate_as_used(&file, (&origin, &source), &shaders, |n| {
                    read_shader(assets, &beside(n)).or_else(|_| read_shader(assets, n))
                })
            }),
        };
        match result {
            Ok(()) => say!("ok     {name}"),
            Err(e) => {
                failures += 1;
                say!("error  {e}");
            }
        }
    }
    for name in &isf_files {
        match indra::techniques::isf::IsfFiles::read(assets, name).and_then(|f| f.compile().map_err(|e| e.to_string()))
        {
            Ok(_) => say!("ok     {name}"),
            Err(e) => {
                failures += 1;
                say!("error  {e}");
            }
        }
    }
    say!("{} checked, {failures} with errors", targets.len() + isf_files.len());
    if failures > 0 { Err(format!("{failures} file(s) have errors")) } else { Ok(()) }
}

fn read_shader(assets: &Assets, name: &str) -> Result<(String, String), String> {
    let path = Path::new(name);
    if path.is_file() {
        return std::fs::read_to_string(path).map(|s| (name.to_string(), s)).map_err(|e| format!("{name}: {e}"));
    }
    assets.load(AssetKind::Shader, name).map(|a| (a.origin, a.source))
}
