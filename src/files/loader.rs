//! Loads on a worker thread: the render thread asks for a file and polls for the result, so a
//! slow disk, a large image or a hostile file never holds a frame. Off-screen renders wait for
//! each load instead, so a frame shows the same file whenever it is rendered. A node's first
//! load (the file its scene names) is waited for in a live show too — it is a regular file of
//! bounded size, and the show then starts with its files in place, instead of taking them up a
//! few frames in and overwriting what a controller set meanwhile.

use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::time::Duration;

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

type Job<T> = Box<dyn FnOnce() -> Result<T, String> + Send>;

/// One node's loads: at most one runs at a time, and of the requests made meanwhile only the
/// newest is kept (a flood of paths starts one thread, not thousands).
pub struct Loader<T> {
    wait: LoadWait,
    /// Whether a load has finished (later ones follow `wait`).
    first_done: bool,
    running: Option<(String, Receiver<Result<T, String>>)>,
    queued: Option<(String, Job<T>)>,
}

impl<T: Send + 'static> Loader<T> {
    /// A loader with no load under way.
    pub fn new(wait: LoadWait) -> Self {
        Self { wait, first_done: false, running: None, queued: None }
    }

    /// Asks for `job`'s result, known as `key` (a path, for messages): starts it, or queues it
    /// behind the load under way, replacing any queued before.
    pub fn request(&mut self, key: &str, job: impl FnOnce() -> Result<T, String> + Send + 'static) {
        self.queued = Some((key.to_string(), Box::new(job)));
        if self.running.is_none() {
            self.start_queued();
        }
    }

    /// Whether a load is under way or queued.
    #[cfg(test)]
    fn busy(&self) -> bool {
        self.running.is_some() || self.queued.is_some()
    }

    /// A finished load with its key, if any (waiting for it under [`LoadWait::Finish`]).
    pub fn poll(&mut self) -> Option<(String, Result<T, String>)> {
        let (key, receiver) = self.running.as_ref()?;
        let wait = if self.first_done { self.wait } else { LoadWait::Finish };
        let result = match wait {
            LoadWait::Finish => match receiver.recv_timeout(WAIT_LIMIT) {
                Ok(result) => result,
                Err(RecvTimeoutError::Timeout) => Err(format!("{key}: still loading after {WAIT_LIMIT:?}")),
                Err(RecvTimeoutError::Disconnected) => Err(format!("{key}: the load failed")),
            },
            LoadWait::Background => match receiver.try_recv() {
                Ok(result) => result,
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => Err(format!("{key}: the load failed")),
            },
        };
        let (key, _) = self.running.take().expect("checked above");
        self.first_done = true;
        self.start_queued();
        Some((key, result))
    }

    fn start_queued(&mut self) {
        let Some((key, job)) = self.queued.take() else { return };
        let (sender, receiver) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("indra-load".into()).spawn(move || {
            let _ = sender.send(job());
        });
        if let Err(e) = spawned {
            let (sender, failed) = std::sync::mpsc::channel();
            let _ = sender.send(Err(format!("{key}: no thread to load it ({e})")));
            self.running = Some((key, failed));
            return;
        }
        self.running = Some((key, receiver));
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
