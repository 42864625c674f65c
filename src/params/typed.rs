//! Typed parameter structs. A technique lists its parameters once, in a [`technique_params!`]
//! block: each field's doc comment, name, Rust type and declaration (default, range, unit, role)
//! sit together, and the block makes both the struct the technique reads — by position, once per
//! step, options as Rust enums ([`param_enum!`]) — and the [`ParamDecl`]s the panel, OSC,
//! OSCQuery, MIDI and presets are generated from. A misspelt or reordered parameter no longer
//! compiles into a run-time panic.
//!
//! Declarations made at run time (an imported shader's inputs) stay plain `Vec<ParamDecl>` read
//! by position through [`FromValue`]: one value model, typed where the list is known at build time.

use super::{ParamSet, ParamValue, Text};

/// A Rust type a parameter value converts to.
pub trait FromValue: Sized {
    /// `value` as this type (every value the declared type allows converts).
    fn from_value(value: ParamValue) -> Self;
}

impl FromValue for f32 {
    fn from_value(value: ParamValue) -> Self {
        value.components().first().copied().unwrap_or(0.0)
    }
}

impl FromValue for i32 {
    fn from_value(value: ParamValue) -> Self {
        match value {
            ParamValue::Int(i) => i,
            other => f32::from_value(other).round() as i32,
        }
    }
}

impl FromValue for bool {
    /// A bool, or whether a trigger fired this step.
    fn from_value(value: ParamValue) -> Self {
        match value {
            ParamValue::Bool(b) | ParamValue::Trigger(b) => b,
            other => f32::from_value(other) != 0.0,
        }
    }
}

impl<const N: usize> FromValue for [f32; N] {
    fn from_value(value: ParamValue) -> Self {
        let components = value.components();
        std::array::from_fn(|i| components.get(i).copied().unwrap_or(0.0))
    }
}

impl FromValue for Text {
    fn from_value(value: ParamValue) -> Self {
        match value {
            ParamValue::Text(t) => t,
            _ => Text::new(""),
        }
    }
}

/// An enum parameter's options as a Rust enum (made by [`param_enum!`]).
pub trait ParamEnum: Copy {
    /// The option names, in index order (what files, OSC and the panel use).
    const OPTIONS: &'static [&'static str];
    /// The option at `index` (the last one past the end: ranges already clamp).
    fn from_index(index: u32) -> Self;
    /// This option's index.
    fn index(self) -> u32;
}

/// The option index an enum parameter's value holds.
pub fn option_index(value: ParamValue) -> u32 {
    match value {
        ParamValue::Enum(i) => i,
        other => f32::from_value(other).max(0.0) as u32,
    }
}

/// A declaration's doc text from a field's doc comment lines (trimmed, joined by spaces).
pub fn doc_text(lines: &[&str]) -> String {
    lines.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ")
}

/// Reads field `index` of a typed parameter struct from `set`.
pub fn field<T: FromValue>(set: &ParamSet, index: usize) -> T {
    T::from_value(set.value_at(index))
}

/// Declares an enum parameter's options as a Rust enum:
/// `param_enum! { /// doc  pub enum Layout { /// doc  Grid = "grid", /// doc  Ring = "ring" } }`.
/// Its [`ParamEnum::OPTIONS`] feed `ParamDecl::choice`.
#[macro_export]
macro_rules! param_enum {
    ($(#[$meta:meta])* $vis:vis enum $name:ident { $($(#[$vmeta:meta])* $variant:ident = $label:literal),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        $vis enum $name {
            $($(#[$vmeta])* $variant),+
        }

        #[allow(dead_code)]
        impl $name {
            /// The option names, in index order.
            $vis const OPTIONS: &'static [&'static str] = &[$($label),+];

            /// This option's index (what the shader or a file takes).
            $vis fn index(self) -> u32 {
                self as u32
            }
        }

        impl $crate::params::ParamEnum for $name {
            const OPTIONS: &'static [&'static str] = $name::OPTIONS;

            fn from_index(index: u32) -> Self {
                const ALL: &[$name] = &[$($name::$variant),+];
                ALL[(index as usize).min(ALL.len() - 1)]
            }

            fn index(self) -> u32 {
                $name::index(self)
            }
        }

        impl $crate::params::FromValue for $name {
            fn from_value(value: $crate::params::ParamValue) -> Self {
                <$name as $crate::params::ParamEnum>::from_index($crate::params::option_index(value))
            }
        }
    };
}

/// Declares a technique's parameters once: a struct of their values and its declarations.
///
/// ```ignore
/// technique_params! {
///     /// What a limit-set node reads each step.
///     pub struct Settings {
///         /// escape-time iteration cap per sample
///         iterations: i32 = |name, doc| ParamDecl::new(name, Int(500), Some((1.0, 5000.0)), doc),
///     }
/// }
/// ```
///
/// Each field's doc comment is the parameter's description (panel tooltip, OSCQuery); its name
/// is the parameter's name; the closure builds the declaration from both. The struct gets
/// `decls()` (the declarations, in field order: a technique's `params`) and `read(&ParamSet)`
/// (the values, by position).
#[macro_export]
macro_rules! technique_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $($(#[doc = $doc:literal])+ $field:ident : $ty:ty = $decl:expr),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        $vis struct $name {
            $($(#[doc = $doc])+ pub $field: $ty),+
        }

        impl $name {
            /// The declarations, in field order.
            pub fn decls() -> Vec<$crate::params::ParamDecl> {
                vec![$({
                    let doc = $crate::params::doc_text(&[$($doc),+]);
                    let declare: fn(&str, &str) -> $crate::params::ParamDecl = $decl;
                    declare(stringify!($field), &doc)
                }),+]
            }

            /// The values of a set made from [`Self::decls`], read by position (a technique whose
            /// file declares more parameters has those after these).
            pub fn read(set: &$crate::params::ParamSet) -> Self {
                let mut index = 0usize;
                $(
                    let $field: $ty = $crate::params::field(set, index);
                    index += 1;
                )+
                debug_assert!(index <= set.decls().len(), "a set made from another declaration list");
                Self { $($field),+ }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamDecl;
    use crate::params::ParamValue::{Float, Int, Vec2};

    crate::param_enum! {
        /// How cells are laid out.
        enum Layout {
            /// In rows.
            Grid = "grid",
            /// On a circle.
            Ring = "ring",
        }
    }

    crate::technique_params! {
        /// A test technique's settings.
        struct Settings {
            /// how many
            /// (a second line)
            count: i32 = |n, doc| ParamDecl::new(n, Int(3), Some((1.0, 9.0)), doc),
            /// how large
            size: f32 = |n, doc| ParamDecl::new(n, Float(0.5), Some((0.0, 1.0)), doc).with_unit("m"),
            /// where
            at: [f32; 2] = |n, doc| ParamDecl::new(n, Vec2([0.1, 0.2]), None, doc),
            /// the layout
            layout: Layout = |n, doc| ParamDecl::choice(n, Layout::OPTIONS, 1, doc),
            /// start again
            reset: bool = |n, doc| ParamDecl::trigger(n, doc),
        }
    }

    #[test]
    fn a_typed_struct_declares_its_fields_and_reads_them_by_position() {
        let decls = Settings::decls();
        let names: Vec<&str> = decls.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(names, ["count", "size", "at", "layout", "reset"]);
        assert_eq!(decls[0].doc, "how many (a second line)");
        assert_eq!((decls[1].unit.as_str(), decls[3].options.clone()), ("m", vec!["grid".into(), "ring".into()]));
        let mut set = ParamSet::new(decls);
        assert_eq!(
            Settings::read(&set),
            Settings { count: 3, size: 0.5, at: [0.1, 0.2], layout: Layout::Ring, reset: false }
        );
        set.set_at(0, Int(7));
        set.set_at(3, ParamValue::Enum(0));
        set.set_at(4, ParamValue::Trigger(true));
        set.snap();
        let read = Settings::read(&set);
        assert_eq!((read.count, read.layout, read.reset), (7, Layout::Grid, true));
        assert_eq!(Layout::from_index(99), Layout::Ring, "past the end is the last option");
    }
}
