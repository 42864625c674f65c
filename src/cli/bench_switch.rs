//! Where the costliest switch frame of `indra bench --cue-every` spent its GPU time: its passes
//! against the same passes in the frame after it, the passes that grew most first. A bench waits
//! for every frame, so each frame's timestamps are read as the next one starts.

/// Passes told for the costliest switch.
const LINES: usize = 8;

/// A frame's passes and their GPU milliseconds.
type Passes = Vec<(String, f64)>;

/// The costliest switch seen so far, and the one being read.
#[derive(Default)]
pub struct SwitchPasses {
    /// (loop index of the switch, its wall ms, its passes once read).
    reading: Option<(u64, f64, Option<Passes>)>,
    /// (wall ms, the switch frame's passes, the next frame's).
    worst: Option<(f64, Passes, Passes)>,
}

impl SwitchPasses {
    /// After loop index `i` rendered and was waited for (frame `i − 1`'s passes were read as
    /// `latest` when it started): `switch` is frame `i`'s wall ms when it was a switch.
    pub fn push(&mut self, i: u64, latest: Passes, switch: Option<f64>) {
        if let Some((at, wall, read)) = &mut self.reading {
            if i == *at + 1 {
                *read = Some(latest);
            } else if i == *at + 2
                && let Some(passes) = read.take()
            {
                if self.worst.as_ref().is_none_or(|w| *wall > w.0) {
                    self.worst = Some((*wall, passes, latest));
                }
                self.reading = None;
            }
        }
        if let Some(wall) = switch {
            self.reading = Some((i, wall, None));
        }
    }

    /// Lines on the costliest switch's passes (none without timestamps or switches).
    pub fn report(&self) -> Vec<String> {
        let Some((wall, switch, after)) = &self.worst else { return Vec::new() };
        let in_after = |name: &str| after.iter().filter(|(n, _)| n == name).map(|(_, ms)| ms).sum::<f64>();
        let mut grown: Vec<(&str, f64, f64)> =
            switch.iter().map(|(name, ms)| (name.as_str(), *ms, in_after(name))).collect();
        grown.sort_by(|a, b| (b.1 - b.2).total_cmp(&(a.1 - a.2)));
        let sum = |passes: &Passes| passes.iter().map(|(_, ms)| ms).sum::<f64>();
        let mut lines = vec![format!(
            "costliest switch ({wall:.3} ms wall): passes {:.3} ms GPU, the frame after {:.3} ms; grown most:",
            sum(switch),
            sum(after)
        )];
        for (name, ms, before) in grown.into_iter().take(LINES) {
            lines.push(format!("  {name:<32} {ms:>9.3} ms  (after: {before:.3} ms)"));
        }
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::SwitchPasses;

    #[test]
    fn the_costliest_switch_is_told_against_the_frame_after_it() {
        let frame = |a: f64, b: f64| vec![("a".to_string(), a), ("b".to_string(), b)];
        let mut passes = SwitchPasses::default();
        // Switches at loop indices 2 (5 ms) and 6 (9 ms); index i reads frame i − 1.
        for i in 0..10u64 {
            let latest = match i {
                3 => frame(1.0, 3.0),
                7 => frame(4.0, 1.0),
                _ => frame(1.0, 1.0),
            };
            let switch = match i {
                2 => Some(5.0),
                6 => Some(9.0),
                _ => None,
            };
            passes.push(i, latest, switch);
        }
        let lines = passes.report();
        assert!(lines[0].contains("9.000 ms wall") && lines[0].contains("passes 5.000 ms"), "{lines:?}");
        assert!(lines[1].trim_start().starts_with('a') && lines[1].contains("4.000 ms"), "{lines:?}");
    }
}
