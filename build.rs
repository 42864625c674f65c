//! Embeds every file of `shaders/`, `scenes/` and `shows/` into the binary as a fallback, so that adding a
//! technique means adding files, not editing a list of `include_str!`s.

use std::{env, fs, path::Path};

fn main() {
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let out = Path::new(&env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("embedded.rs");
    let mut code = String::new();
    for (dir, ext, konst) in [("shaders", "wgsl", "SHADERS"), ("scenes", "ron", "SCENES"), ("shows", "ron", "SHOWS")] {
        println!("cargo:rerun-if-changed={dir}");
        let mut names: Vec<String> = fs::read_dir(Path::new(&manifest).join(dir))
            .map(|entries| {
                entries
                    .filter_map(|e| e.ok())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.ends_with(&format!(".{ext}")))
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        code.push_str(&format!("/// Every `{dir}/*.{ext}` at build time: (file name, contents).\n"));
        code.push_str(&format!("pub const {konst}: &[(&str, &str)] = &[\n"));
        for name in names {
            println!("cargo:rerun-if-changed={dir}/{name}");
            code.push_str(&format!(
                "    ({name:?}, include_str!(concat!(env!(\"CARGO_MANIFEST_DIR\"), \"/{dir}/{name}\"))),\n"
            ));
        }
        code.push_str("];\n");
    }
    fs::write(out, code).expect("write embedded.rs");
}
