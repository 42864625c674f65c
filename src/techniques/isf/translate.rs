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

use super::header::{Header, InputKind};
use super::program::{
    COMPUTE_FORMATS, FIRST_TEXTURE_BINDING, Program, SAMPLER_BINDING, Scalar, Stage, TextureSlot, TextureSource,
    TranslateError, UniformLayout, storage_binding,
};
use super::rewrite::{Context, Locations, StageKind, is_ident, rewrite};

/// Identifiers a shader may use only when rasterised.
const FRAGMENT_ONLY: &[&str] =
    &["dFdx", "dFdy", "fwidth", "discard", "gl_FrontFacing", "gl_PointCoord", "gl_FragDepth"];

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

/// Helpers every stage gets (one line).
/// `_isf_encode` takes a node's image (linear, premultiplied) to what ISF shaders expect
/// (display values, straight alpha); `_isf_decode` goes back.
/// `_isf_pow` and `_isf_smoothstep` are built-ins as GL hosts compute them where GLSL leaves
/// the result undefined and shaders rely on the hosts' answer (the reference renderer's, on
/// SwiftShader, and desktop drivers'): `pow` of a negative base is `pow(|x|, y)` (Butterfly Wave
/// Scrawler raises a sine to the 5th, which Vulkan drivers make NaN), and `smoothstep` is the
/// spec's formula whatever its edges, with equal edges a step at them (RGB Halftone's dots of a
/// channel at 0: GL divides by zero to ±∞).
const COMMON: &str = "vec2 _isf_flip(vec2 c) { return vec2(c.x, 1.0 - c.y); } \
    vec4 _isf_encode(vec4 c) { float a = clamp(c.a, 0.0, 1.0); vec3 x = max(a > 0.0 ? c.rgb / a : c.rgb, vec3(0.0)); \
    return vec4(mix(x * 12.92, 1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), x)), a); } \
    vec4 _isf_decode(vec4 c) { float a = clamp(c.a, 0.0, 1.0); vec3 x = max(c.rgb, vec3(0.0)); \
    return vec4(mix(x / 12.92, pow((x + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), x)) * a, a); } \
    float _isf_pow(float x, float y) { return pow(abs(x), y); } \
    vec2 _isf_pow(vec2 x, vec2 y) { return pow(abs(x), y); } vec3 _isf_pow(vec3 x, vec3 y) { return pow(abs(x), y); } \
    vec4 _isf_pow(vec4 x, vec4 y) { return pow(abs(x), y); } \
    float _isf_smoothstep(float a, float b, float x) { if (a == b) { return x > a ? 1.0 : 0.0; } \
    float t = clamp((x - a) / (b - a), 0.0, 1.0); return t * t * (3.0 - 2.0 * t); } \
    vec2 _isf_smoothstep(vec2 a, vec2 b, vec2 x) { \
    return vec2(_isf_smoothstep(a.x, b.x, x.x), _isf_smoothstep(a.y, b.y, x.y)); } \
    vec3 _isf_smoothstep(vec3 a, vec3 b, vec3 x) { \
    return vec3(_isf_smoothstep(a.xy, b.xy, x.xy), _isf_smoothstep(a.z, b.z, x.z)); } \
    vec4 _isf_smoothstep(vec4 a, vec4 b, vec4 x) { \
    return vec4(_isf_smoothstep(a.xy, b.xy, x.xy), _isf_smoothstep(a.zw, b.zw, x.zw)); } \
    vec2 _isf_smoothstep(float a, float b, vec2 x) { return _isf_smoothstep(vec2(a), vec2(b), x); } \
    vec3 _isf_smoothstep(float a, float b, vec3 x) { return _isf_smoothstep(vec3(a), vec3(b), x); } \
    vec4 _isf_smoothstep(float a, float b, vec4 x) { return _isf_smoothstep(vec4(a), vec4(b), x); }";

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
