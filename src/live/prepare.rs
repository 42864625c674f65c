//! The work of one file's reload that can wait: reading it, parsing and validating it, and
//! building the nodes it changes (pipelines compile for up to seconds). A live show does this on
//! a worker thread from a snapshot of the running scene, and the render thread only installs the
//! result (see [`super::LiveReload`]); renders and tests do it in place.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::watcher::read_stable;
use crate::assets::{Asset, AssetKind, Assets};
use crate::gpu::{Gpu, validate_as_used};
use crate::scene::show::{build_show, parse_show};
use crate::scene::{NodeRebuild, Replacement, SceneNode, SceneSnapshot, Transitions, load_scene, parse_scene_with};

/// Everything one file's reload needs, owned (it may travel to a worker thread).
pub(super) struct Job {
    /// The changed file.
    pub path: PathBuf,
    /// The assets the show runs with.
    pub running: Assets,
    /// The running scene now.
    pub snapshot: SceneSnapshot,
    pub gpu: Gpu,
    pub size: (u32, u32),
    /// The text of this file that stalled the GPU, with its message: saved again unchanged, it
    /// is refused without being tried.
    pub stalled: Option<(String, String)>,
}

/// What a reload built, for the render thread to install.
pub(super) enum Prepared {
    /// A WGSL shader: the assets with it, and the nodes (maybe none) rebuilt with them.
    Shader { next: Assets, name: String, source: String, rebuild: NodeRebuild },
    /// An edited scene or show.
    Scene(Replacement),
    /// An ISF file: the assets with it, and the scene reloaded with the nodes that read it
    /// rebuilt (`None` when no node reads it).
    Declared { next: Assets, real: PathBuf, source: String, replacement: Option<Replacement> },
    /// A file the running scene does not use.
    Unused,
}

impl Job {
    /// Reads, validates and builds; an error keeps the last good version running.
    pub fn run(self) -> Result<Prepared, String> {
        match self.path.extension().and_then(|e| e.to_str()) {
            Some("wgsl") => self.shader(),
            Some("ron") => self.scene(),
            Some("fs" | "vs" | "glsl") => self.declared(),
            _ => Ok(Prepared::Unused),
        }
    }

    /// The text of the file now, unless it is the text that stalled the GPU (then its message).
    fn read_untried(&self) -> Result<String, String> {
        let source = read(&self.path)?;
        match &self.stalled {
            Some((text, message)) if *text == source => Err(message.clone()),
            _ => Ok(source),
        }
    }

    fn shader(self) -> Result<Prepared, String> {
        let name = self.path.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_string();
        let source = self.read_untried()?;
        let origin = self.path.display().to_string();
        let running = &self.running;
        let shaders = running.names(AssetKind::Shader);
        validate_as_used(&name, (&origin, &source), &shaders, |n| {
            running.load(AssetKind::Shader, n).map(|a| (a.origin, a.source))
        })?;
        let next = running.with_shader(Asset { name: name.clone(), origin, source: source.clone() });
        let rebuild =
            NodeRebuild::prepare(&self.snapshot, &name, &self.gpu, &next, self.size).map_err(|e| e.to_string())?;
        Ok(Prepared::Shader { next, name, source, rebuild })
    }

    fn scene(self) -> Result<Prepared, String> {
        let same_file = |origin: &str| {
            let running = Path::new(origin);
            running.canonicalize().ok().zip(self.path.canonicalize().ok()).is_some_and(|(a, b)| a == b)
        };
        let running = &self.snapshot.scene;
        let scene = match &running.show {
            // A show reloads when its file or one of its clips' scenes changes; a clip that
            // breaks keeps the whole show as it was (its last good version plays on).
            Some(show) => {
                if !show.sources.iter().any(|s| same_file(s)) {
                    return Ok(Prepared::Unused);
                }
                let origin = &running.origin;
                match show.file.as_deref().filter(|_| !same_file(origin)) {
                    // A clip's scene changed: the show as it runs (its chains as edited live)
                    // is built again with it.
                    Some(running) => build_show(&self.running, origin, &running.text, running.file.clone(), false),
                    None => parse_show(&self.running, origin, &read(Path::new(origin))?, false),
                }
                .map_err(|e| e.to_string())?
            }
            None => {
                if !same_file(&running.origin) {
                    return Ok(Prepared::Unused);
                }
                let source = read(&self.path)?;
                let origin = self.path.display().to_string();
                parse_scene_with(&self.running, &origin, &source).map_err(|e| e.to_string())?
            }
        };
        let replacement = Replacement::prepare(
            &self.snapshot,
            scene,
            &self.gpu,
            &self.running,
            self.size,
            (&|_| false, Transitions::Compile),
        )
        .map_err(|e| e.to_string())?;
        Ok(Prepared::Scene(replacement))
    }

    /// An ISF shader (`.fs` or its `.vs`): nodes declare their parameters from it, so the scene
    /// is loaded again with the nodes that read it rebuilt (its inputs may have changed).
    fn declared(self) -> Result<Prepared, String> {
        let source = self.read_untried()?;
        let real = self.path.canonicalize().map_err(|e| format!("{}: {e}", self.path.display()))?;
        let next = self.running.with_file(real.clone(), Arc::from(source.as_bytes()));
        let replacement = rebuild_reading(&self.path, &self.snapshot, &self.gpu, self.size, &next)?;
        Ok(Prepared::Declared { next, real, source, replacement })
    }
}

/// The text of `path` once an editor has finished writing it, or a message naming the file.
fn read(path: &Path) -> Result<String, String> {
    read_stable(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The running scene loaded again from `assets`, with the nodes that read the ISF file `path`
/// (or its companion) rebuilt; `None` when no node reads it.
pub(super) fn rebuild_reading(
    path: &Path,
    snapshot: &SceneSnapshot,
    gpu: &Gpu,
    size: (u32, u32),
    assets: &Assets,
) -> Result<Option<Replacement>, String> {
    let shader = path.with_extension("fs").canonicalize().ok();
    let reads_it = |n: &SceneNode| {
        n.technique.declare.is_some_and(|d| {
            let file = n.params.index(d.file_param).map(|i| n.params.value_at(i));
            let Some(crate::params::ParamValue::Text(file)) = file else { return false };
            let located = assets.locate_file(file.as_str()).ok().and_then(|p| p.canonicalize().ok());
            located.is_some() && located == shader
        })
    };
    if !snapshot.scene.nodes.iter().any(reads_it) {
        return Ok(None);
    }
    let origin = &snapshot.scene.origin;
    // A built-in scene reloads by its name; one from disk (or a bare .fs) by its path.
    let name = origin.strip_prefix("<embedded>/scenes/").unwrap_or(origin);
    let scene = load_scene(assets, name).map_err(|e| e.to_string())?;
    Replacement::prepare(snapshot, scene, gpu, assets, size, (&reads_it, Transitions::Compile))
        .map(Some)
        .map_err(|e| e.to_string())
}
