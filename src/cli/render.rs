//! `indra render`: frames to PNGs or a video file, off-screen and exact.

use std::path::PathBuf;

use clap::Args;
use indra::assets::Assets;
use indra::gpu::GpuOptions;
use indra::offscreen::{OffscreenRenderer, RenderedFrame, VideoSettings, VideoWriter, encode_png};
use indra::scene::Scene;
use indra::timecode::chase::{Follow, follow};

use super::assemble::{Manifest, frame_file};
use super::chase::{LtcArgs, LtcTrack};
use super::source::LoadedSource;
use super::{FrameSpan, SceneEdits, check_timing, parse_size};

/// What fixes a render's frames — the scene and its edits, size, step, seed, and the control
/// events it plays — shared by `render` and `bake`, whose checkpoints pin all of it.
#[derive(Args, Clone)]
pub struct RenderSource {
    /// Scene name (from scenes/) or path to a .ron file.
    pub scene: String,
    /// Output size WxH (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Fixed time step in seconds (default: the scene's).
    #[arg(long)]
    pub dt: Option<f32>,
    /// Seed (default: the scene's).
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub edits: SceneEdits,
    /// Replay a control stream recorded with `run --record-controls`, frame-exactly.
    #[arg(long)]
    pub replay: Option<PathBuf>,
    /// A sound file the scene's audio mappings hear (frame n hears it up to (n + 1) × dt, so
    /// renders are exact): WAV, or any format ffmpeg decodes (MP3, FLAC, Ogg, …); with --video it
    /// is also the video's sound track.
    #[arg(long, value_name = "FILE")]
    pub audio: Option<PathBuf>,
}

/// `indra render`.
#[derive(Args, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub source: RenderSource,
    /// Frames to render: a count from --start (120), or a range of frame numbers, both ends
    /// included (600-699: a farm task's chunk).
    #[arg(long, default_value = "1", value_parser = FrameSpan::parse)]
    pub frames: FrameSpan,
    /// The frames of a farm task as Open Job Description writes a CHUNK[INT] range — 600-699,
    /// 600,601 or 600 — in place of --frames and --start.
    #[arg(long, value_name = "RANGE", value_parser = FrameSpan::parse_chunk, conflicts_with_all = ["frames", "start"])]
    pub chunk: Option<FrameSpan>,
    /// First frame index (time = frame × dt), with a count of --frames.
    #[arg(long, default_value_t = 0)]
    pub start: u64,
    /// Start from the nearest checkpoint at or before the first frame in this folder (made by
    /// `indra bake`) instead of simulating every frame before it.
    #[arg(long, value_name = "DIR")]
    pub checkpoints: Option<PathBuf>,
    /// Take a checkpoint made on another adapter or driver: the frames are then close to,
    /// not the same bytes as, a render from frame 0 here.
    #[arg(long, requires = "checkpoints")]
    pub accept_other_adapter: bool,
    /// Output folder; frames are written as <scene>_<frame>.png, with a manifest of their
    /// SHA-256 sums (<scene>_<first>-<last>.sha256, as sha256sum writes it).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Write the frames as one video file instead of PNGs (.mp4 and .mkv: H.264; .mov: ProRes
    /// 422 HQ; .webm: VP9), through ffmpeg, at 1/dt frames per second.
    #[arg(long, value_name = "FILE")]
    pub video: Option<PathBuf>,
    /// Send the frames to a network stream instead: srt://HOST:PORT, udp://HOST:PORT or
    /// rtmp://HOST/APP/KEY — H.264 tuned for latency (no B-frames, a keyframe a second) in
    /// MPEG-TS (FLV for RTMP), through ffmpeg.
    #[arg(long, value_name = "URL", conflicts_with = "video")]
    pub stream: Option<String>,
    /// Also send the frames as an NDI source of this name, in real time (each frame waits until
    /// it is due at 1/dt frames per second), stamped with their frame numbers as timecodes.
    #[arg(long, value_name = "NAME")]
    pub ndi_out: Option<String>,
    /// Also offer the frames as a PipeWire video source of this name, in real time (each frame
    /// waits until it is due at 1/dt frames per second).
    #[arg(long, value_name = "NAME")]
    pub pipewire_out: Option<String>,
    /// Video codec: h264, h265, prores, vp9, av1, ffv1, hap, hap_alpha, hap_q (in .mov; clips
    /// indra and VJ tools play frame-exact), or an ffmpeg encoder name (default: the container's).
    #[arg(long, requires = "video")]
    pub codec: Option<String>,
    /// Video quality: the CRF for h264/h265/vp9/av1 (lower is better; default 18, 20, 30, 30),
    /// the ProRes profile (0 proxy … 3 HQ, 4 4444).
    #[arg(long, requires = "video")]
    pub quality: Option<u32>,
    /// Which output to render: 0 the scene's output (default), 1… its `outputs` as their
    /// windows show them (warped).
    #[arg(long, default_value_t = 0)]
    pub output: usize,
    /// Send the fixtures of this DMX patch file (Art-Net or sACN, see docs/lights.md) the
    /// pixels of each frame, in real time (each frame waits until it is due at 1/dt); default:
    /// the patch the scene or show names (`dmx:`).
    #[arg(long, value_name = "PATCH", conflicts_with = "ltc")]
    pub dmx_out: Option<PathBuf>,
    /// Also write every frame's universes to this file (per universe: the frame as u64, the
    /// universe as u16, little-endian, then its 512 channels).
    #[arg(long, value_name = "FILE")]
    pub dmx_record: Option<PathBuf>,
    #[command(flatten)]
    pub ltc: LtcArgs,
}

/// Renders a PNG sequence (with its manifest) or a video.
pub fn render(assets: &Assets, gpu: &GpuOptions, args: &RenderArgs) -> Result<(), String> {
    let (start, frames) = args.chunk.unwrap_or(args.frames).resolve(args.start)?;
    check_timing(start, frames, args.source.dt)?;
    if args.ltc.ltc_start.is_some() && args.ltc.ltc.is_none() && args.ltc.ltc_out.is_none() {
        return Err("--ltc-start labels the code of --ltc or --ltc-out: give one of them".into());
    }
    let mut ltc = LtcTrack::open(&args.ltc)?;
    // Chasing a code, the timeline may be anywhere the code says, past the last output frame.
    let end = |scene: &Scene, dt| {
        let last = ltc.as_ref().map_or(0, |track| track.last_frame(args.ltc.settings(scene), dt) + 1);
        start.saturating_add(frames).max(last)
    };
    let loaded = LoadedSource::load(assets, &args.source, end)?;
    if let Some(track) = ltc.as_mut() {
        track.chase_with(args.ltc.settings(&loaded.scene))?;
    }
    let (assets, scene) = (&loaded.assets, &loaded.scene);
    let dt = f64::from(args.source.dt.unwrap_or(scene.dt));
    // A patch the scene names but that cannot be found costs the lights, not the frames.
    let patch = super::dmx_file(assets, args.dmx_out.as_deref(), scene.dmx.as_deref(), &scene.name, "DMX patch")
        .unwrap_or_else(|e| {
            eprintln!("warning: no DMX out: {e}");
            None
        });
    if args.dmx_record.is_some() && patch.is_none() {
        return Err(format!("--dmx-record needs a patch: '{}' names none; give --dmx-out", scene.name));
    }
    let size = args.source.size.unwrap_or(scene.size);
    let fps = 1.0 / dt;
    // ffmpeg starts before the GPU and the seek, so a missing one or a bad codec fails at once.
    let mut sink = match &args.video {
        None if args.stream.is_some() => {
            let settings = VideoSettings::stream(args.stream.as_deref().unwrap_or_default(), size, fps, true);
            FrameSink::Video(VideoWriter::start(settings).map_err(|e| e.to_string())?)
        }
        Some(path) => {
            let settings = VideoSettings {
                path: path.clone(),
                size,
                fps,
                codec: args.codec.clone(),
                quality: args.quality,
                audio: args.source.audio.clone().map(|file| (file, start as f64 * dt)),
                stream: false,
                pace: false,
            };
            if settings.encoded_size() != size {
                let (w, h) = settings.encoded_size();
                eprintln!("the video is {w}x{h}: odd sides are padded by one black pixel (4:2:0 chroma)");
            }
            FrameSink::Video(VideoWriter::start(settings).map_err(|e| e.to_string())?)
        }
        None => {
            std::fs::create_dir_all(&args.out).map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
            FrameSink::Png { folder: args.out.clone(), stem: loaded.stem.clone(), manifest: Manifest::default() }
        }
    };
    // Sends beside the frames written. A render is faster than real time: each send paces the
    // frames to the scene's rate.
    let mut sends: Vec<Box<dyn indra::offscreen::FrameOutlet>> = Vec::new();
    if let Some(name) = &args.ndi_out {
        sends.push(indra::offscreen::ndi_outlet(name, size, fps, true)?);
    }
    if let Some(name) = &args.pipewire_out {
        sends.push(Box::new(indra::offscreen::PipeWireOut::start(name, size, fps, true)?));
    }
    let first = match ltc.as_mut() {
        Some(track) => track.frame_at(start as f64 * dt, dt),
        None => start,
    };
    let mut renderer = start_renderer(&loaded, gpu, args, first)?;
    let mut lights = match patch {
        Some(patch) => Some(super::RenderDmx::start(&patch, args.dmx_record.as_deref(), &mut renderer, dt)?),
        None => None,
    };
    let bar = indicatif::ProgressBar::new(frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
            .expect("valid template"),
    );
    let mut shown: Option<RenderedFrame> = None;
    for index in start..start + frames {
        let wanted = ltc.as_mut().map(|track| track.frame_at(index as f64 * dt, dt));
        let drawn = shown.as_ref().map(|f| f.time.frame);
        let fresh = match wanted.map(|w| (w, follow(w, drawn, u32::MAX, 0))) {
            None => Some(renderer.render_next().map_err(|e| e.to_string())?),
            // The code stands (or holds after a dropout): the frame on screen stays.
            Some((_, Follow::Hold)) => None,
            Some((wanted, _)) => {
                if wanted < renderer.next_frame() {
                    // The code jumped back: the timeline plays again from its start (or the
                    // nearest checkpoint), as `--start` does.
                    bar.suspend(|| eprintln!("the code jumped back: seeking to frame {wanted}"));
                    renderer = start_renderer(&loaded, gpu, args, wanted)?;
                }
                renderer.seek(wanted).map_err(|e| e.to_string())?;
                Some(renderer.render_next().map_err(|e| e.to_string())?)
            }
        };
        let frame = match fresh {
            Some(frame) => shown.insert(frame),
            None => shown.as_mut().expect("a frame is drawn before one is held"),
        };
        sink.write(index, frame)?;
        for send in &mut sends {
            send.take(&frame.rgba, 1, index).map_err(|e| e.to_string())?;
        }
        if let Some(lights) = lights.as_mut() {
            lights.frame(&mut renderer, frame.time.frame)?;
        }
        // What a node tells the performer (a clip that cannot play, a bad image path) is said
        // once, as the window's overlay says it; the render goes on.
        for message in renderer.instance_mut().take_messages() {
            bar.suspend(|| eprintln!("warning: {message}"));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    for e in renderer.gpu().take_uncaptured_errors() {
        eprintln!("GPU error during the render: {e}");
    }
    let place = match sink {
        FrameSink::Video(video) => {
            let path = video.settings().path.display().to_string();
            video.finish().map_err(|e| e.to_string())?;
            path
        }
        FrameSink::Png { folder, stem, manifest } => match manifest.write(&folder, &stem)? {
            Some(path) => format!("{} (SHA-256 in {})", folder.display(), path.display()),
            None => folder.display().to_string(),
        },
    };
    for send in sends {
        send.close().map_err(|e| e.to_string())?;
    }
    if let Some(lights) = lights {
        eprintln!("sent {} DMX packet(s)", lights.finish()?);
    }
    if let Some(track) = ltc {
        eprintln!("read {} LTC frame(s)", track.frames_read());
    }
    if let (Some(path), Some(rate)) = (&args.ltc.ltc_out, args.ltc.ltc_rate) {
        let (from, to) = (start as f64 * dt, (start + frames) as f64 * dt);
        let written = super::ltc_out::write_ltc(path, rate, args.ltc.settings(scene).start, from, to)?;
        eprintln!("wrote {written} LTC frame(s) at {rate} to {}", path.display());
    }
    eprintln!("wrote {frames} frame(s) to {place}");
    Ok(())
}

/// A renderer of `loaded` whose next frame is `frame`: from the nearest checkpoint at or
/// before it when `--checkpoints` is given, with the control events from there on.
fn start_renderer(
    loaded: &LoadedSource,
    gpu: &GpuOptions,
    args: &RenderArgs,
    frame: u64,
) -> Result<OffscreenRenderer, String> {
    let mut renderer = loaded.renderer(gpu, &args.source, "rendering")?;
    renderer.show_output(args.output)?;
    if let Some(folder) = &args.checkpoints {
        super::bake::resume(&mut renderer, folder, frame, &loaded.controls, args.accept_other_adapter)?;
    }
    loaded.schedule(&mut renderer);
    if frame > renderer.next_frame() {
        eprintln!("seeking to frame {frame} (every step runs; nothing before it is drawn)");
    }
    renderer.seek(frame).map_err(|e| e.to_string())?;
    Ok(renderer)
}

/// Where `render` puts its frames.
enum FrameSink {
    /// `<folder>/<stem>_<frame>.png`, and their sums.
    Png { folder: PathBuf, stem: String, manifest: Manifest },
    /// One video file.
    Video(VideoWriter),
}

impl FrameSink {
    /// Writes `frame` as output frame `index` (the timeline's frame, unless a code is chased).
    fn write(&mut self, index: u64, frame: &RenderedFrame) -> Result<(), String> {
        match self {
            FrameSink::Png { folder, stem, manifest } => {
                let name = frame_file(stem, index);
                let path = folder.join(&name);
                let png = encode_png(frame.size, &frame.rgba)?;
                std::fs::write(&path, &png).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                manifest.add(index, &name, &png);
                Ok(())
            }
            FrameSink::Video(video) => video.write(&frame.rgba).map_err(|e| e.to_string()),
        }
    }
}
