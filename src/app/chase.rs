//! The window chasing timecode (`run --mtc-in`): each frame, the steps that bring the frame on
//! screen to the frame the code says — none while it waits for code or stands, a few to catch
//! up — or, when the code jumps, a seek on a thread of its own while the frame on screen holds;
//! the sought scene is swapped in when it is ready. Live control goes on throughout, on the
//! scene that is showing; a jump shows the timeline's frame as a render from 0 shows it. A show
//! that runs free seeks the same way where the performer puts it (the lane view's ruler).

use std::time::{Duration, Instant, SystemTime};

use super::panel::Overlay;
use crate::assets::Assets;
use crate::gpu::Gpu;
use crate::graph::GraphRuntime;
use crate::live::{BackgroundSeek, SeekCheckpoints};
use crate::scene::Player;
use crate::timecode::chase::{Chasing, Follow, follow, frame_at};

/// The most steps one displayed frame runs to catch up with the code; further is a seek.
const MAX_CATCH_UP_STEPS: u32 = 12;

/// How far (seconds) the code may be behind the screen before that is a jump back, sought;
/// less is waited for. A live input's timing wobbles, and on a busy machine audio reaches the
/// show in late bursts: the code read from it can seem to go back by half a second (the LTC
/// chase test saw up to 0.57 s while the machine compiled). A desk's locate is further.
const JITTER_SECONDS: f64 = 0.75;

/// How long after a seek that failed no other is tried (it would fail each frame).
const RETRY_AFTER: Duration = Duration::from_secs(2);

/// The window's chase state.
#[derive(Default)]
pub(super) struct WindowChase {
    /// The seek in progress.
    seek: Option<BackgroundSeek>,
    /// The checkpoints seeks keep on their way, for the next.
    checkpoints: SeekCheckpoints,
    /// When the last seek failed.
    failed: Option<Instant>,
    /// The frame a performer put the free-running show at, while it is sought.
    placed: Option<u64>,
}

/// What a seek is built with: the window's device, the shaders running, the window's size.
pub(super) struct SeekFrom<'a> {
    /// The window's device.
    pub gpu: &'a Gpu,
    /// The shaders the show runs now (a live reload's, else the start's).
    pub assets: &'a Assets,
    /// The window's size in pixels.
    pub size: (u32, u32),
}

impl WindowChase {
    /// Stops a seek in progress and waits for its thread (at exit).
    pub(super) fn finish(&mut self) {
        if let Some(seek) = self.seek.take() {
            seek.finish();
        }
    }

    /// Drops a seek in progress: it was built from a scene or on a device that is no longer the
    /// show's (a reload, a new device). The next frame seeks again if the code is still away.
    pub(super) fn cancel(&mut self) {
        (self.seek, self.placed) = (None, None);
    }

    /// Puts the free-running show at `frame` (the performer dropped the play position there):
    /// sought off the render thread while the frame on screen holds, as a jump in the code is.
    pub(super) fn place(&mut self, frame: u64, player: &Player, from: SeekFrom<'_>) {
        log::info!("the show is put at frame {frame} (it was at {}): seeking", player.now().frame);
        self.failed = None;
        self.placed = Some(frame);
        self.start_seek(frame, player, from);
    }

    /// The steps a free-running show runs for `elapsed` seconds; none while a seek the performer
    /// asked for runs, then the few from where the sought scene stopped to the frame asked for.
    pub(super) fn free_steps(
        &mut self,
        elapsed: f64,
        player: &mut Player,
        runtime: &mut GraphRuntime,
        overlay: &mut Overlay,
    ) -> u32 {
        let steps = player.accumulate(elapsed);
        let Some(frame) = self.placed else { return steps };
        if !self.take_sought(frame, player, runtime, overlay) {
            return 0;
        }
        self.placed = None;
        // The sought scene stops a step or two short; the frame asked for is the one shown.
        (frame + 1).saturating_sub(player.now().frame).min(u64::from(MAX_CATCH_UP_STEPS)) as u32
    }

    /// The steps `player` runs now to show the frame `chasing` says; a sought scene that is
    /// ready replaces `player` and `runtime` first.
    pub(super) fn steps(
        &mut self,
        chasing: Chasing,
        player: &mut Player,
        runtime: &mut GraphRuntime,
        from: SeekFrom<'_>,
        overlay: &mut Overlay,
    ) -> u32 {
        let Some(seconds) = chasing.seconds() else { return 0 };
        let wanted = frame_at(seconds, f64::from(player.now().dt));
        let jitter = (JITTER_SECONDS / f64::from(player.now().dt)) as u64;
        if !self.take_sought(wanted, player, runtime, overlay) {
            return 0;
        }
        let next = player.now().frame;
        let plan = match next.checked_sub(1) {
            // Nothing stepped yet: a code near the start is stepped to, as a show plays.
            None if wanted < u64::from(MAX_CATCH_UP_STEPS) => Follow::Step(wanted as u32 + 1),
            drawn => follow(wanted, drawn, MAX_CATCH_UP_STEPS, jitter),
        };
        let steps = match plan {
            Follow::Hold => 0,
            Follow::Step(n) => n,
            Follow::Seek(frame) => {
                if self.failed.is_none_or(|at| at.elapsed() >= RETRY_AFTER) {
                    log::info!("timecode: the code jumped to frame {frame} (the show was at {next}): seeking");
                    self.start_seek(frame, player, from);
                }
                0
            }
        };
        if log::log_enabled!(target: "indra::chase", log::Level::Debug) {
            log_frame(chasing, seconds, wanted, player, next, steps);
        }
        steps
    }

    /// Takes a finished seek's scene in; false while one is still running (the frame holds).
    fn take_sought(
        &mut self,
        wanted: u64,
        player: &mut Player,
        runtime: &mut GraphRuntime,
        overlay: &mut Overlay,
    ) -> bool {
        let Some(seek) = self.seek.as_mut() else { return true };
        seek.want(wanted);
        match seek.try_take() {
            None => false,
            Some(Ok(sought)) => {
                let (frame, from) = (sought.player.now().frame, sought.from);
                match self.placed {
                    Some(_) => log::info!("sought frame {frame} from frame {from}, for frame {wanted}"),
                    None => log::info!("timecode: sought frame {frame} from frame {from}, the code is at {wanted}"),
                }
                (*player, *runtime) = (sought.player, sought.runtime);
                self.seek = None;
                true
            }
            Some(Err(e)) => {
                overlay.report(format!("timecode: the seek failed ({e}); the show holds its frame"));
                (self.seek, self.failed) = (None, Some(Instant::now()));
                true
            }
        }
    }

    /// Starts seeking `frame` off the render thread.
    fn start_seek(&mut self, frame: u64, player: &Player, from: SeekFrom<'_>) {
        let scene = player.instance().scene().clone();
        self.seek = Some(BackgroundSeek::start(from.gpu, from.assets, scene, from.size, frame, &self.checkpoints));
    }
}

/// One frame's chase in the log (`RUST_LOG=indra::chase=debug`): the wall clock, the code's
/// position, the frame it wants and the frame shown — what the MTC test compares with its desk.
fn log_frame(chasing: Chasing, seconds: f64, wanted: u64, player: &Player, next: u64, steps: u32) {
    let shown = if steps == 0 { player.last_step().frame } else { next + u64::from(steps) - 1 };
    let unix = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    let state = match chasing {
        Chasing::Locked { .. } => "locked",
        Chasing::Freewheel { .. } => "freewheel",
        _ => "stopped",
    };
    log::debug!(target: "indra::chase", "unix {unix:.4} code {seconds:.4} s wants {wanted} shows {shown} {state}");
}
