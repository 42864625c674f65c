//! The show's output as an NDI source (`run --ndi-out NAME`): a [`FrameOutlet`] for the live
//! recorder's readback ring (`LiveRecorder`), so the show never waits for the network — frames
//! the sender cannot take in time are dropped and counted like a recording's.

use super::capture::FrameOutlet;
use super::video::VideoError;
use crate::media::ndi::NdiSender;

/// An NDI sender fed by a live recorder; frames are stamped with the show frame they are.
struct NdiOutlet {
    sender: NdiSender,
}

impl FrameOutlet for NdiOutlet {
    /// A network source runs in real time: each frame goes once, however many steps it stood.
    fn take(&mut self, rgba: &[u8], _repeats: u32, frame: u64) -> Result<(), VideoError> {
        self.sender.send(rgba, frame).map_err(VideoError::Settings)
    }

    fn close(self: Box<Self>) -> Result<u64, VideoError> {
        Ok(self.sender.sent())
    }

    fn destination(&self) -> std::path::PathBuf {
        format!("NDI '{}'", self.sender.name()).into()
    }
}

/// An outlet sending frames of `size` at `fps` as the NDI source `name`. With `paced` (a render,
/// faster than real time) each frame waits until it is due; a live show, already in real time,
/// sends unpaced — a clocked send would hold the recorder's thread and drop frames the network
/// could take.
pub fn ndi_outlet(name: &str, size: (u32, u32), fps: f64, paced: bool) -> Result<Box<dyn FrameOutlet>, String> {
    Ok(Box::new(NdiOutlet { sender: NdiSender::start(name, size, fps, paced)? }))
}
