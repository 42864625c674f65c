//! `render --ltc FILE`: a render that chases the LTC on a sound file, as a show chases the
//! sound desk. Output frame k, at k × dt into the file, shows the timeline frame the code says
//! then: the code's label less `--ltc-start`, in the show's steps. Where the code jumps the
//! render seeks (exactly, as every indra seek); where it drops out the timeline runs on for
//! `--freewheel` seconds, then holds until the code comes back.

use std::path::PathBuf;

use indra::control::audio::AudioFile;
use indra::scene::Scene;
use indra::timecode::Timecode;
use indra::timecode::chase::{Chase, ChaseOverrides, ChaseSettings, frame_at};
use indra::timecode::ltc::{LtcDecoder, LtcFrame};

/// The LTC a render chases.
#[derive(clap::Args, Clone, Debug)]
pub struct LtcArgs {
    /// A sound file with LTC on it (WAV, or anything ffmpeg decodes): each frame shows the
    /// timeline's frame that the code says at its time.
    #[arg(long, value_name = "FILE")]
    pub ltc: Option<PathBuf>,
    /// The channel of --ltc that carries the code, from 1 (default: the mix of all channels,
    /// right for a file of the code alone).
    #[arg(long, value_name = "N", requires = "ltc")]
    pub ltc_channel: Option<u16>,
    /// The code's label at the timeline's first frame, for --ltc and --ltc-out (default: the
    /// show's `timeline.chase`, else 00:00:00:00).
    #[arg(long, value_name = "HH:MM:SS:FF", value_parser = Timecode::parse)]
    pub ltc_start: Option<Timecode>,
    /// Seconds the timeline runs on when the code drops out, before it holds (default: the
    /// show's, else 2).
    #[arg(long, value_name = "SECONDS", requires = "ltc")]
    pub freewheel: Option<f64>,
    /// Also write the LTC of the rendered frames to this WAV (48 kHz mono): sample 0 is the
    /// first frame's time, labelled from --ltc-start.
    #[arg(long, value_name = "FILE", conflicts_with = "ltc", requires = "ltc_rate")]
    pub ltc_out: Option<PathBuf>,
    /// The rate of --ltc-out's code: 24, 25, 29.97df or 30.
    #[arg(long, value_name = "RATE", requires = "ltc_out")]
    pub ltc_rate: Option<indra::timecode::Rate>,
}

impl LtcArgs {
    /// How `scene` chases: these flags over its show's `timeline.chase`, over the defaults.
    pub fn settings(&self, scene: &Scene) -> ChaseSettings {
        ChaseOverrides { start: self.ltc_start, freewheel: self.freewheel }.over(scene.chase())
    }
}

/// A sound file's LTC, read whole before the render.
pub struct LtcTrack {
    /// The frames read, in the order they ended.
    frames: Vec<LtcFrame>,
    /// The file's sample rate.
    rate: f64,
    /// Frames heard so far.
    heard: usize,
    chase: Chase,
}

impl LtcTrack {
    /// The track `args` names, if any; an unreadable file or channel, or a file without code,
    /// is one sentence. It chases with the defaults until [`LtcTrack::chase_with`].
    pub fn open(args: &LtcArgs) -> Result<Option<Self>, String> {
        let Some(path) = &args.ltc else { return Ok(None) };
        let audio = match args.ltc_channel {
            Some(channel) => AudioFile::open_channel(path, channel)?,
            None => AudioFile::open(path)?,
        };
        let mut frames = Vec::new();
        LtcDecoder::new(audio.rate).write(&audio.samples, &mut frames);
        if frames.is_empty() {
            return Err(format!("{}: no LTC found (is it on another channel? --ltc-channel)", path.display()));
        }
        let chase = Chase::new(ChaseSettings::default());
        Ok(Some(LtcTrack { frames, rate: f64::from(audio.rate), heard: 0, chase }))
    }

    /// Chases with `settings` from the start of the file; a freewheel that is not a number of
    /// seconds is one sentence.
    pub fn chase_with(&mut self, settings: ChaseSettings) -> Result<(), String> {
        if !settings.freewheel.is_finite() || settings.freewheel < 0.0 {
            return Err(format!("a freewheel of {} is not a number of seconds", settings.freewheel));
        }
        (self.chase, self.heard) = (Chase::new(settings), 0);
        Ok(())
    }

    /// The timeline's frame (at step `dt`) at `seconds` into the file: the first frame before
    /// any code, and before the code reaches the chase's start.
    pub fn frame_at(&mut self, seconds: f64, dt: f64) -> u64 {
        while let Some(frame) = self.frames.get(self.heard).filter(|f| f.end / self.rate <= seconds + 1e-6) {
            self.heard += 1;
            if let Some(position) = frame.position() {
                self.chase.heard(position, frame.rate, frame.end / self.rate);
            }
        }
        self.chase.at(seconds).seconds().map_or(0, |s| frame_at(s, dt))
    }

    /// The last timeline frame (at step `dt`) the code can ask for when chased with `settings`:
    /// its latest label, freewheel included. Control events (a replay, an audio file's
    /// mappings) are read up to it.
    pub fn last_frame(&self, settings: ChaseSettings, dt: f64) -> u64 {
        let mut probe = Chase::new(settings);
        let mut last = 0;
        for frame in &self.frames {
            if let Some(position) = frame.position() {
                probe.heard(position, frame.rate, 0.0);
                last = last.max(probe.at(settings.freewheel).seconds().map_or(0, |s| frame_at(s, dt)));
            }
        }
        last
    }

    /// Code frames read in the file.
    pub fn frames_read(&self) -> usize {
        self.frames.len()
    }
}
