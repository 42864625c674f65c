//! Decoding ahead on a worker thread, so a frame never waits for a disk read, Snappy or ffmpeg:
//! the node tells the worker which frames it will show next (the current one first, then the
//! next few in play order — loops and ping-pong included, since the node's playhead predicts
//! them), and takes decoded frames from a small cache. Off-screen renders wait for the frame they
//! show instead, so every render has the same pixels.

use std::collections::BTreeMap;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use super::clip::{Clip, ClipInfo};
use super::picture::Picture;

/// The decoded frames kept at most, by bytes (a 4K RGBA frame is 33 MB; a 4K Hap frame 4 MB).
pub const CACHE_BYTES: usize = 256 << 20;

/// How many frames ahead a clip is decoded at most.
pub const MAX_AHEAD: usize = 8;

/// How many decode times [`Prefetcher::decode_median_ms`] looks at.
const DECODE_TIMES_KEPT: usize = 240;

/// A clip decoding on its own thread.
pub struct Prefetcher {
    shared: Arc<Shared>,
    info: ClipInfo,
    worker: Option<std::thread::JoinHandle<()>>,
}

struct Shared {
    state: Mutex<State>,
    changed: Condvar,
}

#[derive(Default)]
struct State {
    /// The frames to have, most urgent first.
    wanted: Vec<usize>,
    ready: BTreeMap<usize, Arc<Picture>>,
    failed: BTreeMap<usize, String>,
    /// The frame decoded last, kept when no longer wanted: what a late live frame shows.
    newest: Option<(usize, Arc<Picture>)>,
    /// How long the last frames took to decode, seconds (for `indra bench`).
    decode_seconds: std::collections::VecDeque<f64>,
    quit: bool,
}

impl Prefetcher {
    /// Starts decoding `clip` on a new thread (named after `label`).
    pub fn new(mut clip: Clip, label: &str) -> Self {
        let info = clip.info();
        let shared = Arc::new(Shared { state: Mutex::new(State::default()), changed: Condvar::new() });
        let worker_shared = Arc::clone(&shared);
        let random_access = info.random_access;
        let worker = std::thread::Builder::new()
            .name(format!("clip {label}"))
            .spawn(move || {
                while let Some(index) = next_job(&worker_shared, random_access) {
                    let started = std::time::Instant::now();
                    let result = clip.read(index);
                    let took = started.elapsed().as_secs_f64();
                    let mut state = worker_shared.state.lock().unwrap_or_else(|e| e.into_inner());
                    if state.decode_seconds.len() == DECODE_TIMES_KEPT {
                        state.decode_seconds.pop_front();
                    }
                    state.decode_seconds.push_back(took);
                    match result {
                        Ok(picture) => {
                            let picture = Arc::new(picture);
                            state.newest = Some((index, Arc::clone(&picture)));
                            state.ready.insert(index, picture);
                        }
                        Err(e) => {
                            state.failed.insert(index, e);
                        }
                    }
                    worker_shared.changed.notify_all();
                }
            })
            .ok();
        Self { shared, info, worker }
    }

    /// What the clip is.
    pub fn info(&self) -> &ClipInfo {
        &self.info
    }

    /// How many frames to decode ahead: [`MAX_AHEAD`], fewer for large frames.
    pub fn ahead(&self) -> usize {
        let frame = self.info.width as usize * self.info.height as usize * 4;
        (CACHE_BYTES / frame.max(1)).clamp(2, MAX_AHEAD)
    }

    /// Asks for `frames`, most urgent first; frames not among them are let go.
    pub fn want(&self, frames: &[usize]) {
        let wanted: Vec<usize> = frames.iter().copied().filter(|&f| f < self.info.frames).collect();
        let mut state = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        if state.wanted == wanted {
            return;
        }
        state.wanted = wanted;
        let State { wanted, ready, failed, .. } = &mut *state;
        ready.retain(|f, _| wanted.contains(f));
        failed.retain(|f, _| wanted.contains(f));
        self.shared.changed.notify_all();
    }

    /// Frame `index` if decoded: `Some(Ok)`, `Some(Err)` when it could not be, `None` while it
    /// is on its way.
    pub fn get(&self, index: usize) -> Option<Result<Arc<Picture>, String>> {
        let state = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        lookup(&state, index)
    }

    /// The median time one frame took to decode (read, Snappy or ffmpeg) over the last 240, ms.
    pub fn decode_median_ms(&self) -> Option<f64> {
        let state = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        let mut times: Vec<f64> = state.decode_seconds.iter().copied().collect();
        times.sort_by(f64::total_cmp);
        times.get(times.len() / 2).map(|s| s * 1000.0)
    }

    /// The frame decoded last, wanted or not (a late live frame shows it rather than none).
    pub fn newest(&self) -> Option<(usize, Arc<Picture>)> {
        self.shared.state.lock().unwrap_or_else(|e| e.into_inner()).newest.clone()
    }

    /// Frame `index`, waiting for it (at most `limit`). It must have been asked for.
    pub fn wait(&self, index: usize, limit: Duration) -> Result<Arc<Picture>, String> {
        let deadline = std::time::Instant::now() + limit;
        let mut state = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            if let Some(result) = lookup(&state, index) {
                return result;
            }
            if self.worker.is_none() {
                return Err("the clip's decoding thread could not start".into());
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Err(format!("frame {index} took longer than {} s to decode", limit.as_secs()));
            }
            state = self.shared.changed.wait_timeout(state, left).unwrap_or_else(|e| e.into_inner()).0;
        }
    }
}

fn lookup(state: &State, index: usize) -> Option<Result<Arc<Picture>, String>> {
    if let Some(p) = state.ready.get(&index) {
        return Some(Ok(Arc::clone(p)));
    }
    state.failed.get(&index).map(|e| Err(e.clone()))
}

/// The next frame to decode, waiting until there is one (`None`: quit). A clip that decodes best
/// in order (ffmpeg) takes the missing frames lowest first, so playing backwards costs one seek
/// per batch, not one per frame.
fn next_job(shared: &Shared, random_access: bool) -> Option<usize> {
    let mut state = shared.state.lock().unwrap_or_else(|e| e.into_inner());
    loop {
        if state.quit {
            return None;
        }
        let missing =
            state.wanted.iter().copied().filter(|f| !state.ready.contains_key(f) && !state.failed.contains_key(f));
        let next = if random_access { missing.take(1).next() } else { missing.min() };
        if let Some(next) = next {
            return Some(next);
        }
        state = shared.changed.wait(state).unwrap_or_else(|e| e.into_inner());
    }
}

impl Drop for Prefetcher {
    fn drop(&mut self) {
        self.shared.state.lock().unwrap_or_else(|e| e.into_inner()).quit = true;
        self.shared.changed.notify_all();
        // The worker finishes the frame it is on (bounded) and ends; not joined, so a slow disk
        // never holds the render thread.
        drop(self.worker.take());
    }
}
