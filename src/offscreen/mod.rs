//! The headless runtime: a fixed clock, N frames, PNG or video output and image comparison
//! against golden references. Knows nothing of windows or UI.

pub mod capture;
mod frame_pipe;
#[cfg(feature = "golden")]
mod golden;
mod ndi_out;
mod pipewire_out;
mod renderer;
pub mod video;

pub use capture::{CaptureCounts, CaptureReport, FinishingTake, FrameOutlet, LiveRecorder};
#[cfg(feature = "golden")]
pub use golden::{FlipScore, GoldenCheck, flip_score};
pub use ndi_out::ndi_outlet;
pub use pipewire_out::{GST_LAUNCH_ENV, PipeWireOut};
pub use renderer::{OffscreenRenderer, RenderError, RenderedFrame, encode_png, write_png};
pub use video::{VideoError, VideoSettings, VideoWriter};
