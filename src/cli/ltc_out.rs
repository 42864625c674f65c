//! `render --ltc-out FILE`: the LTC of the rendered span, written as a WAV — indra as the
//! timecode master of an offline render. Sample 0 is the first output frame's time; the code
//! labels the timeline's frame 0 with the chase start (`--ltc-start`, else the show's
//! `timeline.chase`, else 00:00:00:00), so a sound desk or an editor lines the frames up by it,
//! and `render --ltc` of the file shows the same frames again.

use std::path::Path;

use indra::timecode::ltc::LtcEncoder;
use indra::timecode::{Rate, Timecode};

/// Samples a second of the written file.
const SAMPLE_RATE: u32 = 48_000;
/// The square wave's level: −6 dBFS, well above a line input's noise, clear of clipping.
const LEVEL: f32 = 0.5;

/// Writes the LTC at `rate` of the timeline's seconds `from..to` (frame 0 labelled `start`) to
/// `path` as a 48 kHz, 16-bit mono WAV; returns the code frames begun in it. An unwritable file,
/// or a start label the rate has not, is one sentence.
pub fn write_ltc(path: &Path, rate: Rate, start: Timecode, from: f64, to: f64) -> Result<u64, String> {
    let start = rate.count(start).map_err(|e| format!("--ltc-out: {e}"))?;
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: SAMPLE_RATE,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let fail = |e: hound::Error| format!("{}: {e}", path.display());
    let mut wav = hound::WavWriter::create(path, spec).map_err(fail)?;
    let fps = rate.fps();
    let samples_a_second = f64::from(SAMPLE_RATE);
    // The code frame running at `from` is encoded whole; its samples before `from` are not kept.
    let first = (from * fps).floor() as u64;
    let mut skip = ((from - first as f64 / fps) * samples_a_second).round() as u64;
    let mut left = ((to - from).max(0.0) * samples_a_second).round() as u64;
    let mut encoder = LtcEncoder::new(SAMPLE_RATE, rate, LEVEL);
    let (mut frame, mut samples) = (first, Vec::new());
    while left > 0 {
        samples.clear();
        encoder.frame(rate.timecode(start + frame), 0, &mut samples);
        frame += 1;
        let dropped = skip.min(samples.len() as u64);
        skip -= dropped;
        for &s in samples.iter().skip(dropped as usize).take(left as usize) {
            wav.write_sample((s * f32::from(i16::MAX)).round() as i16).map_err(fail)?;
            left -= 1;
        }
    }
    wav.finalize().map_err(fail)?;
    Ok(frame - first)
}
