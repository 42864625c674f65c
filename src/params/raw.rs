//! Values as files write them (scenes, presets, recordings, learn files), before a declaration
//! gives them a type, and the conversions both ways.

use serde::Deserialize;

use super::{ParamDecl, ParamType, ParamValue};

/// A value as written in a file, before the declared type gives it meaning.
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(untagged)]
pub enum RawValue {
    /// `true` / `false`.
    Bool(bool),
    /// `1.9` or `50`.
    Number(f64),
    /// `(1.0, 0.5)` or `[1.0, 0.5]`.
    List(Vec<f64>),
    /// `"Additive"`: an enum option by name.
    Text(String),
}

impl RawValue {
    /// The numbers it holds (bools as 0/1).
    pub fn numbers(&self) -> Vec<f64> {
        match self {
            RawValue::Bool(b) => vec![if *b { 1.0 } else { 0.0 }],
            RawValue::Number(x) => vec![*x],
            RawValue::List(v) => v.clone(),
            RawValue::Text(_) => Vec::new(),
        }
    }
}

/// A value as a file, preset or recording writes it for `decl` (enums by option name).
pub fn raw_from_value(value: &ParamValue, decl: &ParamDecl) -> RawValue {
    match value {
        ParamValue::Bool(b) | ParamValue::Trigger(b) => RawValue::Bool(*b),
        ParamValue::Enum(i) => RawValue::Text(decl.options.get(*i as usize).cloned().unwrap_or_default()),
        ParamValue::Text(t) => RawValue::Text(t.as_str().to_string()),
        ParamValue::Float(x) => RawValue::Number(f64::from(*x)),
        ParamValue::Int(i) => RawValue::Number(f64::from(*i)),
        other => RawValue::List(other.components().iter().map(|&c| f64::from(c)).collect()),
    }
}

/// A file, preset or recording value as a value of `decl`'s type, if it fits.
pub fn value_from_raw(raw: &RawValue, decl: &ParamDecl) -> Option<ParamValue> {
    coerce(raw, decl.ty(), &decl.options)
}

/// A file value as a typed value: bools only for bool parameters, option names (or indices)
/// for enums, numbers for the rest.
pub fn coerce(raw: &RawValue, ty: ParamType, options: &[String]) -> Option<ParamValue> {
    match (raw, ty) {
        (RawValue::Bool(b), ParamType::Bool) => Some(ParamValue::Bool(*b)),
        (RawValue::Bool(b), ParamType::Trigger) => Some(ParamValue::Trigger(*b)),
        (RawValue::Text(name), ParamType::Enum) => {
            options.iter().position(|o| o.eq_ignore_ascii_case(name)).map(|i| ParamValue::Enum(i as u32))
        }
        (RawValue::Number(i), ParamType::Enum) if (*i as usize) < options.len() => ty.value_from(&[*i]),
        (RawValue::Text(text), ParamType::Text) => Some(ParamValue::Text(super::Text::new(text))),
        (RawValue::Bool(_) | RawValue::Text(_), _)
        | (_, ParamType::Bool | ParamType::Enum | ParamType::Trigger | ParamType::Text) => None,
        (raw, ty) => ty.value_from(&raw.numbers()),
    }
}
