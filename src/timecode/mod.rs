//! SMPTE timecode, as a sound desk sends it: hours, minutes, seconds and frames at 24, 25,
//! 29.97 drop-frame or 30 frames a second, and the frame count it stands for. Read from audio
//! as LTC ([`ltc`]) and from MIDI as MTC ([`mtc`]), and written both ways.
//!
//! Pure arithmetic on integers, below every other layer: a timeline chasing a desk turns the
//! frame count into its own position, and seeks when the count jumps.

pub mod chase;
pub mod ltc;
pub mod ltc_follow;
pub mod mtc;

use serde::{Deserialize, Serialize};

/// A timecode rate, as LTC and MTC carry them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Rate {
    /// 24 frames a second (film).
    #[serde(rename = "24")]
    Fps24,
    /// 25 frames a second (PAL video).
    #[serde(rename = "25")]
    Fps25,
    /// 30000/1001 frames a second with frame labels dropped so that the label keeps to the
    /// clock (NTSC video): frames 00 and 01 are skipped at the start of every minute but each
    /// tenth.
    #[serde(rename = "29.97df")]
    Fps2997Drop,
    /// 30 frames a second.
    #[serde(rename = "30")]
    Fps30,
}

/// Labelled frames in ten minutes of drop-frame timecode: 10 × 60 × 30 less 9 × 2.
const DROP_TEN_MINUTES: u64 = 17_982;
/// Labelled frames in a minute of drop-frame timecode that drops its first two labels.
const DROP_MINUTE: u64 = 1_798;

impl Rate {
    /// Every rate, slowest first.
    pub const ALL: [Rate; 4] = [Rate::Fps24, Rate::Fps25, Rate::Fps2997Drop, Rate::Fps30];

    /// Frame labels a second counts (30 for drop-frame, whose labels run 00–29).
    pub fn nominal(self) -> u32 {
        match self {
            Rate::Fps24 => 24,
            Rate::Fps25 => 25,
            Rate::Fps2997Drop | Rate::Fps30 => 30,
        }
    }

    /// Frames a second of real time.
    pub fn fps(self) -> f64 {
        match self {
            Rate::Fps2997Drop => 30_000.0 / 1_001.0,
            other => f64::from(other.nominal()),
        }
    }

    /// Whether labels are dropped.
    pub fn is_drop(self) -> bool {
        self == Rate::Fps2997Drop
    }

    /// Frames in 24 hours of timecode, after which it wraps to 00:00:00:00.
    pub fn frames_per_day(self) -> u64 {
        match self {
            Rate::Fps2997Drop => 24 * 6 * DROP_TEN_MINUTES,
            other => 24 * 3600 * u64::from(other.nominal()),
        }
    }

    /// The label of frame `count` (counted from 00:00:00:00), wrapping at 24 hours.
    pub fn timecode(self, count: u64) -> Timecode {
        let mut n = count % self.frames_per_day();
        if self.is_drop() {
            // Add back the labels skipped before this frame: 18 per ten minutes, 2 per minute
            // after the first of the ten.
            let (tens, rest) = (n / DROP_TEN_MINUTES, n % DROP_TEN_MINUTES);
            n += 18 * tens + if rest < 2 { 0 } else { 2 * ((rest - 2) / DROP_MINUTE) };
        }
        let fps = u64::from(self.nominal());
        Timecode {
            hours: (n / (3600 * fps)) as u8,
            minutes: (n / (60 * fps) % 60) as u8,
            seconds: (n / fps % 60) as u8,
            frames: (n % fps) as u8,
        }
    }

    /// The frame count `timecode` labels, or why no frame has that label at this rate.
    pub fn count(self, timecode: Timecode) -> Result<u64, String> {
        let Timecode { hours, minutes, seconds, frames } = timecode;
        if hours > 23 || minutes > 59 || seconds > 59 || u32::from(frames) >= self.nominal() {
            return Err(format!("{timecode} is not a time of day at {self}"));
        }
        if self.is_drop() && seconds == 0 && frames < 2 && !minutes.is_multiple_of(10) {
            return Err(format!("{timecode} is a label drop-frame timecode skips"));
        }
        let fps = u64::from(self.nominal());
        let labels = (u64::from(hours) * 3600 + u64::from(minutes) * 60 + u64::from(seconds)) * fps + u64::from(frames);
        if !self.is_drop() {
            return Ok(labels);
        }
        let minutes_total = u64::from(hours) * 60 + u64::from(minutes);
        Ok(labels - 2 * (minutes_total - minutes_total / 10))
    }

    /// The rate `nominal` labels a second stand for (`drop`: with labels dropped), if any.
    pub fn from_nominal(nominal: u32, drop: bool) -> Option<Rate> {
        match (nominal, drop) {
            (24, false) => Some(Rate::Fps24),
            (25, false) => Some(Rate::Fps25),
            (30, true) => Some(Rate::Fps2997Drop),
            (30, false) => Some(Rate::Fps30),
            _ => None,
        }
    }
}

impl std::str::FromStr for Rate {
    type Err = String;

    /// Reads a rate as a show file writes it: `24`, `25`, `29.97df` (or `29.97`) or `30`.
    fn from_str(text: &str) -> Result<Rate, String> {
        match text.trim() {
            "24" => Ok(Rate::Fps24),
            "25" => Ok(Rate::Fps25),
            "29.97df" | "29.97" => Ok(Rate::Fps2997Drop),
            "30" => Ok(Rate::Fps30),
            other => Err(format!("'{other}' is not a timecode rate (24, 25, 29.97df or 30)")),
        }
    }
}

impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Rate::Fps24 => "24 fps",
            Rate::Fps25 => "25 fps",
            Rate::Fps2997Drop => "29.97 fps drop-frame",
            Rate::Fps30 => "30 fps",
        })
    }
}

/// A timecode label: hours, minutes, seconds and frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Timecode {
    /// 0–23.
    pub hours: u8,
    /// 0–59.
    pub minutes: u8,
    /// 0–59.
    pub seconds: u8,
    /// 0 up to the rate's frames a second, less one.
    pub frames: u8,
}

impl Timecode {
    /// Reads `HH:MM:SS:FF` (`;` or `.` before the frames, as drop-frame is often written).
    pub fn parse(text: &str) -> Result<Timecode, String> {
        let bad = || format!("'{text}' is not a timecode (HH:MM:SS:FF)");
        let parts: Vec<&str> = text.trim().split([':', ';', '.']).collect();
        let [h, m, s, f] = parts.as_slice() else { return Err(bad()) };
        let field = |p: &str| if p.len() == 2 { p.parse::<u8>().map_err(|_| bad()) } else { Err(bad()) };
        Ok(Timecode { hours: field(h)?, minutes: field(m)?, seconds: field(s)?, frames: field(f)? })
    }
}

impl std::fmt::Display for Timecode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:02}:{:02}:{:02}:{:02}", self.hours, self.minutes, self.seconds, self.frames)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tc(text: &str) -> Timecode {
        Timecode::parse(text).unwrap()
    }

    #[test]
    fn every_frame_of_a_day_round_trips_through_its_label_at_every_rate() {
        for rate in Rate::ALL {
            let mut previous: Option<Timecode> = None;
            for count in (0..rate.frames_per_day()).step_by(7).chain([rate.frames_per_day() - 1]) {
                let label = rate.timecode(count);
                assert_eq!(rate.count(label), Ok(count), "{rate}: {label}");
                if let Some(p) = previous {
                    assert!(p < label, "{rate}: labels run in order ({p} then {label})");
                }
                previous = Some(label);
            }
            assert_eq!(rate.timecode(rate.frames_per_day()), Timecode::default(), "{rate} wraps at 24 h");
        }
    }

    #[test]
    fn drop_frame_skips_two_labels_a_minute_but_each_tenth() {
        let r = Rate::Fps2997Drop;
        assert_eq!(r.timecode(1799), tc("00:00:59:29"));
        assert_eq!(r.timecode(1800), tc("00:01:00:02"), "00 and 01 are skipped");
        assert_eq!(r.timecode(17_982), tc("00:10:00:00"), "not at the tenth minute");
        assert_eq!(r.timecode(17_981), tc("00:09:59:29"));
        assert!(r.count(tc("00:01:00:00")).is_err());
        assert!(r.count(tc("00:01:00:01")).is_err());
        assert_eq!(r.count(tc("00:10:00:01")), Ok(17_983));
        // An hour of drop-frame labels is 3600 s × 29.97 less the rounding: 107,892 frames,
        // 3.6 ms short of an hour of real time.
        assert_eq!(r.count(tc("01:00:00:00")), Ok(107_892));
        assert!((107_892.0 / r.fps() - 3600.0).abs() < 0.004);
    }

    #[test]
    fn labels_out_of_range_and_bad_text_are_refused_in_a_sentence() {
        assert!(Rate::Fps25.count(tc("00:00:00:25")).unwrap_err().contains("25 fps"));
        assert!(Rate::Fps24.count(tc("24:00:00:00")).is_err());
        for bad in ["1:00:00:00", "00:00:00", "aa:00:00:00", "00:00:00:00:00"] {
            assert!(Timecode::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(tc("01:12:03;15"), Timecode { hours: 1, minutes: 12, seconds: 3, frames: 15 });
        assert_eq!(tc("01:12:03;15").to_string(), "01:12:03:15");
    }
}
