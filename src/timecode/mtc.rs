//! MTC (MIDI timecode): a timecode label sent in eight quarter-frame messages (`F1 nd`, piece
//! `n` carrying nibble `d`) over two frames while the desk runs, and as one full-frame SysEx
//! (`F0 7F 7F 01 01 hh mm ss ff F7`) when it locates. The hours byte carries the rate in bits
//! 5–6.
//!
//! Eight bytes of arithmetic, so written here (no crate reads MTC apart from a whole MIDI
//! stack).

use super::{Rate, Timecode};

/// What a message says about the desk's position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MtcEvent {
    /// Running: the desk is at `frame` (a count from 00:00:00:00, with a quarter-frame
    /// fraction) as this message arrives.
    Running {
        /// The frame count now.
        frame: f64,
        /// The code's rate.
        rate: Rate,
    },
    /// Located (a full-frame message): the desk stands at `frame`, and may start from there.
    Located {
        /// The frame count.
        frame: u64,
        /// The code's rate.
        rate: Rate,
    },
}

/// The rate an hours byte's bits 5–6 name.
fn rate_of(code: u8) -> Rate {
    [Rate::Fps24, Rate::Fps25, Rate::Fps2997Drop, Rate::Fps30][usize::from(code & 3)]
}

/// The code bits 5–6 of the hours byte carry for `rate`.
fn code_of(rate: Rate) -> u8 {
    match rate {
        Rate::Fps24 => 0,
        Rate::Fps25 => 1,
        Rate::Fps2997Drop => 2,
        Rate::Fps30 => 3,
    }
}

/// Reads MTC messages into positions.
#[derive(Clone, Debug, Default)]
pub struct MtcReader {
    /// The eight pieces of the label being assembled.
    pieces: [u8; 8],
    /// The piece expected next, and how many arrived in order before it.
    expected: u8,
    in_order: u8,
    /// The position the last quarter frame gave, once a whole label was read.
    position: Option<(f64, Rate)>,
}

impl MtcReader {
    /// A reader that has seen nothing.
    pub fn new() -> Self {
        MtcReader::default()
    }

    /// Reads one MIDI message; anything but MTC is `None`.
    pub fn message(&mut self, bytes: &[u8]) -> Option<MtcEvent> {
        match bytes {
            [0xF1, data] => self.quarter_frame(*data >> 4 & 7, *data & 0xF),
            [0xF0, 0x7F, _, 0x01, 0x01, hh, mm, ss, ff, 0xF7] => {
                let rate = rate_of(hh >> 5);
                let label = Timecode { hours: hh & 0x1F, minutes: *mm, seconds: *ss, frames: *ff };
                let frame = rate.count(label).ok()?;
                // A locate breaks the run: the next label is read whole before positions resume.
                *self = MtcReader::default();
                Some(MtcEvent::Located { frame, rate })
            }
            _ => None,
        }
    }

    fn quarter_frame(&mut self, piece: u8, nibble: u8) -> Option<MtcEvent> {
        if piece != self.expected || self.in_order == 0 && piece != 0 {
            // Out of order (a dropped byte, a reversed desk): start again at the next piece 0.
            self.in_order = 0;
            self.position = None;
            if piece != 0 {
                self.expected = 0;
                return None;
            }
        }
        self.pieces[usize::from(piece)] = nibble;
        self.expected = (piece + 1) % 8;
        self.in_order = self.in_order.saturating_add(1);
        if piece == 7 && self.in_order >= 8 {
            let p = self.pieces;
            let rate = rate_of(p[7] >> 1);
            let label = Timecode {
                frames: p[0] | (p[1] & 1) << 4,
                seconds: p[2] | (p[3] & 3) << 4,
                minutes: p[4] | (p[5] & 3) << 4,
                hours: p[6] | (p[7] & 1) << 4,
            };
            // The label is the frame at piece 0, sent a quarter frame apart: piece 7 comes
            // 1.75 frames later.
            let Ok(frame) = rate.count(label) else {
                self.position = None;
                return None;
            };
            self.position = Some((frame as f64 + 1.75, rate));
        } else if let Some((frame, _)) = &mut self.position {
            *frame += 0.25;
        }
        self.position.map(|(frame, rate)| MtcEvent::Running { frame, rate })
    }
}

/// The quarter-frame message number `quarter` of a run at `rate` that starts at frame count 0
/// with quarter 0: frame ⌊quarter / 4⌋ is running as it is sent.
pub fn quarter_frame(quarter: u64, rate: Rate) -> [u8; 2] {
    let piece = (quarter % 8) as u8;
    let label = rate.timecode((quarter - u64::from(piece)) / 4);
    let nibble = match piece {
        0 => label.frames & 0xF,
        1 => label.frames >> 4,
        2 => label.seconds & 0xF,
        3 => label.seconds >> 4,
        4 => label.minutes & 0xF,
        5 => label.minutes >> 4,
        6 => label.hours & 0xF,
        _ => label.hours >> 4 | code_of(rate) << 1,
    };
    [0xF1, piece << 4 | nibble]
}

/// The full-frame message that locates a desk at frame count `frame`.
pub fn full_frame(frame: u64, rate: Rate) -> [u8; 10] {
    let label = rate.timecode(frame);
    [0xF0, 0x7F, 0x7F, 0x01, 0x01, code_of(rate) << 5 | label.hours, label.minutes, label.seconds, label.frames, 0xF7]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_running_desk_is_followed_a_quarter_frame_at_a_time_at_every_rate() {
        for rate in Rate::ALL {
            let start = rate.count(Timecode::parse("00:59:59:00").unwrap()).unwrap() & !1;
            let mut reader = MtcReader::new();
            let mut positions = Vec::new();
            // The desk's quarters, from frame `start` on (sets start on even frames).
            for q in 4 * start..4 * (start + 40) {
                if let Some(MtcEvent::Running { frame, rate: r }) = reader.message(&quarter_frame(q, rate)) {
                    assert_eq!(r, rate);
                    positions.push((q, frame));
                }
            }
            assert_eq!(positions.first().map(|p| p.0), Some(4 * start + 7), "{rate}: locked after one label");
            for (q, frame) in positions {
                assert_eq!(frame, q as f64 / 4.0, "{rate}: quarter {q}");
            }
        }
    }

    #[test]
    fn a_locate_or_a_lost_byte_restarts_the_reading() {
        let rate = Rate::Fps2997Drop;
        let mut reader = MtcReader::new();
        let located = reader.message(&full_frame(17_983, rate));
        assert_eq!(located, Some(MtcEvent::Located { frame: 17_983, rate }));
        let mut read = 0;
        for q in 0..64u64 {
            if q == 21 {
                continue; // a byte the cable lost
            }
            read += usize::from(reader.message(&quarter_frame(q, rate)).is_some());
        }
        // Locked at quarter 7 (…21 lost), again at 31: 14 then 33 positions.
        assert_eq!(read, 14 + 33);
        assert_eq!(reader.message(&[0x90, 60, 100]), None, "a note is not timecode");
        assert_eq!(
            reader.message(&[0xF0, 0x7F, 0x7F, 0x01, 0x01, 0x40 | 1, 1, 0, 0, 0xF7]),
            None,
            "a label drop-frame skips"
        );
    }
}
