//! A camera as a node: a Linux V4L2 device read through ffmpeg's `v4l2` input (or, with device
//! `test`, ffmpeg's moving test pattern through the same reader), its newest frame fitted into
//! the node's image. A machine without the camera gets one sentence and a black image, and the
//! camera is tried again every few seconds, so one plugged in later appears; nothing crashes.
//!
//! A camera is live input: frames come when the device sends them, not on the fixed clock, so a
//! render that uses one is not repeatable (every other node stays exact). `indra --list-cameras`
//! lists the devices. Tests: `render_tests.rs` (the stand-in source through the whole node, a
//! missing device).

#[cfg(test)]
mod render_tests;

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::media::camera::{CameraSource, LiveFeed};
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::picture_pass::{Fit, PicturePass};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "camera",
    chapter: "media: cameras",
    summary: "a camera's newest frame (V4L2 through ffmpeg; `test` for a moving test pattern)",
    params: Settings::decls,
    inputs: &[],
    shaders: &["picture.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

crate::technique_params! {
    /// What a camera node reads each step.
    pub struct Settings {
        /// the camera: 0 for /dev/video0, /dev/videoN, or test (a moving test pattern)
        device: Text = |n, doc| ParamDecl::text(n, "0", doc),
        /// frame width asked of the camera
        width: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(1280), Some((16.0, 7680.0)), doc).with_unit("px"),
        /// frame height asked of the camera
        height: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(720), Some((16.0, 4320.0)), doc).with_unit("px"),
        /// frames per second asked of the camera
        fps: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(30), Some((1.0, 240.0)), doc).with_unit("fps"),
        /// how a picture of another shape fills the image
        fit: Fit = |n, doc| ParamDecl::choice(n, Fit::OPTIONS, 0, doc),
    }
}

/// What reopens the camera when it changes.
#[derive(Clone, Debug, PartialEq)]
struct FeedKey {
    device: String,
    size: (u32, u32),
    fps: u32,
}

impl FeedKey {
    fn of(s: &Settings) -> Self {
        // Even sides: cameras and ffmpeg's RGBA conversion deliver those.
        let side = |v: i32| (v.clamp(16, 7680) as u32) & !1;
        Self {
            device: s.device.as_str().trim().to_string(),
            size: (side(s.width), side(s.height)),
            fps: s.fps.clamp(1, 240) as u32,
        }
    }
}

/// A camera node.
pub struct Camera {
    picture: PicturePass,
    key: FeedKey,
    feed: Option<LiveFeed>,
    /// The number of the frame now shown.
    shown: u64,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let key = FeedKey::of(&Settings::read(setup.params));
    let mut camera = Camera {
        picture: PicturePass::new(setup, true)?,
        key: key.clone(),
        feed: None,
        shown: 0,
        messages: Vec::new(),
    };
    camera.open(key);
    Ok(Box::new(camera))
}

impl Camera {
    fn open(&mut self, key: FeedKey) {
        self.feed = match CameraSource::parse(&key.device) {
            Ok(source) => Some(LiveFeed::start(source, key.size, key.fps)),
            Err(e) => {
                self.messages.push(e);
                None
            }
        };
        self.key = key;
        self.shown = 0;
    }
}

impl Technique for Camera {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        let key = FeedKey::of(&Settings::read(params));
        if key != self.key {
            self.open(key);
        }
        if let Some(message) = self.feed.as_ref().and_then(LiveFeed::take_message) {
            self.messages.push(message);
        }
    }

    fn status(&self) -> Option<String> {
        let (w, h) = self.key.size;
        Some(match self.shown {
            0 => format!("{} {w}×{h} · waiting for frames", self.key.device),
            n => format!("{} {w}×{h} · frame {n}", self.key.device),
        })
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        if let Some(feed) = &self.feed
            && let Some((number, frame)) = feed.latest()
            && number != self.shown
        {
            self.shown = number;
            if let Err(e) = self.picture.upload_rgba(&frame, feed.size()) {
                self.messages.push(e);
            }
        }
        self.picture.declare(graph, "camera", Settings::read(params).fit)
    }
}
