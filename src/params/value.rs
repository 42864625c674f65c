//! Parameter values and their declarations.

use std::fmt;

/// The type of a parameter; decides its UI widget and how values are coerced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamType {
    /// One float (slider).
    Float,
    /// One integer (integer slider).
    Int,
    /// On/off (checkbox).
    Bool,
    /// Two floats (2-D pad).
    Vec2,
    /// Three floats.
    Vec3,
    /// Four floats.
    Vec4,
    /// RGBA, sRGB-encoded as a colour picker shows it (colour picker).
    Color,
    /// One of the declaration's named options (drop-down).
    Enum,
    /// A momentary event (button): true for the one frame it fires in, never smoothed.
    Trigger,
    /// A short string (text field); up to [`Text::CAPACITY`] bytes of UTF-8.
    Text,
}

impl ParamType {
    /// A number, a bool or a trigger: one value a level can drive (an audio mapping's whole
    /// target; enums and text are not).
    pub fn is_scalar(self) -> bool {
        matches!(self, ParamType::Float | ParamType::Int | ParamType::Bool | ParamType::Trigger)
    }

    /// Number of float components.
    pub fn components(self) -> usize {
        match self {
            ParamType::Float | ParamType::Int | ParamType::Bool | ParamType::Enum | ParamType::Trigger => 1,
            ParamType::Vec2 => 2,
            ParamType::Vec3 => 3,
            ParamType::Vec4 | ParamType::Color => 4,
            ParamType::Text => 0,
        }
    }

    /// Lower-case name used in files and messages.
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Float => "float",
            ParamType::Int => "int",
            ParamType::Bool => "bool",
            ParamType::Vec2 => "vec2",
            ParamType::Vec3 => "vec3",
            ParamType::Vec4 => "vec4",
            ParamType::Color => "color",
            ParamType::Enum => "enum",
            ParamType::Trigger => "trigger",
            ParamType::Text => "text",
        }
    }

    /// Builds a value of this type from numbers; `None` if the count or kind does not fit.
    /// Colours accept 3 numbers (alpha 1). Ints must be whole; bools are 0 or 1.
    pub fn value_from(self, numbers: &[f64]) -> Option<ParamValue> {
        let f = |i: usize| numbers[i] as f32;
        let exact = numbers.len() == self.components();
        Some(match self {
            ParamType::Float if exact => ParamValue::Float(f(0)),
            ParamType::Int
                if exact
                    && numbers[0].fract() == 0.0
                    && (f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&numbers[0]) =>
            {
                ParamValue::Int(numbers[0] as i32)
            }
            ParamType::Bool if exact && (numbers[0] == 0.0 || numbers[0] == 1.0) => ParamValue::Bool(numbers[0] == 1.0),
            ParamType::Vec2 if exact => ParamValue::Vec2([f(0), f(1)]),
            ParamType::Vec3 if exact => ParamValue::Vec3([f(0), f(1), f(2)]),
            ParamType::Vec4 if exact => ParamValue::Vec4([f(0), f(1), f(2), f(3)]),
            ParamType::Color if exact => ParamValue::Color([f(0), f(1), f(2), f(3)]),
            ParamType::Color if numbers.len() == 3 => ParamValue::Color([f(0), f(1), f(2), 1.0]),
            ParamType::Trigger if numbers.len() <= 1 => ParamValue::Trigger(numbers.first().is_none_or(|&x| x != 0.0)),
            ParamType::Enum if exact && numbers[0].fract() == 0.0 && (0.0..65536.0).contains(&numbers[0]) => {
                ParamValue::Enum(numbers[0] as u32)
            }
            _ => return None,
        })
    }
}

impl fmt::Display for ParamType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A parameter value.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ParamValue {
    /// See [`ParamType::Float`].
    Float(f32),
    /// See [`ParamType::Int`].
    Int(i32),
    /// See [`ParamType::Bool`].
    Bool(bool),
    /// See [`ParamType::Vec2`].
    Vec2([f32; 2]),
    /// See [`ParamType::Vec3`].
    Vec3([f32; 3]),
    /// See [`ParamType::Vec4`].
    Vec4([f32; 4]),
    /// See [`ParamType::Color`].
    Color([f32; 4]),
    /// See [`ParamType::Enum`]: the index of the chosen option.
    Enum(u32),
    /// See [`ParamType::Trigger`]: whether it fired this frame.
    Trigger(bool),
    /// See [`ParamType::Text`].
    Text(Text),
}

/// A short UTF-8 string stored inline, so that values stay `Copy` (they are written from
/// control threads and snapshotted every frame). Longer input is cut at a character boundary.
#[derive(Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(from = "String", into = "String")]
pub struct Text {
    len: u8,
    bytes: [u8; Text::CAPACITY],
}

impl Text {
    /// Most bytes a text value holds.
    pub const CAPACITY: usize = 62;

    /// `text`, cut to [`Text::CAPACITY`] bytes at a character boundary.
    pub fn new(text: &str) -> Self {
        let mut end = text.len().min(Self::CAPACITY);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let mut bytes = [0; Self::CAPACITY];
        bytes[..end].copy_from_slice(&text.as_bytes()[..end]);
        Self { len: end as u8, bytes }
    }

    /// The string.
    pub fn as_str(&self) -> &str {
        // Only `new` writes the bytes, from a &str cut at a boundary.
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or_default()
    }
}

impl From<String> for Text {
    fn from(text: String) -> Self {
        Self::new(&text)
    }
}

impl From<Text> for String {
    fn from(text: Text) -> Self {
        text.as_str().to_string()
    }
}

impl fmt::Debug for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl ParamValue {
    /// The value's type.
    pub fn ty(&self) -> ParamType {
        match self {
            ParamValue::Float(_) => ParamType::Float,
            ParamValue::Int(_) => ParamType::Int,
            ParamValue::Bool(_) => ParamType::Bool,
            ParamValue::Vec2(_) => ParamType::Vec2,
            ParamValue::Vec3(_) => ParamType::Vec3,
            ParamValue::Vec4(_) => ParamType::Vec4,
            ParamValue::Color(_) => ParamType::Color,
            ParamValue::Enum(_) => ParamType::Enum,
            ParamValue::Trigger(_) => ParamType::Trigger,
            ParamValue::Text(_) => ParamType::Text,
        }
    }

    /// All components as floats (bool → 0/1), inline: reading a parameter allocates nothing.
    pub fn components(&self) -> Components {
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        match *self {
            ParamValue::Float(x) => Components::new(&[x]),
            ParamValue::Int(i) => Components::new(&[i as f32]),
            ParamValue::Bool(b) | ParamValue::Trigger(b) => Components::new(&[flag(b)]),
            ParamValue::Vec2(v) => Components::new(&v),
            ParamValue::Vec3(v) => Components::new(&v),
            ParamValue::Vec4(v) | ParamValue::Color(v) => Components::new(&v),
            ParamValue::Enum(i) => Components::new(&[i as f32]),
            ParamValue::Text(_) => Components::new(&[]),
        }
    }

    /// A value of type `ty` from float components (ints round, bools threshold at 0.5; text has
    /// no components and comes out empty).
    pub fn from_components(ty: ParamType, c: &[f32]) -> ParamValue {
        let at = |i: usize| c.get(i).copied().unwrap_or(0.0);
        match ty {
            ParamType::Float => ParamValue::Float(at(0)),
            ParamType::Int => ParamValue::Int(at(0).round() as i32),
            ParamType::Bool => ParamValue::Bool(at(0) >= 0.5),
            ParamType::Vec2 => ParamValue::Vec2([at(0), at(1)]),
            ParamType::Vec3 => ParamValue::Vec3([at(0), at(1), at(2)]),
            ParamType::Vec4 => ParamValue::Vec4([at(0), at(1), at(2), at(3)]),
            ParamType::Color => ParamValue::Color([at(0), at(1), at(2), at(3)]),
            ParamType::Enum => ParamValue::Enum(at(0).round().max(0.0) as u32),
            ParamType::Trigger => ParamValue::Trigger(at(0) >= 0.5),
            ParamType::Text => ParamValue::Text(Text::new("")),
        }
    }

    /// Clamps every component into `range` (colours are not clamped by a range; they keep [0, ∞)).
    pub fn clamped(&self, range: Option<(f32, f32)>) -> ParamValue {
        let Some((lo, hi)) = range else { return *self };
        if matches!(self, ParamValue::Bool(_) | ParamValue::Trigger(_) | ParamValue::Text(_)) {
            return *self;
        }
        // Integers clamp as integers (through f32 they would lose digits past 2²⁴).
        let whole = |x: f32, round: fn(f32) -> f32| round(x) as i64;
        match *self {
            ParamValue::Int(i) => {
                return ParamValue::Int(i64::from(i).max(whole(lo, f32::ceil)).min(whole(hi, f32::floor)) as i32);
            }
            ParamValue::Enum(i) => {
                return ParamValue::Enum(
                    i64::from(i).max(whole(lo, f32::ceil)).min(whole(hi, f32::floor)).max(0) as u32
                );
            }
            _ => {}
        }
        // max/min, not clamp: a range that is somehow not finite must never panic the show.
        let c: Vec<f32> = self.components().iter().map(|x| x.max(lo).min(hi)).collect();
        ParamValue::from_components(self.ty(), &c)
    }
}

impl fmt::Display for ParamValue {
    /// As a scene file would write it: `1.9`, `50`, `true`, `(1.98795, 0.005859)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Enum(i) => write!(f, "#{i}"),
            ParamValue::Bool(b) | ParamValue::Trigger(b) => write!(f, "{b}"),
            ParamValue::Float(x) => write!(f, "{x}"),
            ParamValue::Text(t) => write!(f, "{:?}", t.as_str()),
            other => {
                let parts: Vec<String> = other.components().iter().map(|c| c.to_string()).collect();
                write!(f, "({})", parts.join(", "))
            }
        }
    }
}

/// The float components of a value (up to four), held inline; derefs to a slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Components {
    values: [f32; 4],
    len: usize,
}

impl Components {
    /// The first (at most four) of `values`.
    pub fn new(values: &[f32]) -> Self {
        let len = values.len().min(4);
        let mut inline = [0.0; 4];
        inline[..len].copy_from_slice(&values[..len]);
        Self { values: inline, len }
    }
}

impl std::ops::Deref for Components {
    type Target = [f32];

    fn deref(&self) -> &[f32] {
        &self.values[..self.len]
    }
}

impl IntoIterator for Components {
    type Item = f32;
    type IntoIter = std::iter::Take<std::array::IntoIter<f32, 4>>;

    fn into_iter(self) -> Self::IntoIter {
        self.values.into_iter().take(self.len)
    }
}

impl std::ops::DerefMut for Components {
    fn deref_mut(&mut self) -> &mut [f32] {
        &mut self.values[..self.len]
    }
}

/// A parameter a technique exposes: name, type, default, range, unit and meaning.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamDecl {
    /// snake_case name, unique in its node; also the last part of its OSC address.
    pub name: String,
    /// Default value (its type is the parameter's type).
    pub default: ParamValue,
    /// Inclusive range of each component, if bounded; UI sliders and incoming values use it.
    pub range: Option<(f32, f32)>,
    /// Unit shown next to the value ("", "px", "s", "°").
    pub unit: String,
    /// One sentence on what it does.
    pub doc: String,
    /// Option names of an enum parameter (empty otherwise).
    pub options: Vec<String>,
    /// Smoothing time constant in seconds (0: changes apply at once). Only continuous types
    /// (float, vectors, colours) are smoothed.
    pub smoothing: f32,
    /// What the window's mouse or keyboard does to it, if anything: a technique declares this
    /// and gets mouse and keys without any change to the app.
    pub role: Option<InputRole>,
}

/// How the window's pointer and keys drive a parameter. The window turns input into ordinary
/// parameter writes, so OSC, MIDI, presets and recordings drive the same parameters the same way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputRole {
    /// A vec2 that follows the pointer on each click, in view units (0–1, y up).
    Pointer,
    /// A trigger fired by a primary-button click (after the pointer is written).
    PrimaryClick,
    /// A trigger fired by a secondary-button click (after the pointer is written).
    SecondaryClick,
    /// A trigger fired by a key (a lower-case letter; the key works with or without shift).
    Key(char),
    /// A bool that is true while the primary button is held; the pointer parameters follow the
    /// mouse while it is (stirring a fluid, painting).
    Drag,
}

impl ParamDecl {
    /// A declaration; `range` bounds each component.
    pub fn new(name: &str, default: ParamValue, range: Option<(f32, f32)>, doc: &str) -> Self {
        Self {
            name: name.into(),
            default,
            range,
            unit: String::new(),
            doc: doc.into(),
            options: Vec::new(),
            smoothing: 0.0,
            role: None,
        }
    }

    /// This declaration driven by the window's pointer or keys as `role` says.
    pub fn with_role(mut self, role: InputRole) -> Self {
        self.role = Some(role);
        self
    }

    /// An enum parameter choosing one of `options` (default: option `default`).
    pub fn choice(name: &str, options: &[&str], default: u32, doc: &str) -> Self {
        let last = options.len().saturating_sub(1) as f32;
        let mut decl = Self::new(name, ParamValue::Enum(default), Some((0.0, last)), doc);
        decl.options = options.iter().map(|o| o.to_string()).collect();
        decl
    }

    /// A text parameter.
    pub fn text(name: &str, default: &str, doc: &str) -> Self {
        Self::new(name, ParamValue::Text(Text::new(default)), None, doc)
    }

    /// A trigger (momentary button) parameter.
    pub fn trigger(name: &str, doc: &str) -> Self {
        Self::new(name, ParamValue::Trigger(false), None, doc)
    }

    /// The same declaration with a smoothing time constant (seconds).
    #[must_use]
    pub fn with_smoothing(mut self, seconds: f32) -> Self {
        self.smoothing = seconds.max(0.0);
        self
    }

    /// Whether values of this type glide when smoothed (continuous types only).
    pub fn is_smoothable(&self) -> bool {
        matches!(self.ty(), ParamType::Float | ParamType::Vec2 | ParamType::Vec3 | ParamType::Vec4 | ParamType::Color)
    }

    /// The option index named `name` (case-insensitive), for enum parameters.
    pub fn option_index(&self, name: &str) -> Option<u32> {
        self.options.iter().position(|o| o.eq_ignore_ascii_case(name)).map(|i| i as u32)
    }

    /// A value as text: option names for enums, scene syntax otherwise.
    pub fn format(&self, value: &ParamValue) -> String {
        match value {
            ParamValue::Enum(i) => self.options.get(*i as usize).cloned().unwrap_or_else(|| value.to_string()),
            other => other.to_string(),
        }
    }

    /// The same declaration with a unit.
    #[must_use]
    pub fn with_unit(mut self, unit: &str) -> Self {
        self.unit = unit.into();
        self
    }

    /// The parameter's type.
    pub fn ty(&self) -> ParamType {
        self.default.ty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coercion_checks_count_and_kind() {
        assert_eq!(ParamType::Int.value_from(&[50.0]), Some(ParamValue::Int(50)));
        assert_eq!(ParamType::Int.value_from(&[50.5]), None);
        assert_eq!(ParamType::Vec2.value_from(&[1.0]), None);
        assert_eq!(ParamType::Color.value_from(&[1.0, 0.5, 0.0]), Some(ParamValue::Color([1.0, 0.5, 0.0, 1.0])));
        assert_eq!(ParamType::Bool.value_from(&[2.0]), None);
    }

    #[test]
    fn display_is_scene_syntax() {
        assert_eq!(ParamValue::Vec2([1.5, 0.25]).to_string(), "(1.5, 0.25)");
        assert_eq!(ParamValue::Int(50).to_string(), "50");
        assert_eq!(ParamValue::Bool(true).to_string(), "true");
    }

    #[test]
    fn text_is_cut_at_a_character_boundary() {
        let long = "é".repeat(40);
        let t = Text::new(&long);
        assert_eq!(t.as_str().len(), 62);
        assert_eq!(t.as_str(), "é".repeat(31));
        assert_eq!(ParamValue::Text(Text::new("hi")).to_string(), "\"hi\"");
    }

    #[test]
    fn components_are_inline_and_as_long_as_the_type() {
        let c = ParamValue::Vec3([1.0, 2.0, 3.0]).components();
        assert_eq!((&*c, c.into_iter().count()), (&[1.0, 2.0, 3.0][..], 3));
        assert!(ParamValue::Text(Text::new("x")).components().is_empty());
        assert_eq!(&*ParamValue::Trigger(true).components(), &[1.0]);
    }

    #[test]
    fn integers_stay_integers_to_the_ends_of_i32() {
        assert_eq!(ParamType::Int.value_from(&[2_000_000_000.0]), Some(ParamValue::Int(2_000_000_000)));
        assert_eq!(ParamType::Int.value_from(&[f64::from(i32::MAX)]), Some(ParamValue::Int(i32::MAX)));
        assert_eq!(ParamType::Int.value_from(&[f64::from(i32::MAX) + 1.0]), None);
        let odd = ParamValue::Int(16_777_217); // 2²⁴ + 1: not representable in f32
        assert_eq!(odd.clamped(Some((1.0, 2.1e9))), odd, "in range, unchanged");
        assert_eq!(ParamValue::Int(5).clamped(Some((1.5, 3.5))), ParamValue::Int(3));
        assert_eq!(ParamValue::Enum(9).clamped(Some((0.0, 2.0))), ParamValue::Enum(2));
    }

    #[test]
    fn clamping_is_per_component() {
        let v = ParamValue::Vec2([-3.0, 0.5]).clamped(Some((0.0, 1.0)));
        assert_eq!(v, ParamValue::Vec2([0.0, 0.5]));
        assert_eq!(ParamValue::Int(900).clamped(Some((1.0, 500.0))), ParamValue::Int(500));
    }
}
