//! A node's parameters: declarations plus current values, looked up by name.

use super::value::{ParamDecl, ParamValue};

/// The declared parameters of one node: the target each source last set, and the current value
/// techniques read, which glides towards the target when the parameter has a smoothing time.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSet {
    decls: Vec<ParamDecl>,
    targets: Vec<ParamValue>,
    values: Vec<ParamValue>,
}

impl ParamSet {
    /// All parameters at their defaults.
    pub fn new(decls: Vec<ParamDecl>) -> Self {
        let values: Vec<ParamValue> = decls.iter().map(|d| d.default).collect();
        Self { decls, targets: values.clone(), values }
    }

    /// The declarations, in declaration order.
    pub fn decls(&self) -> &[ParamDecl] {
        &self.decls
    }

    /// Index of a parameter by name.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.decls.iter().position(|d| d.name == name)
    }

    /// The current (smoothed) value of parameter `i`.
    pub fn value_at(&self, i: usize) -> ParamValue {
        self.values[i]
    }

    /// The value parameter `i` is heading to (what the last source set).
    pub fn target_at(&self, i: usize) -> ParamValue {
        self.targets[i]
    }

    /// Every parameter's target and smoothed value, in declaration order (for checkpoints).
    pub fn parts(&self) -> (&[ParamValue], &[ParamValue]) {
        (&self.targets, &self.values)
    }

    /// Puts back targets and smoothed values from [`ParamSet::parts`]; refused (false, nothing
    /// changed) unless there is one of each per parameter, of its type and finite.
    pub fn set_parts(&mut self, targets: &[ParamValue], values: &[ParamValue]) -> bool {
        let n = self.decls.len();
        let fits = |v: &[ParamValue]| {
            v.len() == n
                && v.iter()
                    .zip(&self.decls)
                    .all(|(v, d)| v.ty() == d.ty() && v.components().iter().all(|c| c.is_finite()))
        };
        if !fits(targets) || !fits(values) {
            return false;
        }
        self.targets = targets.to_vec();
        self.values = values.to_vec();
        true
    }

    /// Sets parameter `i`'s target, converting to its type and clamping to its range. Without
    /// smoothing (or for discrete types) the value follows at once. A value with a NaN or
    /// infinite component is refused (the parameter keeps its value; returns false): every
    /// source — OSC, MIDI, `--set`, presets, replays, tracks — writes through here.
    pub fn set_at(&mut self, i: usize, value: ParamValue) -> bool {
        if value.components().iter().any(|c| !c.is_finite()) {
            return false;
        }
        let decl = &self.decls[i];
        let typed =
            if value.ty() == decl.ty() { value } else { ParamValue::from_components(decl.ty(), &value.components()) };
        self.targets[i] = typed.clamped(decl.range);
        if decl.smoothing <= 0.0 || !decl.is_smoothable() {
            self.values[i] = self.targets[i];
        }
        true
    }

    /// Sets one float component of parameter `i`'s target (tracks on `t.x`, OSC on `/t/x`);
    /// false if refused (not finite).
    pub fn set_component(&mut self, i: usize, component: usize, x: f32) -> bool {
        let mut c = self.targets[i].components();
        if let Some(slot) = c.get_mut(component) {
            *slot = x;
        }
        self.set_at(i, ParamValue::from_components(self.decls[i].ty(), &c))
    }

    /// Moves smoothed values towards their targets over `dt` seconds: an exponential approach
    /// with each parameter's time constant, so the glide is the same at any frame rate.
    pub fn advance(&mut self, dt: f32) {
        for (i, decl) in self.decls.iter().enumerate() {
            if decl.smoothing <= 0.0 || !decl.is_smoothable() {
                self.values[i] = self.targets[i];
                continue;
            }
            let k = 1.0 - (-dt / decl.smoothing).exp();
            self.values[i] = super::track::mix(self.values[i], self.targets[i], k);
        }
    }

    /// Jumps every value to its target (after loading, or recalling a preset instantly).
    pub fn snap(&mut self) {
        self.values.clone_from(&self.targets);
    }

    /// Jumps parameter `i` to its target (a value loaded from a file: no glide).
    pub fn snap_at(&mut self, i: usize) {
        self.values[i] = self.targets[i];
    }

    /// Clears triggers that fired: called after the fixed step that saw them, so a trigger fires
    /// for exactly one step whatever the number of steps a displayed frame runs.
    pub fn end_step(&mut self) {
        for (t, v) in self.targets.iter_mut().zip(self.values.iter_mut()) {
            if matches!(t, ParamValue::Trigger(true)) {
                *t = ParamValue::Trigger(false);
                *v = ParamValue::Trigger(false);
            }
        }
    }

    /// The value of `name`.
    ///
    /// # Panics
    /// If the technique asks for a parameter it never declared: a programming error that every
    /// render test of that technique would show.
    pub fn get(&self, name: &str) -> ParamValue {
        let i = self.index(name).unwrap_or_else(|| panic!("parameter '{name}' is not declared"));
        self.values[i]
    }

    /// A float parameter (ints convert).
    pub fn float(&self, name: &str) -> f32 {
        self.get(name).components()[0]
    }

    /// An int parameter.
    pub fn int(&self, name: &str) -> i32 {
        match self.get(name) {
            ParamValue::Int(i) => i,
            other => other.components()[0].round() as i32,
        }
    }

    /// An enum parameter's option index.
    pub fn choice(&self, name: &str) -> u32 {
        match self.get(name) {
            ParamValue::Enum(i) => i,
            other => other.components()[0].max(0.0) as u32,
        }
    }

    /// Whether a trigger parameter fired this frame.
    pub fn fired(&self, name: &str) -> bool {
        matches!(self.get(name), ParamValue::Trigger(true))
    }

    /// A bool parameter.
    pub fn bool(&self, name: &str) -> bool {
        self.get(name).components()[0] >= 0.5
    }

    /// A 2-component parameter.
    pub fn vec2(&self, name: &str) -> [f32; 2] {
        let c = self.get(name).components();
        [c[0], c.get(1).copied().unwrap_or(0.0)]
    }

    /// A colour (or any 4-component) parameter.
    pub fn color(&self, name: &str) -> [f32; 4] {
        let c = self.get(name).components();
        std::array::from_fn(|i| c.get(i).copied().unwrap_or(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(smoothing: f32) -> ParamSet {
        ParamSet::new(vec![
            ParamDecl::new("x", ParamValue::Float(0.0), Some((0.0, 10.0)), "").with_smoothing(smoothing),
            ParamDecl::new("n", ParamValue::Int(0), Some((0.0, 10.0)), "").with_smoothing(smoothing),
            ParamDecl::trigger("go", ""),
        ])
    }

    #[test]
    fn smoothing_is_frame_rate_independent() {
        let (mut at_30, mut at_240) = (set(0.1), set(0.1));
        at_30.set_at(0, ParamValue::Float(10.0));
        at_240.set_at(0, ParamValue::Float(10.0));
        for _ in 0..3 {
            at_30.advance(1.0 / 30.0);
        }
        for _ in 0..24 {
            at_240.advance(1.0 / 240.0);
        }
        let (a, b) = (at_30.float("x"), at_240.float("x"));
        // After 0.1 s (one time constant) both are at 1 − 1/e of the way.
        assert!((a - b).abs() < 1e-4 && (a - 6.3212).abs() < 1e-3, "{a} {b}");
        assert_eq!(at_30.target_at(0), ParamValue::Float(10.0));
    }

    #[test]
    fn discrete_values_and_unsmoothed_params_jump() {
        let mut p = set(0.5);
        p.set_at(1, ParamValue::Int(7));
        assert_eq!(p.int("n"), 7, "ints are never smoothed");
        let mut q = set(0.0);
        q.set_at(0, ParamValue::Float(4.0));
        assert_eq!(q.float("x"), 4.0);
    }

    #[test]
    fn nan_and_infinity_never_get_in() {
        let mut p = set(0.0);
        p.set_at(0, ParamValue::Float(4.0));
        assert!(!p.set_at(0, ParamValue::Float(f32::NAN)));
        assert!(!p.set_at(0, ParamValue::Float(f32::INFINITY)));
        p.set_component(0, 0, f32::NEG_INFINITY);
        assert_eq!(p.float("x"), 4.0, "the last finite value stays");
    }

    #[test]
    fn a_trigger_fires_for_one_step() {
        let mut p = set(0.0);
        p.set_at(2, ParamValue::Trigger(true));
        assert!(p.fired("go"));
        p.end_step();
        assert!(!p.fired("go"));
    }
}
