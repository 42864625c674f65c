//! The gl-transitions format (`*.glsl`, the library of the npm package `gl-transitions`) as an
//! ISF transition, so that such a file plays through the same GLSL path as any ISF shader — as
//! a show transition kind, or a node. The format: a function `vec4 transition(vec2 uv)` that reads
//! `getFromColor(uv)` and `getToColor(uv)`, the uniforms `progress` and `ratio` (width / height),
//! and its own uniforms declared `uniform <type> <name>; // = <default>`.
//!
//! The translation: an ISF header with the images `startImage` and `endImage`, `progress`, and one
//! input per uniform ISF has a type for — `float`, `int` (as `long`), `bool`, `vec2` (`point2D`),
//! `vec4` (`color`), `sampler2D` (an image) — while a `vec3` or `ivec2` uniform becomes a constant
//! of its default; `ratio` becomes `RENDERSIZE.x / RENDERSIZE.y`; and a `main` that writes
//! `transition(isf_FragNormCoord.xy)`. The file's own lines keep their numbers plus one (the
//! header is one line), which [`GL_LINE_OFFSET`] takes back in errors.

use serde_json::{Value, json};

/// The extension of gl-transitions files.
pub const EXTENSION: &str = "glsl";

/// Lines the translation adds before the file's first line.
pub const GL_LINE_OFFSET: u32 = 1;

/// Whether `file` is a gl-transitions file (by its extension).
pub fn is_gl_transition(file: &str) -> bool {
    std::path::Path::new(file).extension().is_some_and(|e| e == EXTENSION)
}

/// One uniform the file declares.
struct Uniform {
    ty: String,
    name: String,
    /// The numbers (or `true`/`false`) of its `// = ...` default, if it has one.
    default: Vec<f64>,
}

/// The ISF text of gl-transition source `source`, or why it cannot be one (with its line).
pub fn to_isf(source: &str) -> Result<String, (u32, String)> {
    let mut uniforms = Vec::new();
    let mut body = Vec::new();
    for (i, line) in source.lines().enumerate() {
        match parse_uniform(line) {
            Some(Ok(u)) => {
                body.push(constant_for(&u).unwrap_or_default());
                uniforms.push(u);
            }
            Some(Err(message)) => return Err((i as u32 + 1, message)),
            None => body.push(line.to_string()),
        }
    }
    let body = replace_ratio(&body.join("\n"));
    if !body.contains("transition") {
        return Err((1, "no `vec4 transition(vec2 uv)`: not a gl-transition".into()));
    }
    let author = credit(source, "Author");
    let license = credit(source, "License");
    let mut inputs = vec![
        json!({ "NAME": "startImage", "TYPE": "image" }),
        json!({ "NAME": "endImage", "TYPE": "image" }),
        json!({ "NAME": "progress", "TYPE": "float", "DEFAULT": 0.0, "MIN": 0.0, "MAX": 1.0 }),
    ];
    inputs.extend(uniforms.iter().filter_map(isf_input));
    let header = json!({
        "ISFVSN": "2",
        "DESCRIPTION": "a gl-transition",
        "CREDIT": format!("{} ({})", author.as_deref().unwrap_or("unknown"), license.as_deref().unwrap_or("MIT")),
        "CATEGORIES": ["Transition", "gl-transitions"],
        "INPUTS": Value::Array(inputs),
    });
    // One line: the file's own lines follow from line 2.
    let prelude = "vec4 getFromColor(vec2 uv) { return IMG_NORM_PIXEL(startImage, uv); } \
                   vec4 getToColor(vec2 uv) { return IMG_NORM_PIXEL(endImage, uv); }";
    Ok(format!(
        "/*{header}*/ {prelude}\n{}\nvoid main() {{ gl_FragColor = transition(isf_FragNormCoord.xy); }}\n",
        body
    ))
}

/// The uniform declared on `line`, if it declares one (`progress` and `ratio` are the format's
/// own and are not inputs).
fn parse_uniform(line: &str) -> Option<Result<Uniform, String>> {
    let rest = line.trim_start().strip_prefix("uniform ")?;
    let (decl, comment) = match rest.find(';') {
        Some(end) => (&rest[..end], &rest[end + 1..]),
        None => return Some(Err("a uniform declaration must end on its line with ;".into())),
    };
    // A default may sit in a comment before the `;` too: `uniform vec3 c /* = vec3(1) */;`.
    let (decl, inner) = match decl.find("/*") {
        Some(at) => (&decl[..at], &decl[at..]),
        None => (decl, ""),
    };
    let mut words = decl.split_whitespace();
    let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
        return Some(Err(format!("cannot read the uniform '{}'", decl.trim())));
    };
    let text = format!("{inner} {comment}");
    let default = text.split_once('=').map(|(_, d)| numbers(d)).unwrap_or_default();
    Some(Ok(Uniform { ty: ty.into(), name: name.into(), default }))
}

/// The numbers of a default expression: `vec2(0.0, 1.0)` → [0, 1], `true` → [1], `ivec2(4)` → [4].
fn numbers(text: &str) -> Vec<f64> {
    let text = text.trim().trim_end_matches("*/");
    if text.trim_start().starts_with("true") {
        return vec![1.0];
    }
    if text.trim_start().starts_with("false") {
        return vec![0.0];
    }
    let inside = text.split_once('(').map_or(text, |(_, r)| r);
    let inside = inside.split(')').next().unwrap_or_default();
    inside.split(',').filter_map(|n| n.trim().trim_end_matches('f').parse().ok()).collect()
}

/// Component `i` of a default of `n` components (`ivec2(4)` gives every component 4).
fn component(default: &[f64], i: usize) -> f64 {
    match default.len() {
        0 => 0.0,
        1 => default[0],
        _ => default.get(i).copied().unwrap_or(0.0),
    }
}

/// The ISF input of a uniform ISF has a type for.
fn isf_input(u: &Uniform) -> Option<Value> {
    let d = |i| component(&u.default, i);
    let span = |x: f64| (x.min(0.0).min(2.0 * x), x.max(1.0).max(2.0 * x));
    Some(match u.ty.as_str() {
        "float" => {
            let (lo, hi) = span(d(0));
            json!({ "NAME": u.name, "TYPE": "float", "DEFAULT": d(0), "MIN": lo, "MAX": hi })
        }
        "int" => {
            let (lo, hi) = span(d(0));
            json!({ "NAME": u.name, "TYPE": "long", "DEFAULT": d(0), "MIN": lo.floor(), "MAX": hi.ceil() })
        }
        "bool" => json!({ "NAME": u.name, "TYPE": "bool", "DEFAULT": d(0) != 0.0 }),
        "vec2" => json!({ "NAME": u.name, "TYPE": "point2D", "DEFAULT": [d(0), d(1)] }),
        "vec4" => json!({ "NAME": u.name, "TYPE": "color", "DEFAULT": [d(0), d(1), d(2), d(3)] }),
        "sampler2D" => json!({ "NAME": u.name, "TYPE": "image" }),
        _ => return None,
    })
}

/// The constant a uniform without an ISF type becomes (its default), on the uniform's line.
fn constant_for(u: &Uniform) -> Option<String> {
    let d = |i| component(&u.default, i);
    match u.ty.as_str() {
        "vec3" => Some(format!("const vec3 {} = vec3({:?}, {:?}, {:?});", u.name, d(0), d(1), d(2))),
        "ivec2" => Some(format!("const ivec2 {} = ivec2({}, {});", u.name, d(0) as i32, d(1) as i32)),
        _ => None,
    }
}

/// `// Author: …` or `// License: …` from the file's head comment.
fn credit(source: &str, key: &str) -> Option<String> {
    source.lines().take(10).find_map(|l| {
        let l = l.trim_start().strip_prefix("//")?.trim();
        l.strip_prefix(key)?.strip_prefix(':').map(|v| v.trim().to_string())
    })
}

/// `code` with the format's `ratio` read from the render size: every use of the identifier
/// outside comments, except inside a block that declares a local of that name (from its
/// declaration to the block's end), where the local is meant.
fn replace_ratio(code: &str) -> String {
    const WORD: &str = "ratio";
    const ASPECT: &str = "(RENDERSIZE.x / RENDERSIZE.y)";
    let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = String::with_capacity(code.len());
    let (mut depth, mut shadowed_from) = (0usize, None::<usize>);
    let mut i = 0;
    while i < code.len() {
        let rest = &code[i..];
        let skip = if rest.starts_with("//") {
            rest.find('\n').unwrap_or(rest.len())
        } else if rest.starts_with("/*") {
            rest.find("*/").map_or(rest.len(), |e| e + 2)
        } else {
            0
        };
        if skip > 0 {
            out.push_str(&rest[..skip]);
            i += skip;
            continue;
        }
        let c = rest.chars().next().unwrap_or(' ');
        match c {
            '{' => depth += 1,
            '}' => {
                depth = depth.saturating_sub(1);
                if shadowed_from.is_some_and(|d| depth < d) {
                    shadowed_from = None;
                }
            }
            _ => {}
        }
        let before = code[..i].chars().next_back();
        let word_here = rest.starts_with(WORD)
            && !before.is_some_and(|b| is_ident(b) || b == '.')
            && !rest[WORD.len()..].chars().next().is_some_and(is_ident);
        if !word_here {
            out.push(c);
            i += c.len_utf8();
            continue;
        }
        // `<type> ratio` declares a local: it is the local from here to its block's end.
        let previous = code[..i].trim_end().rsplit(|c: char| !is_ident(c)).next().unwrap_or_default();
        let declares = ["float", "int", "vec2", "vec3", "vec4", "bool"].contains(&previous);
        if declares && depth > 0 {
            shadowed_from = Some(depth);
        }
        out.push_str(if declares || shadowed_from.is_some() { WORD } else { ASPECT });
        i += WORD.len();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniforms_become_inputs_or_constants_and_ratio_the_render_size() {
        let source = "// Author: someone\n// License: MIT\nuniform float size; // = 0.04\n\
                      uniform vec3 tint /* = vec3(0.9, 0.4, 0.2) */;\nuniform ivec2 grid; // = ivec2(4)\n\
                      uniform bool flip; // = true\nuniform int bars; // =30\n\
                      vec4 transition(vec2 uv) { float r = ratio; vec2 ratio2 = vec2(ratio); // ratio\n\
                      if (r > 0.0) { float ratio = 2.0; r = ratio; } r += ratio; \
                      return mix(getFromColor(uv), getToColor(uv), progress); }\n";
        let isf = to_isf(source).unwrap();
        let header = crate::techniques::isf::header::Header::parse(&isf).unwrap();
        let names: Vec<&str> = header.inputs.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["startImage", "endImage", "progress", "size", "flip", "bars"]);
        assert!(isf.contains("const vec3 tint = vec3(0.9, 0.4, 0.2);"), "{isf}");
        assert!(isf.contains("const ivec2 grid = ivec2(4, 4);"), "{isf}");
        let aspect = "(RENDERSIZE.x / RENDERSIZE.y)";
        assert!(isf.contains(&format!("float r = {aspect}; vec2 ratio2 = vec2({aspect}); // ratio")), "{isf}");
        // A local of the name is the local in its block, and the aspect after it.
        assert!(isf.contains(&format!("{{ float ratio = 2.0; r = ratio; }} r += {aspect};")), "{isf}");
        assert!(isf.contains("someone (MIT)"), "{isf}");
        // The file's line 3 is line 4 of the translation.
        assert_eq!(isf.lines().nth(3), Some(""), "the uniform's line stays, empty");
        assert!(to_isf("void main() {}").is_err());
    }

    #[test]
    fn an_error_is_located_at_the_line_of_the_glsl_file() {
        let source = "// License: MIT\nuniform float a; // = 1.0\nvec4 transition(vec2 uv) {\n  return nope(uv);\n}\n";
        let fs = ("t.glsl".to_string(), to_isf(source).unwrap());
        let files = super::super::IsfFiles { fs, vs: None, path: None, gl_transition: true };
        let e = files.compile().unwrap_err();
        assert_eq!((e.origin.as_str(), e.line), ("t.glsl", 4), "{e}");
    }
}
