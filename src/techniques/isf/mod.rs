//! ISF import: a shader in the Interactive Shader Format — what VDMX, Resolume, MadMapper and
//! ossia score read — as a node like any other. The file's JSON header declares its inputs: each
//! number, option, switch, event, colour and point becomes one of the node's parameters (so the
//! panel, OSC, OSCQuery, MIDI and audio learn, presets, tracks and LFOs reach it), each `image`
//! one of its input slots, wired in the scene. Its passes (`PASSES`: targets, persistent feedback
//! buffers, float buffers, sizes as expressions) are frame-graph passes.
//!
//! - [`header`]: the JSON header; [`expr`]: pass sizes; [`translate`]: the GLSL rewrite;
//!   [`compile`]: naga's GLSL front end and validation, errors at the `.fs`/`.vs` line;
//!   `pipeline`: the compute or render pipelines; `sound`: audio inputs as textures; `node`:
//!   buffers and the frame's passes.
//! - Time is the fixed clock's (`TIME`, `TIMEDELTA`, `FRAMEINDEX`) and `DATE` the node's `date`
//!   parameter advanced by it — never the wall clock — so an ISF scene renders the same bytes
//!   twice and frame N sought equals frame N played.
//! - The 64 shaders of Vidvox's collection ship in `shaders/isf/` (MIT, `LICENSE` beside them) and
//!   are built into the binary; a file on disk of the same path wins.

pub mod compile;
pub mod expr;
pub mod gl_transition;
pub mod header;
mod node;
mod pipeline;
pub mod program;
#[cfg(test)]
mod render_tests;
mod rewrite;
mod sound;
pub mod targets;
pub mod translate;

use crate::assets::Assets;
use crate::files::{FileError, NamedBytes};
use crate::params::{ParamDecl, ParamValue, Text};

use super::{Declared, Declarer, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "isf",
    chapter: "import: ISF shaders (generators, filters, transitions)",
    summary: "a shader in the Interactive Shader Format; its inputs become parameters and input slots",
    params: Settings::decls,
    inputs: &[],
    shaders: &["isf_present.wgsl"],
    create: node::create,
    check: None,
    stage: None,
    declare: Some(Declarer {
        file_param: "file",
        extensions: &["fs", gl_transition::EXTENSION],
        declare,
        scene_for,
        texture_bytes: targets::declared_bytes,
    }),
};

crate::technique_params! {
    /// What an ISF node reads each step besides the shader's own inputs.
    pub struct Settings {
        /// the ISF shader (.fs; a .vs of the same name beside it is its vertex stage)
        file: Text = |n, doc| ParamDecl::text(n, "shaders/isf/Linear Gradient.fs", doc),
        /// DATE at the start: year, month, day, seconds since midnight (the clock advances it)
        date: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Vec4([2026.0, 1.0, 1.0, 0.0]), None, doc),
    }
}

/// The largest `.fs` or `.vs` file read.
const SHADER_FILE_LIMIT: u64 = 1 << 20;

/// An ISF file as read: the fragment shader and, if there is one, its vertex companion, each as
/// (origin, text).
#[derive(Clone, Debug)]
pub struct IsfFiles {
    /// The `.fs`.
    pub fs: (String, String),
    /// The `.vs`, if one lies beside it.
    pub vs: Option<(String, String)>,
    /// The `.fs` on disk (`None`: the built-in copy), for IMPORTED files beside it.
    pub path: Option<std::path::PathBuf>,
    /// Whether the file is a gl-transition, translated to ISF (its errors' lines are moved back).
    pub gl_transition: bool,
}

impl IsfFiles {
    /// Reads `file` (and its `.vs`) under the file rules, the built-in copy as the fallback.
    pub fn read(assets: &Assets, file: &str) -> Result<Self, String> {
        let bundled = |name: &str| crate::assets::bundled_isf().find(|(p, _)| *p == name).map(|(_, t)| t.as_bytes());
        let text = |bytes: Vec<u8>, origin: &str| {
            String::from_utf8(bytes).map_err(|_| format!("{origin}: not UTF-8 text, so not an ISF shader"))
        };
        // A file on disk wins; a built-in copy stands in where there is none (or no folder to
        // look in at all: a binary run from anywhere).
        let read = |name: &str| match (assets.read_file(name, SHADER_FILE_LIMIT, None), bundled(name)) {
            (Err(_), Some(bytes)) => Ok(NamedBytes {
                path: None,
                origin: format!("<embedded>/{name}"),
                bytes: std::borrow::Cow::Borrowed(bytes),
            }),
            (result, _) => result,
        };
        let fs = read(file).map_err(|e| e.to_string())?;
        let path = fs.path.clone();
        let fs = (fs.origin.clone(), text(fs.bytes.into_owned(), &fs.origin)?);
        if gl_transition::is_gl_transition(file) {
            let isf = gl_transition::to_isf(&fs.1).map_err(|(line, e)| format!("{}:{line}: {e}", fs.0))?;
            return Ok(Self { fs: (fs.0, isf), vs: None, path, gl_transition: true });
        }
        let vs_name = format!("{}.vs", file.strip_suffix(".fs").unwrap_or(file));
        let vs = match read(&vs_name) {
            Ok(vs) => Some((vs.origin.clone(), text(vs.bytes.into_owned(), &vs.origin)?)),
            Err(FileError::NotFound(_)) => None,
            Err(e) => return Err(e.to_string()),
        };
        Ok(Self { fs, vs, path, gl_transition: false })
    }

    /// Parses, translates and validates the shader.
    pub fn compile(&self) -> Result<compile::Compiled, crate::gpu::ShaderError> {
        let vs = self.vs.as_ref().map(|(o, t)| (o.as_str(), t.as_str()));
        compile::compile(&compile::Sources { fs: (&self.fs.0, &self.fs.1), vs }).map_err(|mut e| {
            if self.gl_transition {
                e.line = e.line.saturating_sub(gl_transition::GL_LINE_OFFSET).max(1);
            }
            e
        })
    }
}

/// What an ISF file declares for its node: its inputs as parameters and image slots.
fn declare(assets: &Assets, file: &str) -> Result<Declared, String> {
    let compiled = IsfFiles::read(assets, file)?.compile().map_err(|e| e.to_string())?;
    let own = Settings::decls();
    if let Some(clash) = compiled.header.inputs.iter().find(|i| own.iter().any(|d| d.name == i.name)) {
        return Err(format!("{file}: input '{}' has the name of the node's own parameter; rename it", clash.name));
    }
    let header = &compiled.header;
    let hears_audio = header.inputs.iter().any(|i| i.kind.is_audio());
    Ok(Declared { params: header.param_decls(), inputs: header.image_inputs(), hears_audio })
}

/// The scene text that plays ISF file `file` on its own (`indra run shader.fs`): a generator as
/// the output; a filter over the bundled test pattern; a transition from the Kleinian limit set to
/// the test pattern, its `progress` swept by an LFO.
pub fn scene_for(assets: &Assets, file: &str) -> Result<String, crate::gpu::ShaderError> {
    let files = IsfFiles::read(assets, file).map_err(|message| crate::gpu::ShaderError {
        origin: file.to_string(),
        line: 1,
        column: 1,
        message,
    })?;
    let compiled = files.compile()?;
    let header = &compiled.header;
    let name = std::path::Path::new(file).file_stem().and_then(|s| s.to_str()).unwrap_or("isf").replace('"', "'");
    // A filter's input is the bundled test pattern (RGB ramps: hue and brightness vary, so what a
    // filter does shows); a
    // transition goes from the Kleinian limit set to it.
    let pattern = "(id: \"pattern\", technique: \"isf\", params: { \"file\": \"shaders/isf/Test Pattern Generator.fs\", \
                   \"pattern\": \"RGB Ramps\" })";
    let sources = [("limit_set", "(id: \"limit_set\", technique: \"kleinian\")"), ("pattern", pattern)];
    let transition = header.role() == header::Role::Transition;
    let mut nodes = String::new();
    let mut wiring = Vec::new();
    for (k, slot) in header.image_inputs().iter().enumerate() {
        let (id, node) = sources[usize::from(!(transition && k == 0))];
        if !nodes.contains(node) {
            nodes.push_str(&format!("        {node},\n"));
        }
        wiring.push(format!("\"{slot}\": \"{id}\""));
    }
    // A transition sweeps back and forth, starting half way.
    let lfos = if transition {
        "    controls: (lfo: [(target: \"isf.progress\", shape: Triangle, rate: Hz(0.25), range: (0.0, 1.0), \
         phase: 0.25)]),\n"
    } else {
        ""
    };
    let file_text = file.replace('\\', "\\\\").replace('"', "\\\"");
    Ok(format!(
        "(\n    name: \"{name}\",\n    description: \"the ISF shader {name} on its own\",\n    size: (1280, 720),\n    \
         seed: 1,\n    nodes: [\n{nodes}        \
         (id: \"isf\", technique: \"isf\", params: {{ \"file\": \"{file_text}\" }}, inputs: {{ {} }}),\n    ],\n    \
         output: \"isf\",\n{lfos})\n",
        wiring.join(", ")
    ))
}

/// The ISF shaders and gl-transitions there are: those in `shaders/isf/` and
/// `shaders/gl-transitions/` on disk and the built-in ones, as the paths scenes and shows name
/// them by, sorted.
pub fn shader_names(assets: &Assets) -> Vec<String> {
    let ours = |name: &str| name.ends_with(".fs") || gl_transition::is_gl_transition(name);
    let mut names: Vec<String> = crate::assets::bundled_isf().map(|(p, _)| p.to_string()).filter(|p| ours(p)).collect();
    for dir in ["shaders/isf", "shaders/gl-transitions"] {
        if let Some(Ok(entries)) = assets.root().map(|r| std::fs::read_dir(r.join(dir))) {
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                if ours(&name) {
                    names.push(format!("{dir}/{name}"));
                }
            }
        }
    }
    names.sort();
    names.dedup();
    names
}

/// One line on what an ISF file is and takes (for `indra list`): its kind, passes, image inputs
/// and parameters with their ranges.
pub fn describe(assets: &Assets, file: &str) -> Result<String, String> {
    let header = IsfFiles::read(assets, file)?.compile().map_err(|e| e.to_string())?.header;
    let role = format!("{:?}", header.role()).to_lowercase();
    let params: Vec<String> = header
        .param_decls()
        .iter()
        .map(|d| match d.range {
            Some((lo, hi)) if d.options.is_empty() => format!("{} {} [{lo} … {hi}]", d.name, d.ty()),
            _ if !d.options.is_empty() => format!("{} ({})", d.name, d.options.join("|")),
            _ => format!("{} {}", d.name, d.ty()),
        })
        .collect();
    let images = header.image_inputs();
    let audio: Vec<&str> = header
        .inputs
        .iter()
        .filter(|i| matches!(i.kind, header::InputKind::Audio { .. } | header::InputKind::AudioFft { .. }))
        .map(|i| i.name.as_str())
        .collect();
    Ok(format!(
        "{role}, {} pass(es); images: {}; audio: {}; parameters: {}",
        header.passes.len(),
        if images.is_empty() { "none".into() } else { images.join(", ") },
        if audio.is_empty() { "none".into() } else { audio.join(", ") },
        if params.is_empty() { "none".into() } else { params.join(", ") },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bundled_shader_reads_and_declares() {
        let assets = Assets::new(None);
        let names: Vec<&str> = crate::assets::bundled_isf().map(|(p, _)| p).filter(|p| p.ends_with(".fs")).collect();
        assert_eq!(names.len(), 64, "{names:?}");
        for name in names {
            let declared = declare(&assets, name).unwrap_or_else(|e| panic!("{e}"));
            let files = IsfFiles::read(&assets, name).unwrap();
            let compiled = files.compile().unwrap();
            assert_eq!(declared.inputs, compiled.header.image_inputs());
            // Every shader without a vertex stage runs as a compute shader; of those with one,
            // only 3d Rotate moves the quad (so only it clears its target first).
            assert_eq!(compiled.compute.is_some(), files.vs.is_none(), "{name}");
            assert_eq!(compiled.program.covers_target, !name.contains("3d Rotate"), "{name}");
        }
    }
}
