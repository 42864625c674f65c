//! An ISF file, start to end on the CPU: header, translation, naga's GLSL front end and
//! validation. Every error is one [`ShaderError`] at its line in the `.fs` or `.vs` file — what
//! scene checks, `indra check` and live reload report.

use naga::front::glsl::{Frontend, Options};

use super::header::Header;
use super::translate::{Program, Stage, translate};
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
    let program = translate(&header, fs, sources.vs.map(|v| v.1)).map_err(|(stage, line, message)| {
        let origin = if stage == "vs" { sources.vs.map_or(fs_origin, |v| v.0) } else { fs_origin };
        located(origin, line, 1, message)
    })?;
    let vs_origin = sources.vs.map_or("<indra>/isf_default.vs", |v| v.0);
    let fragment = stage_module(fs_origin, &program.fragment, naga::ShaderStage::Fragment)?;
    let vertex = stage_module(vs_origin, &program.vertex, naga::ShaderStage::Vertex)?;
    Ok(Compiled { header, program, vertex, fragment })
}

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
    fn a_good_file_compiles_both_stages() {
        let fs = "/*{ \"INPUTS\": [ { \"NAME\": \"level\", \"TYPE\": \"float\" } ] }*/\n\
                  void main() { gl_FragColor = vec4(isf_FragNormCoord, level, TIME); }\n";
        let c = compile_file(fs).unwrap();
        assert_eq!(c.fragment.entry_points.len(), 1);
        assert_eq!(c.vertex.entry_points[0].stage, naga::ShaderStage::Vertex);
    }
}
