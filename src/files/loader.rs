//! Loads on a worker thread: the render thread asks for a file and polls for the result, so a
//! slow disk, a large image or a hostile file never holds a frame. Off-screen renders wait for
//! each load instead, so a frame shows the same file whenever it is rendered. A load a node asks
//! for as it is made (the file its scene names) is waited for in a live show too — it is a
//! regular file of bounded size, and the show then starts with its files in place, instead of
//! taking them up a few frames in and overwriting what a controller set meanwhile. A live change
//! never waits. A load that hangs (a file that reads for ever) is abandoned when a newer one is
//! asked for after [`STUCK_AFTER`], so the node loads again; abandoned threads are bounded.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

/// Whether a frame waits for the loads asked for in its step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LoadWait {
    /// The step that asks waits for the result (deterministic: off-screen renders, tests).
    #[default]
    Finish,
    /// The step returns at once; the result is taken up by a later step (a live show).
    Background,
}

/// How long a waiting step gives one load before it is reported as failed.
const WAIT_LIMIT: Duration = Duration::from_secs(60);

/// How long a load may run before a newer request abandons it.
pub const STUCK_AFTER: Duration = Duration::from_secs(5);

/// Load threads running in the process, abandoned ones included: past [`MAX_LOAD_THREADS`] a
/// stuck load is waited for rather than abandoned, so hung files cannot pile up threads.
static RUNNING: AtomicUsize = AtomicUsize::new(0);

/// The most load threads at once before stuck loads are no longer abandoned.
pub const MAX_LOAD_THREADS: usize = 16;

type Job<T> = Box<dyn FnOnce() -> Result<T, String> + Send>;

/// A load under way: its key, where its result comes, and when it began.
struct Running<T> {
    key: String,
    receiver: Receiver<Result<T, String>>,
    since: Instant,
}

/// One node's loads: at most one runs at a time, and of the requests made meanwhile only the
/// newest is kept (a flood of paths starts one thread, not thousands).
pub struct Loader<T> {
    wait: LoadWait,
    /// No step has polled yet: a load asked for now is the node's own, waited for.
    initial: bool,
    running: Option<Running<T>>,
    queued: Option<(String, Job<T>)>,
}

impl<T: Send + 'static> Loader<T> {
    /// A loader with no load under way.
    pub fn new(wait: LoadWait) -> Self {
        Self { wait, initial: true, running: None, queued: None }
    }

    /// Asks for `job`'s result, known as `key` (a path, for messages): starts it, or queues it
    /// behind the load under way, replacing any queued before; a load stuck for longer than
    /// [`STUCK_AFTER`] is abandoned for it.
    pub fn request(&mut self, key: &str, job: impl FnOnce() -> Result<T, String> + Send + 'static) {
        self.queued = Some((key.to_string(), Box::new(job)));
        let stuck = self.running.as_ref().is_some_and(|r| r.since.elapsed() > STUCK_AFTER);
        if stuck
            && RUNNING.load(Ordering::Relaxed) < MAX_LOAD_THREADS
            && let Some(r) = self.running.take()
        {
            log::warn!("{}: still loading after {:?}; abandoned for a newer file", r.key, STUCK_AFTER);
        }
        if self.running.is_none() {
            self.start_queued();
        }
    }

    /// Whether a load is under way or queued.
    #[cfg(test)]
    fn busy(&self) -> bool {
        self.running.is_some() || self.queued.is_some()
    }

    /// A finished load with its key, if any (waiting for it under [`LoadWait::Finish`], and for
    /// the node's own first load).
    pub fn poll(&mut self) -> Option<(String, Result<T, String>)> {
        let wait = if std::mem::take(&mut self.initial) { LoadWait::Finish } else { self.wait };
        let running = self.running.as_ref()?;
        let key = &running.key;
        let result = match wait {
            LoadWait::Finish => match running.receiver.recv_timeout(WAIT_LIMIT) {
                Ok(result) => result,
                Err(RecvTimeoutError::Timeout) => Err(format!("{key}: still loading after {WAIT_LIMIT:?}")),
                Err(RecvTimeoutError::Disconnected) => Err(format!("{key}: the load failed")),
            },
            LoadWait::Background => match running.receiver.try_recv() {
                Ok(result) => result,
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => Err(format!("{key}: the load failed")),
            },
        };
        let key = self.running.take().expect("checked above").key;
        self.start_queued();
        Some((key, result))
    }

    fn start_queued(&mut self) {
        let Some((key, job)) = self.queued.take() else { return };
        let (sender, receiver) = std::sync::mpsc::channel();
        RUNNING.fetch_add(1, Ordering::Relaxed);
        let spawned = std::thread::Builder::new().name("indra-load".into()).spawn(move || {
            let _ = sender.send(job());
            RUNNING.fetch_sub(1, Ordering::Relaxed);
        });
        let receiver = match spawned {
            Ok(_) => receiver,
            Err(e) => {
                RUNNING.fetch_sub(1, Ordering::Relaxed);
                let (sender, failed) = std::sync::mpsc::channel();
                let _ = sender.send(Err(format!("{key}: no thread to load it ({e})")));
                failed
            }
        };
        self.running = Some(Running { key, receiver, since: Instant::now() });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_finishing_loader_returns_the_result_in_the_same_step() {
        let mut loader = Loader::new(LoadWait::Finish);
        loader.request("a", || Ok(1));
        assert_eq!(loader.poll(), Some(("a".to_string(), Ok(1))));
        assert_eq!(loader.poll(), None);
    }

    #[test]
    fn a_background_loader_waits_for_its_first_load_only() {
        let mut loader = Loader::new(LoadWait::Background);
        loader.request("scene's", || {
            std::thread::sleep(std::time::Duration::from_millis(50));
            Ok(1)
        });
        assert_eq!(loader.poll(), Some(("scene's".to_string(), Ok(1))), "the first is waited for");
        loader.request("live", || {
            std::thread::sleep(std::time::Duration::from_millis(200));
            Ok(2)
        });
        assert_eq!(loader.poll(), None, "a later one is not");
    }

    #[test]
    fn a_live_change_never_waits_even_as_the_nodes_first_load() {
        // A node that opened its file as it was made, and polled since: the first load it asks
        // the loader for is a live change (a video node's new clip), taken up later.
        let mut loader = Loader::new(LoadWait::Background);
        assert_eq!(loader.poll(), None);
        loader.request("slow", || {
            std::thread::sleep(std::time::Duration::from_millis(300));
            Ok(1)
        });
        let asked = std::time::Instant::now();
        assert_eq!(loader.poll(), None);
        assert!(asked.elapsed() < std::time::Duration::from_millis(100), "the step waited");
    }

    #[test]
    fn a_load_that_hangs_is_abandoned_for_a_newer_one() {
        let mut loader = Loader::new(LoadWait::Background);
        assert_eq!(loader.poll(), None);
        let (_release, gate) = std::sync::mpsc::channel::<()>();
        loader.request("hangs", move || {
            let _ = gate.recv();
            Ok(0)
        });
        let running = loader.running.as_mut().unwrap();
        running.since = running.since.checked_sub(STUCK_AFTER * 2).unwrap_or(running.since);
        loader.request("next", || Ok(2));
        let started = std::time::Instant::now();
        loop {
            if let Some(done) = loader.poll() {
                assert_eq!(done, ("next".to_string(), Ok(2)));
                break;
            }
            assert!(started.elapsed() < std::time::Duration::from_secs(5), "the hung load still blocks");
            std::thread::yield_now();
        }
    }

    #[test]
    fn a_background_loader_keeps_only_the_newest_request_behind_the_running_one() {
        let (release, gate) = std::sync::mpsc::channel::<()>();
        let mut loader = Loader::new(LoadWait::Background);
        loader.request("first", || Ok(-1));
        assert!(loader.poll().is_some());
        loader.request("slow", move || {
            gate.recv().map_err(|e| e.to_string())?;
            Ok(0)
        });
        for i in 1..=100 {
            loader.request(&format!("n{i}"), move || Ok(i));
        }
        assert_eq!(loader.poll(), None, "the first load is still held");
        release.send(()).unwrap();
        let mut seen = Vec::new();
        while loader.busy() {
            if let Some((key, result)) = loader.poll() {
                seen.push((key, result.unwrap()));
            }
            std::thread::yield_now();
        }
        assert_eq!(seen, vec![("slow".to_string(), 0), ("n100".to_string(), 100)]);
    }
}
