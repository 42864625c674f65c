//! LTC (SMPTE 12M linear timecode): 80 bits a frame in biphase mark code on an audio channel.
//! Every bit cell starts with a level change and a 1 has a second one in its middle, so the code
//! reads the same inverted and at any level; the last 16 bits are a sync word that also tells
//! the direction the tape ran.
//!
//! Written here rather than taken from a crate: the two on crates.io are unmaintained since
//! 2020 and 2022, and neither reads drop-frame (`timecode-coder` says so; `ltc` has no rate at
//! all). The tests hold this decoder to frames that libltc (Debian's, the reference encoder)
//! wrote.

use super::{Rate, Timecode};

/// The sync word, bits 64–79 as they are sent (bit 64 first).
const SYNC: u128 = 0xBFFC;
/// The sync word as it arrives when the tape runs backwards (bit 79 first).
const SYNC_REVERSED: u128 = 0x3FFD;
/// Bits in a frame.
const BITS: usize = 80;

/// One frame read from the signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LtcFrame {
    /// The frame's label.
    pub timecode: Timecode,
    /// The rate, from the frame's length and its drop-frame flag.
    pub rate: Rate,
    /// The eight user-bit groups, group 1 in the low nibble.
    pub user_bits: u32,
    /// Where the frame ended, in samples since the decoder began (with the fraction): the start
    /// of the next frame when running forwards.
    pub end: f64,
    /// Whether the code ran backwards (the tape or the desk's transport in reverse).
    pub reverse: bool,
}

impl LtcFrame {
    /// The code's position (a frame count, fractional) when this frame has just been read:
    /// forwards a frame ends where the next begins, backwards where it began. `None` for a label
    /// that does not exist at its rate (a dropped drop-frame label).
    pub fn position(&self) -> Option<f64> {
        let count = self.rate.count(self.timecode).ok()? as f64;
        Some(if self.reverse { count } else { count + 1.0 })
    }
}

/// Reads LTC from audio samples, any level or polarity, at 24 to 30 frames a second.
#[derive(Clone, Debug)]
pub struct LtcDecoder {
    sample_rate: f64,
    /// Samples per bit, followed as the code's speed drifts.
    period: f64,
    /// Recent peak level, for the hysteresis that keeps noise from making edges.
    peak: f32,
    /// The level's side: above (true) or below the hysteresis band.
    high: bool,
    /// The latest crossing of zero, in samples (fractional).
    zero: f64,
    /// The edge before this one.
    last_edge: Option<f64>,
    /// The first half of a 1, waiting for its second.
    half: Option<f64>,
    /// The last 80 bits, the newest in bit 79.
    word: u128,
    /// Bits in `word` since the last break in the signal (up to 80).
    valid: usize,
    /// When each of the last 81 bits ended, to measure a frame's length.
    bit_ends: [f64; BITS + 1],
    bits_seen: usize,
    /// Samples read so far.
    position: u64,
    previous: f32,
}

impl LtcDecoder {
    /// A decoder for audio at `sample_rate` samples a second.
    pub fn new(sample_rate: u32) -> Self {
        let sample_rate = f64::from(sample_rate);
        LtcDecoder {
            sample_rate,
            period: sample_rate / (27.0 * BITS as f64),
            peak: 0.0,
            high: false,
            zero: 0.0,
            last_edge: None,
            half: None,
            word: 0,
            valid: 0,
            bit_ends: [0.0; BITS + 1],
            bits_seen: 0,
            position: 0,
            previous: 0.0,
        }
    }

    /// Samples read so far: the position the next sample has in [`LtcFrame::end`]'s count.
    pub fn position(&self) -> u64 {
        self.position
    }

    /// Reads `samples` (one channel), appending the frames completed in them to `frames`.
    pub fn write(&mut self, samples: &[f32], frames: &mut Vec<LtcFrame>) {
        for &s in samples {
            let at = self.position as f64;
            if (s >= 0.0) != (self.previous >= 0.0) {
                // Where the line between the two samples crosses zero.
                let t = f64::from(self.previous / (self.previous - s));
                self.zero = at - 1.0 + t.clamp(0.0, 1.0);
            }
            self.peak = (self.peak * 0.9995).max(s.abs());
            let band = (0.2 * self.peak).max(0.002);
            let flipped = if self.high { s < -band } else { s > band };
            if flipped {
                self.high = !self.high;
                let edge = self.zero;
                if let Some(frame) = self.edge(edge) {
                    frames.push(frame);
                }
            }
            self.previous = s;
            self.position += 1;
        }
    }

    /// Takes an edge at `edge` samples: the end of a bit cell or of half of one.
    fn edge(&mut self, edge: f64) -> Option<LtcFrame> {
        let last = self.last_edge.replace(edge)?;
        let d = edge - last;
        if !(0.3 * self.period..1.6 * self.period).contains(&d) {
            // Silence, a dropout or a glitch: what was read so far cannot be trusted.
            self.half = None;
            self.valid = 0;
            return None;
        }
        if d >= 0.75 * self.period {
            if self.half.take().is_some() {
                // Half a cell then a whole one: the halves were paired wrongly.
                self.valid = 0;
            }
            self.follow(d);
            return self.bit(false, edge);
        }
        match self.half.take() {
            Some(first) => {
                self.follow(first + d);
                self.bit(true, edge)
            }
            None => {
                self.half = Some(d);
                None
            }
        }
    }

    /// Follows the code's speed, within the rates LTC runs at (±10 %).
    fn follow(&mut self, cell: f64) {
        let (slowest, fastest) = (self.sample_rate / (22.0 * BITS as f64), self.sample_rate / (33.0 * BITS as f64));
        self.period = (self.period + 0.1 * (cell - self.period)).clamp(fastest, slowest);
    }

    /// Takes a bit that ended at `end`, returning a frame when its 80th bit completes one.
    fn bit(&mut self, one: bool, end: f64) -> Option<LtcFrame> {
        self.word = (self.word >> 1) | (u128::from(one) << (BITS - 1));
        self.valid = (self.valid + 1).min(BITS);
        self.bit_ends[self.bits_seen % (BITS + 1)] = end;
        self.bits_seen += 1;
        if self.valid < BITS {
            return None;
        }
        let (bits, reverse) = if (self.word >> 64) & 0xFFFF == SYNC {
            (self.word, false)
        } else if self.word & 0xFFFF == SYNC_REVERSED {
            (reverse_bits(self.word), true)
        } else {
            return None;
        };
        let start = self.bit_ends[self.bits_seen % (BITS + 1)];
        let fps = self.sample_rate / (end - start);
        let nominal = [24u32, 25, 30]
            .into_iter()
            .min_by(|a, b| (f64::from(*a) - fps).abs().total_cmp(&(f64::from(*b) - fps).abs()))?;
        let (timecode, drop, user_bits) = fields(bits)?;
        let rate = Rate::from_nominal(nominal, drop)?;
        rate.count(timecode).ok()?;
        Some(LtcFrame { timecode, rate, user_bits, end, reverse })
    }
}

/// The 80 bits in the other order (bit 0 becomes bit 79).
fn reverse_bits(word: u128) -> u128 {
    word.reverse_bits() >> (128 - BITS)
}

/// The bits of one frame: `width` bits at `from`.
fn take(bits: u128, from: usize, width: usize) -> u8 {
    ((bits >> from) & ((1 << width) - 1)) as u8
}

/// A frame's label, drop-frame flag and user bits, if its digits are digits.
fn fields(bits: u128) -> Option<(Timecode, bool, u32)> {
    let digit = |units: u8, tens: u8| (units <= 9).then_some(tens * 10 + units);
    let timecode = Timecode {
        frames: digit(take(bits, 0, 4), take(bits, 8, 2))?,
        seconds: digit(take(bits, 16, 4), take(bits, 24, 3))?,
        minutes: digit(take(bits, 32, 4), take(bits, 40, 3))?,
        hours: digit(take(bits, 48, 4), take(bits, 56, 2))?,
    };
    let user_bits = (0..8).fold(0u32, |ub, g| ub | u32::from(take(bits, 4 + 8 * g, 4)) << (4 * g));
    Some((timecode, take(bits, 10, 1) == 1, user_bits))
}

/// The 80 bits of the frame labelled `timecode` at `rate`, with `user_bits`, its polarity bit
/// set so that every frame starts on the same level.
pub fn frame_bits(timecode: Timecode, rate: Rate, user_bits: u32) -> u128 {
    let mut bits = SYNC << 64;
    let mut put = |value: u8, from: usize| bits |= u128::from(value) << from;
    put(timecode.frames % 10, 0);
    put(timecode.frames / 10, 8);
    put(u8::from(rate.is_drop()), 10);
    put(timecode.seconds % 10, 16);
    put(timecode.seconds / 10, 24);
    put(timecode.minutes % 10, 32);
    put(timecode.minutes / 10, 40);
    put(timecode.hours % 10, 48);
    put(timecode.hours / 10, 56);
    for g in 0..8 {
        put(((user_bits >> (4 * g)) & 0xF) as u8, 4 + 8 * g);
    }
    // An even count of zeros: the polarity bit is bit 59 at 25 fps, bit 27 otherwise.
    let polarity = if rate == Rate::Fps25 { 59 } else { 27 };
    if (BITS as u32 - bits.count_ones()) % 2 == 1 {
        bits |= 1 << polarity;
    }
    bits
}

/// Writes LTC as audio samples, frame after frame.
#[derive(Clone, Debug)]
pub struct LtcEncoder {
    /// Samples in half a bit cell.
    half_cell: f64,
    /// Samples in half a bit cell at normal speed.
    normal_half_cell: f64,
    rate: Rate,
    level: f32,
    /// The signal's side now.
    high: bool,
    /// Where the next half cell begins, in samples since the encoder began.
    next_half: f64,
    /// Samples written so far.
    written: u64,
    /// Half cells still to send, newest last: whether each begins with a level change.
    pending: std::collections::VecDeque<bool>,
}

impl LtcEncoder {
    /// An encoder at `sample_rate` for `rate`, its square wave at ±`level`.
    pub fn new(sample_rate: u32, rate: Rate, level: f32) -> Self {
        let half_cell = f64::from(sample_rate) / (rate.fps() * BITS as f64 * 2.0);
        LtcEncoder {
            half_cell,
            normal_half_cell: half_cell,
            rate,
            level,
            high: false,
            next_half: 0.0,
            written: 0,
            pending: std::collections::VecDeque::new(),
        }
    }

    /// Plays the frames that follow at `speed` times the code's rate (1: normal), as a tape
    /// runs a little fast or slow; readers follow a code's speed.
    pub fn set_speed(&mut self, speed: f64) {
        self.half_cell = self.normal_half_cell / speed;
    }

    /// Appends the samples of the frame labelled `timecode` to `out`. A frame is
    /// `sample_rate / fps` samples long, with the fraction carried to the next.
    pub fn frame(&mut self, timecode: Timecode, user_bits: u32, out: &mut Vec<f32>) {
        let bits = frame_bits(timecode, self.rate, user_bits);
        for i in 0..BITS {
            self.pending.push_back(true);
            self.pending.push_back((bits >> i) & 1 == 1);
        }
        let end = self.next_half + self.pending.len() as f64 * self.half_cell;
        // Sample j stands for time j: it is the square wave's mean over j ± ½, so an edge
        // between two samples lands where it belongs, not on a sample.
        while (self.written as f64) + 0.5 <= end {
            let (from, to) = (self.written as f64 - 0.5, self.written as f64 + 0.5);
            let mut sum = 0.0;
            let mut at = from;
            while self.next_half < to && !self.pending.is_empty() {
                let side = if self.high { self.level } else { -self.level };
                sum += side * (self.next_half.max(at) - at) as f32;
                at = self.next_half.max(at);
                if self.pending.pop_front() == Some(true) {
                    self.high = !self.high;
                }
                self.next_half += self.half_cell;
            }
            let side = if self.high { self.level } else { -self.level };
            sum += side * (to - at) as f32;
            out.push(sum);
            self.written += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `count` frames from `first` at `rate`, encoded and decoded at 48 kHz.
    fn round_trip(rate: Rate, first: u64, count: u64, level: f32) -> Vec<LtcFrame> {
        let mut encoder = LtcEncoder::new(48_000, rate, level);
        let mut audio = Vec::new();
        for n in first..first + count {
            encoder.frame(rate.timecode(n), 0x1234_5678, &mut audio);
        }
        let mut decoder = LtcDecoder::new(48_000);
        let mut frames = Vec::new();
        for block in audio.chunks(256) {
            decoder.write(block, &mut frames);
        }
        frames
    }

    #[test]
    fn frames_written_are_read_back_at_every_rate() {
        for rate in Rate::ALL {
            let first = rate.count(Timecode::parse("01:09:59:20").unwrap()).unwrap();
            let frames = round_trip(rate, first, 60, 0.5);
            // The first frame is lost to finding the bit period and the bits' pairing.
            assert!(frames.len() >= 58, "{rate}: {} frames read", frames.len());
            for f in &frames {
                let n = rate.count(f.timecode).unwrap();
                assert!(!f.reverse && f.rate == rate && f.user_bits == 0x1234_5678, "{rate}: {f:?}");
                // A frame ends where the next begins: frame n+1 of the run from `first`.
                let expected_end = (n + 1 - first) as f64 * 48_000.0 / rate.fps();
                assert!(
                    (f.end - expected_end).abs() < 0.5,
                    "{rate}: {} ends at {} not {expected_end}",
                    f.timecode,
                    f.end
                );
            }
        }
    }

    #[test]
    fn inverted_quiet_or_reversed_code_is_read_too() {
        let rate = Rate::Fps25;
        let mut encoder = LtcEncoder::new(48_000, rate, -0.02);
        let mut audio = Vec::new();
        for n in 100..130 {
            encoder.frame(rate.timecode(n), 0, &mut audio);
        }
        let mut frames = Vec::new();
        LtcDecoder::new(48_000).write(&audio, &mut frames);
        assert!(frames.len() >= 28 && frames.iter().all(|f| !f.reverse), "inverted and quiet: {}", frames.len());
        audio.reverse();
        let mut backwards = Vec::new();
        LtcDecoder::new(48_000).write(&audio, &mut backwards);
        assert!(backwards.len() >= 28, "{} frames backwards", backwards.len());
        assert!(backwards.iter().all(|f| f.reverse));
        assert!(
            backwards.windows(2).all(|w| rate.count(w[1].timecode).unwrap() + 1 == rate.count(w[0].timecode).unwrap())
        );
    }

    #[test]
    fn silence_and_noise_read_as_nothing() {
        let mut decoder = LtcDecoder::new(48_000);
        let mut frames = Vec::new();
        let mut x = 1u32;
        let noise: Vec<f32> = (0..96_000)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                (x as f32 / u32::MAX as f32 - 0.5) * 0.6
            })
            .collect();
        decoder.write(&vec![0.0; 48_000], &mut frames);
        decoder.write(&noise, &mut frames);
        assert!(frames.is_empty(), "{frames:?}");
    }

    #[test]
    fn every_frame_has_an_even_count_of_zeros_and_the_sync_word_last() {
        for rate in Rate::ALL {
            for n in (0..rate.frames_per_day()).step_by(9_973) {
                let bits = frame_bits(rate.timecode(n), rate, n as u32);
                assert_eq!((BITS as u32 - bits.count_ones()) % 2, 0);
                assert_eq!(bits >> 64, SYNC);
                assert_eq!(fields(bits), Some((rate.timecode(n), rate.is_drop(), n as u32)));
            }
        }
    }
}
