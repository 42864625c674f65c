//! A video clip as a node: its current frame, fitted into the node's image in linear light with
//! premultiplied alpha, so a clip can feed StarGlow, displace the tessellated surface, be warped
//! onto a wall, or play as a show's clip.
//!
//! HAP clips (Hap, Hap Alpha, Hap Q, Hap Q Alpha, Hap7) are read frame by frame from their
//! QuickTime sample tables and uploaded as BC textures the GPU decodes as it samples (HAP Q's
//! YCoCg is turned into RGB in `shaders/picture.wgsl`); every other codec comes through ffmpeg
//! (`crate::media`). A worker decodes the next frames ahead of the show; off-screen renders wait
//! for each frame, so frame n of a scene shows the clip's frame for the play position reached by
//! n fixed steps — played, sought or split, the same bytes. Live, a frame not decoded in time is
//! counted as late and the last one stays.
//!
//! Shader: `shaders/picture.wgsl` (through [`super::picture_pass`]). Tests: `render_tests.rs` (ffmpeg-made clips against ffmpeg's decode, a
//! burnt-in frame counter through every play mode, seek = play, bad files).

#[cfg(test)]
mod render_tests;

use std::sync::Arc;
use std::time::Duration;

use crate::assets::Assets;
use crate::checkpoint::{CheckpointError, NodeState};
use crate::files::{LoadWait, Loader};
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::media::clip::Clip;
use crate::media::picture::Picture;
use crate::media::playhead::{self, PlaySettings, Playhead};
use crate::media::prefetch::Prefetcher;
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::picture_pass::{Fit, PicturePass};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "video",
    chapter: "media: video clips",
    summary: "a video clip's current frame: HAP straight to the GPU, other codecs through ffmpeg, frame-exact",
    params: Settings::decls,
    inputs: &[],
    shaders: &["picture.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The clip bundled with indra (made by `tools/make-demo-clip` from the Kleinian scene).
pub const DEMO_CLIP: &str = "assets/clips/kleinian_hap.mov";

/// How long an off-screen render waits for one frame before calling it failed.
const FRAME_WAIT: Duration = Duration::from_secs(60);

/// The most fixed steps one `step` call moves the playhead (a clock that jumped far).
const MAX_STEPS_AT_ONCE: u64 = 1 << 20;

crate::param_enum! {
    /// What a clip does at its out point (or in point, backwards).
    pub enum LoopMode {
        /// Jump back to the other end.
        Loop = "loop",
        /// Turn round and play the other way.
        PingPong = "ping_pong",
        /// Stop and hold the last frame.
        Once = "once",
    }
}

crate::technique_params! {
    /// What a video node reads each step.
    pub struct Settings {
        /// video file (HAP .mov, anything ffmpeg reads, or numbered images as frames/shot_%04d.png);
        /// relative to the folder holding scenes/
        file: Text = |n, doc| ParamDecl::text(n, DEMO_CLIP, doc),
        /// whether the clip moves
        playing: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// clip seconds per second; negative plays backwards
        speed: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((-4.0, 4.0)), doc).with_unit("×"),
        /// what happens at the out point
        loop_mode: LoopMode = |n, doc| ParamDecl::choice(n, LoopMode::OPTIONS, 0, doc),
        /// where the clip starts, a share of its length
        in_point: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 1.0)), doc),
        /// where the clip ends, a share of its length
        out_point: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
        /// scrub: setting it jumps to that share of the way from the in to the out point
        position: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 1.0)), doc),
        /// back to the in point (the out point when playing backwards)
        restart: bool = |n, doc| ParamDecl::trigger(n, doc),
        /// frames per second of an image sequence (`frames/shot_%04d.png`); a movie has its own
        sequence_fps: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(30.0), Some((0.1, 240.0)), doc).with_unit("fps"),
        /// how a clip of another shape fills the image
        fit: Fit = |n, doc| ParamDecl::choice(n, Fit::OPTIONS, 0, doc),
    }
}

impl Settings {
    fn play(&self) -> PlaySettings {
        PlaySettings {
            playing: self.playing,
            speed: f64::from(self.speed),
            mode: match self.loop_mode {
                LoopMode::Loop => playhead::LoopMode::Loop,
                LoopMode::PingPong => playhead::LoopMode::PingPong,
                LoopMode::Once => playhead::LoopMode::Once,
            },
            in_point: f64::from(self.in_point),
            out_point: f64::from(self.out_point),
        }
    }
}

/// An open clip and where it plays.
struct Playing {
    frames: Prefetcher,
    head: Playhead,
    /// The clip frame now in the textures.
    shown: Option<usize>,
}

/// A video node.
pub struct Video {
    picture: PicturePass,
    device: wgpu::Device,
    assets: Assets,
    wait: LoadWait,
    loader: Loader<Clip>,
    /// The clip last asked for (opened or not), so a bad name is reported once.
    requested: ClipKey,
    clip: Option<Playing>,
    /// The scene frame of the last step (the playhead moves one step per frame since).
    stepped: Option<u64>,
    /// The position parameter last seen: a change is a scrub.
    scrubbed: f32,
    /// Frames not decoded in time for a live frame (the last frame stayed).
    late: u64,
    /// The last decoding error, so a bad frame is reported once.
    last_error: Option<String>,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(Video::new(setup, true)?))
}

/// Which clip the settings name: the file, and for an image sequence its frame rate too.
#[derive(Clone, Debug, PartialEq)]
struct ClipKey {
    name: String,
    sequence_fps: Option<f32>,
}

impl ClipKey {
    fn of(settings: &Settings) -> Self {
        let name = settings.file.as_str().trim().to_string();
        let sequence_fps = crate::media::sequence::is_pattern(&name).then_some(settings.sequence_fps.clamp(0.1, 240.0));
        Self { name, sequence_fps }
    }

    /// Opens the clip under the file rules, for a device taking textures of `max_side`.
    fn open(&self, assets: &Assets, max_side: u32) -> Result<Clip, String> {
        let name = &self.name;
        let failed = |e: String| format!("cannot play {name}: {e}");
        let limit = crate::media::DECODED_LIMIT;
        if let Some(fps) = self.sequence_fps {
            // A pattern names no file: its folder is looked up under the rules instead.
            let (folder, pattern) = name.rsplit_once('/').unwrap_or((".", name));
            let folder = assets.locate_file(folder).map_err(|e| format!("cannot open clip: {e}"))?;
            return Clip::open_sequence(&folder, pattern, f64::from(fps), max_side, limit).map_err(failed);
        }
        let path = assets.locate_file(name).map_err(|e| format!("cannot open clip: {e}"))?;
        Clip::open(&path, max_side, limit).map_err(failed)
    }
}

impl Video {
    /// A node playing its file from its in point; with `allow_blocks` false, HAP is decoded on
    /// the CPU even where the GPU could (the fallback path, for tests).
    pub fn new(setup: &NodeSetup<'_>, allow_blocks: bool) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let settings = Settings::read(setup.params);
        let mut video = Self {
            picture: PicturePass::new(setup, allow_blocks)?,
            device: device.clone(),
            assets: setup.assets.clone(),
            wait: setup.assets.load_wait(),
            loader: Loader::new(setup.assets.load_wait()),
            requested: ClipKey::of(&settings),
            clip: None,
            stepped: None,
            scrubbed: settings.position,
            late: 0,
            last_error: None,
            messages: Vec::new(),
        };
        // The scene's clip is opened now (a show prepares clips on worker threads), so its first
        // frame has it.
        let max_side = device.limits().max_texture_dimension_2d;
        match video.requested.open(setup.assets, max_side) {
            Ok(clip) => video.start(clip, &settings),
            Err(e) => video.messages.push(e),
        }
        Ok(video)
    }

    fn start(&mut self, clip: Clip, settings: &Settings) {
        let frames = Prefetcher::new(clip, &self.requested.name);
        let (play, duration) = (settings.play(), frames.info().duration());
        let mut head = Playhead::new(&play, duration, frames.info().fps);
        // A scene (or preset) that names a position starts there.
        if settings.position > 0.0 {
            head.scrub(f64::from(settings.position), &play, duration);
        }
        self.scrubbed = settings.position;
        self.clip = Some(Playing { frames, head, shown: None });
        self.last_error = None;
    }

    /// Asks for the clip the settings name if it changed, and starts one that has been opened
    /// (true then).
    fn take_up_clip(&mut self, settings: &Settings) -> bool {
        let key = ClipKey::of(settings);
        if key != self.requested {
            let (assets, wanted) = (self.assets.clone(), key.clone());
            let max_side = self.device.limits().max_texture_dimension_2d;
            self.loader.request(&key.name, move || wanted.open(&assets, max_side));
            self.requested = key;
        }
        match self.loader.poll() {
            Some((_, Ok(clip))) => {
                self.start(clip, settings);
                return true;
            }
            Some((_, Err(e))) => self.messages.push(format!("{e}; keeping the last clip")),
            None => {}
        }
        false
    }

    /// Live frames whose decode was not ready in time.
    pub fn late_frames(&self) -> u64 {
        self.late
    }

    /// Makes the current frame the textures' (waiting for it in off-screen renders).
    fn take_up_frame(&mut self, settings: &Settings, dt: f64) {
        let Some(playing) = &mut self.clip else { return };
        let info = playing.frames.info();
        let (size, fps, frames) = ((info.width, info.height), info.fps, info.frames);
        let play = settings.play();
        let current = playing.head.frame(&play, fps, frames);
        let upcoming = playing.head.upcoming(&play, dt, fps, frames, playing.frames.ahead());
        playing.frames.want(&upcoming);
        if playing.shown == Some(current) {
            return;
        }
        let got: Option<Result<Arc<Picture>, String>> = match self.wait {
            LoadWait::Finish => Some(playing.frames.wait(current, FRAME_WAIT)),
            LoadWait::Background => playing.frames.get(current),
        };
        let result = match got {
            None => {
                // Late: the newest frame decoded stands in (if it is not already shown), so a
                // clip that decodes slower than the show still moves, at its decode rate.
                self.late += 1;
                if let Some((index, picture)) = playing.frames.newest()
                    && playing.shown != Some(index)
                    && self.picture.upload(&picture, size).is_ok()
                {
                    playing.shown = Some(index);
                }
                return;
            }
            Some(Ok(picture)) => self.picture.upload(&picture, size),
            Some(Err(e)) => Err(e),
        };
        playing.shown = Some(current);
        if let Err(e) = result
            && self.last_error.as_deref() != Some(e.as_str())
        {
            self.messages.push(format!("{}: {e}; showing the last good frame", self.requested.name));
            self.last_error = Some(e);
        }
    }
}

impl Technique for Video {
    fn step(&mut self, params: &ParamSet, time: &FrameTime) {
        let settings = Settings::read(params);
        let started = self.take_up_clip(&settings);
        // A clip taken up in this step shows its first frame now.
        let steps = match self.stepped {
            Some(last) if time.frame > last && !started => (time.frame - last).min(MAX_STEPS_AT_ONCE),
            _ => 0,
        };
        self.stepped = Some(time.frame);
        let Some(playing) = &mut self.clip else { return };
        let play = settings.play();
        let (duration, fps) = (playing.frames.info().duration(), playing.frames.info().fps);
        for _ in 0..steps {
            playing.head.step(&play, f64::from(time.dt), duration, fps);
        }
        if settings.restart {
            playing.head.restart(&play, duration, fps);
        }
        if settings.position != self.scrubbed {
            playing.head.scrub(f64::from(settings.position), &play, duration);
            self.scrubbed = settings.position;
        }
    }

    fn status(&self) -> Option<String> {
        let Some(playing) = &self.clip else { return Some("no clip".into()) };
        let info = playing.frames.info();
        let frame = playing.shown.map_or("–".to_string(), |f| (f + 1).to_string());
        Some(format!(
            "{} {}×{} · frame {frame}/{} · {} late",
            info.codec, info.width, info.height, info.frames, self.late
        ))
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, _gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        // The playhead moves by steps (speed, ping-pong, loops): its position is state.
        state.put_option("head", self.clip.as_ref().map(|p| p.head.parts()));
        state.put_option("stepped", self.stepped);
        state.put_pod("scrubbed", &[self.scrubbed]);
        Ok(())
    }

    fn load_state(
        &mut self,
        _gpu: &Gpu,
        params: &ParamSet,
        _time: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        // The clip is opened now (an off-screen render waits for it), so the first step goes on
        // from the checkpoint's playhead instead of starting the clip again.
        self.take_up_clip(&Settings::read(params));
        if let (Some(playing), Some(parts)) = (&mut self.clip, state.get_option::<[f64; 2]>("head")?) {
            playing.head =
                Playhead::from_parts(parts).ok_or_else(|| state.error("head", "is not a playhead".into()))?;
        }
        self.stepped = state.get_option("stepped")?;
        self.scrubbed = state.get_pod::<f32>("scrubbed")?.first().copied().unwrap_or(0.0);
        Ok(())
    }

    fn bench_report(&mut self) -> Vec<String> {
        let Some(playing) = &self.clip else { return vec!["no clip".into()] };
        let info = playing.frames.info();
        let path = if self.picture.uploads_blocks() { "BC textures" } else { "decoded on the CPU" };
        let decode = playing.frames.decode_median_ms().map_or("–".into(), |ms| format!("{ms:.2} ms"));
        vec![format!(
            "{} {}×{} at {:.3} fps, {} frames ({path}); decode median {decode} a frame on its thread; {} live frames late",
            info.codec, info.width, info.height, info.fps, info.frames, self.late
        )]
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let settings = Settings::read(params);
        self.take_up_frame(&settings, f64::from(time.dt));
        self.picture.declare(graph, "video", settings.fit)
    }
}
