//! The headless runtime: a fixed clock, N frames, PNG or video output and image comparison
//! against golden references. Knows nothing of windows or UI.

pub mod capture;
mod golden;
mod renderer;
pub mod video;

pub use capture::{CaptureCounts, CaptureReport, FinishingTake, LiveRecorder};
pub use golden::{FlipScore, GoldenCheck, flip_score};
pub use renderer::{OffscreenRenderer, RenderError, RenderedFrame, write_png};
pub use video::{VideoError, VideoSettings, VideoWriter};
