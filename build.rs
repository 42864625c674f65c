//! Embeds every file of `shaders/` (the ISF shaders of `shaders/isf/` too), `scenes/` and `shows/`, and every technique's own shaders
//! (`src/techniques/<name>/*.wgsl`), into the binary as a fallback, so that adding a technique
//! means adding files, not editing a list of `include_str!`s. Shaders are known by file name:
//! two with one name would be ambiguous, and stop the build.

use std::{env, fs, path::Path};

/// Files of `dir` (relative to the crate) ending in `.ext`, as (file name, path from the crate).
fn files(manifest: &Path, dir: &str, ext: &str) -> Vec<(String, String)> {
    println!("cargo:rerun-if-changed={dir}");
    let mut found: Vec<(String, String)> = fs::read_dir(manifest.join(dir))
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(&format!(".{ext}")))
                .map(|n| (n.clone(), format!("{dir}/{n}")))
                .collect()
        })
        .unwrap_or_default();
    found.sort();
    found
}

/// The folders of `src/techniques/`.
fn technique_dirs(manifest: &Path) -> Vec<String> {
    println!("cargo:rerun-if-changed=src/techniques");
    let mut dirs: Vec<String> = fs::read_dir(manifest.join("src/techniques"))
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .filter(|e| e.path().is_dir())
                .map(|e| format!("src/techniques/{}", e.file_name().to_string_lossy()))
                .collect()
        })
        .unwrap_or_default();
    dirs.sort();
    dirs
}

fn main() {
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let manifest = Path::new(&manifest);
    let out = Path::new(&env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("embedded.rs");
    let mut shaders = files(manifest, "shaders", "wgsl");
    for dir in technique_dirs(manifest) {
        shaders.extend(files(manifest, &dir, "wgsl"));
    }
    shaders.sort();
    for pair in shaders.windows(2) {
        assert!(pair[0].0 != pair[1].0, "two shaders named {}: {} and {}", pair[0].0, pair[0].1, pair[1].1);
    }
    let mut code = String::new();
    for (konst, what, list) in [
        ("SHADERS", "`shaders/*.wgsl` and `src/techniques/*/*.wgsl`", shaders),
        ("SCENES", "`scenes/*.ron`", files(manifest, "scenes", "ron")),
        ("SHOWS", "`shows/*.ron`", files(manifest, "shows", "ron")),
        (
            "ISF",
            "`shaders/isf/*.fs` and `*.vs`, and `shaders/gl-transitions/*.glsl`",
            [
                files(manifest, "shaders/isf", "fs"),
                files(manifest, "shaders/isf", "vs"),
                files(manifest, "shaders/gl-transitions", "glsl"),
            ]
            .concat(),
        ),
    ] {
        code.push_str(&format!("/// Every {what} at build time: (file name, path in the source tree, contents).\n"));
        code.push_str(&format!("pub const {konst}: &[(&str, &str, &str)] = &[\n"));
        for (name, path) in list {
            println!("cargo:rerun-if-changed={path}");
            code.push_str(&format!(
                "    ({name:?}, {path:?}, include_str!(concat!(env!(\"CARGO_MANIFEST_DIR\"), \"/{path}\"))),\n"
            ));
        }
        code.push_str("];\n");
    }
    fs::write(out, code).expect("write embedded.rs");
}
