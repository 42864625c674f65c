//! Morphing between two sets of values over time (preset recall with a duration): numeric
//! values interpolate, discrete ones (bools, enums, ints' rounding aside) switch at the end.

use super::ParamValue;
use super::track::mix;

/// A morph from the values a recall found to the preset's values.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Morph {
    /// (node, param, from, to).
    pub entries: Vec<(usize, usize, ParamValue, ParamValue)>,
    /// Clock time the morph started, seconds.
    pub start: f64,
    /// Length, seconds (0: instant).
    pub duration: f64,
}

impl Morph {
    /// The values at clock time `now`, and whether the morph is complete.
    pub fn sample(&self, now: f64) -> (Vec<(usize, usize, ParamValue)>, bool) {
        let w = if self.duration <= 0.0 { 1.0 } else { ((now - self.start) / self.duration).clamp(0.0, 1.0) };
        let values = self.entries.iter().map(|&(n, p, from, to)| (n, p, mix(from, to, w as f32))).collect();
        (values, w >= 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_glide_and_discrete_values_switch_at_the_end() {
        let m = Morph {
            entries: vec![
                (0, 0, ParamValue::Float(0.0), ParamValue::Float(10.0)),
                (0, 1, ParamValue::Bool(false), ParamValue::Bool(true)),
            ],
            start: 1.0,
            duration: 2.0,
        };
        let (mid, done) = m.sample(2.0);
        assert!(!done);
        assert_eq!(mid[0].2, ParamValue::Float(5.0));
        assert_eq!(mid[1].2, ParamValue::Bool(false));
        let (end, done) = m.sample(3.5);
        assert!(done);
        assert_eq!((end[0].2, end[1].2), (ParamValue::Float(10.0), ParamValue::Bool(true)));
    }
}
