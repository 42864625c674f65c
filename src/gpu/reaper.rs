//! Dropping GPU objects off the render thread. Releasing pipelines, buffers and textures costs
//! the driver time a frame cannot spare — the old show a chain edit replaces held up to 0.7 ms of
//! a lavapipe frame in drops alone — so what a switch lets go of goes to one background thread,
//! through a bounded queue; when the queue is full it is dropped where it is, as before.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{SyncSender, sync_channel};
use std::sync::{Mutex, OnceLock};

/// Values waiting to be dropped at most; past it a value is dropped by its caller.
const QUEUE: usize = 64;

/// Where values go to be dropped.
type Queue = Mutex<SyncSender<Box<dyn Send>>>;

/// Drops `value` on the reaper thread (or here, if there is none or its queue is full).
pub fn drop_later<T: Send + 'static>(value: T) {
    static REAPER: OnceLock<Option<Queue>> = OnceLock::new();
    let reaper = REAPER.get_or_init(|| {
        let (sender, receiver) = sync_channel::<Box<dyn Send>>(QUEUE);
        let spawned = std::thread::Builder::new().name("indra-reaper".into()).spawn(move || {
            for value in receiver {
                drop(value);
            }
        });
        spawned.ok().map(|_| Mutex::new(sender))
    });
    let Some(sender) = reaper else { return };
    if let Ok(sender) = sender.lock() {
        // Full or gone: `value` comes back in the error and is dropped here.
        let _ = sender.try_send(Box::new(value));
    }
}

/// Tells its sender when it is dropped: everything queued before it has been dropped too.
struct Marker(SyncSender<()>);

impl Drop for Marker {
    fn drop(&mut self) {
        let _ = self.0.try_send(());
    }
}

/// Worker threads started by [`spawn_worker`] that have not ended.
static WORKERS: AtomicUsize = AtomicUsize::new(0);

/// Counts its worker out when the thread ends, however it ends.
struct Working;

impl Drop for Working {
    fn drop(&mut self) {
        WORKERS.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Starts `work` on a thread named `name` that [`wait_for_drops`] waits for: every thread that
/// builds or drops GPU objects (clip copies, chain edits, reloads) starts here. One still
/// building when the process ended called the driver while it unloaded: `indra bench` of a show
/// that switches clips ended in a segmentation fault on an H100 in one run of three.
pub fn spawn_worker(name: &str, work: impl FnOnce() + Send + 'static) -> std::io::Result<()> {
    WORKERS.fetch_add(1, Ordering::SeqCst);
    let spawned = std::thread::Builder::new().name(name.into()).spawn(move || {
        let _working = Working;
        work();
    });
    if spawned.is_err() {
        WORKERS.fetch_sub(1, Ordering::SeqCst);
    }
    spawned.map(|_| ())
}

/// Waits (at most `timeout`) until every worker thread has ended and everything handed to
/// [`drop_later`] so far (by them too) is dropped: call it before the process ends, so that no
/// driver call runs while the driver unloads.
pub fn wait_for_drops(timeout: std::time::Duration) {
    let deadline = std::time::Instant::now() + timeout;
    while WORKERS.load(Ordering::SeqCst) > 0 && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let (sender, receiver) = sync_channel(1);
    drop_later(Marker(sender));
    let _ = receiver.recv_timeout(deadline.saturating_duration_since(std::time::Instant::now()));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    struct Flag(Arc<AtomicBool>, std::thread::ThreadId);

    impl Drop for Flag {
        fn drop(&mut self) {
            // Dropped on another thread than the one that let go of it.
            self.0.store(std::thread::current().id() != self.1, Ordering::SeqCst);
        }
    }

    #[test]
    fn the_wait_ends_after_the_workers_and_what_they_let_go_of() {
        let dropped = Arc::new(AtomicBool::new(false));
        let flag = Flag(dropped.clone(), std::thread::current().id());
        spawn_worker("indra-test-worker", move || {
            std::thread::sleep(std::time::Duration::from_millis(200));
            drop_later(flag);
        })
        .unwrap();
        wait_for_drops(std::time::Duration::from_secs(10));
        assert!(dropped.load(Ordering::SeqCst), "the wait ended before the worker's drop");
    }

    #[test]
    fn a_value_let_go_of_is_dropped_on_the_reaper_before_the_wait_ends() {
        let dropped = Arc::new(AtomicBool::new(false));
        drop_later(Flag(dropped.clone(), std::thread::current().id()));
        wait_for_drops(std::time::Duration::from_secs(10));
        assert!(dropped.load(Ordering::SeqCst), "not dropped, or dropped on the caller's thread");
    }
}
