//! Where shaders and scenes come from: files on disk win, the copies embedded at build time are
//! the fallback, so a release binary copied anywhere still runs every scene.

use std::path::{Path, PathBuf};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/embedded.rs"));
}

/// The kind of asset, which decides its folder and extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssetKind {
    /// WGSL shader sources in `shaders/`.
    Shader,
    /// RON scene files in `scenes/`.
    Scene,
}

impl AssetKind {
    /// The folder under the asset root.
    pub fn dir(self) -> &'static str {
        match self {
            AssetKind::Shader => "shaders",
            AssetKind::Scene => "scenes",
        }
    }

    /// The file extension, without the dot.
    pub fn ext(self) -> &'static str {
        match self {
            AssetKind::Shader => "wgsl",
            AssetKind::Scene => "ron",
        }
    }

    fn embedded(self) -> &'static [(&'static str, &'static str)] {
        match self {
            AssetKind::Shader => embedded::SHADERS,
            AssetKind::Scene => embedded::SCENES,
        }
    }
}

/// One loaded asset: its text and where it came from (for error messages and reload).
#[derive(Clone, Debug)]
pub struct Asset {
    /// The file name, e.g. `kleinian.wgsl`.
    pub name: String,
    /// A path on disk, or `<embedded>/name` for the built-in copy.
    pub origin: String,
    /// The text.
    pub source: String,
}

/// Resolves asset names against a root folder on disk with the embedded copies as fallback.
#[derive(Clone, Debug)]
pub struct Assets {
    root: Option<PathBuf>,
}

impl Assets {
    /// Looks for assets under `root`; `None` uses the embedded copies only.
    pub fn new(root: Option<PathBuf>) -> Self {
        Self { root }
    }

    /// The default root: `$INDRA_ROOT`, else the current folder if it has `scenes/` or `shaders/`,
    /// else the source tree this binary was built from (if it still exists).
    pub fn discover() -> Self {
        if let Some(root) = std::env::var_os("INDRA_ROOT") {
            return Self::new(Some(root.into()));
        }
        let cwd = std::env::current_dir().ok();
        let candidates = cwd.into_iter().chain([PathBuf::from(env!("CARGO_MANIFEST_DIR"))]);
        for dir in candidates {
            if dir.join("scenes").is_dir() || dir.join("shaders").is_dir() {
                return Self::new(Some(dir));
            }
        }
        Self::new(None)
    }

    /// The root folder on disk, if any.
    pub fn root(&self) -> Option<&Path> {
        self.root.as_deref()
    }

    /// The folder on disk that holds assets of `kind`, if there is a root.
    pub fn dir(&self, kind: AssetKind) -> Option<PathBuf> {
        self.root.as_ref().map(|r| r.join(kind.dir()))
    }

    /// Loads `name` (with or without extension): the file on disk if present, else the embedded
    /// copy. The error says where it looked.
    pub fn load(&self, kind: AssetKind, name: &str) -> Result<Asset, String> {
        let file = with_ext(name, kind);
        if let Some(dir) = self.dir(kind) {
            let path = dir.join(&file);
            if path.is_file() {
                return std::fs::read_to_string(&path)
                    .map(|source| Asset { name: file.clone(), origin: path.display().to_string(), source })
                    .map_err(|e| format!("cannot read {}: {e}", path.display()));
            }
        }
        kind.embedded()
            .iter()
            .find(|(n, _)| *n == file)
            .map(|(n, s)| Asset {
                name: n.to_string(),
                origin: format!("<embedded>/{}/{n}", kind.dir()),
                source: s.to_string(),
            })
            .ok_or_else(|| {
                let place =
                    self.dir(kind).map(|d| d.display().to_string()).unwrap_or_else(|| "no folder on disk".into());
                format!(
                    "no {} named '{file}' (looked in {place} and the built-in copies; `indra list` shows what exists)",
                    kind.dir().trim_end_matches('s')
                )
            })
    }

    /// Every asset name of `kind`: those on disk and the embedded ones, sorted, without duplicates.
    pub fn names(&self, kind: AssetKind) -> Vec<String> {
        let mut names: Vec<String> = kind.embedded().iter().map(|(n, _)| n.to_string()).collect();
        if let Some(Ok(entries)) = self.dir(kind).map(std::fs::read_dir) {
            for entry in entries.flatten() {
                let n = entry.file_name().to_string_lossy().into_owned();
                if n.ends_with(&format!(".{}", kind.ext())) {
                    names.push(n);
                }
            }
        }
        names.sort();
        names.dedup();
        names
    }
}

fn with_ext(name: &str, kind: AssetKind) -> String {
    if name.ends_with(&format!(".{}", kind.ext())) { name.to_string() } else { format!("{name}.{}", kind.ext()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_copy_is_the_fallback_and_disk_wins() {
        let tmp = std::env::temp_dir().join(format!("indra-assets-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("shaders")).unwrap();
        std::fs::write(tmp.join("shaders/kleinian.wgsl"), "// on disk").unwrap();
        let assets = Assets::new(Some(tmp.clone()));
        assert_eq!(assets.load(AssetKind::Shader, "kleinian").unwrap().source, "// on disk");
        let scene = assets.load(AssetKind::Scene, "kleinian").unwrap();
        assert!(scene.origin.starts_with("<embedded>"), "{}", scene.origin);
        let err = assets.load(AssetKind::Scene, "no_such_scene").unwrap_err();
        assert!(err.contains("no_such_scene.ron"), "{err}");
        std::fs::remove_dir_all(tmp).unwrap();
    }
}
