//! An ISF file, start to end on the CPU: header, translation, naga's GLSL front end and
//! validation. Every error is one [`ShaderError`] at its line in the `.fs` or `.vs` file — what
//! scene checks, `indra check` and live reload report.

use naga::front::glsl::{Frontend, Options};

use super::header::Header;
use super::program::{Program, Stage};
use super::translate::translate;
use crate::gpu::ShaderError;

/// An ISF shader ready to build: its header, what the host binds, and both stages as naga modules.
#[derive(Clone, Debug)]
pub struct Compiled {
    /// The parsed header.
    pub header: Header,
    /// Bindings and the uniform layout.
    pub program: Program,
    /// The vertex stage.
    pub vertex: naga::Module,
    /// The fragment stage.
    pub fragment: naga::Module,
    /// The compute variants (see [`Program::compute`]), one per storage format, where the shader
    /// has them and naga takes them; `None`: it is rasterised.
    pub compute: Option<[naga::Module; 2]>,
}

/// The `.fs` text and, if there is one, the `.vs` companion, each with the origin its errors name.
pub struct Sources<'a> {
    /// (origin, text) of the fragment shader.
    pub fs: (&'a str, &'a str),
    /// (origin, text) of the vertex shader, if the file has one.
    pub vs: Option<(&'a str, &'a str)>,
}

/// Parses, translates and validates `sources`.
pub fn compile(sources: &Sources<'_>) -> Result<Compiled, ShaderError> {
    let (fs_origin, fs) = sources.fs;
    let header = Header::parse(fs).map_err(|(line, message)| located(fs_origin, line, 1, message))?;
    check_sizes(&header).map_err(|message| located(fs_origin, header.passes_line, 1, message))?;
    let program = translate(&header, fs, sources.vs.map(|v| v.1)).map_err(|(stage, line, message)| {
        let origin = if stage == "vs" { sources.vs.map_or(fs_origin, |v| v.0) } else { fs_origin };
        located(origin, line, 1, message)
    })?;
    let vs_origin = sources.vs.map_or("<indra>/isf_default.vs", |v| v.0);
    let fragment = stage_module(fs_origin, &program.fragment, naga::ShaderStage::Fragment)?;
    let vertex = stage_module(vs_origin, &program.vertex, naga::ShaderStage::Vertex)?;
    // The fragment stage is what errors are reported from; a compute variant naga refuses
    // (a construct only rasterising allows) leaves the shader rasterised.
    let compute = program.compute.as_ref().and_then(|[a, b]| {
        let module = |s: &Stage| stage_module(fs_origin, s, naga::ShaderStage::Compute).ok();
        Some([module(a)?, module(b)?])
    });
    Ok(Compiled { header, program, vertex, fragment, compute })
}

/// The size expressions of every pass, evaluated at 1920×1080 with the inputs' defaults: one
/// that does not parse, names an unknown variable, or gives 0, a negative or a non-finite
/// number is refused with the file, and so are targets that take more than
/// [`MAX_NODE_TARGET_BYTES`](super::targets::MAX_NODE_TARGET_BYTES) together (the node checks
/// again at its render size, against the device).
fn check_sizes(header: &Header) -> Result<(), String> {
    let var = super::targets::default_var(header, (1920, 1080));
    super::targets::pass_sizes(&header.passes, (1920, 1080), CHECK_MAX_SIDE, &var).map(|_| ())
}

/// The largest side a pass may ask for where no device is at hand (what desktop GPUs allow).
const CHECK_MAX_SIDE: u32 = 16_384;

fn stage_module(origin: &str, stage: &Stage, kind: naga::ShaderStage) -> Result<naga::Module, ShaderError> {
    let relocate = |mut e: ShaderError| {
        if e.line > stage.prelude_lines {
            e.line -= stage.prelude_lines;
        } else {
            e.origin = format!("{origin} (indra's ISF prelude)");
        }
        e
    };
    let module = Frontend::default().parse(&Options::from(kind), &stage.glsl).map_err(|errors| {
        let first = errors.errors.first();
        let (line, column) =
            first.and_then(|e| e.location(&stage.glsl)).map(|l| (l.line_number, l.line_position)).unwrap_or((1, 1));
        let message = first.map_or_else(|| "the GLSL does not parse".to_string(), |e| e.kind.to_string());
        let more = errors.errors.len().saturating_sub(1);
        let message = if more > 0 { format!("{message} (and {more} more)") } else { message };
        relocate(located(origin, line, column, message))
    })?;
    crate::gpu::validate_module(origin, &stage.glsl, &module).map_err(relocate)?;
    Ok(module)
}

fn located(origin: &str, line: u32, column: u32, message: String) -> ShaderError {
    ShaderError { origin: origin.to_string(), line: line.max(1), column: column.max(1), message }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn compile_file(fs: &str) -> Result<Compiled, ShaderError> {
        compile(&Sources { fs: ("t.fs", fs), vs: None })
    }

    #[test]
    fn a_glsl_error_is_located_in_the_fs_file() {
        let fs = "/*{ \"INPUTS\": [] }*/\nvoid main() {\n    float x = 1.0;\n    gl_FragColor = vec4(y);\n}\n";
        let e = compile_file(fs).unwrap_err();
        assert_eq!((e.origin.as_str(), e.line), ("t.fs", 4), "{e}");
        let bad_header = compile_file("/*{ \"INPUTS\": [ }*/ void main() {}").unwrap_err();
        assert!(bad_header.message.contains("not JSON"), "{bad_header}");
    }

    #[test]
    fn a_bad_size_expression_is_located_at_passes() {
        for (expression, says) in [("floor($WIDTH", "floor"), ("$WIDTH - $WIDTH", "is 0"), ("$DEPTH", "$DEPTH")] {
            let fs = format!(
                "/*{{\n\"PASSES\": [\n {{ \"TARGET\": \"a\", \"WIDTH\": \"{expression}\" }}, {{}} ] }}*/\nvoid main() {{}}\n"
            );
            let e = compile_file(&fs).unwrap_err();
            assert_eq!(e.line, 2, "{e}");
            assert!(e.message.contains(says), "{e}");
        }
    }

    #[test]
    fn what_older_files_write_compiles() {
        // GL ES guards and precision, gl_FragData, an input declared again, a uniform the host
        // does not know (0, as in GL hosts), a varying with no vertex stage to feed it.
        let fs = r#"/*{ "INPUTS": [ { "NAME": "inputImage", "TYPE": "image" }, { "NAME": "amt", "TYPE": "float" } ] }*/
#ifdef GL_ES
precision mediump float;
#endif
uniform sampler2D inputImage;
uniform float amt, extra;
varying vec2 left_coord;
const int N = 2;
void main() {
    vec4 c = vec4(0.0);
    for (int i = 0; i < N; i++) c += texture2D(inputImage, vv_FragNormCoord + left_coord * float(i));
    gl_FragData[0] = c * amt + extra;
}
"#;
        let c = compile_file(fs).unwrap_or_else(|e| panic!("{e}"));
        assert!(c.compute.is_some(), "no vertex stage: it runs as compute");
    }

    #[test]
    fn a_good_file_compiles_both_stages() {
        let fs = "/*{ \"INPUTS\": [ { \"NAME\": \"level\", \"TYPE\": \"float\" } ] }*/\n\
                  void main() { gl_FragColor = vec4(isf_FragNormCoord, level, TIME); }\n";
        let c = compile_file(fs).unwrap();
        assert_eq!(c.fragment.entry_points.len(), 1);
        assert_eq!(c.vertex.entry_points[0].stage, naga::ShaderStage::Vertex);
    }
}
