//! Watching folders for changed shader and scene files.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use notify::RecursiveMode;
use notify_debouncer_full::{DebounceEventResult, Debouncer, RecommendedCache, new_debouncer};

/// How long a burst of file events must be quiet before it is reported.
pub const DEBOUNCE: Duration = Duration::from_millis(40);

/// A debounced watcher over a few folders.
pub struct Watcher {
    _debouncer: Debouncer<notify::RecommendedWatcher, RecommendedCache>,
    events: Receiver<DebounceEventResult>,
}

impl Watcher {
    /// Watches each existing folder of `dirs` (non-recursively).
    pub fn watch(dirs: &[PathBuf]) -> Result<Self, String> {
        let (tx, events) = channel();
        let mut debouncer = new_debouncer(DEBOUNCE, Some(Duration::from_millis(10)), move |r| drop(tx.send(r)))
            .map_err(|e| format!("cannot watch files: {e}"))?;
        for dir in dirs.iter().filter(|d| d.is_dir()) {
            debouncer
                .watch(dir, RecursiveMode::NonRecursive)
                .map_err(|e| format!("cannot watch {}: {e}", dir.display()))?;
        }
        Ok(Self { _debouncer: debouncer, events })
    }

    /// Shader and scene files created, modified or renamed into place since the last call.
    pub fn changed(&self) -> Vec<PathBuf> {
        let mut paths = BTreeSet::new();
        for result in self.events.try_iter() {
            match result {
                Ok(events) => {
                    for e in events {
                        if e.kind.is_create() || e.kind.is_modify() {
                            paths.extend(e.paths.iter().filter(|p| is_asset(p)).cloned());
                        }
                    }
                }
                Err(errors) => log::warn!("file watching: {errors:?}"),
            }
        }
        paths.into_iter().filter(|p| p.is_file()).collect()
    }
}

fn is_asset(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "wgsl" || e == "ron" || e == "fs" || e == "vs" || e == "glsl")
}

/// Reads a file until two reads 10 ms apart agree (an editor may still be writing it).
pub fn read_stable(path: &Path) -> std::io::Result<String> {
    let mut last = std::fs::read_to_string(path)?;
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(10));
        let now = std::fs::read_to_string(path)?;
        if now == last {
            return Ok(now);
        }
        last = now;
    }
    Ok(last)
}
