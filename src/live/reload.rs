//! Applying changed files to the running scene, keeping the last good version on any error.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::watcher::{Watcher, read_stable};
use crate::assets::{Asset, AssetKind, Assets};
use crate::gpu::{Gpu, validate_as_used};
use crate::params::Remap;
use crate::scene::show::parse_show;
use crate::scene::{Player, SceneInstance, load_scene, parse_scene_with};

/// What one poll did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReloadReport {
    /// Files applied to the running show.
    pub applied: Vec<String>,
    /// New errors (each reported once: a file that stays broken is not reported again).
    pub errors: Vec<String>,
    /// Files whose error is gone.
    pub fixed: Vec<String>,
    /// Whether the scene's structure changed (control maps must be rebuilt).
    pub scene_changed: bool,
    /// Where the old scene's parameters are in the new one, when the scene was replaced: apply
    /// it to everything holding parameter positions (queued events, scripts, MIDI learn).
    pub remap: Option<Remap>,
}

/// Watches the asset folders and applies changes to a running scene.
pub struct LiveReload {
    watcher: Option<Watcher>,
    /// The assets with every shader pinned to the version the show runs: what nodes are rebuilt
    /// from, whatever is on disk right now.
    running: Assets,
    /// File → its current error, while broken.
    broken: BTreeMap<PathBuf, String>,
    /// The newest shader reload applied (WGSL or ISF), to roll back if the GPU stalls or is lost
    /// soon after.
    newest: Option<AppliedShader>,
    /// File → the text that stalled the GPU: saved again unchanged, it is not tried again.
    stalled: BTreeMap<PathBuf, String>,
}

/// A shader reload that was applied, with the version it replaced.
struct AppliedShader {
    path: PathBuf,
    previous: Previous,
    source: String,
    at: Instant,
}

/// What a reload replaced.
enum Previous {
    /// A WGSL shader: nodes are built from it by name.
    Shader(Asset),
    /// A file nodes declare their parameters from (an ISF shader), by its canonical path.
    Declared(Arc<[u8]>),
}

/// What [`LiveReload::roll_back_newest`] took back, for the caller to rebuild.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RolledBack {
    /// The WGSL shader of this name: rebuild the nodes that use it.
    Shader(String),
    /// The ISF file at this path: reload the scene with it (see [`LiveReload::rebuild_declared`]).
    Declared(PathBuf),
}

/// The most bytes of ISF files pinned at start (what a stall rolls back to); files past it are
/// read from disk as before and cannot be rolled back.
const MAX_PINNED_DECLARED: u64 = 64 << 20;

impl LiveReload {
    /// Watches `assets`' `shaders/`, `scenes/` and `shows/` folders and, under a source
    /// checkout, the technique folders' shaders (see [`Assets::watched_dirs`]).
    pub fn new(assets: &Assets) -> Result<Self, String> {
        let dirs = assets.watched_dirs();
        let watcher = if dirs.is_empty() { None } else { Some(Watcher::watch(&dirs)?) };
        let running = pin_declared_files(assets.with_shaders_pinned(), &dirs);
        Ok(Self { watcher, running, broken: BTreeMap::new(), newest: None, stalled: BTreeMap::new() })
    }

    /// Marks a file as broken from the start (the show began with the built-in copy).
    pub fn mark_broken(&mut self, path: PathBuf, error: String) {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if let Ok(built_in) = Assets::new(None).load(AssetKind::Shader, name) {
            self.running = self.running.with_shader(built_in);
        }
        self.broken.insert(path, error);
    }

    /// The assets the running show is built from (shaders as last applied).
    pub fn running_assets(&self) -> &Assets {
        &self.running
    }

    /// How long ago the newest shader reload was applied, if one was.
    pub fn newest_reload_age(&self) -> Option<Duration> {
        self.newest.as_ref().map(|n| n.at.elapsed())
    }

    /// Takes the newest shader reload back (the GPU stalled or was lost after it): the version
    /// before it is what nodes are built from again, and the file counts as broken with `why`
    /// until it is saved with different text. Returns the shader's name and the message for the
    /// performer; the caller rebuilds the nodes that use it.
    pub fn roll_back_newest(&mut self, why: &str) -> Option<(RolledBack, String)> {
        let newest = self.newest.take()?;
        let taken = match newest.previous {
            Previous::Shader(previous) => {
                let shader = previous.name.clone();
                self.running = self.running.with_shader(previous);
                RolledBack::Shader(shader)
            }
            Previous::Declared(bytes) => {
                let path = newest.path.canonicalize().unwrap_or_else(|_| newest.path.clone());
                self.running = self.running.with_file(path.clone(), bytes);
                RolledBack::Declared(path)
            }
        };
        let message = format!("{}: {why}; rolled back to the version before it", newest.path.display());
        self.broken.insert(newest.path.clone(), message.clone());
        self.stalled.insert(newest.path, newest.source);
        Some((taken, message))
    }

    /// Reloads the running scene with the ISF file at `path` as the running assets hold it now
    /// (after [`LiveReload::roll_back_newest`]): the nodes that read it are rebuilt.
    pub fn rebuild_declared(
        &self,
        path: &Path,
        player: &mut Player,
        gpu: &Gpu,
        size: (u32, u32),
    ) -> Result<(), String> {
        let mut report = ReloadReport::default();
        self.rebuild_reading(path, player.instance_mut(), gpu, size, &mut report, &self.running).map(|_| ())?;
        if let Some(remap) = &report.remap {
            player.remap(remap);
        }
        Ok(())
    }

    /// Files currently broken, with their errors.
    pub fn broken(&self) -> impl Iterator<Item = (&PathBuf, &String)> {
        self.broken.iter()
    }

    /// Applies whatever changed on disk since the last poll to `player`'s scene.
    pub fn poll(&mut self, player: &mut Player, gpu: &Gpu, size: (u32, u32)) -> ReloadReport {
        let changed = self.watcher.as_ref().map(Watcher::changed).unwrap_or_default();
        self.apply(&changed, player, gpu, size)
    }

    /// Applies the given changed files. When the scene is replaced, the player's scheduled
    /// events follow the [`ReloadReport::remap`]; the caller applies it to whatever else holds
    /// parameter positions (queued UI events, MIDI learn).
    pub fn apply(&mut self, files: &[PathBuf], player: &mut Player, gpu: &Gpu, size: (u32, u32)) -> ReloadReport {
        let mut report = ReloadReport::default();
        let instance = player.instance_mut();
        for path in files {
            let shown = path.display().to_string();
            let result = match path.extension().and_then(|e| e.to_str()) {
                Some("wgsl") => self.reload_shader(path, instance, gpu, size),
                Some("ron") => self.reload_scene(path, instance, gpu, size, &mut report),
                Some("fs" | "vs") => self.reload_declared(path, instance, gpu, size, &mut report),
                _ => continue,
            };
            match result {
                Ok(true) => {
                    report.applied.push(shown.clone());
                    if self.broken.remove(path).is_some() {
                        report.fixed.push(shown);
                    }
                }
                Ok(false) => {}
                Err(e) => {
                    // Reported once: the same error again (another save, same mistake) stays quiet.
                    // The caller shows and logs it.
                    if self.broken.get(path) != Some(&e) {
                        report.errors.push(e.clone());
                    }
                    self.broken.insert(path.clone(), e);
                }
            }
        }
        if let Some(remap) = &report.remap {
            player.remap(remap);
        }
        report
    }

    /// Ok(true) if nodes were rebuilt, Ok(false) if no node uses the shader.
    fn reload_shader(
        &mut self,
        path: &Path,
        instance: &mut SceneInstance,
        gpu: &Gpu,
        size: (u32, u32),
    ) -> Result<bool, String> {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_string();
        let source = self.read_untried(path)?;
        self.stalled.remove(path);
        let origin = path.display().to_string();
        let running = &self.running;
        let shaders = running.names(AssetKind::Shader);
        validate_as_used(&name, (&origin, &source), &shaders, |n| {
            running.load(AssetKind::Shader, n).map(|a| (a.origin, a.source))
        })?;
        let next = self.running.with_shader(Asset { name: name.clone(), origin, source: source.clone() });
        let used = instance.rebuild_nodes_using(&name, gpu, &next, size).map_err(|e| e.to_string())?;
        let previous = self.running.load(AssetKind::Shader, &name).ok();
        self.running = next;
        if let Some(previous) = previous.filter(|_| used) {
            let previous = Previous::Shader(previous);
            self.newest = Some(AppliedShader { path: path.to_path_buf(), previous, source, at: Instant::now() });
        }
        Ok(used)
    }

    /// The text of `path` now, unless it is the text that stalled the GPU (then its error).
    fn read_untried(&self, path: &Path) -> Result<String, String> {
        let source = read_stable(path).map_err(|e| format!("{}: {e}", path.display()))?;
        if self.stalled.get(path) == Some(&source) {
            return Err(self.broken.get(path).cloned().unwrap_or_default());
        }
        Ok(source)
    }

    /// For a file nodes declare their parameters from (an ISF shader, `.fs` or its `.vs`):
    /// Ok(true) if nodes read it and the scene was loaded again with them rebuilt — its inputs
    /// may have changed, so the scene's parameters are declared anew; an error keeps the last
    /// good version running. An applied edit is the newest reload: a stall right after it
    /// takes it back, and the text that stalled is not tried again until it changes.
    fn reload_declared(
        &mut self,
        path: &Path,
        instance: &mut SceneInstance,
        gpu: &Gpu,
        size: (u32, u32),
        report: &mut ReloadReport,
    ) -> Result<bool, String> {
        let source = self.read_untried(path)?;
        let real = path.canonicalize().map_err(|e| format!("{}: {e}", path.display()))?;
        let previous = self.running.pinned_file(&real);
        let next = self.running.with_file(real, Arc::from(source.as_bytes()));
        if !self.rebuild_reading(path, instance, gpu, size, report, &next)? {
            return Ok(false);
        }
        self.stalled.remove(path);
        self.running = next;
        if let Some(previous) = previous {
            let previous = Previous::Declared(previous);
            self.newest = Some(AppliedShader { path: path.to_path_buf(), previous, source, at: Instant::now() });
        }
        Ok(true)
    }

    /// Loads the running scene again from `assets` and rebuilds the nodes that read the ISF
    /// file `path` (or its companion); Ok(false) when none does.
    fn rebuild_reading(
        &self,
        path: &Path,
        instance: &mut SceneInstance,
        gpu: &Gpu,
        size: (u32, u32),
        report: &mut ReloadReport,
        assets: &Assets,
    ) -> Result<bool, String> {
        let shader = path.with_extension("fs").canonicalize().ok();
        let reads_it = |n: &crate::scene::SceneNode| {
            n.technique.declare.is_some_and(|d| {
                let file = n.params.index(d.file_param).map(|i| n.params.value_at(i));
                let Some(crate::params::ParamValue::Text(file)) = file else { return false };
                let located = self.running.locate_file(file.as_str()).ok().and_then(|p| p.canonicalize().ok());
                located.is_some() && located == shader
            })
        };
        if !instance.scene().nodes.iter().any(reads_it) {
            return Ok(false);
        }
        let origin = instance.scene().origin.clone();
        // A built-in scene reloads by its name; one from disk (or a bare .fs) by its path.
        let name = origin.strip_prefix("<embedded>/scenes/").unwrap_or(&origin);
        let scene = load_scene(assets, name).map_err(|e| e.to_string())?;
        let remap =
            instance.replace_scene_rebuilding(scene, gpu, assets, size, &reads_it).map_err(|e| e.to_string())?;
        report.scene_changed = true;
        report.remap = Some(remap);
        Ok(true)
    }

    /// Ok(true) if the running scene was replaced by its edited file.
    fn reload_scene(
        &self,
        path: &Path,
        instance: &mut SceneInstance,
        gpu: &Gpu,
        size: (u32, u32),
        report: &mut ReloadReport,
    ) -> Result<bool, String> {
        let same_file = |origin: &str| {
            let running = Path::new(origin);
            running.canonicalize().ok().zip(path.canonicalize().ok()).is_some_and(|(a, b)| a == b)
        };
        let scene = match &instance.scene().show {
            // A show reloads when its file or one of its clips' scenes changes; a clip that
            // breaks keeps the whole show as it was (its last good version plays on).
            Some(show) => {
                if !show.sources.iter().any(|s| same_file(s)) {
                    return Ok(false);
                }
                let origin = instance.scene().origin.clone();
                let source = read_stable(Path::new(&origin)).map_err(|e| format!("{origin}: {e}"))?;
                parse_show(&self.running, &origin, &source, false).map_err(|e| e.to_string())?
            }
            None => {
                if !same_file(&instance.scene().origin) {
                    return Ok(false);
                }
                let source = read_stable(path).map_err(|e| format!("{}: {e}", path.display()))?;
                parse_scene_with(&self.running, &path.display().to_string(), &source).map_err(|e| e.to_string())?
            }
        };
        let remap = instance.replace_scene(scene, gpu, &self.running, size).map_err(|e| e.to_string())?;
        report.scene_changed = true;
        report.remap = Some(remap);
        Ok(true)
    }
}

/// `assets` with every ISF file (`.fs`, `.vs`) in `dirs` pinned to its text now, up to
/// [`MAX_PINNED_DECLARED`] bytes: what a stalled edit of one rolls back to.
fn pin_declared_files(assets: Assets, dirs: &[PathBuf]) -> Assets {
    let mut left = MAX_PINNED_DECLARED;
    let mut files = Vec::new();
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(dir) else { continue };
        for path in entries.flatten().map(|e| e.path()) {
            if !path.extension().is_some_and(|e| e == "fs" || e == "vs") {
                continue;
            }
            let Ok(real) = path.canonicalize() else { continue };
            let Ok(bytes) = crate::files::read_limited(&real, left) else { continue };
            left -= bytes.len() as u64;
            files.push((real, Arc::from(bytes)));
        }
    }
    assets.with_files(files)
}
