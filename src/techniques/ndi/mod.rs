//! An NDI source as a node: the newest frame of a named source on the network (OBS, a media
//! server, another indra), fitted into the node's image. The runtime is loaded when the first
//! `ndi` node starts; without it the node is black and says so once. A source not there yet is
//! waited for; one that stops sending keeps its last frame, with a notice, and is shown again
//! when it comes back.
//!
//! An NDI source is live input: frames come when the sender sends them, not on the fixed clock,
//! so a render that uses one is not repeatable (every other node stays exact). `indra --list-ndi`
//! lists the sources seen. Tests: `tests/suite/ndi.rs` (frames from cyndilib's sender through
//! the node, in a network namespace of their own).

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::media::ndi::NdiFeed;
use crate::params::{ParamDecl, ParamSet, Text};
use crate::time::FrameTime;

use super::picture_pass::{Fit, PicturePass};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "ndi",
    chapter: "media: NDI",
    summary: "the newest frame of an NDI source on the network (`indra --list-ndi` lists them)",
    params: Settings::decls,
    inputs: &[],
    shaders: &["picture.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

crate::technique_params! {
    /// What an NDI node reads each step.
    pub struct Settings {
        /// the source: its full name, MACHINE (stream), or the stream's name alone
        source: Text = |n, doc| ParamDecl::text(n, "", doc),
        /// how a picture of another shape fills the image
        fit: Fit = |n, doc| ParamDecl::choice(n, Fit::OPTIONS, 0, doc),
    }
}

/// An NDI node.
pub struct Ndi {
    picture: PicturePass,
    /// The source asked for.
    wanted: String,
    feed: Option<NdiFeed>,
    /// The number of the frame now shown.
    shown: u64,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let mut node = Ndi {
        picture: PicturePass::new(setup, false)?,
        wanted: String::new(),
        feed: None,
        shown: 0,
        messages: Vec::new(),
    };
    node.open(Settings::read(setup.params).source.as_str());
    Ok(Box::new(node))
}

impl Ndi {
    /// Follows `source`: a new name starts a new feed; an empty one shows nothing.
    fn open(&mut self, source: &str) {
        self.wanted = source.trim().to_string();
        self.feed = (!self.wanted.is_empty()).then(|| NdiFeed::start(&self.wanted));
        self.shown = 0;
    }
}

impl Technique for Ndi {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        let settings = Settings::read(params);
        if settings.source.as_str().trim() != self.wanted {
            self.open(settings.source.as_str());
        }
        if let Some(message) = self.feed.as_ref().and_then(NdiFeed::take_message) {
            self.messages.push(message);
        }
    }

    fn status(&self) -> Option<String> {
        let feed = self.feed.as_ref()?;
        Some(match feed.connection() {
            (None, _) => format!("looking for '{}'", self.wanted),
            (Some(name), _) if self.shown == 0 => format!("{name} · waiting for frames"),
            (Some(name), true) => format!("{name} · frame {}", self.shown),
            (Some(name), false) => format!("{name} · stopped, showing frame {}", self.shown),
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
        if let Some(frame) = self.feed.as_ref().and_then(NdiFeed::latest)
            && frame.number != self.shown
        {
            self.shown = frame.number;
            if let Err(e) = self.picture.upload_rgba(&frame.rgba, frame.size) {
                self.messages.push(e);
            }
        }
        self.picture.declare(graph, "ndi", Settings::read(params).fit)
    }
}
