//! What `indra bench` keeps of the frames it measures: rolling medians of the last [`WINDOW`]
//! frames' wall and CPU times, and each cue switch against the frames that follow it. All of it
//! is bounded, so a bench that plays a show for hours (`tools/soak`) measures the show's memory,
//! not its own: keeping every frame's times grew by 16 bytes a frame, 50 MB in 20 minutes of a
//! show at over 1,000 frames a second.

use indra::graph::RollingMedian;

/// The frames the medians are taken over: the last 65,536 (every frame of a usual bench).
pub const WINDOW: usize = 1 << 16;

/// The switches told one by one; the rest count in the summary.
const MAX_SWITCH_LINES: usize = 64;

/// A measured frame at which `bench --cue-every` triggered a cue, and the frames after it.
struct Switch {
    /// The show's frame.
    frame: u64,
    /// Its wall time, milliseconds.
    ms: f64,
    /// Milliseconds spent stepping and recording it (the rest of its wall time is the GPU's).
    cpu: f64,
    /// The wall times of the frames after it, until the next switch.
    after: Vec<f64>,
}

/// The measured frames, bounded (see the module's comment).
pub struct FrameRecord {
    walls: RollingMedian,
    cpu: RollingMedian,
    /// Frames from one switch to the next (at most [`WINDOW`]: the frames after a switch are
    /// kept only that far).
    every: usize,
    open: Option<Switch>,
    lines: Vec<String>,
    switches: usize,
    /// The worst switch frame's milliseconds, and the worst ratio to the frames after it.
    worst: (f64, f64),
    /// What a switch is called in the report (a cue's `switch`, an effect `edit`), and its plural.
    noun: (&'static str, &'static str),
}

impl FrameRecord {
    /// A record for switches every `every` frames (any number when there are none).
    pub fn new(every: u64) -> Self {
        Self {
            walls: RollingMedian::new(WINDOW),
            cpu: RollingMedian::new(WINDOW),
            every: usize::try_from(every).unwrap_or(WINDOW).clamp(1, WINDOW),
            open: None,
            lines: Vec::new(),
            switches: 0,
            worst: (0.0, 0.0),
            noun: ("switch", "switches"),
        }
    }

    /// The same record, its switches called `singular` (`plural`) in the report.
    #[must_use]
    pub fn calling_them(mut self, singular: &'static str, plural: &'static str) -> Self {
        self.noun = (singular, plural);
        self
    }

    /// Adds a frame's wall and CPU milliseconds; `switch` is the show's frame where a cue was
    /// triggered in it.
    pub fn push(&mut self, wall: f64, cpu: f64, switch: Option<u64>) {
        self.walls.push(wall);
        self.cpu.push(cpu);
        if let Some(frame) = switch {
            self.close();
            let after = Vec::with_capacity(self.every - 1);
            self.open = Some(Switch { frame, ms: wall, cpu, after });
        } else if let Some(open) = &mut self.open {
            open.after.push(wall);
            if open.after.len() + 1 >= self.every {
                self.close();
            }
        }
    }

    /// The median wall time of the window, milliseconds.
    pub fn wall_median(&self) -> f64 {
        self.walls.median().unwrap_or(0.0)
    }

    /// The median CPU time of the window, milliseconds.
    pub fn cpu_median(&self) -> f64 {
        self.cpu.median().unwrap_or(0.0)
    }

    /// Each switch frame against the median of the frames that follow it until the next switch
    /// (the same clips on screen, so a costly clip does not count as a costly switch), and the
    /// worst switch against the median of the window; nothing without switches.
    pub fn switch_report(mut self) -> Vec<String> {
        self.close();
        if self.switches == 0 {
            return Vec::new();
        }
        let median = self.wall_median();
        let mut lines = std::mem::take(&mut self.lines);
        if self.switches > MAX_SWITCH_LINES {
            lines.push(format!("{:<10} … and {} more", self.noun.0, self.switches - MAX_SWITCH_LINES));
        }
        let (ms, ratio) = self.worst;
        lines.push(format!(
            "{:<28} {:>9.3} ms  ({:.2}× the median frame)",
            format!("worst frame at {} {}", if self.noun.0.starts_with('e') { "an" } else { "a" }, self.noun.0),
            ms,
            ms / median.max(1e-9)
        ));
        let (one, many) = self.noun;
        lines.push(format!(
            "{:<28} {:>9.2}×  ({} {many})",
            format!("worst {one} / frames after"),
            ratio,
            self.switches
        ));
        lines
    }

    /// Tells the open switch, if any.
    fn close(&mut self) {
        let Some(Switch { frame, ms, cpu, mut after }) = self.open.take() else { return };
        after.sort_by(f64::total_cmp);
        let steady = after.get(after.len() / 2).copied().unwrap_or(ms);
        let ratio = ms / steady.max(1e-9);
        if self.lines.len() < MAX_SWITCH_LINES {
            self.lines.push(format!(
                "{:<10} frame {frame}: {ms:.3} ms ({cpu:.3} ms on the CPU), then {steady:.3} ms: {ratio:.2}×",
                self.noun.0
            ));
        }
        self.switches += 1;
        self.worst = (self.worst.0.max(ms), self.worst.1.max(ratio));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_switch_is_judged_against_the_frames_after_it() {
        let mut record = FrameRecord::new(4);
        for (i, wall) in [1.0, 1.0, 1.0, 1.0, 9.0, 2.0, 2.0, 2.0, 4.0, 1.0].into_iter().enumerate() {
            let switch = (i > 0 && i % 4 == 0).then_some(i as u64);
            record.push(wall, 0.5, switch);
        }
        let lines = record.switch_report();
        assert!(lines[0].contains("frame 4: 9.000 ms") && lines[0].ends_with("then 2.000 ms: 4.50×"), "{lines:?}");
        assert!(lines[1].contains("frame 8: 4.000 ms") && lines[1].ends_with("then 1.000 ms: 4.00×"), "{lines:?}");
        assert!(lines[3].contains("4.50×") && lines[3].contains("(2 switches)"), "{lines:?}");
    }

    #[test]
    fn the_record_stays_bounded_however_long_the_bench() {
        let mut record = FrameRecord::new(3);
        for i in 0..(3 * WINDOW as u64) {
            record.push((i % 7) as f64, 1.0, (i > 0 && i % 3 == 0).then_some(i));
        }
        assert_eq!(record.walls.len(), WINDOW);
        assert_eq!(record.lines.len(), MAX_SWITCH_LINES);
        let lines = record.switch_report();
        assert!(lines.iter().any(|l| l.contains("… and")), "{:?}", &lines[MAX_SWITCH_LINES..]);
    }
}
