//! ISF GLSL into what naga's GLSL front end takes: `#version 450`, separate textures and a
//! sampler instead of `sampler2D` uniforms, the inputs in one std140 uniform block (bools as
//! ints), `gl_FragColor` and `varying` replaced, the `IMG_*` macros expanded, and a `main` of
//! ours around the shader's (renamed `isf_main`) that writes the colour out.
//!
//! Orientation: every texture indra holds has its top row first, and ISF's coordinates have y up.
//! So a sample flips `y` (`_isf_flip`) and `gl_FragCoord` is seen as GL shows it
//! (`isf_FragCoord`, y from the bottom) — buffers a shader writes are stored top row first like
//! every other image, and nothing needs a copy to be turned over.
//!
//! Colour: ISF shaders work in display values (what a GL host's 8-bit textures hold); indra's
//! images are linear. A node input is encoded to sRGB as it is sampled, and the pass that makes
//! the node's image decodes its colour to linear; buffers between passes hold display values.
//!
//! The rewrite keeps every line where it was, so an error naga finds is reported at its line in
//! the `.fs` or `.vs` file.

use std::collections::BTreeMap;

use super::header::{Header, InputKind};

/// The binding of the uniform block.
pub const UNIFORM_BINDING: u32 = 0;
/// The binding of the one sampler.
pub const SAMPLER_BINDING: u32 = 1;
/// The binding of the first texture; the others follow in [`Program::textures`] order.
pub const FIRST_TEXTURE_BINDING: u32 = 2;

/// Where a texture the shader samples comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSource {
    /// An `image` input, wired from another node (linear, encoded when sampled).
    Node,
    /// A pass `TARGET` of this shader.
    Target,
    /// An `IMPORTED` image file.
    Imported,
    /// An `audio` (waveform) input.
    Audio,
    /// An `audioFFT` (spectrum) input.
    AudioFft,
}

/// One texture the shader samples: its name in the ISF file and where it comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureSlot {
    /// The name the shader uses.
    pub name: String,
    /// Where its texels come from.
    pub source: TextureSource,
}

/// The type of one uniform block member.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `int`.
    Int,
    /// `float`.
    Float,
    /// `vec2`.
    Vec2,
    /// `vec4`.
    Vec4,
}

impl Scalar {
    fn glsl(self) -> &'static str {
        match self {
            Scalar::Int => "int",
            Scalar::Float => "float",
            Scalar::Vec2 => "vec2",
            Scalar::Vec4 => "vec4",
        }
    }

    /// (size, alignment) in std140.
    fn layout(self) -> (u32, u32) {
        match self {
            Scalar::Int | Scalar::Float => (4, 4),
            Scalar::Vec2 => (8, 8),
            Scalar::Vec4 => (16, 16),
        }
    }
}

/// The uniform block: members with their std140 offsets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UniformLayout {
    /// (GLSL name, type, byte offset).
    pub members: Vec<(String, Scalar, u32)>,
    /// The block's size in bytes (a multiple of 16).
    pub size: u32,
}

impl UniformLayout {
    fn push(&mut self, name: &str, ty: Scalar) {
        let (size, align) = ty.layout();
        let offset = self.size.next_multiple_of(align);
        self.members.push((name.to_string(), ty, offset));
        self.size = offset + size;
    }

    fn finish(&mut self) {
        self.size = self.size.next_multiple_of(16).max(16);
    }

    /// The byte offset of member `name`.
    pub fn offset(&self, name: &str) -> Option<u32> {
        self.members.iter().find(|(n, _, _)| n == name).map(|m| m.2)
    }

    fn declaration(&self) -> String {
        let members: String = self.members.iter().map(|(n, ty, _)| format!(" {} {n};", ty.glsl())).collect();
        format!("layout(std140, set = 0, binding = {UNIFORM_BINDING}) uniform IsfUniforms {{{members} }};")
    }
}

/// An ISF shader made ready for naga: both stages' GLSL and what the host binds.
#[derive(Clone, Debug)]
pub struct Program {
    /// The fragment stage.
    pub fragment: Stage,
    /// The vertex stage (the `.vs` companion, or the default that only places the quad).
    pub vertex: Stage,
    /// The uniform block.
    pub uniforms: UniformLayout,
    /// The textures, bound from [`FIRST_TEXTURE_BINDING`] on, in this order.
    pub textures: Vec<TextureSlot>,
    /// The same fragment shader as a compute shader writing a storage image (one per target
    /// format: `rgba8`, `rgba16f`), where it needs nothing only rasterising gives — no `.vs`
    /// (varyings without one are plain globals), no derivatives or `discard`. GPUs built for compute (the H200) rasterise at a
    /// fraction of their memory bandwidth; this runs at full speed on all.
    pub compute: Option<[Stage; 2]>,
    /// Whether a rasterised pass draws every pixel of its target: the vertex stage leaves the
    /// quad where `isf_vertShaderInit` puts it (it never writes `gl_Position` itself) and the
    /// fragment stage never discards, so the target needs no clear first.
    pub covers_target: bool,
}

/// The binding of the storage image a compute variant writes: after the textures.
pub fn storage_binding(textures: usize) -> u32 {
    FIRST_TEXTURE_BINDING + textures as u32
}

/// The storage formats of [`Program::compute`], in order.
pub const COMPUTE_FORMATS: [&str; 2] = ["rgba8", "rgba16f"];

/// Identifiers a shader may use only when rasterised.
const FRAGMENT_ONLY: &[&str] =
    &["dFdx", "dFdy", "fwidth", "discard", "gl_FrontFacing", "gl_PointCoord", "gl_FragDepth"];

/// One stage's translated text.
#[derive(Clone, Debug)]
pub struct Stage {
    /// The GLSL naga parses.
    pub glsl: String,
    /// Lines of ours before the file's first line: translated line `n` is the file's `n − prelude`.
    pub prelude_lines: u32,
}

/// A translation error: the stage (`"fs"` or `"vs"`), the 1-based line, and what is wrong.
pub type TranslateError = (&'static str, u32, String);

/// The built-in uniforms, before the inputs. `_isf_final` is 1 in the pass that writes the
/// node's (linear) image.
const BUILT_INS: &[(&str, Scalar)] = &[
    ("PASSINDEX", Scalar::Int),
    ("FRAMEINDEX", Scalar::Int),
    ("TIME", Scalar::Float),
    ("TIMEDELTA", Scalar::Float),
    ("RENDERSIZE", Scalar::Vec2),
    ("_isf_final", Scalar::Int),
    ("DATE", Scalar::Vec4),
];

/// Translates `fs` (and its `.vs` companion) as `header` declares them.
pub fn translate(header: &Header, fs: &str, vs: Option<&str>) -> Result<Program, TranslateError> {
    let mut textures = Vec::new();
    let mut add = |name: &str, source: TextureSource| {
        if !textures.iter().any(|t: &TextureSlot| t.name == name) {
            textures.push(TextureSlot { name: name.to_string(), source });
        }
    };
    for input in &header.inputs {
        match input.kind {
            InputKind::Image => add(&input.name, TextureSource::Node),
            InputKind::Audio { .. } => add(&input.name, TextureSource::Audio),
            InputKind::AudioFft { .. } => add(&input.name, TextureSource::AudioFft),
            _ => {}
        }
    }
    for pass in &header.passes {
        if let Some(t) = &pass.target {
            add(t, TextureSource::Target);
        }
    }
    for (name, _) in &header.imported {
        add(name, TextureSource::Imported);
    }

    let mut uniforms = UniformLayout::default();
    for (name, ty) in BUILT_INS {
        uniforms.push(name, *ty);
    }
    let mut bools = Vec::new();
    for input in &header.inputs {
        match &input.kind {
            InputKind::Float { .. } => uniforms.push(&input.name, Scalar::Float),
            InputKind::Long { .. } => uniforms.push(&input.name, Scalar::Int),
            InputKind::Bool { .. } | InputKind::Event => {
                uniforms.push(&format!("_isf_b_{}", input.name), Scalar::Int);
                bools.push(input.name.clone());
            }
            InputKind::Color { .. } => uniforms.push(&input.name, Scalar::Vec4),
            InputKind::Point2D { .. } => uniforms.push(&input.name, Scalar::Vec2),
            _ => {}
        }
    }
    for t in &textures {
        uniforms.push(&format!("_isf_size_{}", t.name), Scalar::Vec2);
    }
    uniforms.finish();

    let declarations = {
        let mut d = uniforms.declaration();
        d.push_str(&format!(" layout(set = 0, binding = {SAMPLER_BINDING}) uniform sampler _isf_sampler;"));
        for (i, t) in textures.iter().enumerate() {
            let binding = FIRST_TEXTURE_BINDING + i as u32;
            d.push_str(&format!(" layout(set = 0, binding = {binding}) uniform texture2D _isf_tex_{};", t.name));
        }
        d
    };
    let context = Context { textures: &textures, bools: &bools, uniforms: &uniforms };

    // Varyings get locations by name, the same in both stages; 0 is isf_FragNormCoord.
    let vs_text = vs.unwrap_or(DEFAULT_VS);
    let mut locations = Locations::default();
    for (text, stage) in [(vs_text, StageKind::Vertex), (fs, StageKind::Fragment)] {
        let scan = rewrite(text, stage, &context, &mut locations.clone()).map_err(|(l, m)| (stage.tag(), l, m))?;
        for v in scan.varyings {
            locations.assign(&v.name, v.count);
        }
    }

    let fs_out = rewrite(fs, StageKind::Fragment, &context, &mut locations).map_err(|(l, m)| ("fs", l, m))?;
    let vs_out = rewrite(vs_text, StageKind::Vertex, &context, &mut locations).map_err(|(l, m)| ("vs", l, m))?;
    let fragment = assemble(
        &[
            "#version 450".into(),
            declarations.clone(),
            format!("{COMMON} layout(location = 0) in vec2 isf_FragNormCoord; layout(location = 0) out vec4 _isf_out;"),
            "vec4 isf_FragColor; vec4 isf_FragCoord;".into(),
        ],
        &fs_out.text,
        &format!(
            "void main() {{ isf_FragCoord = vec4(gl_FragCoord.x, RENDERSIZE.y - gl_FragCoord.y, gl_FragCoord.zw); \
             isf_FragColor = vec4(0.0); {} {} isf_main(); \
             _isf_out = _isf_final != 0 ? _isf_decode(isf_FragColor) : isf_FragColor; }}",
            fs_out.inits, fs_out.copies
        ),
    );
    let vertex = assemble(
        &[
            "#version 450".into(),
            declarations.clone(),
            format!("{COMMON} layout(location = 0) out vec2 isf_FragNormCoord; {VERT_INIT}"),
        ],
        &vs_out.text,
        &format!(
            "void main() {{ {} isf_main(); {} gl_Position.z = (gl_Position.z + gl_Position.w) * 0.5; }}",
            vs_out.inits, vs_out.copies
        ),
    );
    let rasterised_only = vs.is_some() || FRAGMENT_ONLY.iter().any(|w| contains_word(&fs_out.text, w));
    let cs_out = if rasterised_only {
        None
    } else {
        Some(rewrite(fs, StageKind::Compute, &context, &mut locations).map_err(|(l, m)| ("fs", l, m))?)
    };
    let compute = cs_out.map(|cs_out| {
        COMPUTE_FORMATS.map(|format| {
            let binding = storage_binding(textures.len());
            assemble(
                &[
                    "#version 450".into(),
                    format!("layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in; {declarations}"),
                    format!(
                        "layout(set = 0, binding = {binding}, {format}) uniform writeonly image2D _isf_dst; {COMMON} \
                         vec2 isf_FragNormCoord;"
                    ),
                    "vec4 isf_FragColor; vec4 isf_FragCoord;".into(),
                ],
                &cs_out.text,
                &format!(
                    "void main() {{ ivec2 _isf_p = ivec2(gl_GlobalInvocationID.xy); \
                     if (_isf_p.x >= int(RENDERSIZE.x) || _isf_p.y >= int(RENDERSIZE.y)) {{ return; }} \
                     vec2 _isf_c = vec2(_isf_p) + 0.5; \
                     isf_FragNormCoord = vec2(_isf_c.x / RENDERSIZE.x, 1.0 - _isf_c.y / RENDERSIZE.y); \
                     isf_FragCoord = vec4(_isf_c.x, RENDERSIZE.y - _isf_c.y, 0.5, 1.0); \
                     isf_FragColor = vec4(0.0); {} isf_main(); \
                     imageStore(_isf_dst, _isf_p, _isf_final != 0 ? _isf_decode(isf_FragColor) : isf_FragColor); }}",
                    cs_out.inits
                ),
            )
        })
    });
    let covers_target = !contains_word(&vs_out.text, "gl_Position") && !contains_word(&fs_out.text, "discard");
    Ok(Program { fragment, vertex, uniforms, textures, compute, covers_target })
}

/// Whether `word` occurs in `text` as a whole identifier.
fn contains_word(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(i, _)| {
        let before = text[..i].bytes().next_back().is_none_or(|c| !is_ident(c));
        let after = text[i + word.len()..].bytes().next().is_none_or(|c| !is_ident(c));
        before && after
    })
}

/// The vertex stage when a shader has no `.vs`.
const DEFAULT_VS: &str = "void main() { isf_vertShaderInit(); }\n";

/// Helpers both stages get (one line).
/// `_isf_encode` takes a node's image (linear, premultiplied) to what ISF shaders expect
/// (display values, straight alpha); `_isf_decode` goes back.
const COMMON: &str = "vec2 _isf_flip(vec2 c) { return vec2(c.x, 1.0 - c.y); } \
    vec4 _isf_encode(vec4 c) { float a = clamp(c.a, 0.0, 1.0); vec3 x = max(a > 0.0 ? c.rgb / a : c.rgb, vec3(0.0)); \
    return vec4(mix(x * 12.92, 1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), x)), a); } \
    vec4 _isf_decode(vec4 c) { float a = clamp(c.a, 0.0, 1.0); vec3 x = max(c.rgb, vec3(0.0)); \
    return vec4(mix(x / 12.92, pow((x + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), x)) * a, a); }";

/// `isf_vertShaderInit`: the quad (two triangles over the whole target, from the vertex index)
/// and the normalised coordinate, y up.
const VERT_INIT: &str = "void isf_vertShaderInit() { int i = int(gl_VertexIndex); \
    float x = (i == 1 || i == 4 || i == 5) ? 1.0 : -1.0; float y = (i == 2 || i == 3 || i == 5) ? 1.0 : -1.0; \
    gl_Position = vec4(x, y, 0.0, 1.0); isf_FragNormCoord = vec2(x, y) * 0.5 + 0.5; }";

fn assemble(prelude: &[String], body: &str, epilogue: &str) -> Stage {
    let mut glsl = prelude.join("\n");
    glsl.push('\n');
    glsl.push_str(body);
    glsl.push('\n');
    glsl.push_str(epilogue);
    glsl.push('\n');
    Stage { glsl, prelude_lines: prelude.len() as u32 }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum StageKind {
    Vertex,
    Fragment,
    /// The fragment shader as a compute shader: no stage before it, varyings are plain globals.
    Compute,
}

impl StageKind {
    fn tag(self) -> &'static str {
        match self {
            StageKind::Vertex => "vs",
            StageKind::Fragment | StageKind::Compute => "fs",
        }
    }
}

/// Varying name → (first location, count).
#[derive(Clone, Default)]
struct Locations {
    by_name: BTreeMap<String, (u32, u32)>,
    next: u32,
}

/// The most locations varyings may use besides `isf_FragNormCoord` (WebGPU guarantees 16).
const MAX_VARYING_LOCATIONS: u32 = 14;

impl Locations {
    fn assign(&mut self, name: &str, count: u32) {
        if name != "isf_FragNormCoord" && !self.by_name.contains_key(name) {
            self.by_name.insert(name.to_string(), (self.next + 1, count));
            self.next += count;
        }
    }
}

struct Context<'a> {
    textures: &'a [TextureSlot],
    bools: &'a [String],
    uniforms: &'a UniformLayout,
}

impl Context<'_> {
    /// Whether `name` is something the host declares (an input, a built-in, an image).
    fn declares(&self, name: &str) -> bool {
        self.uniforms.offset(name).is_some()
            || self.bools.iter().any(|b| b == name)
            || self.textures.iter().any(|t| t.name == name)
    }
}

struct Varying {
    name: String,
    count: u32,
}

struct Rewritten {
    text: String,
    varyings: Vec<Varying>,
    /// Statements copying array varyings between the shader's array and the per-element
    /// varyings (into the array before the fragment shader runs, out of it after the vertex).
    copies: String,
    /// Assignments of globals whose initializers GL runs at the start of main.
    inits: String,
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

fn rewrite(
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

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

#[cfg(test)]
mod tests {
    use super::*;

    fn program(fs: &str) -> Program {
        let header = Header::parse(fs).unwrap();
        translate(&header, fs, None).unwrap()
    }

    #[test]
    fn macros_expand_and_lines_stay() {
        let fs = "/*{ \"INPUTS\": [ { \"NAME\": \"inputImage\", \"TYPE\": \"image\" },\n\
                  { \"NAME\": \"on\", \"TYPE\": \"bool\" } ] }*/\n\
                  void main() {\n\
                  vec4 c = IMG_NORM_PIXEL(inputImage,\n isf_FragNormCoord);\n\
                  if (on) gl_FragColor = c;\n}\n";
        let p = program(fs);
        let body: Vec<&str> = p.fragment.glsl.lines().skip(p.fragment.prelude_lines as usize).collect();
        assert!(body[2].contains("void isf_main()"), "{body:?}");
        assert!(body[3].contains("_isf_encode(textureLod(sampler2D(_isf_tex_inputImage"), "{}", body[3]);
        assert!(body[5].contains("if ((_isf_b_on != 0)) isf_FragColor = c;"), "{}", body[5]);
        assert_eq!(p.textures, [TextureSlot { name: "inputImage".into(), source: TextureSource::Node }]);
        assert_eq!(p.uniforms.offset("RENDERSIZE"), Some(16));
        assert_eq!(p.uniforms.offset("DATE"), Some(32));
        assert_eq!(p.uniforms.offset("_isf_b_on"), Some(48));
        assert_eq!(p.uniforms.size % 16, 0);
    }

    #[test]
    fn an_unknown_image_is_a_located_error() {
        let fs = "/*{}*/\nvoid main() {\n gl_FragColor = IMG_THIS_PIXEL(nothing);\n}\n";
        let header = Header::parse(fs).unwrap();
        let (stage, line, message) = translate(&header, fs, None).unwrap_err();
        assert_eq!((stage, line), ("fs", 3));
        assert!(message.contains("'nothing'"), "{message}");
    }
}
