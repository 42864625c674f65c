//! The line-keeping rewrite of one ISF stage's GLSL: `gl_FragColor`, `varying` and the `IMG_*`
//! macros replaced word by word, global initialisers moved into the shader's `main`, varyings
//! given locations. Nothing is added or removed across lines, so naga's errors keep their line.

use std::collections::BTreeMap;

use super::program::{TextureSlot, TextureSource, UniformLayout};

#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum StageKind {
    Vertex,
    Fragment,
    /// The fragment shader as a compute shader: no stage before it, varyings are plain globals.
    Compute,
}

impl StageKind {
    pub(super) fn tag(self) -> &'static str {
        match self {
            StageKind::Vertex => "vs",
            StageKind::Fragment | StageKind::Compute => "fs",
        }
    }
}

/// Varying name → (first location, count).
#[derive(Clone, Default)]
pub(super) struct Locations {
    pub(super) by_name: BTreeMap<String, (u32, u32)>,
    pub(super) next: u32,
}

/// The most locations varyings may use besides `isf_FragNormCoord` (WebGPU guarantees 16).
const MAX_VARYING_LOCATIONS: u32 = 14;

impl Locations {
    pub(super) fn assign(&mut self, name: &str, count: u32) {
        if name != "isf_FragNormCoord" && !self.by_name.contains_key(name) {
            self.by_name.insert(name.to_string(), (self.next + 1, count));
            self.next += count;
        }
    }
}

pub(super) struct Context<'a> {
    pub(super) textures: &'a [TextureSlot],
    pub(super) bools: &'a [String],
    pub(super) uniforms: &'a UniformLayout,
}

impl Context<'_> {
    /// Whether `name` is something the host declares (an input, a built-in, an image).
    pub(super) fn declares(&self, name: &str) -> bool {
        self.uniforms.offset(name).is_some()
            || self.bools.iter().any(|b| b == name)
            || self.textures.iter().any(|t| t.name == name)
    }
}

pub(super) struct Varying {
    pub(super) name: String,
    pub(super) count: u32,
}

pub(super) struct Rewritten {
    pub(super) text: String,
    pub(super) varyings: Vec<Varying>,
    /// Statements copying array varyings between the shader's array and the per-element
    /// varyings (into the array before the fragment shader runs, out of it after the vertex).
    pub(super) copies: String,
    /// Assignments of globals whose initializers GL runs at the start of main.
    pub(super) inits: String,
}

/// The macros ISF defines over images.
const IMAGE_MACROS: &[&str] = &[
    "IMG_NORM_PIXEL",
    "IMG_PIXEL",
    "IMG_THIS_PIXEL",
    "IMG_THIS_NORM_PIXEL",
    "IMG_SIZE",
    "texture2D",
    "texture2DRect",
    "texture",
];

pub(super) fn rewrite(
    src: &str,
    stage: StageKind,
    cx: &Context<'_>,
    locations: &mut Locations,
) -> Result<Rewritten, (u32, String)> {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len() + src.len() / 4);
    let mut varyings = Vec::new();
    let mut copies = String::new();
    let (mut i, mut depth) = (0usize, 0i32);
    let mut inits = String::new();
    let mut last_word = String::new();
    let line = |at: usize| super::header::line_of(src, at);
    while i < b.len() {
        let c = b[i];
        // Comments are kept as they are (the header among them): lines stay where they were.
        if src[i..].starts_with("//") {
            let end = src[i..].find('\n').map_or(b.len(), |e| i + e);
            out.push_str(&src[i..end]);
            i = end;
            continue;
        }
        if src[i..].starts_with("/*") {
            let end = src[i + 2..].find("*/").map_or(b.len(), |e| i + 2 + e + 2);
            out.push_str(&src[i..end]);
            i = end;
            continue;
        }
        if c == b'#' && src[..i].rsplit('\n').next().is_some_and(|l| l.trim().is_empty()) {
            let end = src[i..].find('\n').map_or(b.len(), |e| i + e);
            let directive = src[i + 1..end].trim_start();
            if directive.starts_with("version") || directive.starts_with("extension") {
                // Ours comes first; a file's own #version would be a second one.
                i = end;
                continue;
            }
        }
        if c == b'{' || c == b'(' {
            depth += 1;
        } else if c == b'}' || c == b')' {
            depth -= 1;
        }
        let starts_word = (c.is_ascii_alphabetic() || c == b'_') && (i == 0 || !is_ident(b[i - 1]));
        if !starts_word {
            out.push(c as char);
            i += 1;
            continue;
        }
        let start = i;
        while i < b.len() && is_ident(b[i]) {
            i += 1;
        }
        let word = &src[start..i];
        if IMAGE_MACROS.contains(&word)
            && let Some((args, end)) = call_args(src, i)
        {
            let mut expanded = Vec::new();
            for a in &args {
                expanded.push(rewrite(a, stage, cx, locations)?.text);
            }
            match expand(word, &expanded, cx) {
                Some(Ok(text)) => {
                    // Keep the lines the call spanned.
                    let lost = src[i..end].matches('\n').count().saturating_sub(text.matches('\n').count());
                    out.push_str(&text);
                    out.extend(std::iter::repeat_n('\n', lost));
                    i = end;
                    continue;
                }
                Some(Err(message)) => return Err((line(start), message)),
                None => {}
            }
        }
        if depth == 0
            && GLOBAL_TYPES.contains(&word)
            && last_word != "const"
            && let Some((name, expression, end)) = global_initializer(src, i)
        {
            // GL drivers run a global's initializer at the start of main, so it may read
            // uniforms (`float ratio = RENDERSIZE.x / RENDERSIZE.y;`); naga wants a constant
            // there. Declare it bare and assign it first thing in main, as GL does.
            let expression = rewrite(&expression, stage, cx, locations)?.text;
            inits.push_str(&format!("{name} = {}; ", expression.replace('\n', " ")));
            out.push_str(&format!("{word} {name}"));
            out.extend(std::iter::repeat_n('\n', src[i..end].matches('\n').count()));
            i = end;
            last_word = name;
            continue;
        }
        if depth == 0 && word == "uniform" {
            // A shader that declares uniforms itself (old files redeclare their inputs): the
            // host's declaration stands; one the host does not know reads 0 in GL hosts, as a
            // plain global does here. A sampler of its own has nothing to sample.
            let end = src[i..].find(';').map(|e| i + e).ok_or_else(|| (line(start), "a uniform without ';'".into()))?;
            let words: Vec<&str> = src[i..end]
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|w| !w.is_empty() && !matches!(*w, "highp" | "mediump" | "lowp"))
                .collect();
            let ty = words.first().copied().unwrap_or_default();
            let names = &words[1.min(words.len())..];
            let unknown: Vec<&str> =
                names.iter().copied().filter(|n| !cx.declares(n.split('[').next().unwrap_or(n))).collect();
            out.extend(std::iter::repeat_n('\n', src[i..end].matches('\n').count()));
            if ty.starts_with("sampler") || unknown.is_empty() {
                i = end + 1;
            } else {
                out.push_str(&format!("{ty} {}", unknown.join(", ")));
                i = end;
            }
            continue;
        }
        if word == "gl_FragData" {
            // GL 2's array of outputs: an ISF shader has one.
            let rest = &src[i..];
            let index: String = rest.chars().take_while(|c| *c != ']').filter(|c| !c.is_whitespace()).collect();
            if index == "[0" {
                out.push_str("isf_FragColor");
                i += rest.find(']').map_or(0, |e| e + 1);
                continue;
            }
        }
        let global_io = depth == 0
            && (word == "varying"
                || (word == "in" && stage != StageKind::Vertex)
                || (word == "out" && stage == StageKind::Vertex));
        if global_io {
            let end = src[i..].find(';').map(|e| i + e).ok_or_else(|| (line(start), "a varying without ';'".into()))?;
            let (decl, names) = varying_declaration(&src[i..end], stage, locations).map_err(|m| (line(start), m))?;
            for (name, count) in names {
                if name == "isf_FragNormCoord" {
                    continue;
                }
                if count > 0 && locations.by_name.contains_key(&name) {
                    for k in 0..count {
                        let element = format!("_isf_v_{name}_{k}");
                        copies.push_str(&match stage {
                            StageKind::Vertex => format!("{element} = {name}[{k}]; "),
                            StageKind::Fragment => format!("{name}[{k}] = {element}; "),
                            StageKind::Compute => String::new(),
                        });
                    }
                }
                varyings.push(Varying { name, count: count.max(1) });
            }
            out.push_str(decl.strip_suffix(';').unwrap_or(&decl));
            out.extend(std::iter::repeat_n('\n', src[i..end].matches('\n').count()));
            i = end;
            continue;
        }
        out.push_str(&replace_word(word, stage, cx));
        last_word = word.to_string();
    }
    Ok(Rewritten { text: out, varyings, copies, inits })
}

/// An identifier's replacement (or itself).
fn replace_word(word: &str, stage: StageKind, cx: &Context<'_>) -> String {
    match word {
        "gl_FragColor" => return "isf_FragColor".into(),
        "gl_FragCoord" if stage != StageKind::Vertex => return "isf_FragCoord".into(),
        "main" => return "isf_main".into(),
        "vv_FragNormCoord" => return "isf_FragNormCoord".into(),
        "vv_vertShaderInit" => return "isf_vertShaderInit".into(),
        "attribute" => return "in".into(),
        // GLSL leaves these undefined where GL hosts agree on a value (see translate.rs, COMMON).
        "pow" => return "_isf_pow".into(),
        "smoothstep" => return "_isf_smoothstep".into(),
        _ => {}
    }
    if cx.bools.iter().any(|b| b == word) {
        return format!("(_isf_b_{word} != 0)");
    }
    // What GL hosts generate per image, which some shaders read directly.
    for t in cx.textures {
        let n = &t.name;
        if let Some(rest) = word.strip_prefix('_').and_then(|w| w.strip_prefix(n.as_str())) {
            match rest {
                "_imgSize" => return format!("_isf_size_{n}"),
                "_imgRect" => return format!("vec4(0.0, 0.0, _isf_size_{n})"),
                "_flip" => return "false".into(),
                "_texCoord" | "_normTexCoord" => return "isf_FragNormCoord".into(),
                _ => {}
            }
        }
    }
    word.to_string()
}

/// The types a global variable of an ISF shader may have.
const GLOBAL_TYPES: &[&str] = &[
    "float", "int", "uint", "bool", "vec2", "vec3", "vec4", "ivec2", "ivec3", "ivec4", "uvec2", "uvec3", "uvec4",
    "bvec2", "bvec3", "bvec4", "mat2", "mat3", "mat4",
];

/// After a type at the top level (ending at `at`): `name = expression;` as (name, expression, the
/// byte of its `;`), when it is one variable with an initializer.
fn global_initializer(src: &str, at: usize) -> Option<(String, String, usize)> {
    let rest = &src[at..];
    let name_start = rest.len() - rest.trim_start().len();
    let name_len = rest[name_start..].bytes().take_while(|c| is_ident(*c)).count();
    let name = &rest[name_start..name_start + name_len];
    let after = rest[name_start + name_len..].trim_start();
    if name.is_empty() || !after.starts_with('=') || after.starts_with("==") {
        return None;
    }
    let expression_start = at + rest.len() - after.len() + 1;
    let (mut depth, mut end) = (0i32, None);
    for (k, c) in src[expression_start..].char_indices() {
        match c {
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' => depth -= 1,
            ',' if depth == 0 => return None,
            ';' if depth == 0 => {
                end = Some(expression_start + k);
                break;
            }
            _ => {}
        }
    }
    let end = end?;
    Some((name.to_string(), src[expression_start..end].to_string(), end))
}

/// `varying vec2 a, b[3]` (after the keyword) as declarations with locations; the names and
/// array lengths (0: not an array).
fn varying_declaration(
    rest: &str,
    stage: StageKind,
    locations: &Locations,
) -> Result<(String, Vec<(String, u32)>), String> {
    let io = if stage == StageKind::Vertex { "out" } else { "in" };
    let mut words = rest.split(',');
    let first = words.next().unwrap_or_default().trim();
    let mut parts: Vec<&str> = first.split_whitespace().collect();
    let Some(first_name) = parts.pop() else { return Err("a varying without a name".into()) };
    let qualifiers_and_type = parts.join(" ");
    let mut out = String::new();
    let mut names = Vec::new();
    for raw in std::iter::once(first_name).chain(words.map(str::trim)) {
        let raw = raw.split_whitespace().collect::<String>();
        let matrix = qualifiers_and_type.split_whitespace().last().and_then(matrix_columns);
        let (name, count) = match raw.split_once('[') {
            Some((n, len)) => {
                let len = len.trim_end_matches(']');
                let count: u32 =
                    len.parse().map_err(|_| format!("varying array '{n}' needs a literal length, not '{len}'"))?;
                (n.to_string(), count.clamp(1, MAX_VARYING_LOCATIONS))
            }
            None => (raw.clone(), matrix.map_or(0, |(columns, _)| columns)),
        };
        if name == "isf_FragNormCoord" {
            names.push((name, count));
            continue;
        }
        if stage == StageKind::Compute {
            // Nothing feeds it: a plain global, zero, as an unwritten varying reads in GL hosts.
            let ty = qualifiers_and_type.split_whitespace().last().unwrap_or("float");
            let array = raw.find('[').map_or("", |b| &raw[b..]);
            out.push_str(&format!("{ty} {name}{array};"));
            names.push((name, 0));
            continue;
        }
        let (location, _) = locations.by_name.get(&name).copied().unwrap_or((1, 1));
        if location + count.max(1) > MAX_VARYING_LOCATIONS + 1 {
            return Err(format!("the varyings need more than {MAX_VARYING_LOCATIONS} locations"));
        }
        if count == 0 {
            out.push_str(&format!("layout(location = {location}) {io} {qualifiers_and_type} {name};"));
        } else {
            // naga takes no arrays or matrices between stages: one varying per element or
            // column, copied in main.
            let ty = qualifiers_and_type.split_whitespace().last().unwrap_or("float");
            let qualifiers = qualifiers_and_type.strip_suffix(ty).unwrap_or_default();
            let (global, element) = match matrix {
                Some((_, column)) => (format!("{ty} {name};"), column.to_string()),
                None => (format!("{ty} {name}[{count}];"), ty.to_string()),
            };
            out.push_str(&global);
            for k in 0..count {
                out.push_str(&format!(
                    " layout(location = {}) {io} {qualifiers}{element} _isf_v_{name}_{k};",
                    location + k
                ));
            }
        }
        names.push((name, count));
    }
    Ok((out, names))
}

/// A matrix type's columns and column type (`mat3` → 3 × `vec3`).
fn matrix_columns(ty: &str) -> Option<(u32, &'static str)> {
    match ty {
        "mat2" | "mat2x2" => Some((2, "vec2")),
        "mat3" | "mat3x3" => Some((3, "vec3")),
        "mat4" | "mat4x4" => Some((4, "vec4")),
        _ => None,
    }
}

/// One image macro or texture call, expanded; `None` when it is not about an ISF image (a
/// `texture()` call on something else) and stays as it is.
fn expand(word: &str, args: &[String], cx: &Context<'_>) -> Option<Result<String, String>> {
    let name = args.first().map(|a| a.trim().to_string()).unwrap_or_default();
    let Some(slot) = cx.textures.iter().find(|t| t.name == name) else {
        return word.starts_with("IMG_").then(|| {
            let known: Vec<&str> = cx.textures.iter().map(|t| t.name.as_str()).collect();
            Err(format!("{word}: '{name}' is not an image of this shader (images: {})", known.join(", ")))
        });
    };
    let want = |n: usize| {
        if args.len() == n {
            Ok(())
        } else {
            Err(format!("{word}({name}, …) takes {n} argument(s), not {}", args.len()))
        }
    };
    let sample = |norm: String| {
        let raw = format!("textureLod(sampler2D(_isf_tex_{name}, _isf_sampler), _isf_flip({norm}), 0.0)");
        if slot.source == TextureSource::Node { format!("_isf_encode({raw})") } else { raw }
    };
    let size = format!("_isf_size_{name}");
    Some(match word {
        "IMG_NORM_PIXEL" | "texture2D" | "texture" => want(2).map(|()| sample(format!("({})", args[1]))),
        "IMG_PIXEL" | "texture2DRect" => want(2).map(|()| sample(format!("(({}) / {size})", args[1]))),
        "IMG_THIS_PIXEL" | "IMG_THIS_NORM_PIXEL" => want(1).map(|()| sample("isf_FragNormCoord".into())),
        _ => want(1).map(|()| size),
    })
}

/// The comma-separated arguments of a call whose name ends at `at` (spaces, then `(`), and the
/// byte after its `)`; `None` if no call follows.
fn call_args(src: &str, at: usize) -> Option<(Vec<String>, usize)> {
    let open = at + src[at..].len() - src[at..].trim_start().len();
    if src.as_bytes().get(open) != Some(&b'(') {
        return None;
    }
    let (mut depth, mut args, mut start) = (0i32, Vec::new(), open + 1);
    for (k, c) in src[open..].char_indices() {
        let pos = open + k;
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => {
                depth -= 1;
                if depth == 0 {
                    args.push(src[start..pos].to_string());
                    return Some((args, pos + 1));
                }
            }
            ',' if depth == 1 => {
                args.push(src[start..pos].to_string());
                start = pos + 1;
            }
            _ => {}
        }
    }
    None
}

pub(super) fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}
