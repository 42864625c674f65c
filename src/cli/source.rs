//! What `render` and `bake` share: a scene loaded with its edits, the control events it plays
//! (a replay, an audio file's analysis) and what pins them for checkpoints, and the renderer.

use std::collections::BTreeMap;
use std::path::Path;

use indra::assets::Assets;
use indra::gpu::{Gpu, GpuOptions};
use indra::offscreen::OffscreenRenderer;
use indra::params::ControlEvent;
use indra::scene::Scene;

use super::render::RenderSource;
use super::{scene_with_edits, with_scene_folder};

/// A render's scene and control events, ready for a renderer.
pub struct LoadedSource {
    /// The assets, allowed the scene's folder and rendering at the asked size.
    pub assets: Assets,
    /// The scene with its edits.
    pub scene: Scene,
    /// Control events by frame, up to the last frame asked for.
    pub script: BTreeMap<u64, Vec<ControlEvent>>,
    /// What fixes the control events (the replay's and audio file's SHA-256): a checkpoint's
    /// controls hash is made of it.
    pub controls: String,
    /// The scene file's stem: frames are `<stem>_<frame>.png`, checkpoints `<stem>_<frame>.ckpt`.
    pub stem: String,
}

impl LoadedSource {
    /// Loads `source`'s scene and control events for frames before `end(scene, dt)` (`dt` the
    /// step the render runs at).
    pub fn load(assets: &Assets, source: &RenderSource, end: impl FnOnce(&Scene, f64) -> u64) -> Result<Self, String> {
        let assets = with_scene_folder(assets, &source.scene).rendering_at(source.size);
        let scene = scene_with_edits(&assets, &source.scene, &source.edits)?;
        let end = end(&scene, f64::from(source.dt.unwrap_or(scene.dt)));
        let mut script = match &source.replay {
            Some(path) => indra::control::record::read_replay(path, &scene, &assets)?,
            None => Default::default(),
        };
        let dt = f64::from(source.dt.unwrap_or(scene.dt));
        if let Some(path) = &source.audio {
            let file = indra::control::audio::AudioFile::open(path)?;
            if scene.audio.is_empty() {
                eprintln!("'{}' maps no audio (controls.audio): the file is only the sound track", scene.name);
            }
            for (frame, events) in indra::control::audio::file_script(&file, &scene, end, dt) {
                script.entry(frame).or_default().extend(events);
            }
        }
        scene.check_texture_budget(source.size.unwrap_or(scene.size))?;
        let controls =
            format!("replay {}\naudio {}\n", file_hash(source.replay.as_deref())?, file_hash(source.audio.as_deref())?);
        let stem = Path::new(&source.scene).file_stem().map_or("frame".into(), |s| s.to_string_lossy().into_owned());
        Ok(Self { assets, scene, script, controls, stem })
    }

    /// The renderer of the scene on a new headless device.
    pub fn renderer(&self, gpu: &GpuOptions, source: &RenderSource, verb: &str) -> Result<OffscreenRenderer, String> {
        let device = Gpu::headless(gpu).map_err(|e| e.to_string())?;
        eprintln!("{verb} '{}' on {}", self.scene.name, device.adapter_label());
        OffscreenRenderer::new(device, &self.assets, self.scene.clone(), source.size, source.dt, source.seed)
            .map_err(|e| e.to_string())
    }

    /// Gives `renderer` the control events from its next frame on (a checkpoint holds what the
    /// earlier ones did); they apply at their own frames, also those a seek passes over.
    pub fn schedule(&self, renderer: &mut OffscreenRenderer) {
        let from = renderer.next_frame();
        for (&frame, events) in self.script.range(from..) {
            renderer.schedule(frame, events.clone());
        }
    }
}

/// The SHA-256 of a file the render reads, or "-" for none.
fn file_hash(path: Option<&Path>) -> Result<String, String> {
    let Some(path) = path else { return Ok("-".into()) };
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(indra::checkpoint::sha256_hex(&bytes))
}
