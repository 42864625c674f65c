//! Chasing a sound desk's timecode live: MTC on the MIDI inputs (quarter frames and full-frame
//! locates, stamped by the MIDI thread as they arrive) or LTC on the audio input (stamped by the
//! audio callback with the time its first sample was captured), into the chase of
//! [`crate::timecode::chase`]. The window asks where the timeline is at the instant it steps; the
//! answer runs on between code frames at the code's speed, freewheels through a dropout, and
//! stops after it.

use std::time::Instant;

use crate::scene::Scene;
use crate::timecode::Rate;
use crate::timecode::chase::{Chase, ChaseOverrides, Chasing};
use crate::timecode::ltc::LtcDecoder;
use crate::timecode::mtc::{MtcEvent, MtcReader};

/// Where the code comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CodeSource {
    /// MTC on the MIDI inputs.
    Mtc,
    /// LTC on the audio input: one channel (from 1), or the mix of all.
    Ltc {
        /// The channel that carries the code; `None`: the mix.
        channel: Option<u16>,
    },
}

/// How a running show chases: the source and the settings given over the show's own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChaseInput {
    /// Where the code comes from.
    pub source: CodeSource,
    /// The command line's start and freewheel, over the show's.
    pub overrides: ChaseOverrides,
}

impl ChaseInput {
    /// The audio input's channel an LTC chase reads (from 1, or `None` for the mix); `None` for
    /// an MTC chase.
    pub fn ltc_channel(&self) -> Option<Option<u16>> {
        match self.source {
            CodeSource::Ltc { channel } => Some(channel),
            CodeSource::Mtc => None,
        }
    }
}

/// What reads the code.
#[derive(Clone, Debug)]
enum Reader {
    Mtc(MtcReader),
    /// The decoder, made at the input's sample rate when the first samples come.
    Ltc(Option<Box<LtcDecoder>>),
}

/// The timecode chase of a running show.
#[derive(Clone, Debug)]
pub struct TimecodeIn {
    input: ChaseInput,
    reader: Reader,
    chase: Chase,
    /// Local time 0 of the chase's clock.
    epoch: Instant,
    /// The last position read, for the status line.
    last: Option<(f64, Rate)>,
    /// When the code was last heard (seconds on the chase's clock).
    heard_at: f64,
}

/// Silence between quarter frames (a tenth of a frame apart at most rates) that breaks a run:
/// the reader counts quarter frames on from the last whole label, so after a dropout it must
/// read a whole label again rather than go on from where the code was.
const RUN_BREAK_SECONDS: f64 = 0.1;

impl TimecodeIn {
    /// A chase of `scene` as `input` says, that has heard nothing.
    pub fn new(input: ChaseInput, scene: &Scene) -> Self {
        let chase = Chase::new(input.overrides.over(scene.chase()));
        let reader = Self::reader(input.source);
        Self { input, reader, chase, epoch: Instant::now(), last: None, heard_at: 0.0 }
    }

    fn reader(source: CodeSource) -> Reader {
        match source {
            CodeSource::Mtc => Reader::Mtc(MtcReader::new()),
            CodeSource::Ltc { .. } => Reader::Ltc(None),
        }
    }

    /// Where the code comes from.
    pub fn source(&self) -> CodeSource {
        self.input.source
    }

    /// Takes a reloaded show's chase settings; the code is found again from the next frame of
    /// it, a few hundredths of a second away while the desk runs.
    pub fn set_scene(&mut self, scene: &Scene) {
        let settings = self.input.overrides.over(scene.chase());
        if settings != self.chase.settings() {
            self.chase = Chase::new(settings);
            self.reader = Self::reader(self.input.source);
        }
    }

    /// Reads one MIDI message that arrived at `at`; true when it was MTC taken by an MTC chase
    /// (not to be mapped).
    pub fn message(&mut self, at: Instant, bytes: &[u8]) -> bool {
        let Reader::Mtc(reader) = &mut self.reader else { return false };
        if !matches!(bytes, [0xF1, _] | [0xF0, 0x7F, _, 0x01, 0x01, ..]) {
            return false;
        }
        let seconds = at.saturating_duration_since(self.epoch).as_secs_f64();
        if seconds - self.heard_at > RUN_BREAK_SECONDS {
            *reader = MtcReader::new();
        }
        self.heard_at = seconds;
        match reader.message(bytes) {
            Some(MtcEvent::Running { frame, rate }) => {
                self.chase.heard(frame, rate, seconds);
                self.last = Some((frame, rate));
            }
            Some(MtcEvent::Located { frame, rate }) => {
                self.chase.located(frame, rate, seconds);
                self.last = Some((frame as f64, rate));
            }
            None => {}
        }
        true
    }

    /// Reads audio for an LTC chase: `samples` at `rate` a second, the first captured at
    /// `first`. Each code frame read counts at the time its last bit ended.
    pub fn audio(&mut self, samples: &[f32], rate: u32, first: Instant) {
        let Reader::Ltc(decoder) = &mut self.reader else { return };
        let decoder = decoder.get_or_insert_with(|| Box::new(LtcDecoder::new(rate)));
        let start = decoder.position() as f64;
        let first = first.saturating_duration_since(self.epoch).as_secs_f64();
        let mut frames = Vec::new();
        decoder.write(samples, &mut frames);
        for frame in frames {
            let Some(position) = frame.position() else { continue };
            let at = first + (frame.end - start) / f64::from(rate);
            self.chase.heard(position, frame.rate, at);
            self.last = Some((position, frame.rate));
            self.heard_at = at;
        }
    }

    /// Where the timeline is at `now`.
    pub fn at(&self, now: Instant) -> Chasing {
        self.chase.at(now.saturating_duration_since(self.epoch).as_secs_f64())
    }

    /// One line for the overlay: the source, the last label heard, its rate, and whether the
    /// show is locked to it.
    pub fn status(&self, now: Instant) -> String {
        let source = match self.input.source {
            CodeSource::Mtc => "MTC",
            CodeSource::Ltc { .. } => "LTC",
        };
        let Some((frame, rate)) = self.last else { return format!("{source}: waiting for code") };
        let label = rate.timecode(frame.max(0.0) as u64);
        let state = match self.at(now) {
            Chasing::NoCode => "waiting".to_string(),
            Chasing::Locked { .. } => "locked".to_string(),
            Chasing::Freewheel { for_seconds, .. } => format!("freewheel {for_seconds:.1} s"),
            Chasing::Stopped { .. } => "stopped".to_string(),
        };
        format!("{source} {label} ({rate}): {state}")
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::timecode::Timecode;
    use crate::timecode::mtc::{full_frame, quarter_frame};

    #[test]
    fn quarter_frames_lock_the_timeline_to_the_code_and_other_messages_pass() {
        let start = Timecode::parse("01:00:00:00").unwrap();
        let scene = crate::scene::load_scene(&crate::assets::Assets::new(None), "kleinian_classic").unwrap();
        let overrides = ChaseOverrides { start: Some(start), freewheel: Some(1.0) };
        let mut mtc = TimecodeIn::new(ChaseInput { source: CodeSource::Mtc, overrides }, &scene);
        let t0 = mtc.epoch;
        assert!(!mtc.message(t0, &[0x90, 60, 100]), "a note is not MTC");
        assert_eq!(mtc.at(t0), Chasing::NoCode);
        let rate = Rate::Fps25;
        // A desk running from 01:00:10:00, a quarter frame every 10 ms.
        let from = rate.count(Timecode::parse("01:00:10:00").unwrap()).unwrap();
        let at = |q: u64| t0 + Duration::from_millis(10 * q);
        for q in 0..16 {
            assert!(mtc.message(at(q), &quarter_frame(from * 4 + q, rate)));
        }
        // The last piece (15) came at 150 ms, when the desk was 3.75 frames on.
        let seconds = mtc.at(at(15)).seconds().unwrap();
        assert!((seconds - (10.0 + 3.75 / 25.0)).abs() < 1e-9, "{seconds}");
        assert!(mtc.status(at(15)).contains("locked") && mtc.status(at(15)).contains("01:00:10:03"));
        // After a dropout of a second (past the freewheel) the desk goes on 24 frames later, from
        // a piece 0: those pieces are not counted on from before the dropout; the first whole
        // label is the position.
        let later = |q: u64| at(q) + Duration::from_secs(1);
        for q in 16..23 {
            mtc.message(later(q), &quarter_frame(from * 4 + 96 + q, rate));
            let seconds = mtc.at(later(q)).seconds().unwrap();
            assert!(seconds > 11.0, "{q}: back to {seconds}");
        }
        mtc.message(later(23), &quarter_frame(from * 4 + 96 + 23, rate));
        let seconds = mtc.at(later(23)).seconds().unwrap();
        assert!((seconds - (10.0 + 29.75 / 25.0)).abs() < 1e-9, "{seconds}");
        // Silence past the freewheel stops it; a full frame locates.
        assert!(matches!(mtc.at(later(23) + Duration::from_millis(500)), Chasing::Freewheel { .. }));
        assert!(matches!(mtc.at(later(23) + Duration::from_secs(2)), Chasing::Stopped { .. }));
        let back = rate.count(Timecode::parse("01:00:02:00").unwrap()).unwrap();
        assert!(mtc.message(at(300), &full_frame(back, rate)));
        assert_eq!(mtc.at(at(400)), Chasing::Stopped { seconds: 2.0 });
    }
}
