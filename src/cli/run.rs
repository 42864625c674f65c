//! `indra run`: the show in a window, with its live inputs.

use std::path::PathBuf;

use clap::Args;
use indra::assets::Assets;
use indra::gpu::GpuOptions;

use super::{DEFAULT_SCENE, SceneEdits, scene_with_edits, with_scene_folder};

/// `indra run`.
#[derive(Args, Clone)]
#[command(group = clap::ArgGroup::new("chase").args(["mtc_in", "ltc_in"]).multiple(false))]
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
    #[command(flatten)]
    pub edits: SceneEdits,
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
    /// The pad controller's profile: apc40-mk2, apc-mini-mk2, launchpad-x, launchpad-mini-mk3,
    /// generic-grid, or a profile file [default: picked by port name, from those and the user's
    /// controllers/ folder].
    #[arg(long, value_name = "PROFILE")]
    pub controller: Option<String>,
    /// Send MIDI to the first output port whose name contains this: every MIDI-mapped parameter
    /// as its control change or note when it changes (motor faders, LED rings, other gear).
    #[arg(long, value_name = "PORT")]
    pub midi_out: Option<String>,
    /// Send MIDI clock at the show's tempo on the --midi-out port.
    #[arg(long, requires = "midi_out")]
    pub midi_clock: bool,
    /// Send MTC on the --midi-out port at this rate (24, 25, 29.97df or 30): the show's position,
    /// its first frame labelled as its timeline's chase start says (else 00:00:00:00).
    #[arg(long, value_name = "RATE", requires = "midi_out")]
    pub mtc_out: Option<indra::timecode::Rate>,
    /// Send LTC at this rate (24, 25, 29.97df or 30) on the audio output's first channel (the
    /// default output, or --audio-out): the show's position, labelled as for --mtc-out.
    #[arg(long, value_name = "RATE")]
    pub ltc_out: Option<indra::timecode::Rate>,
    /// Audio output for --ltc-out: the first whose name contains this (default: the default
    /// output).
    #[arg(long, value_name = "NAME", requires = "ltc_out")]
    pub audio_out: Option<String>,
    /// Chase MTC from the MIDI inputs (a desk's quarter frames and locates, at 24, 25, 29.97df
    /// or 30 fps): the timeline shows the frame the code says, holds before any code, runs on
    /// through a dropout for --freewheel seconds, and seeks when the code jumps.
    #[arg(long, conflicts_with_all = ["no_midi", "ltc_in"])]
    pub mtc_in: bool,
    /// Chase LTC from the audio input (--audio-in; the mix of its channels, or --ltc-channel),
    /// as --mtc-in chases MTC.
    #[arg(long, conflicts_with = "no_audio")]
    pub ltc_in: bool,
    /// The audio input's channel that carries --ltc-in's code, from 1 (default: the mix of all
    /// channels, right for an input of the code alone).
    #[arg(long, value_name = "N", requires = "ltc_in")]
    pub ltc_channel: Option<u16>,
    /// The code's label at the timeline's first frame for --mtc-in or --ltc-in (default: the
    /// show's `timeline.chase`, else 00:00:00:00).
    #[arg(long, value_name = "HH:MM:SS:FF", requires = "chase", value_parser = indra::timecode::Timecode::parse)]
    pub chase_start: Option<indra::timecode::Timecode>,
    /// Seconds the timeline runs on when the chased code drops out, before it holds (default:
    /// the show's, else 2).
    #[arg(long, value_name = "SECONDS", requires = "chase", value_parser = parse_freewheel)]
    pub freewheel: Option<f64>,
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
    /// Send the fixtures of this DMX patch file the pixels they sit on, over Art-Net or sACN
    /// (see docs/lights.md), from a thread of its own at the patch's rate; default: the patch
    /// the scene or show names (`dmx:`).
    #[arg(long, value_name = "PATCH")]
    pub dmx_out: Option<PathBuf>,
    /// Take DMX in from a lighting desk as this file says: where to listen, and which channels
    /// drive which parameters (see docs/lights.md); default: the file the scene or show names
    /// (`dmx_in:`).
    #[arg(long, value_name = "FILE")]
    pub dmx_in: Option<PathBuf>,
}

/// Where OSC listens unless told otherwise: loopback, so nothing on the network can reach it.
pub const DEFAULT_OSC: &str = "127.0.0.1:9000";

impl Default for RunArgs {
    /// What `indra` with no arguments does: `indra run`'s own defaults, read from its arguments'
    /// declarations so that the two cannot drift apart.
    fn default() -> Self {
        use clap::FromArgMatches;
        let command = Self::augment_args(clap::Command::new("run"));
        Self::from_arg_matches(&command.get_matches_from(["run"])).expect("`indra run` parses with no arguments")
    }
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
            .and_then(|scene| args.edits.apply(scene))
    } else {
        scene_with_edits(assets, &args.scene, &args.edits)
    };
    let mut scene = match loaded {
        Ok(scene) => scene,
        Err(e) => match scene_with_edits(&assets.builtin_only(), &args.scene, &args.edits) {
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
    scene.check_texture_budget(scene.size)?;
    let options = indra::app::WindowOptions {
        fullscreen: args.fullscreen,
        monitor: args.monitor,
        watch: !args.no_watch,
        record_video: args.record_video.clone(),
        stream: args.stream.clone(),
        ndi_out: args.ndi_out.clone(),
        pipewire_out: args.pipewire_out.clone(),
        dmx_out: match super::dmx_file(assets, args.dmx_out.as_deref(), scene.dmx.as_deref(), &scene.name, "DMX patch")
        {
            Ok(patch) => patch,
            Err(e) => {
                notices.push(format!("no DMX out: {e}"));
                None
            }
        },
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
        controller: args.controller.clone(),
        controllers_dir: indra::files::user_data("controllers"),
        midi_out: args.midi_out.clone(),
        midi_clock: args.midi_clock,
        mtc_out: args.mtc_out,
        ltc_out: args.ltc_out,
        audio_out: args.audio_out.clone(),
        chase_in: chase_input(args),
        record: args.record_controls.clone(),
        presets_dir: args.presets.clone().unwrap_or_else(|| indra::files::user_data("presets")),
        learn_file: args.midi_learn.clone().unwrap_or_else(|| indra::files::user_data("midi-learn.ron")),
        audio_learn_file: args.audio_learn.clone().unwrap_or_else(|| indra::files::user_data("audio-learn.ron")),
        link: args.link,
        sites: indra::control::site::SiteRules { hosts: args.web_hosts.clone(), cors: args.oscquery_cors.clone() },
        dmx_in: match super::dmx_file(
            assets,
            args.dmx_in.as_deref(),
            scene.dmx_in.as_deref(),
            &scene.name,
            "DMX-in file",
        ) {
            Ok(file) => file,
            Err(e) => {
                notices.push(format!("no DMX in: {e}"));
                None
            }
        },
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

/// The timecode `args` ask the show to chase, if any.
fn chase_input(args: &RunArgs) -> Option<indra::control::timecode_in::ChaseInput> {
    use indra::control::timecode_in::{ChaseInput, CodeSource};
    let source = match (args.mtc_in, args.ltc_in) {
        (true, _) => CodeSource::Mtc,
        (_, true) => CodeSource::Ltc { channel: args.ltc_channel },
        _ => return None,
    };
    let overrides = indra::timecode::chase::ChaseOverrides { start: args.chase_start, freewheel: args.freewheel };
    Some(ChaseInput { source, overrides })
}

/// A freewheel time, in the range a show's `timeline.chase` takes.
fn parse_freewheel(text: &str) -> Result<f64, String> {
    use indra::timecode::chase::MAX_FREEWHEEL;
    text.parse::<f64>()
        .ok()
        .filter(|s| (0.0..=MAX_FREEWHEEL).contains(s))
        .ok_or_else(|| format!("{text}: a freewheel is 0 to {MAX_FREEWHEEL} seconds"))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indra_with_no_arguments_runs_with_the_defaults_of_indra_run() {
        let args = RunArgs::default();
        assert_eq!(args.scene, DEFAULT_SCENE);
        assert_eq!(args.osc, DEFAULT_OSC);
        assert_eq!(args.web_sessions, 16);
        assert!(args.edits.sets.is_empty() && args.edits.msaa.is_none());
        assert!(!args.no_osc && !args.no_midi && !args.no_watch && args.presets.is_none());
    }
}
