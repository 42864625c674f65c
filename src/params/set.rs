//! A node's parameters: declarations plus current values, looked up by name.

use super::value::{ParamDecl, ParamValue};

/// The declared parameters of one node and their current values.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSet {
    decls: Vec<ParamDecl>,
    values: Vec<ParamValue>,
}

impl ParamSet {
    /// All parameters at their defaults.
    pub fn new(decls: Vec<ParamDecl>) -> Self {
        let values = decls.iter().map(|d| d.default).collect();
        Self { decls, values }
    }

    /// The declarations, in declaration order.
    pub fn decls(&self) -> &[ParamDecl] {
        &self.decls
    }

    /// Index of a parameter by name.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.decls.iter().position(|d| d.name == name)
    }

    /// The current value of parameter `i`.
    pub fn value_at(&self, i: usize) -> ParamValue {
        self.values[i]
    }

    /// Sets parameter `i`, converting to its type and clamping to its range.
    pub fn set_at(&mut self, i: usize, value: ParamValue) {
        let decl = &self.decls[i];
        let typed =
            if value.ty() == decl.ty() { value } else { ParamValue::from_components(decl.ty(), &value.components()) };
        self.values[i] = typed.clamped(decl.range);
    }

    /// Sets one float component of parameter `i` (for tracks on `t.x` and the like).
    pub fn set_component(&mut self, i: usize, component: usize, x: f32) {
        let mut c = self.values[i].components();
        if let Some(slot) = c.get_mut(component) {
            *slot = x;
        }
        self.set_at(i, ParamValue::from_components(self.decls[i].ty(), &c));
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
