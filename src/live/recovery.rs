//! Keeping the show alive through a stuck or lost GPU. A frame that misses the watchdog's limit
//! takes back the shader reload that likely caused it and waits for the GPU without blocking the
//! show; a device that is lost, or stays stuck, is replaced: every node moves to a new device
//! built from the last good shaders, and the performer is told.

use std::time::{Duration, Instant};

use super::LiveReload;
use super::reload::RolledBack;
use crate::assets::Assets;
use crate::gpu::{Gpu, Watchdog};
use crate::scene::Player;

/// A device loss this soon after a shader reload is blamed on the reload (a driver reset after
/// a shader that ran too long looks exactly like this).
const RELOAD_BLAME_WINDOW: Duration = Duration::from_secs(10);

/// A stalled frame is waited for this many stall limits before the device is abandoned.
const STUCK_AFTER_LIMITS: u32 = 4;

/// What went wrong with the device.
#[derive(Clone, Debug, PartialEq)]
pub enum GpuTrouble {
    /// A frame did not finish within the watchdog's limit (seconds waited).
    Stalled(Duration),
    /// A stalled frame still had not finished after this long: the device is given up.
    Stuck(Duration),
    /// wgpu reported the device lost, with its reason.
    Lost(String),
}

impl std::fmt::Display for GpuTrouble {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GpuTrouble::Stalled(waited) => {
                write!(f, "a frame did not finish within {:.1} s (the GPU is stuck)", waited.as_secs_f64())
            }
            GpuTrouble::Stuck(waited) => {
                write!(f, "the GPU has not finished a frame for {:.1} s", waited.as_secs_f64())
            }
            GpuTrouble::Lost(reason) => write!(f, "the GPU device was lost ({reason})"),
        }
    }
}

/// Whether the device can take the next frame.
#[derive(Clone, Debug, PartialEq)]
pub enum GpuState {
    /// Every frame so far has finished.
    Ready,
    /// A stalled frame is still running; skip this frame and check again.
    Waiting,
    /// Something to act on: [`roll_back_stall`] for a stall, [`recover`] otherwise.
    Trouble(GpuTrouble),
}

/// Watches a device between frames.
pub struct GpuGuard {
    watchdog: Watchdog,
    stuck_after: Duration,
}

impl GpuGuard {
    /// A guard that calls a frame stalled after `limit` and the device stuck after four limits.
    pub fn new(limit: Duration) -> Self {
        Self::with_limits(limit, limit * STUCK_AFTER_LIMITS)
    }

    /// A guard that calls a frame stalled after `stall` and the device stuck after `stuck`.
    pub fn with_limits(stall: Duration, stuck: Duration) -> Self {
        Self { watchdog: Watchdog::new(stall), stuck_after: stuck }
    }

    /// Notes a frame's submission.
    pub fn submitted(&mut self, index: wgpu::SubmissionIndex) {
        self.watchdog.submitted(index);
    }

    /// Waits (within the limit) for the newest frame, and reports a lost or stuck device.
    pub fn check(&mut self, gpu: &Gpu) -> GpuState {
        let state = match self.watchdog.check(&gpu.device) {
            Ok(()) => GpuState::Ready,
            Err(stall) if stall.first => GpuState::Trouble(GpuTrouble::Stalled(stall.waited)),
            Err(stall) if stall.waited >= self.stuck_after => {
                self.watchdog.reset();
                GpuState::Trouble(GpuTrouble::Stuck(stall.waited))
            }
            Err(_) => GpuState::Waiting,
        };
        // The lost callback runs while wgpu polls.
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        match gpu.lost_reason() {
            Some(reason) => GpuState::Trouble(GpuTrouble::Lost(reason)),
            None => state,
        }
    }

    /// Forgets the frames of the old device.
    pub fn reset(&mut self) {
        self.watchdog.reset();
    }
}

/// After a stall: takes back the newest shader reload, if any, and rebuilds the nodes that use
/// that shader on the same device, so that once the stuck frame finishes the show goes on with
/// the version before it. Returns the message for the performer.
pub fn roll_back_stall(
    trouble: &GpuTrouble,
    gpu: &Gpu,
    player: &mut Player,
    live: Option<&mut LiveReload>,
    size: (u32, u32),
) -> String {
    let Some(live) = live else { return format!("{trouble}; waiting for it") };
    let Some((taken, rolled_back)) = live.roll_back_newest(&trouble.to_string()) else {
        return format!("{trouble}; waiting for it");
    };
    let rebuilt = match taken {
        RolledBack::Shader(shader) => {
            let instance = player.instance_mut();
            instance
                .rebuild_nodes_using(&shader, gpu, live.running_assets(), size)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }
        RolledBack::Declared(path) => live.rebuild_declared(&path, player, gpu, size),
    };
    match rebuilt {
        Ok(_) => format!("{rolled_back}; the show resumes when the GPU has finished the stuck frame"),
        Err(e) => format!("{rolled_back}, but its nodes did not rebuild: {e}"),
    }
}

/// Moves the show to a new device after `trouble` (a loss, or a device stuck for good). A loss
/// soon after a shader reload rolls the reload back first. Every node is rebuilt from the last
/// good shaders (`live`'s, else `assets`) with the player's parameters, clock, script and
/// morphs intact; simulations restart from their initial state. Returns the new device and the
/// message for the performer. `surface` is the window's, when there is one.
pub fn recover(
    trouble: &GpuTrouble,
    old: &Gpu,
    surface: Option<&wgpu::Surface<'_>>,
    player: &mut Player,
    live: Option<&mut LiveReload>,
    assets: &Assets,
    size: (u32, u32),
) -> Result<(Gpu, String), String> {
    let started = Instant::now();
    let mut rolled_back = None;
    let assets = match live {
        Some(live) => {
            let blamed = matches!(trouble, GpuTrouble::Lost(_))
                && live.newest_reload_age().is_some_and(|age| age < RELOAD_BLAME_WINDOW);
            if blamed {
                rolled_back = live.roll_back_newest(&trouble.to_string()).map(|(_, message)| message);
            }
            live.running_assets().clone()
        }
        None => assets.clone(),
    };
    if !matches!(trouble, GpuTrouble::Lost(_)) {
        // Dropping the last handle to a queue waits for it to go idle, which a stuck queue never
        // does: one handle is kept for good, so the old device is abandoned rather than awaited.
        std::mem::forget(old.queue.clone());
    }
    let gpu = pollster::block_on(old.replacement(surface))
        .map_err(|e| format!("{trouble}, and no new device could be made: {e}"))?;
    let instance = player.instance_mut();
    if let Err(e) = instance.rebuild_all(&gpu, &assets, size) {
        // The last good shaders should build; if the new adapter disagrees, the built-in ones.
        log::warn!("rebuilding from the running shaders failed ({e}); using the built-in copies");
        instance
            .rebuild_all(&gpu, &assets.builtin_only(), size)
            .map_err(|e| format!("{trouble}; rebuilding failed: {e}"))?;
    }
    let mut message = format!(
        "{trouble}; the show moved to a new device on {} in {} ms (parameters kept, simulations restarted)",
        gpu.adapter_label(),
        started.elapsed().as_millis()
    );
    if let Some(rolled_back) = rolled_back {
        message = format!("{message}. {rolled_back}");
    }
    Ok((gpu, message))
}
