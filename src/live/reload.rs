//! Applying changed files to the running scene, keeping the last good version on any error.
//! In a live show a changed file is read, parsed, validated and built on a worker thread (see
//! [`Job`]), one file at a time in the order they changed; the render thread only starts the
//! job and installs what it built, so a large or hostile file never holds a frame.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use super::prepare::{Job, Prepared, rebuild_reading};
use super::watcher::Watcher;
use crate::assets::{Asset, AssetKind, Assets};
use crate::gpu::Gpu;
use crate::params::Remap;
use crate::scene::{Outdated, Player};

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
    /// Changed files waiting for their reload, oldest first, each once.
    queue: VecDeque<PathBuf>,
    /// The reload being built on a worker thread.
    building: Option<Building>,
    /// Counts the changes of `running`: a reload built from older assets is made again.
    generation: u64,
}

/// A reload under way on a worker thread.
struct Building {
    path: PathBuf,
    generation: u64,
    receiver: Receiver<Result<Prepared, String>>,
}

/// The most changed files waiting at once (each file once); past it a change is dropped, told.
pub const MAX_QUEUED_RELOADS: usize = 256;

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
        Ok(Self {
            watcher,
            running,
            broken: BTreeMap::new(),
            newest: None,
            stalled: BTreeMap::new(),
            queue: VecDeque::new(),
            building: None,
            generation: 0,
        })
    }

    /// Marks a file as broken from the start (the show began with the built-in copy).
    pub fn mark_broken(&mut self, path: PathBuf, error: String) {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if let Ok(built_in) = Assets::new(None).load(AssetKind::Shader, name) {
            self.running = self.running.with_shader(built_in);
            self.generation += 1;
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
        self.generation += 1;
        let message = format!("{}: {why}; rolled back to the version before it", newest.path.display());
        self.broken.insert(newest.path.clone(), message.clone());
        self.stalled.insert(newest.path, newest.source);
        Some((taken, message))
    }

    /// Reloads the running scene with the ISF file at `path` as the running assets hold it now
    /// (after [`LiveReload::roll_back_newest`]): the nodes that read it are rebuilt, at once.
    pub fn rebuild_declared(
        &self,
        path: &Path,
        player: &mut Player,
        gpu: &Gpu,
        size: (u32, u32),
    ) -> Result<(), String> {
        let snapshot = player.instance().snapshot();
        let Some(replacement) = rebuild_reading(path, &snapshot, gpu, size, &self.running)? else { return Ok(()) };
        let remap = player.instance_mut().install(replacement).expect("built from the running scene");
        player.remap(&remap);
        Ok(())
    }

    /// The file whose reload is being built on a worker thread, if one is.
    pub fn building(&self) -> Option<&Path> {
        self.building.as_ref().map(|b| b.path.as_path())
    }

    /// Files currently broken, with their errors.
    pub fn broken(&self) -> impl Iterator<Item = (&PathBuf, &String)> {
        self.broken.iter()
    }

    /// Takes up what changed on disk since the last poll: installs a reload built meanwhile, and
    /// starts building the next changed file's on a worker thread. Never waits.
    pub fn poll(&mut self, player: &mut Player, gpu: &Gpu, size: (u32, u32)) -> ReloadReport {
        for path in self.watcher.as_ref().map(Watcher::changed).unwrap_or_default() {
            self.enqueue(path);
        }
        let mut report = ReloadReport::default();
        if let Some((building, result)) = self.finished() {
            self.finish(building.path, building.generation, result, player, &mut report);
        }
        if self.building.is_none()
            && let Some(path) = self.queue.pop_front()
        {
            self.start(path, player, gpu, size);
        }
        report
    }

    /// Applies the given changed files at once, in order, on this thread (renders and tests).
    /// When the scene is replaced, the player's scheduled events follow the
    /// [`ReloadReport::remap`]; the caller applies it to whatever else holds parameter positions
    /// (queued UI events, MIDI learn).
    pub fn apply(&mut self, files: &[PathBuf], player: &mut Player, gpu: &Gpu, size: (u32, u32)) -> ReloadReport {
        let mut report = ReloadReport::default();
        for path in files {
            let result = self.job(path.clone(), player, gpu, size).run();
            self.finish(path.clone(), self.generation, result, player, &mut report);
        }
        report
    }

    /// Queues `path` for reloading, unless it waits already.
    fn enqueue(&mut self, path: PathBuf) {
        if self.queue.contains(&path) {
            return;
        }
        if self.queue.len() >= MAX_QUEUED_RELOADS {
            log::warn!("{}: {MAX_QUEUED_RELOADS} files wait for reloading; this change is dropped", path.display());
            return;
        }
        self.queue.push_back(path);
    }

    /// What reloading `path` needs, taken from the running show now.
    fn job(&self, path: PathBuf, player: &Player, gpu: &Gpu, size: (u32, u32)) -> Job {
        let stalled =
            self.stalled.get(&path).map(|text| (text.clone(), self.broken.get(&path).cloned().unwrap_or_default()));
        Job {
            path,
            running: self.running.clone(),
            snapshot: player.instance().snapshot(),
            gpu: gpu.clone(),
            size,
            stalled,
        }
    }

    /// Starts building `path`'s reload on a worker thread.
    fn start(&mut self, path: PathBuf, player: &Player, gpu: &Gpu, size: (u32, u32)) {
        let job = self.job(path.clone(), player, gpu, size);
        let (sender, receiver) = std::sync::mpsc::channel();
        let spawned = crate::gpu::spawn_worker("indra-reload", move || {
            let _ = sender.send(job.run());
        });
        let receiver = match spawned {
            Ok(_) => receiver,
            Err(e) => {
                let (sender, failed) = std::sync::mpsc::channel();
                let _ = sender.send(Err(format!("{}: no thread to reload it ({e})", path.display())));
                failed
            }
        };
        self.building = Some(Building { path, generation: self.generation, receiver });
    }

    /// The reload under way, with its result, once it is built.
    fn finished(&mut self) -> Option<(Building, Result<Prepared, String>)> {
        let result = match self.building.as_ref()?.receiver.try_recv() {
            Ok(result) => result,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => Err("the reload failed".to_string()),
        };
        let building = self.building.take().expect("checked above");
        Some((building, result))
    }

    /// Installs a built reload and reports it; one built for assets or a scene that changed
    /// since goes back to the front of the queue, to be built again.
    fn finish(
        &mut self,
        path: PathBuf,
        generation: u64,
        result: Result<Prepared, String>,
        player: &mut Player,
        report: &mut ReloadReport,
    ) {
        let installed = match result {
            _ if generation != self.generation => Err(Outdated),
            Ok(prepared) => self.install(&path, prepared, player, report).map(Ok),
            Err(e) => Ok(Err(e)),
        };
        let shown = path.display().to_string();
        match installed {
            Err(Outdated) => self.queue.push_front(path),
            Ok(Ok(true)) => {
                report.applied.push(shown.clone());
                if self.broken.remove(&path).is_some() {
                    report.fixed.push(shown);
                }
            }
            Ok(Ok(false)) => {}
            Ok(Err(e)) => {
                // Reported once: the same error again (another save, same mistake) stays quiet.
                // The caller shows and logs it.
                if self.broken.get(&path) != Some(&e) {
                    report.errors.push(e.clone());
                }
                self.broken.insert(path, e);
            }
        }
    }

    /// Swaps what `prepared` built into the running show: Ok(true) if nodes changed, Ok(false)
    /// if the running show does not use the file.
    fn install(
        &mut self,
        path: &Path,
        prepared: Prepared,
        player: &mut Player,
        report: &mut ReloadReport,
    ) -> Result<bool, Outdated> {
        let mut replace = |replacement| -> Result<(), Outdated> {
            let remap = player.instance_mut().install(replacement)?;
            player.remap(&remap);
            report.scene_changed = true;
            report.remap = Some(remap);
            Ok(())
        };
        let (previous, source, used) = match prepared {
            Prepared::Unused | Prepared::Declared { replacement: None, .. } => return Ok(false),
            Prepared::Scene(replacement) => return replace(replacement).map(|()| true),
            Prepared::Shader { next, name, source, rebuild } => {
                let used = !rebuild.is_empty();
                player.instance_mut().install_nodes(rebuild)?;
                let previous = self.running.load(AssetKind::Shader, &name).ok().map(Previous::Shader);
                self.running = next;
                (previous, source, used)
            }
            Prepared::Declared { next, real, source, replacement: Some(replacement) } => {
                replace(replacement)?;
                let previous = self.running.pinned_file(&real).map(Previous::Declared);
                self.running = next;
                (previous, source, true)
            }
        };
        self.generation += 1;
        self.stalled.remove(path);
        if let Some(previous) = previous.filter(|_| used) {
            self.newest = Some(AppliedShader { path: path.to_path_buf(), previous, source, at: Instant::now() });
        }
        Ok(used)
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
            if !path.extension().is_some_and(|e| e == "fs" || e == "vs" || e == "glsl") {
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
