//! Noticing a GPU that stopped finishing frames: a shader stuck in a loop on a device without
//! a reset (lavapipe), or a driver that has not reported the loss yet.

use std::time::{Duration, Instant};

/// How long a frame may stay unfinished before the show calls the GPU stalled. Long enough for
/// any frame a show would want (a slow seek step on lavapipe takes well under a second), short
/// enough that the audience sees a pause, not a dead screen.
pub const DEFAULT_STALL_TIMEOUT: Duration = Duration::from_secs(3);

/// How long a stalled frame is waited for, a little at a time, before each later check.
const RECHECK_WAIT: Duration = Duration::from_millis(20);

/// Waits, with a time limit, for a frame's submission to finish. A frame is checked before it
/// is shown and before the next is submitted, because on some drivers (lavapipe) the next
/// submission or present blocks until the previous work is done — a later check would never run.
/// A frame that misses the limit is remembered and waited for briefly at each later check, so
/// the caller keeps its event loop running while the GPU catches up.
pub struct Watchdog {
    newest: Option<wgpu::SubmissionIndex>,
    stalled: Option<(wgpu::SubmissionIndex, Instant)>,
    timeout: Duration,
}

/// A frame that has not finished.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stall {
    /// How long it has been waited for.
    pub waited: Duration,
    /// Whether this check is the one that found it over the limit (later checks of the same
    /// frame say `false`).
    pub first: bool,
}

impl Watchdog {
    /// A watchdog that calls a frame stalled after `timeout`.
    pub fn new(timeout: Duration) -> Self {
        Self { newest: None, stalled: None, timeout }
    }

    /// Notes a frame's last submission.
    pub fn submitted(&mut self, index: wgpu::SubmissionIndex) {
        self.newest = Some(index);
    }

    /// Ok once every noted submission has finished. The first check of a new submission waits
    /// up to the time limit; a stalled one is waited for only briefly per check.
    pub fn check(&mut self, device: &wgpu::Device) -> Result<(), Stall> {
        if let Some((index, since)) = self.stalled.clone() {
            if finished(device, index, RECHECK_WAIT) {
                self.stalled = None;
            } else {
                return Err(Stall { waited: since.elapsed(), first: false });
            }
        }
        let Some(index) = self.newest.take() else { return Ok(()) };
        let since = Instant::now();
        if finished(device, index.clone(), self.timeout) {
            return Ok(());
        }
        self.stalled = Some((index, since));
        Err(Stall { waited: since.elapsed(), first: true })
    }

    /// Forgets every submission (after moving to a new device).
    pub fn reset(&mut self) {
        self.newest = None;
        self.stalled = None;
    }
}

fn finished(device: &wgpu::Device, index: wgpu::SubmissionIndex, timeout: Duration) -> bool {
    let wait = wgpu::PollType::Wait { submission_index: Some(index), timeout: Some(timeout) };
    !matches!(device.poll(wait), Err(wgpu::PollError::Timeout))
}
