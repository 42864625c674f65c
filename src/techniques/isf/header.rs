//! The JSON header of an ISF file (the first `/* … */` comment): its inputs, passes and imported
//! images, as ISF v2 writes them — and v1 (`PERSISTENT_BUFFERS`, `IMPORTED` as a list) too.
//! Every mistake is one message located at its line in the `.fs` file.

use serde_json::{Map, Value};

use crate::params::{ParamDecl, ParamValue};

/// A header error: the 1-based line of the `.fs` file it is at, and what is wrong.
pub type Located = (u32, String);

/// One declared input.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    /// `NAME`: the GLSL identifier, also the parameter name.
    pub name: String,
    /// `LABEL`, if given.
    pub label: Option<String>,
    /// What it is.
    pub kind: InputKind,
}

/// The kinds of input ISF declares.
#[derive(Clone, Debug, PartialEq)]
pub enum InputKind {
    /// `float`: a slider.
    Float {
        /// `DEFAULT`, within the range.
        default: f32,
        /// `MIN` and `MAX` (0–1 where not given).
        range: (f32, f32),
    },
    /// `long`: one of `values`, shown as `labels`.
    Long {
        /// `VALUES` (or `MIN` to `MAX`): what the shader receives.
        values: Vec<i32>,
        /// `LABELS` (the values where missing): the parameter's option names.
        labels: Vec<String>,
        /// The index of `DEFAULT` in `values`.
        default: u32,
    },
    /// `bool`: a checkbox.
    Bool {
        /// `DEFAULT`.
        default: bool,
    },
    /// `event`: true for the one frame it fires in.
    Event,
    /// `color`: RGBA 0–1.
    Color {
        /// `DEFAULT`.
        default: [f32; 4],
    },
    /// `point2D`: a point, in the ranges given (pixels when the shader says so).
    Point2D {
        /// `DEFAULT`.
        default: [f32; 2],
        /// The smallest `MIN` and largest `MAX` component, if given.
        range: Option<(f32, f32)>,
    },
    /// `image`: a texture wired from another node.
    Image,
    /// `audio`: the waveform as a texture.
    Audio {
        /// `MAX`: samples wanted.
        max: Option<u32>,
    },
    /// `audioFFT`: the spectrum as a texture.
    AudioFft {
        /// `MAX`: bins wanted.
        max: Option<u32>,
    },
}

impl InputKind {
    /// Whether this input samples sound (`audio`, `audioFFT`).
    pub fn is_audio(&self) -> bool {
        matches!(self, InputKind::Audio { .. } | InputKind::AudioFft { .. })
    }
}

/// One pass (`PASSES`), or the single implicit pass.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pass {
    /// `TARGET`: the buffer it renders into (`None`: the node's output).
    pub target: Option<String>,
    /// `PERSISTENT`: the target keeps its contents across frames.
    pub persistent: bool,
    /// `FLOAT`: a float target rather than 8 bits per channel.
    pub float: bool,
    /// `WIDTH` and `HEIGHT` expressions (`None`: the render size).
    pub width: Option<String>,
    /// See `width`.
    pub height: Option<String>,
}

/// A parsed header.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Header {
    /// `DESCRIPTION`.
    pub description: String,
    /// `CREDIT`.
    pub credit: String,
    /// `CATEGORIES`.
    pub categories: Vec<String>,
    /// `INPUTS`, in order.
    pub inputs: Vec<Input>,
    /// `PASSES` (at least one).
    pub passes: Vec<Pass>,
    /// `IMPORTED`: (sampler name, file path relative to the shader).
    pub imported: Vec<(String, String)>,
    /// The 1-based line the `.fs` body starts on after the header (for messages).
    pub body_line: u32,
    /// The 1-based line of `PASSES` (where a bad size expression is reported).
    pub passes_line: u32,
}

/// What a shader is by its inputs: a generator, a filter (`inputImage`) or a transition
/// (`startImage`, `endImage`, `progress`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Makes an image from nothing.
    Generator,
    /// Changes `inputImage`.
    Filter,
    /// Goes from `startImage` to `endImage` as `progress` goes 0 → 1.
    Transition,
}

impl Header {
    /// Finds and parses the header of `source` (the `.fs` text).
    pub fn parse(source: &str) -> Result<Header, Located> {
        let start = source.find("/*").filter(|&s| source[..s].trim().is_empty()).ok_or_else(|| {
            (1, "no ISF header: an ISF file starts with a /* JSON */ comment declaring its inputs".to_string())
        })?;
        let end = source[start..]
            .find("*/")
            .map(|e| start + e)
            .ok_or_else(|| (line_of(source, start), "the ISF header comment is never closed (no */)".to_string()))?;
        let json = &source[start + 2..end];
        let first_line = line_of(source, start);
        let value: Value = serde_json::from_str(json).map_err(|e| {
            (first_line + e.line().saturating_sub(1) as u32, format!("the ISF header is not JSON: {e}"))
        })?;
        let Value::Object(top) = value else {
            return Err((first_line, "the ISF header must be a JSON object { … }".into()));
        };
        let at = |key: &str| first_line + json.find(&format!("\"{key}\"")).map_or(0, |i| line_of(json, i) - 1);
        let mut header = Header {
            description: string(&top, "DESCRIPTION"),
            credit: string(&top, "CREDIT"),
            categories: top
                .get("CATEGORIES")
                .and_then(Value::as_array)
                .map(|a| a.iter().filter_map(|c| c.as_str().map(String::from)).collect())
                .unwrap_or_default(),
            body_line: line_of(source, end) + 1,
            ..Header::default()
        };
        if let Some(inputs) = top.get("INPUTS") {
            let list = inputs.as_array().ok_or_else(|| (at("INPUTS"), "INPUTS must be a list".to_string()))?;
            if list.len() > MAX_INPUTS {
                return Err((at("INPUTS"), format!("{} INPUTS; at most {MAX_INPUTS}", list.len())));
            }
            let mut names = std::collections::HashSet::new();
            for item in list {
                // Located only on error: a search of the text per input made a long header quadratic.
                let line = || {
                    let name = item.get("NAME").and_then(Value::as_str).unwrap_or_default();
                    first_line + json.find(&format!("\"{name}\"")).map_or(0, |i| line_of(json, i) - 1)
                };
                let input = parse_input(item).map_err(|m| (line(), m))?;
                if !names.insert(input.name.clone()) {
                    return Err((line(), format!("input '{}' is declared twice", input.name)));
                }
                header.inputs.push(input);
            }
        }
        header.passes_line = at("PASSES");
        header.passes = parse_passes(&top).map_err(|m| (at("PASSES"), m))?;
        header.imported = parse_imported(&top).map_err(|m| (at("IMPORTED"), m))?;
        Ok(header)
    }

    /// Generator, filter or transition, by the inputs the spec names for each.
    pub fn role(&self) -> Role {
        let has = |n: &str| self.inputs.iter().any(|i| i.name == n && i.kind == InputKind::Image);
        if has("startImage") && has("endImage") && self.inputs.iter().any(|i| i.name == "progress") {
            Role::Transition
        } else if has("inputImage") {
            Role::Filter
        } else {
            Role::Generator
        }
    }

    /// The image inputs: the node's input slots, in order.
    pub fn image_inputs(&self) -> Vec<String> {
        self.inputs.iter().filter(|i| i.kind == InputKind::Image).map(|i| i.name.clone()).collect()
    }

    /// The parameters the inputs become (images and audio are not parameters).
    pub fn param_decls(&self) -> Vec<ParamDecl> {
        self.inputs.iter().filter_map(Input::decl).collect()
    }
}

impl Input {
    /// What the shader receives for parameter value `value` of this input, as a number (what
    /// `$name` means in a size expression): a `long`'s chosen VALUE, a bool or event as 0 or 1.
    /// `None` for inputs that are no single number (colours, points, images).
    pub fn number(&self, value: ParamValue) -> Option<f64> {
        Some(match (&self.kind, value) {
            (InputKind::Long { values, .. }, ParamValue::Enum(i)) => {
                f64::from(values.get(i as usize).copied().unwrap_or(0))
            }
            (_, ParamValue::Float(x)) => f64::from(x),
            (_, ParamValue::Bool(b) | ParamValue::Trigger(b)) => f64::from(u8::from(b)),
            _ => return None,
        })
    }

    /// The parameter this input is, if it is one.
    pub fn decl(&self) -> Option<ParamDecl> {
        let doc = self.label.clone().unwrap_or_else(|| self.name.clone());
        let n = self.name.as_str();
        Some(match &self.kind {
            InputKind::Float { default, range } => ParamDecl::new(n, ParamValue::Float(*default), Some(*range), &doc),
            InputKind::Long { labels, default, .. } => {
                let options: Vec<&str> = labels.iter().map(String::as_str).collect();
                ParamDecl::choice(n, &options, *default, &doc)
            }
            InputKind::Bool { default } => ParamDecl::new(n, ParamValue::Bool(*default), None, &doc),
            InputKind::Event => ParamDecl::trigger(n, &doc),
            InputKind::Color { default } => ParamDecl::new(n, ParamValue::Color(*default), Some((0.0, 1.0)), &doc),
            InputKind::Point2D { default, range } => ParamDecl::new(n, ParamValue::Vec2(*default), *range, &doc),
            InputKind::Image | InputKind::Audio { .. } | InputKind::AudioFft { .. } => return None,
        })
    }
}

/// The most inputs a shader may declare: each is a parameter on the panel, OSC and MIDI, and a
/// field of the uniform block (Vidvox's 64 declare at most 17).
pub const MAX_INPUTS: usize = 256;

/// The longest input name indra takes (names become OSC addresses and GLSL identifiers).
const MAX_NAME: usize = 64;

/// The most options a `long` input may have.
const MAX_OPTIONS: usize = 256;

fn parse_input(item: &Value) -> Result<Input, String> {
    let obj = item.as_object().ok_or("each input must be an object with NAME and TYPE")?;
    let name = obj.get("NAME").and_then(Value::as_str).ok_or("an input has no NAME")?.to_string();
    let identifier = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !identifier || name.len() > MAX_NAME || name.starts_with("_isf") || name.starts_with("gl_") {
        return Err(format!("input name '{name}' must be a GLSL identifier of at most {MAX_NAME} characters"));
    }
    let ty = obj.get("TYPE").and_then(Value::as_str).ok_or_else(|| format!("input '{name}' has no TYPE"))?;
    let number = |key: &str| obj.get(key).and_then(Value::as_f64).map(|x| x as f32).filter(|x| x.is_finite());
    let numbers = |key: &str| -> Option<Vec<f32>> {
        let list = obj.get(key)?.as_array()?;
        list.iter().map(|v| v.as_f64().map(|x| x as f32).filter(|x| x.is_finite())).collect()
    };
    let kind = match ty {
        "float" => {
            let default = number("DEFAULT").unwrap_or(0.0);
            let (lo, hi) =
                (number("MIN").unwrap_or(0.0_f32.min(default)), number("MAX").unwrap_or(1.0_f32.max(default)));
            if lo >= hi {
                return Err(format!("input '{name}': MIN {lo} is not below MAX {hi}"));
            }
            InputKind::Float { default: default.clamp(lo, hi), range: (lo, hi) }
        }
        "long" => {
            let values: Vec<i32> = match numbers("VALUES") {
                Some(v) => v.iter().map(|x| *x as i32).collect(),
                None => {
                    let (lo, hi) = (number("MIN").unwrap_or(0.0) as i32, number("MAX").unwrap_or(1.0) as i32);
                    (lo..=hi.min(lo.saturating_add(MAX_OPTIONS as i32 - 1))).collect()
                }
            };
            if values.is_empty() || values.len() > MAX_OPTIONS {
                return Err(format!("input '{name}' must have 1 to {MAX_OPTIONS} VALUES"));
            }
            let given: Vec<String> = obj
                .get("LABELS")
                .and_then(Value::as_array)
                .map(|l| l.iter().map(|s| s.as_str().map_or_else(|| s.to_string(), String::from)).collect())
                .unwrap_or_default();
            let labels = (0..values.len())
                .map(|i| given.get(i).cloned().unwrap_or_else(|| values[i].to_string()))
                .collect::<Vec<_>>();
            let mut unique = labels.clone();
            unique.sort();
            unique.dedup();
            // Option names must be unique to be chosen by name; fall back to the values.
            let labels =
                if unique.len() == labels.len() { labels } else { values.iter().map(i32::to_string).collect() };
            let wanted = number("DEFAULT").map(|d| d as i32).unwrap_or(values[0]);
            let default = values.iter().position(|&v| v == wanted).unwrap_or(0) as u32;
            InputKind::Long { values, labels, default }
        }
        "bool" => InputKind::Bool { default: obj.get("DEFAULT").is_some_and(truthy) },
        "event" => InputKind::Event,
        "color" => {
            let d = numbers("DEFAULT").unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
            let c = |i: usize| d.get(i).copied().unwrap_or(if i == 3 { 1.0 } else { 0.0 }).clamp(0.0, 1.0);
            InputKind::Color { default: [c(0), c(1), c(2), c(3)] }
        }
        "point2D" => {
            let d = numbers("DEFAULT").unwrap_or_default();
            let default = [d.first().copied().unwrap_or(0.0), d.get(1).copied().unwrap_or(0.0)];
            let range = match (numbers("MIN"), numbers("MAX")) {
                (Some(lo), Some(hi)) if !lo.is_empty() && !hi.is_empty() => {
                    let lo = lo.iter().copied().fold(f32::INFINITY, f32::min);
                    let hi = hi.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                    (lo < hi).then_some((lo, hi))
                }
                _ => None,
            };
            let default = range.map_or(default, |(lo, hi)| default.map(|x| x.clamp(lo, hi)));
            InputKind::Point2D { default, range }
        }
        "image" => InputKind::Image,
        "audio" => InputKind::Audio { max: number("MAX").map(|m| m.max(1.0) as u32) },
        "audioFFT" => InputKind::AudioFft { max: number("MAX").map(|m| m.max(1.0) as u32) },
        other => {
            return Err(format!(
                "input '{name}' has TYPE '{other}'; ISF knows float, long, bool, event, color, point2D, image, \
                 audio and audioFFT"
            ));
        }
    };
    let label = obj.get("LABEL").and_then(Value::as_str).map(String::from);
    Ok(Input { name, label, kind })
}

/// The most passes a shader may declare (each is a render pass every frame).
pub const MAX_PASSES: usize = 32;

fn parse_passes(top: &Map<String, Value>) -> Result<Vec<Pass>, String> {
    // v1 declared persistent buffers apart from the passes.
    let mut persistent_v1: Vec<(String, Option<&Value>)> = Vec::new();
    match top.get("PERSISTENT_BUFFERS") {
        Some(Value::Array(names)) => {
            persistent_v1.extend(names.iter().filter_map(|n| Some((n.as_str()?.into(), None))))
        }
        Some(Value::Object(map)) => persistent_v1.extend(map.iter().map(|(k, v)| (k.clone(), Some(v)))),
        _ => {}
    }
    let Some(passes) = top.get("PASSES") else {
        return Ok(vec![Pass::default()]);
    };
    let list = passes.as_array().ok_or("PASSES must be a list of objects")?;
    if list.len() > MAX_PASSES {
        return Err(format!("{} PASSES; at most {MAX_PASSES}", list.len()));
    }
    let mut out = Vec::new();
    for p in list {
        let obj = p.as_object().ok_or("each of PASSES must be an object")?;
        let target = obj.get("TARGET").and_then(Value::as_str).filter(|t| !t.is_empty()).map(String::from);
        let v1 = target.as_ref().and_then(|t| persistent_v1.iter().find(|(n, _)| n == t));
        let field = |key: &str| obj.get(key).or_else(|| v1.and_then(|(_, v)| v.and_then(|v| v.get(key))));
        let expression = |key: &str| match field(key) {
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(Value::Number(n)) => Ok(Some(n.to_string())),
            None => Ok(None),
            Some(other) => Err(format!("{key} {other} must be a number or an expression in quotes")),
        };
        if let Some(t) = &target
            && !(t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') && t.len() <= MAX_NAME)
        {
            return Err(format!("TARGET '{t}' must be a GLSL identifier"));
        }
        out.push(Pass {
            persistent: field("PERSISTENT").is_some_and(truthy) || v1.is_some(),
            float: field("FLOAT").is_some_and(truthy),
            width: expression("WIDTH")?,
            height: expression("HEIGHT")?,
            target,
        });
    }
    if out.is_empty() {
        out.push(Pass::default());
    }
    Ok(out)
}

fn parse_imported(top: &Map<String, Value>) -> Result<Vec<(String, String)>, String> {
    let path_of = |v: &Value| v.get("PATH").and_then(Value::as_str).map(String::from);
    let mut out = Vec::new();
    match top.get("IMPORTED") {
        None => {}
        Some(Value::Object(map)) => {
            for (name, v) in map {
                let name = v.get("NAME").and_then(Value::as_str).unwrap_or(name).to_string();
                out.push((name.clone(), path_of(v).ok_or(format!("IMPORTED '{name}' has no PATH"))?));
            }
        }
        Some(Value::Array(list)) => {
            for v in list {
                let name = v.get("NAME").and_then(Value::as_str).ok_or("each IMPORTED entry needs a NAME")?;
                out.push((name.to_string(), path_of(v).ok_or(format!("IMPORTED '{name}' has no PATH"))?));
            }
        }
        Some(_) => return Err("IMPORTED must be an object of { NAME: { PATH } }".into()),
    }
    for (name, _) in &out {
        if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') || name.len() > MAX_NAME {
            return Err(format!("IMPORTED name '{name}' must be a GLSL identifier"));
        }
    }
    Ok(out)
}

/// JSON's idea of a flag, as ISF files write it: `true`, `1`, `"true"`.
fn truthy(v: &Value) -> bool {
    match v {
        Value::Bool(b) => *b,
        Value::Number(n) => n.as_f64().is_some_and(|x| x != 0.0),
        Value::String(s) => s == "true" || s == "1",
        _ => false,
    }
}

fn string(top: &Map<String, Value>, key: &str) -> String {
    top.get(key).and_then(Value::as_str).unwrap_or_default().to_string()
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> u32 {
    text[..offset.min(text.len())].matches('\n').count() as u32 + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamType;

    const EVERY_TYPE: &str = r#"/*{
    "ISFVSN": "2",
    "INPUTS": [
        { "NAME": "inputImage", "TYPE": "image" },
        { "NAME": "amount", "TYPE": "float", "DEFAULT": 0.25, "MIN": -1, "MAX": 2, "LABEL": "Amount" },
        { "NAME": "mode", "TYPE": "long", "VALUES": [0, 5, 9], "LABELS": ["a", "b", "c"], "DEFAULT": 5 },
        { "NAME": "invert", "TYPE": "bool", "DEFAULT": 1 },
        { "NAME": "flash", "TYPE": "event" },
        { "NAME": "tint", "TYPE": "color", "DEFAULT": [1, 0.5, 0, 1] },
        { "NAME": "center", "TYPE": "point2D", "DEFAULT": [0.5, 0.5], "MIN": [0, 0], "MAX": [1, 1] },
        { "NAME": "wave", "TYPE": "audio" },
        { "NAME": "spectrum", "TYPE": "audioFFT", "MAX": 64 }
    ]
}*/
void main() { gl_FragColor = vec4(amount); }
"#;

    #[test]
    fn every_input_type_becomes_its_parameter() {
        let h = Header::parse(EVERY_TYPE).unwrap();
        let decls = h.param_decls();
        let types: Vec<(String, ParamType)> = decls.iter().map(|d| (d.name.clone(), d.ty())).collect();
        assert_eq!(
            types,
            [
                ("amount".into(), ParamType::Float),
                ("mode".into(), ParamType::Enum),
                ("invert".into(), ParamType::Bool),
                ("flash".into(), ParamType::Trigger),
                ("tint".into(), ParamType::Color),
                ("center".into(), ParamType::Vec2),
            ]
        );
        assert_eq!(decls[0].range, Some((-1.0, 2.0)));
        assert_eq!(decls[0].doc, "Amount");
        assert_eq!(decls[1].options, ["a", "b", "c"]);
        assert_eq!(decls[1].default, ParamValue::Enum(1), "DEFAULT is a value, the parameter an index");
        assert_eq!(decls[2].default, ParamValue::Bool(true));
        assert_eq!(decls[4].default, ParamValue::Color([1.0, 0.5, 0.0, 1.0]));
        assert_eq!(h.image_inputs(), ["inputImage"]);
        assert_eq!(h.role(), Role::Filter);
        assert_eq!(h.inputs[8].kind, InputKind::AudioFft { max: Some(64) });
        assert_eq!(h.body_line, 15);
    }

    #[test]
    fn mistakes_are_located_in_the_file() {
        let (line, message) =
            Header::parse("/*{\n \"INPUTS\": [\n  { \"NAME\": \"x\", \"TYPE\": \"float\", }\n]}*/").unwrap_err();
        assert_eq!(line, 3, "{message}");
        assert!(message.contains("not JSON"), "{message}");
        let unknown = "/*{\n\"INPUTS\": [\n{ \"NAME\": \"x\",\n \"TYPE\": \"vec3\" }]}*/";
        let (line, message) = Header::parse(unknown).unwrap_err();
        assert_eq!(line, 3);
        assert!(message.contains("TYPE 'vec3'"), "{message}");
        assert_eq!(Header::parse("void main() {}").unwrap_err().0, 1);
        assert!(Header::parse("/*{ \"INPUTS\": [ {\"NAME\": \"gl_x\", \"TYPE\": \"float\"} ] }*/").is_err());
    }

    #[test]
    fn v1_persistent_buffers_and_imports_are_read() {
        let v1 = r#"/*{ "PERSISTENT_BUFFERS": ["trail"], "PASSES": [ { "TARGET": "trail", "WIDTH": "$WIDTH/2" }, {} ],
            "IMPORTED": [ { "NAME": "logo", "PATH": "logo.png" } ] }*/"#;
        let h = Header::parse(v1).unwrap();
        assert_eq!(h.passes.len(), 2);
        assert!(h.passes[0].persistent);
        assert_eq!(h.passes[0].width.as_deref(), Some("$WIDTH/2"));
        assert_eq!(h.passes[1], Pass::default());
        assert_eq!(h.imported, [("logo".to_string(), "logo.png".to_string())]);
        let v2 = r#"/*{ "IMPORTED": { "logo": { "PATH": "logo.png" } } }*/"#;
        assert_eq!(Header::parse(v2).unwrap().imported, [("logo".to_string(), "logo.png".to_string())]);
    }
}
