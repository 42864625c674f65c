//! Where shaders and scenes come from: files on disk win, the copies embedded at build time are
//! the fallback, so a release binary copied anywhere still runs every scene. A technique's own
//! shaders live in its folder (`src/techniques/<name>/`); a file of the same name in `shaders/`
//! overrides it, and under a source checkout the folder's file on disk is read (and watched).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::files::{FileError, FileRules, LoadWait, NamedBytes};

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
    /// RON show files in `shows/`: layers of clips, transitions and a cue list.
    Show,
}

impl AssetKind {
    /// The folder under the asset root.
    pub fn dir(self) -> &'static str {
        match self {
            AssetKind::Shader => "shaders",
            AssetKind::Scene => "scenes",
            AssetKind::Show => "shows",
        }
    }

    /// The file extension, without the dot.
    pub fn ext(self) -> &'static str {
        match self {
            AssetKind::Shader => "wgsl",
            AssetKind::Scene | AssetKind::Show => "ron",
        }
    }

    /// The built-in copies: (file name, path in the source tree, text).
    fn embedded(self) -> &'static [(&'static str, &'static str, &'static str)] {
        match self {
            AssetKind::Shader => embedded::SHADERS,
            AssetKind::Scene => embedded::SCENES,
            AssetKind::Show => embedded::SHOWS,
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

/// Resolves asset names against a root folder on disk with the embedded copies as fallback;
/// shaders can be pinned to a given text (the versions a running show is built from).
#[derive(Clone, Debug)]
pub struct Assets {
    root: Option<PathBuf>,
    /// Shader file name → the text to use instead of the disk or the embedded copy.
    pinned: Arc<BTreeMap<String, Asset>>,
    /// File a parameter names (an ISF shader), as located on disk → the bytes to read instead:
    /// the version a running show was built from, whatever is on disk now.
    pinned_files: Arc<BTreeMap<PathBuf, Arc<[u8]>>>,
    /// Where the files that parameters name may be.
    files: FileRules,
    /// Whether a step waits for the files it asks for.
    load_wait: LoadWait,
    /// The size scenes and shows are loaded to render at (the command line's `--size`).
    output_size: Option<(u32, u32)>,
}

impl Assets {
    /// Looks for assets under `root`; `None` uses the embedded copies only.
    /// Files that parameters name may lie under `root` only (see [`Assets::allowing`]).
    pub fn new(root: Option<PathBuf>) -> Self {
        let files = FileRules::new(root.clone());
        let (pinned, pinned_files) = (Arc::default(), Arc::default());
        Self { root, pinned, pinned_files, files, load_wait: LoadWait::default(), output_size: None }
    }

    /// The built-in shaders and scenes only, with these assets' file rules and load mode (what a
    /// show falls back to when a file on disk is broken at start-up).
    pub fn builtin_only(&self) -> Self {
        Self { root: None, pinned: Arc::default(), pinned_files: Arc::default(), ..self.clone() }
    }

    /// These assets with files under `folder` open to file parameters too (`/`: any file).
    pub fn allowing(&self, folder: impl Into<PathBuf>) -> Self {
        Self { files: self.files.allowing(folder), ..self.clone() }
    }

    /// These assets with file loads running as `wait` says (a live show loads in the background).
    pub fn with_load_wait(&self, wait: LoadWait) -> Self {
        Self { load_wait: wait, ..self.clone() }
    }

    /// These assets for scenes that render at `size` (the command line's `--size`): their
    /// texture budget is checked there rather than at each file's own size.
    pub fn rendering_at(&self, size: Option<(u32, u32)>) -> Self {
        Self { output_size: size, ..self.clone() }
    }

    /// The size scenes render at, if the command line gave one (see [`Assets::rendering_at`]).
    pub fn output_size(&self) -> Option<(u32, u32)> {
        self.output_size
    }

    /// Where the files that parameters name may be.
    pub fn file_rules(&self) -> &FileRules {
        &self.files
    }

    /// Whether a step waits for the files it asks for.
    pub fn load_wait(&self) -> LoadWait {
        self.load_wait
    }

    /// The file a parameter's `name` means, beside the root or as given, if the rules allow it.
    pub fn locate_file(&self, name: &str) -> Result<PathBuf, FileError> {
        self.files.locate(self.root.as_deref(), name)
    }

    /// The bytes of the file a parameter's `name` means, at most `limit` of them, or `bundled`'s
    /// where no such file exists (see [`FileRules::read`]).
    pub fn read_file(&self, name: &str, limit: u64, bundled: Option<&'static [u8]>) -> Result<NamedBytes, FileError> {
        if !self.pinned_files.is_empty()
            && let Ok(path) = self.locate_file(name)
            && let Some(bytes) = self.pinned_files.get(&path)
        {
            let bytes = std::borrow::Cow::Owned(bytes.to_vec());
            return Ok(NamedBytes { origin: path.display().to_string(), path: Some(path), bytes });
        }
        self.files.read(self.root.as_deref(), name, limit, bundled)
    }

    /// These assets with the file at `path` (as [`Assets::locate_file`] gives it) read as
    /// `bytes`, whatever is on disk: the version of a file-declared node (an ISF shader) that a
    /// running show was built from.
    pub fn with_file(&self, path: PathBuf, bytes: Arc<[u8]>) -> Self {
        self.with_files([(path, bytes)])
    }

    /// [`Assets::with_file`] for several files at once.
    pub fn with_files(&self, files: impl IntoIterator<Item = (PathBuf, Arc<[u8]>)>) -> Self {
        let mut pinned = (*self.pinned_files).clone();
        pinned.extend(files);
        Self { pinned_files: Arc::new(pinned), ..self.clone() }
    }

    /// The bytes pinned for `path`, if any (see [`Assets::with_file`]).
    pub fn pinned_file(&self, path: &Path) -> Option<Arc<[u8]>> {
        self.pinned_files.get(path).cloned()
    }

    /// Where a parameter's `name` may be saved as a `.ext` file, if the rules allow it.
    pub fn locate_for_saving(&self, name: &str, ext: &str) -> Result<PathBuf, FileError> {
        self.files.locate_for_saving(self.root.as_deref(), name, ext)
    }

    /// These assets with shader `asset.name` pinned to `asset`'s text, whatever is on disk.
    pub fn with_shader(&self, asset: Asset) -> Self {
        let mut pinned = (*self.pinned).clone();
        pinned.insert(asset.name.clone(), asset);
        Self { pinned: Arc::new(pinned), ..self.clone() }
    }

    /// These assets with every shader pinned to its text now: what a running show rebuilds from
    /// when files on disk have changed since (a device loss, a reload rolled back).
    pub fn with_shaders_pinned(&self) -> Self {
        let loaded = self.names(AssetKind::Shader).into_iter().filter_map(|n| self.load(AssetKind::Shader, &n).ok());
        let pinned = loaded.map(|a| (a.name.clone(), a)).collect();
        Self { pinned: Arc::new(pinned), ..self.clone() }
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

    /// Loads `name` (with or without extension): the file on disk if present — in the kind's
    /// folder, or for a technique's shader in its folder of a source checkout — else the
    /// embedded copy. The error says where it looked.
    pub fn load(&self, kind: AssetKind, name: &str) -> Result<Asset, String> {
        let file = with_ext(name, kind);
        if let Some(asset) = self.pinned.get(&file).filter(|_| kind == AssetKind::Shader) {
            return Ok(asset.clone());
        }
        let built_in = kind.embedded().iter().find(|(n, _, _)| *n == file);
        let on_disk = [self.dir(kind).map(|d| d.join(&file)), built_in.and_then(|(_, path, _)| self.in_root(path))];
        if let Some(path) = on_disk.into_iter().flatten().find(|p| p.is_file()) {
            return std::fs::read_to_string(&path)
                .map(|source| Asset { name: file.clone(), origin: path.display().to_string(), source })
                .map_err(|e| format!("cannot read {}: {e}", path.display()));
        }
        built_in
            .map(|(n, path, s)| Asset {
                name: n.to_string(),
                origin: format!("<embedded>/{path}"),
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

    /// `path` (from the source tree's root) under the root on disk, if there is a root.
    fn in_root(&self, path: &str) -> Option<PathBuf> {
        self.root.as_ref().map(|r| r.join(path))
    }

    /// The folders a live show watches for edits: `shaders/` (and `shaders/isf/`), `scenes/`, `shows/`, and under a
    /// source checkout each technique folder that holds shaders. Only those that exist.
    pub fn watched_dirs(&self) -> Vec<PathBuf> {
        let kinds = [AssetKind::Shader, AssetKind::Scene, AssetKind::Show];
        let mut dirs: Vec<PathBuf> = kinds.iter().filter_map(|k| self.dir(*k)).collect();
        dirs.extend(self.dir(AssetKind::Shader).map(|d| d.join("isf")));
        for (_, path, _) in AssetKind::Shader.embedded() {
            if let Some(dir) = self.in_root(path).and_then(|p| p.parent().map(Path::to_path_buf))
                && !dirs.contains(&dir)
            {
                dirs.push(dir);
            }
        }
        dirs.retain(|d| d.is_dir());
        dirs
    }

    /// Every asset name of `kind`: those on disk and the embedded ones, sorted, without duplicates.
    pub fn names(&self, kind: AssetKind) -> Vec<String> {
        let mut names: Vec<String> = kind.embedded().iter().map(|(n, _, _)| n.to_string()).collect();
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

/// The ISF shaders built into the binary (`shaders/isf/*.fs` and `*.vs`): (path in the source
/// tree, text) — what an `isf` node falls back to when the file is not on disk.
pub fn bundled_isf() -> impl Iterator<Item = (&'static str, &'static str)> {
    embedded::ISF.iter().map(|(_, path, text)| (*path, *text))
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

    #[test]
    fn a_technique_shader_is_read_from_its_folder_of_a_checkout_unless_shaders_overrides_it() {
        let tmp = std::env::temp_dir().join(format!("indra-assets-tree-{}", std::process::id()));
        let folder = tmp.join("src/techniques/star_glow");
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("star_glow.wgsl"), "// in its folder").unwrap();
        let assets = Assets::new(Some(tmp.clone()));
        let loaded = assets.load(AssetKind::Shader, "star_glow").unwrap();
        assert_eq!(
            (loaded.source.as_str(), loaded.origin.contains("src/techniques/star_glow")),
            ("// in its folder", true)
        );
        assert!(assets.watched_dirs().contains(&folder), "{:?}", assets.watched_dirs());
        std::fs::create_dir_all(tmp.join("shaders")).unwrap();
        std::fs::write(tmp.join("shaders/star_glow.wgsl"), "// the performer's").unwrap();
        assert_eq!(assets.load(AssetKind::Shader, "star_glow").unwrap().source, "// the performer's");
        let built_in = Assets::new(None).load(AssetKind::Shader, "star_glow").unwrap();
        assert_eq!(built_in.origin, "<embedded>/src/techniques/star_glow/star_glow.wgsl");
        std::fs::remove_dir_all(tmp).unwrap();
    }

    #[test]
    fn pinned_shaders_keep_their_text_when_the_file_changes() {
        let tmp = std::env::temp_dir().join(format!("indra-assets-pin-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("shaders")).unwrap();
        std::fs::write(tmp.join("shaders/kleinian.wgsl"), "// first").unwrap();
        let assets = Assets::new(Some(tmp.clone()));
        let pinned = assets.with_shaders_pinned();
        std::fs::write(tmp.join("shaders/kleinian.wgsl"), "// second").unwrap();
        assert_eq!(pinned.load(AssetKind::Shader, "kleinian").unwrap().source, "// first");
        assert_eq!(assets.load(AssetKind::Shader, "kleinian").unwrap().source, "// second");
        let newer = pinned.load(AssetKind::Shader, "cloth").unwrap();
        assert!(newer.origin.starts_with("<embedded>"), "shaders not on disk pin the built-in copy");
        let repinned = pinned.with_shader(Asset { source: "// third".into(), ..newer });
        assert_eq!(repinned.load(AssetKind::Shader, "cloth.wgsl").unwrap().source, "// third");
        assert_eq!(repinned.load(AssetKind::Shader, "kleinian").unwrap().source, "// first");
        std::fs::remove_dir_all(tmp).unwrap();
    }
}
