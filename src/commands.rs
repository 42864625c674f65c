//! What each CLI command does, on top of the library. Every failure is one sentence for the
//! user; nothing here panics on bad input.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indra::assets::{AssetKind, Assets};
use indra::gpu::{Gpu, GpuOptions, validate_as_used};
use indra::offscreen::{OffscreenRenderer, RenderedFrame, VideoSettings, VideoWriter, write_png};
use indra::scene::{Scene, load_scene};

/// Prints a line to stdout, ignoring a closed pipe (`indra list | head` must not panic).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// The scene `indra` opens with no arguments.
pub const DEFAULT_SCENE: &str = "kleinian";

/// `indra run`.
#[derive(Args, Clone)]
pub struct RunArgs {
    /// Scene name (from scenes/) or path to a .ron file.
    #[arg(default_value = DEFAULT_SCENE)]
    pub scene: String,
    /// Start in borderless fullscreen (F11 toggles, Esc leaves fullscreen).
    #[arg(long)]
    pub fullscreen: bool,
    /// Monitor index for fullscreen (see the log for the list).
    #[arg(long)]
    pub monitor: Option<usize>,
    /// Set a parameter at start (repeatable): node.param=value — 0.5, true, an option name,
    /// a vector as 1,0.3,0.1 or (1.0,0.3,0.1), one component as node.param.x=0.5.
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    pub sets: Vec<String>,
    /// Samples per pixel of rasterising nodes, 1, 2, 4 or 8 (default: the scene's, normally 4);
    /// lowered to what the adapter supports.
    #[arg(long, value_parser = parse_msaa)]
    pub msaa: Option<u32>,
    /// OSC listen address; loopback by default, 0.0.0.0:9000 opens it to the network.
    #[arg(long, default_value = DEFAULT_OSC)]
    pub osc: String,
    /// No OSC input.
    #[arg(long)]
    pub no_osc: bool,
    /// Send every parameter change to this OSC destination (host:port), so faders follow.
    #[arg(long)]
    pub osc_out: Option<String>,
    /// Serve the OSCQuery address tree over HTTP here (e.g. 127.0.0.1:9001).
    #[arg(long)]
    pub oscquery: Option<String>,
    /// Serve the browser control surface, with the OSCQuery tree, here: 127.0.0.1:8080 when
    /// given no address; 0.0.0.0:8080 opens it to the venue network. The printed URL (and QR
    /// code) carries the access token the page needs.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = indra::control::web::DEFAULT_ADDR, conflicts_with = "oscquery")]
    pub web: Option<String>,
    /// Browser pages show the values but cannot change them (a display of the show's state).
    #[arg(long, requires = "web")]
    pub web_read_only: bool,
    /// The access token (12–128 characters of A-Z a-z 0-9 - _) instead of a new random one each
    /// start: for a bookmarked URL or a printed QR code at an installation.
    #[arg(long, value_name = "TOKEN", requires = "web")]
    pub web_token: Option<String>,
    /// One more name the OSCQuery server and the browser surface answer as (repeatable): a DNS
    /// name of the venue's network that points here. Its own addresses, `localhost` and the
    /// machine's name are always answered; any other `Host` is refused (DNS rebinding).
    #[arg(long = "web-host", value_name = "NAME")]
    pub web_hosts: Vec<String>,
    /// Let a third-party OSCQuery web client served from ORIGIN (`http://host:port`, repeatable)
    /// read the tree and open a WebSocket; it controls the show only with the access token.
    /// Pages of any other origin are refused.
    #[arg(long = "oscquery-cors", value_name = "ORIGIN", value_parser = parse_origin)]
    pub oscquery_cors: Vec<String>,
    /// WebSocket sessions open at once: browser pages and OSCQuery clients together (1–256).
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = parse_web_sessions)]
    pub web_sessions: usize,
    /// Only MIDI input ports whose name contains this (default: all ports).
    #[arg(long)]
    pub midi: Option<String>,
    /// No MIDI input.
    #[arg(long)]
    pub no_midi: bool,
    /// Audio input device: the first whose name contains this (default: the default device,
    /// opened when the scene maps audio).
    #[arg(long, value_name = "NAME")]
    pub audio_in: Option<String>,
    /// No audio input.
    #[arg(long)]
    pub no_audio: bool,
    /// Join the Ableton Link session on the local network: follow its tempo and phase, propose
    /// tempo changes made here (builds with `--features link`, GPL-2.0-or-later).
    #[arg(long)]
    pub link: bool,
    /// Open one more output window (repeatable): source=NODE, warp=FILE.ron, monitor=N,
    /// fullscreen — e.g. `--output-window warp=wall.ron,monitor=1,fullscreen`.
    #[arg(long = "output-window", value_name = "SPEC")]
    pub output_windows: Vec<String>,
    /// List the audio input devices and exit.
    #[arg(long)]
    pub list_audio: bool,
    /// Record every control event with its frame to this file (replay with `render --replay`).
    #[arg(long)]
    pub record_controls: Option<PathBuf>,
    /// Folder of presets [default: presets, in %APPDATA%\indra on Windows].
    #[arg(long)]
    pub presets: Option<PathBuf>,
    /// File of MIDI-learned mappings [default: midi-learn.ron, in %APPDATA%\indra on Windows].
    #[arg(long)]
    pub midi_learn: Option<PathBuf>,
    /// File of audio mappings learned from the panel [default: audio-learn.ron, likewise].
    #[arg(long)]
    pub audio_learn: Option<PathBuf>,
    /// Do not watch shaders/ and scenes/ for edits.
    #[arg(long)]
    pub no_watch: bool,
    /// Record the output as shown to this video from the start (.mp4, .mov, .webm, .mkv);
    /// later takes (panel button, OSC /indra/record/start) go beside it. Never overwrites.
    #[arg(long, value_name = "FILE")]
    pub record_video: Option<PathBuf>,
    /// Send the output as shown to a network stream from the start: srt://HOST:PORT,
    /// udp://HOST:PORT or rtmp://HOST/APP/KEY (H.264 tuned for latency, through ffmpeg). The show
    /// never waits for the network: frames the encoder cannot take are dropped and counted.
    #[arg(long, value_name = "URL")]
    pub stream: Option<String>,
    /// Send the output as shown as an NDI source of this name from the start (OBS, Resolume,
    /// TouchDesigner find it). Needs the NDI runtime, loaded at run time (see the README); the
    /// show never waits for the network: frames the sender cannot take are dropped and counted.
    #[arg(long, value_name = "NAME")]
    pub ndi_out: Option<String>,
    /// Offer the output as shown as a PipeWire video source of this name from the start (what
    /// OBS, browsers and `pipewiresrc` read on Linux), through GStreamer's `pipewiresink`. The
    /// show never waits: frames the source cannot take are dropped and counted.
    #[arg(long, value_name = "NAME")]
    pub pipewire_out: Option<String>,
}

/// Where OSC listens unless told otherwise: loopback, so nothing on the network can reach it.
pub const DEFAULT_OSC: &str = "127.0.0.1:9000";

impl Default for RunArgs {
    /// What `indra` with no arguments does (the same defaults as `indra run`).
    fn default() -> Self {
        Self {
            scene: DEFAULT_SCENE.into(),
            fullscreen: false,
            monitor: None,
            sets: Vec::new(),
            msaa: None,
            osc: DEFAULT_OSC.into(),
            no_osc: false,
            osc_out: None,
            oscquery: None,
            web: None,
            web_read_only: false,
            web_token: None,
            web_sessions: 16,
            web_hosts: Vec::new(),
            oscquery_cors: Vec::new(),
            midi: None,
            no_midi: false,
            audio_in: None,
            no_audio: false,
            link: false,
            list_audio: false,
            output_windows: Vec::new(),
            record_controls: None,
            presets: None,
            midi_learn: None,
            audio_learn: None,
            no_watch: false,
            record_video: None,
            stream: None,
            ndi_out: None,
            pipewire_out: None,
        }
    }
}

/// `indra render`.
#[derive(Args, Clone)]
pub struct RenderArgs {
    /// Scene name (from scenes/) or path to a .ron file.
    pub scene: String,
    /// Number of frames to render.
    #[arg(long, default_value_t = 1)]
    pub frames: u64,
    /// First frame index (time = frame × dt).
    #[arg(long, default_value_t = 0)]
    pub start: u64,
    /// Output size WxH (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Fixed time step in seconds (default: the scene's).
    #[arg(long)]
    pub dt: Option<f32>,
    /// Seed (default: the scene's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output folder; frames are written as <scene>_<frame>.png.
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
    /// Set a parameter (repeatable): node.param=value — 0.5, true, an option name, a vector as
    /// 1,0.3,0.1 or (1.0,0.3,0.1), one component as node.param.x=0.5.
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    pub sets: Vec<String>,
    /// Samples per pixel of rasterising nodes, 1, 2, 4 or 8 (default: the scene's, normally 4);
    /// lowered to what the adapter supports.
    #[arg(long, value_parser = parse_msaa)]
    pub msaa: Option<u32>,
    /// Replay a control stream recorded with `run --record-controls`, frame-exactly.
    #[arg(long)]
    pub replay: Option<PathBuf>,
    /// Which output to render: 0 the scene's output (default), 1… its `outputs` as their
    /// windows show them (warped).
    #[arg(long, default_value_t = 0)]
    pub output: usize,
    /// A sound file the scene's audio mappings hear (frame n hears it up to (n + 1) × dt, so
    /// renders are exact): WAV, or any format ffmpeg decodes (MP3, FLAC, Ogg, …); with --video it
    /// is also the video's sound track.
    #[arg(long, value_name = "FILE")]
    pub audio: Option<PathBuf>,
}

/// `indra bench`.
#[derive(Args, Clone)]
pub struct BenchArgs {
    /// Scene name (from scenes/) or path to a .ron file.
    pub scene: String,
    /// Output size WxH.
    #[arg(long, value_parser = parse_size, default_value = "1920x1080")]
    pub size: (u32, u32),
    /// Frames to measure (after warm-up).
    #[arg(long, default_value_t = 100)]
    pub frames: u64,
    /// Frames rendered before measuring.
    #[arg(long, default_value_t = 10)]
    pub warmup: u64,
    /// Seek to this frame first (simulations run every step before it, undrawn), e.g. to
    /// measure a cloth that has settled rather than one at rest.
    #[arg(long, default_value_t = 0)]
    pub start: u64,
    /// Set a parameter (repeatable): node.param=value — 0.5, true, an option name, a vector as
    /// 1,0.3,0.1 or (1.0,0.3,0.1), one component as node.param.x=0.5.
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    pub sets: Vec<String>,
    /// Samples per pixel of rasterising nodes, 1, 2, 4 or 8 (default: the scene's, normally 4);
    /// lowered to what the adapter supports.
    #[arg(long, value_parser = parse_msaa)]
    pub msaa: Option<u32>,
    /// Hold tracks still (measure one parameter set, not an animation).
    #[arg(long)]
    pub no_animation: bool,
    /// For a show with a cue list: GO every this many seconds of the fixed clock, and report
    /// the worst frame at a switch against the median frame.
    #[arg(long, value_name = "SECONDS")]
    pub cue_every: Option<f64>,
    /// Every frame waits for its files and clip frames, as `render` does (default: as live, a
    /// frame whose clip frame is not decoded yet shows an older one): the frame time then
    /// includes decoding that does not keep up.
    #[arg(long)]
    pub wait_for_media: bool,
    /// Keep one frame in flight, as the window does (it records the next frame while the GPU
    /// draws this one): the wall time is then the interval between frames, not each frame's
    /// full latency.
    #[arg(long)]
    pub pipelined: bool,
}

fn parse_msaa(text: &str) -> Result<u32, String> {
    match text.trim().parse::<u32>() {
        Ok(n @ (1 | 2 | 4 | 8)) => Ok(n),
        _ => Err(format!("'{text}' is not a sample count: use 1, 2, 4 or 8")),
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("'{text}' is not WxH (e.g. 1920x1080)"))?;
    let parse = |s: &str| s.trim().parse::<u32>().ok().filter(|v| (1..=16384).contains(v));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("'{text}' is not WxH with sides from 1 to 16384")),
    }
}

/// Most steps a render or bench may seek through (≈ 190 days at 60 fps): beyond it a seek
/// would run for hours, so it is refused with a sentence instead.
const MAX_START: u64 = 1_000_000_000;

/// Checks `--start`, `--frames` and `--dt`: one sentence for each bad value.
fn check_timing(start: u64, frames: u64, dt: Option<f32>) -> Result<(), String> {
    if start > MAX_START {
        return Err(format!("--start {start} is past {MAX_START} steps; split the render or lower it"));
    }
    if frames > MAX_START {
        return Err(format!("--frames {frames} is more than {MAX_START}; render in parts"));
    }
    if let Some(dt) = dt.filter(|dt| !(dt.is_finite() && *dt > 0.0 && *dt <= 1.0)) {
        return Err(format!("--dt {dt} must be a number of seconds in (0, 1], e.g. 0.0166667"));
    }
    Ok(())
}

/// `assets` with the folder of scene file `name` (if it is a path to a file) open to the files
/// its parameters name: a scene kept beside its warp files and images works from any folder.
fn with_scene_folder(assets: &Assets, name: &str) -> Assets {
    let path = std::path::Path::new(name);
    match path.parent() {
        Some(folder) if path.is_file() => {
            assets.allowing(if folder.as_os_str().is_empty() { std::path::Path::new(".") } else { folder })
        }
        _ => assets.clone(),
    }
}

/// Loads a scene and applies `--set` assignments.
fn scene_with_sets(assets: &Assets, name: &str, sets: &[String], msaa: Option<u32>) -> Result<Scene, String> {
    with_sets(load_scene(assets, name).map_err(|e| e.to_string())?, sets, msaa)
}

/// Applies `--set` assignments and `--msaa` to a loaded scene.
fn with_sets(mut scene: Scene, sets: &[String], msaa: Option<u32>) -> Result<Scene, String> {
    for assignment in sets {
        scene.set_from_str(assignment)?;
    }
    if let Some(samples) = msaa {
        scene.msaa = samples;
        scene.check_texture_budget(scene.size)?;
    }
    Ok(scene)
}

/// Opens the scene in a window. A scene file that is broken on disk falls back to its built-in
/// copy (with the error shown) so the show starts; the fix is picked up on save.
pub fn run(assets: &Assets, gpu: &GpuOptions, args: &RunArgs) -> Result<(), String> {
    if args.list_audio {
        return list_audio();
    }
    // A live show never waits for a file a parameter names: it loads in the background.
    let assets = &with_scene_folder(assets, &args.scene).with_load_wait(indra::files::LoadWait::Background);
    let mut notices = Vec::new();
    // A show plays what it can: a clip whose scene is missing or broken is left out and told.
    let loaded = if indra::scene::names_a_show(&args.scene) {
        indra::scene::show::load_show(assets, &args.scene, true)
            .map_err(|e| e.to_string())
            .and_then(|scene| with_sets(scene, &args.sets, args.msaa))
    } else {
        scene_with_sets(assets, &args.scene, &args.sets, args.msaa)
    };
    let mut scene = match loaded {
        Ok(scene) => scene,
        Err(e) => match scene_with_sets(&assets.builtin_only(), &args.scene, &args.sets, args.msaa) {
            Ok(builtin) => {
                notices.push(format!("{e}\n(running the built-in copy until the file is fixed)"));
                builtin
            }
            Err(_) => return Err(e),
        },
    };
    for spec in &args.output_windows {
        scene.add_output(spec)?;
    }
    let options = indra::app::WindowOptions {
        fullscreen: args.fullscreen,
        monitor: args.monitor,
        watch: !args.no_watch,
        record_video: args.record_video.clone(),
        stream: args.stream.clone(),
        ndi_out: args.ndi_out.clone(),
        pipewire_out: args.pipewire_out.clone(),
    };
    let web = match &args.web {
        Some(addr) => {
            let token = match &args.web_token {
                Some(chosen) => indra::control::web::AccessToken::chosen(chosen)?,
                None => indra::control::web::AccessToken::random()?,
            };
            let (read_only, sessions) = (args.web_read_only, args.web_sessions);
            Some(indra::control::web::WebOptions { addr: addr.clone(), read_only, token, sessions })
        }
        None => None,
    };
    let control = indra::control::ControlOptions {
        osc: (!args.no_osc).then(|| args.osc.clone()),
        osc_out: args.osc_out.clone(),
        oscquery: args.oscquery.clone(),
        web,
        midi: !args.no_midi,
        audio_in: (!args.no_audio).then(|| args.audio_in.clone()),
        midi_filter: args.midi.clone(),
        record: args.record_controls.clone(),
        presets_dir: args.presets.clone().unwrap_or_else(|| indra::files::user_data("presets")),
        learn_file: args.midi_learn.clone().unwrap_or_else(|| indra::files::user_data("midi-learn.ron")),
        audio_learn_file: args.audio_learn.clone().unwrap_or_else(|| indra::files::user_data("audio-learn.ron")),
        link: args.link,
        sites: indra::control::site::SiteRules { hosts: args.web_hosts.clone(), cors: args.oscquery_cors.clone() },
    };
    indra::app::run(assets.clone(), gpu.clone(), scene, options, control, notices)
}

/// `--oscquery-cors`: an origin as a browser sends it, `http(s)://host[:port]` with no path.
fn parse_origin(text: &str) -> Result<String, String> {
    let site = text.strip_prefix("http://").or_else(|| text.strip_prefix("https://"));
    match site.map(|s| s.trim_end_matches('/')) {
        Some(site) if !site.is_empty() && !site.contains('/') => Ok(text.trim_end_matches('/').to_string()),
        _ => Err(format!(
            "{text}: an origin is http://HOST:PORT or https://HOST:PORT, as the page's address bar shows it"
        )),
    }
}

/// `--web-sessions`: a count within [`indra::control::web::SESSIONS`].
fn parse_web_sessions(text: &str) -> Result<usize, String> {
    let range = indra::control::web::SESSIONS;
    text.parse::<usize>()
        .ok()
        .filter(|n| range.contains(n))
        .ok_or_else(|| format!("{text}: WebSocket sessions are {} to {}", range.start(), range.end()))
}

/// Prints the audio input devices, one per line.
fn list_audio() -> Result<(), String> {
    #[cfg(feature = "audio")]
    {
        let devices = indra::control::audio::live::list_devices()?;
        if devices.is_empty() {
            say!("no audio input devices");
        }
        for d in devices {
            say!("{d}");
        }
        Ok(())
    }
    #[cfg(not(feature = "audio"))]
    Err("this build has no live audio input (built without the `audio` feature)".into())
}

/// Renders a PNG sequence.
pub fn render(assets: &Assets, gpu: &GpuOptions, args: &RenderArgs) -> Result<(), String> {
    check_timing(args.start, args.frames, args.dt)?;
    let assets = &with_scene_folder(assets, &args.scene);
    let scene = scene_with_sets(assets, &args.scene, &args.sets, args.msaa)?;
    let mut script = match &args.replay {
        Some(path) => indra::control::record::read_replay(path, &scene)?,
        None => Default::default(),
    };
    let dt = f64::from(args.dt.unwrap_or(scene.dt));
    if let Some(path) = &args.audio {
        let file = indra::control::audio::AudioFile::open(path)?;
        if scene.audio.is_empty() {
            eprintln!("'{}' maps no audio (controls.audio): the file is only the sound track", scene.name);
        }
        let frames = args.start.saturating_add(args.frames);
        for (frame, events) in indra::control::audio::file_script(&file, &scene, frames, dt) {
            script.entry(frame).or_default().extend(events);
        }
    }
    scene.check_texture_budget(args.size.unwrap_or(scene.size))?;
    let stem = Path::new(&args.scene).file_stem().map_or("frame".into(), |s| s.to_string_lossy().into_owned());
    let size = args.size.unwrap_or(scene.size);
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
                audio: args.audio.clone().map(|file| (file, args.start as f64 * dt)),
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
            FrameSink::Png { folder: args.out.clone(), stem }
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
    let device = Gpu::headless(gpu).map_err(|e| e.to_string())?;
    eprintln!("rendering '{}' on {}", scene.name, device.adapter_label());
    let mut renderer =
        OffscreenRenderer::new(device, assets, scene, args.size, args.dt, args.seed).map_err(|e| e.to_string())?;
    renderer.show_output(args.output)?;
    // Replayed events apply at their own frames, also those a seek passes over.
    for (frame, events) in script {
        renderer.schedule(frame, events);
    }
    if args.start > 0 {
        eprintln!("seeking to frame {} (every step runs; nothing before it is drawn)", args.start);
    }
    renderer.seek(args.start).map_err(|e| e.to_string())?;
    let bar = indicatif::ProgressBar::new(args.frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
            .expect("valid template"),
    );
    for _ in 0..args.frames {
        let frame = renderer.render_next().map_err(|e| e.to_string())?;
        sink.write(&frame)?;
        for send in &mut sends {
            send.take(&frame.rgba, 1, frame.time.frame).map_err(|e| e.to_string())?;
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
        FrameSink::Png { folder, .. } => folder.display().to_string(),
    };
    for send in sends {
        send.close().map_err(|e| e.to_string())?;
    }
    eprintln!("wrote {} frame(s) to {place}", args.frames);
    Ok(())
}

/// Where `render` puts its frames.
enum FrameSink {
    /// `<folder>/<stem>_<frame>.png`.
    Png { folder: PathBuf, stem: String },
    /// One video file.
    Video(VideoWriter),
}

impl FrameSink {
    fn write(&mut self, frame: &RenderedFrame) -> Result<(), String> {
        match self {
            FrameSink::Png { folder, stem } => {
                write_png(&folder.join(format!("{stem}_{:05}.png", frame.time.frame)), frame.size, &frame.rgba)
            }
            FrameSink::Video(video) => video.write(&frame.rgba).map_err(|e| e.to_string()),
        }
    }
}

/// Validates scenes and shaders; prints every located error.
pub fn check(assets: &Assets, files: &[PathBuf]) -> Result<(), String> {
    let mut targets: Vec<(AssetKind, String)> = Vec::new();
    // ISF shaders (.fs, with a .vs beside them) are checked as the isf node compiles them.
    let mut isf_files: Vec<String> = Vec::new();
    // A file named on the command line may be anywhere.
    let assets = &if files.is_empty() { assets.clone() } else { assets.allowing("/") };
    if files.is_empty() {
        targets.extend(assets.names(AssetKind::Shader).into_iter().map(|n| (AssetKind::Shader, n)));
        targets.extend(assets.names(AssetKind::Scene).into_iter().map(|n| (AssetKind::Scene, n)));
        targets.extend(assets.names(AssetKind::Show).into_iter().map(|n| (AssetKind::Show, format!("shows/{n}"))));
        isf_files.extend(indra::techniques::isf::shader_names(assets));
    } else {
        for f in files {
            let name = f.display().to_string();
            if f.extension().is_some_and(|e| e == "fs") {
                isf_files.push(name);
                continue;
            }
            let kind = if f.extension().is_some_and(|e| e == "wgsl") {
                AssetKind::Shader
            } else if indra::scene::names_a_show(&name) {
                AssetKind::Show
            } else {
                AssetKind::Scene
            };
            targets.push((kind, name));
        }
    }
    let shaders = assets.names(AssetKind::Shader);
    let mut failures = 0;
    for (kind, name) in &targets {
        let result = match kind {
            AssetKind::Scene | AssetKind::Show => load_scene(assets, name).map(|_| ()).map_err(|e| e.to_string()),
            AssetKind::Shader => read_shader(assets, name).and_then(|(origin, source)| {
                // A base is looked for beside the file first, then among the project's shaders;
                // a file they extend is checked through them.
                let beside = |base: &str| Path::new(name).with_file_name(base).display().to_string();
                let file = Path::new(name).file_name().map_or(name.clone(), |f| f.to_string_lossy().into_owned());
                validate_as_used(&file, (&origin, &source), &shaders, |n| {
                    read_shader(assets, &beside(n)).or_else(|_| read_shader(assets, n))
                })
            }),
        };
        match result {
            Ok(()) => say!("ok     {name}"),
            Err(e) => {
                failures += 1;
                say!("error  {e}");
            }
        }
    }
    for name in &isf_files {
        match indra::techniques::isf::IsfFiles::read(assets, name).and_then(|f| f.compile().map_err(|e| e.to_string()))
        {
            Ok(_) => say!("ok     {name}"),
            Err(e) => {
                failures += 1;
                say!("error  {e}");
            }
        }
    }
    say!("{} checked, {failures} with errors", targets.len() + isf_files.len());
    if failures > 0 { Err(format!("{failures} file(s) have errors")) } else { Ok(()) }
}

fn read_shader(assets: &Assets, name: &str) -> Result<(String, String), String> {
    let path = Path::new(name);
    if path.is_file() {
        return std::fs::read_to_string(path).map(|s| (name.to_string(), s)).map_err(|e| format!("{name}: {e}"));
    }
    assets.load(AssetKind::Shader, name).map(|a| (a.origin, a.source))
}

/// Lists scenes and shows with their nodes and parameters.
pub fn list(assets: &Assets) -> Result<(), String> {
    let scenes = assets.names(AssetKind::Scene).into_iter();
    let shows = assets.names(AssetKind::Show).into_iter().map(|n| format!("shows/{n}"));
    for name in scenes.chain(shows) {
        match load_scene(assets, &name) {
            Err(e) => say!("{name}: INVALID\n{e}\n"),
            Ok(scene) => {
                let stem = name.trim_end_matches(".ron");
                say!("{stem} — {} ({}x{}): {}", scene.name, scene.size.0, scene.size.1, scene.description);
                if let Some(show) = &scene.show {
                    list_show(show);
                }
                for (i, node) in scene.nodes.iter().enumerate() {
                    say!("  node {} ({})", node.id, node.technique.name);
                    for (p, decl) in node.params.decls().iter().enumerate() {
                        let animated = scene.tracks.iter().any(|t| t.node == i && t.param == p);
                        let range = decl.range.map(|(lo, hi)| format!(" [{lo} … {hi}]")).unwrap_or_default();
                        say!(
                            "    /indra/{}/{:<18} {:<6} = {}{range}{}",
                            node.id,
                            decl.name,
                            decl.ty(),
                            decl.format(&node.params.value_at(p)),
                            if animated { "  (animated)" } else { "" }
                        );
                    }
                }
                say!();
            }
        }
    }
    say!("ISF shaders (technique \"isf\", params: {{ \"file\": PATH }}; each parameter at /indra/<node>/<name>):");
    for name in indra::techniques::isf::shader_names(assets) {
        match indra::techniques::isf::describe(assets, &name) {
            Ok(line) => say!("  {name} — {line}"),
            Err(e) => say!("  {name}: INVALID {e}"),
        }
    }
    Ok(())
}

/// A show's layers, clips (with their trigger addresses) and cues.
fn list_show(show: &indra::scene::show::Show) {
    for (l, layer) in show.layers.iter().enumerate() {
        say!("  layer {} '{}': /indra/layer/{}/opacity, /indra/layer/{}/blend", l + 1, layer.name, l + 1, l + 1);
        for (c, &clip) in layer.clips.iter().enumerate() {
            let clip = &show.clips[clip];
            say!("    clip {} {} ({}): /indra/layer/{}/clip/{}/connect", c + 1, clip.id, clip.scene, l + 1, c + 1);
        }
    }
    for (i, cue) in show.cues.iter().enumerate() {
        say!("  cue {} {}", i + 1, cue.name);
    }
}

/// Renders `frames` frames and prints per-pass GPU medians and frame time.
pub fn bench(assets: &Assets, gpu: &GpuOptions, args: &BenchArgs) -> Result<(), String> {
    if args.frames == 0 {
        return Err("--frames 0 measures nothing; bench at least one frame".into());
    }
    if args.frames <= MAX_START && args.frames.saturating_add(args.warmup) > MAX_START {
        return Err(format!("--warmup {} and --frames {} together pass {MAX_START} frames", args.warmup, args.frames));
    }
    check_timing(args.start, args.frames, None)?;
    let assets = &with_scene_folder(assets, &args.scene);
    let scene = scene_with_sets(assets, &args.scene, &args.sets, args.msaa)?;
    scene.check_texture_budget(args.size)?;
    let cue_steps = match args.cue_every {
        None => None,
        Some(s) if s.is_finite() && s > 0.0 && scene.show.as_ref().is_some_and(|show| !show.cues.is_empty()) => {
            Some(((s / f64::from(scene.dt)).round() as u64).max(1))
        }
        Some(_) => return Err("--cue-every takes a positive number of seconds and a show with a cue list".into()),
    };
    // Measured as it plays live: clips prepare on worker threads, files load in the background —
    // or, with --wait-for-media, each frame waiting for its files and clip frames as a render
    // does, so the wall time includes any decoding that does not keep up.
    let wait = if args.wait_for_media { indra::files::LoadWait::Finish } else { indra::files::LoadWait::Background };
    let assets = &assets.with_load_wait(wait);
    let device = Gpu::headless(gpu).map_err(|e| e.to_string())?;
    let adapter = device.adapter_label();
    let timestamps = device.has_timestamps();
    let name = scene.name.clone();
    let mut renderer =
        OffscreenRenderer::new(device, assets, scene, Some(args.size), None, None).map_err(|e| e.to_string())?;
    renderer.instance_mut().animate = !args.no_animation;
    renderer.seek(args.start).map_err(|e| e.to_string())?;
    for _ in 0..args.warmup {
        renderer.render_only().map_err(|e| e.to_string())?;
    }
    renderer.restart_timings();
    let mut record = crate::bench_record::FrameRecord::new(cue_steps.unwrap_or(1));
    let mut last = Instant::now();
    let mut stats = None;
    let mut in_flight = None;
    for i in 0..args.frames {
        let go = cue_steps.is_some_and(|n| i > 0 && i % n == 0);
        if go {
            let frame = renderer.next_frame();
            renderer.schedule(frame, vec![indra::params::ControlEvent::Show(indra::params::ShowCommand::CueGo)]);
        }
        let (time, s) = renderer.render_only().map_err(|e| e.to_string())?;
        // Stepping, recording and submitting a frame: the CPU's share of its wall time.
        let recorded = Instant::now();
        // Waiting for this frame makes wall time its full latency; waiting for the one before
        // (pipelined) makes it the interval between frames with one in flight, as live.
        let newest = renderer.last_submission();
        let wait_for = if args.pipelined { std::mem::replace(&mut in_flight, newest) } else { newest };
        if let Some(index) = wait_for {
            let wait = wgpu::PollType::Wait { submission_index: Some(index), timeout: None };
            let _ = renderer.gpu().device.poll(wait);
        }
        let now = Instant::now();
        let ms = |from: Instant, to: Instant| (to - from).as_secs_f64() * 1e3;
        record.push(ms(last, now), ms(last, recorded), go.then_some(time.frame));
        last = now;
        stats = Some(s);
    }
    renderer.finish_timings();
    let wall_median = record.wall_median();
    say!("scene      {name}");
    say!("adapter    {adapter}");
    say!(
        "size       {}x{}   frames {} (+{} warm-up) from frame {}",
        args.size.0,
        args.size.1,
        args.frames,
        args.warmup,
        args.start
    );
    for s in &args.sets {
        say!("set        {s}");
    }
    if timestamps {
        say!("{:<28} {:>12} {:>8}", "pass", "GPU median", "samples");
        for t in renderer.runtime().timings() {
            say!("{:<28} {:>9.3} ms {:>8}", t.name, t.median_ms, t.samples);
        }
        // Per technique: the sum of its passes' medians (the book layout has up to ~100 passes).
        let mut totals: std::collections::BTreeMap<String, (f64, usize)> = Default::default();
        for t in renderer.runtime().timings() {
            let technique = t.name.split('/').next().unwrap_or(&t.name).to_string();
            let entry = totals.entry(technique).or_default();
            entry.0 += t.median_ms;
            entry.1 += 1;
        }
        for (technique, (ms, passes)) in totals {
            say!("{:<28} {:>9.3} ms  ({passes} passes)", format!("total {technique}"), ms);
        }
        if let Some(ms) = renderer.runtime().frame_gpu_median_ms() {
            say!("{:<28} {:>9.3} ms", "all passes (GPU)", ms);
        }
        if let Some(ms) = renderer.runtime().frame_gpu_span_median_ms() {
            say!("{:<28} {:>9.3} ms", "first pass to last (GPU)", ms);
        }
    } else {
        say!("(this adapter has no TIMESTAMP_QUERY_INSIDE_ENCODERS: wall-clock only)");
    }
    say!("{:<28} {:>9.3} ms", "step + record (CPU median)", record.cpu_median());
    let wall_label = if args.pipelined { "frame interval (median)" } else { "frame wall time (median)" };
    say!("{:<28} {:>9.3} ms  ({:.1} fps)", wall_label, wall_median, 1e3 / wall_median.max(1e-9));
    for line in record.switch_report() {
        say!("{line}");
    }
    for line in renderer.instance_mut().bench_reports() {
        say!("node       {line}");
    }
    if let Some(s) = stats {
        say!(
            "graph      passes {}/{} executed, transient {} KiB requested / {} KiB allocated, compile {:.1} µs",
            s.passes_executed,
            s.passes_declared,
            s.transient_bytes_requested / 1024,
            s.transient_bytes_allocated / 1024,
            s.compile_time.as_secs_f64() * 1e6
        );
    }
    Ok(())
}

/// `indra --list-ndi`: the NDI sources an `ndi` node can name.
pub fn list_ndi() -> Result<(), String> {
    let sources = indra::media::ndi::list_sources(std::time::Duration::from_secs(2))?;
    if sources.is_empty() {
        println!("no NDI sources seen within 2 s (senders on other machines: see the README's NDI section)");
    }
    for source in sources {
        println!("{}  {}", source.name, source.url);
    }
    Ok(())
}

/// `indra --list-cameras`: the V4L2 devices a `camera` node can name.
pub fn list_cameras() -> Result<(), String> {
    let cameras = indra::media::camera::list_cameras();
    if cameras.is_empty() {
        println!(
            "no cameras found (no V4L2 devices under /sys/class/video4linux); `device: \"test\"` plays a test pattern"
        );
    }
    for camera in cameras {
        println!("{}  {}", camera.device.display(), camera.name);
    }
    Ok(())
}
