//! Edits a performer makes to a loaded scene from the command line: outputs added with
//! `--output-window` and values set with `--set`, each checked as the file's own would be.

use super::model::{Scene, SceneNode, SceneOutput, corner_aliases, resolve_target};
use super::schema::OutputFile;
use crate::params::{ParamDecl, ParamSet, ParamType, ParamValue, RawValue, coerce};
use crate::techniques::{self};

impl Scene {
    /// Adds an output from the command line (`run --output-window`): `source=NODE` (default the
    /// scene's output), `warp=FILE.ron` (a warp node `output<n>` in between, with its corner
    /// addresses), `monitor=N`, `fullscreen`, `ndi=NAME`, `pipewire=NAME`, `headless` — separated
    /// by commas, as a scene's `outputs` has.
    pub fn add_output(&mut self, spec: &str) -> Result<(), String> {
        let mut output = OutputFile::default();
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part.split_once('=').map(|(k, v)| (k.trim(), v.trim().to_string())) {
                Some(("source", v)) => output.source = Some(v),
                Some(("warp", v)) => output.warp = Some(v),
                Some(("monitor", v)) => {
                    output.monitor = Some(v.parse::<usize>().map_err(|_| format!("monitor '{v}' is not a number"))?);
                }
                Some(("ndi", v)) => output.ndi = Some(v),
                Some(("pipewire", v)) => output.pipewire = Some(v),
                None if part == "fullscreen" => output.fullscreen = true,
                None if part == "headless" => output.headless = true,
                _ => {
                    return Err(format!(
                        "'{part}' in output '{spec}': use source=NODE, warp=FILE.ron, monitor=N, fullscreen, ndi=NAME, pipewire=NAME and headless"
                    ));
                }
            }
        }
        self.attach_output(&output)
    }

    /// Adds output `output` (from the scene file's `outputs` or the command line): resolves its
    /// source, puts a warp node `output<n>` in between when it names a warp file, and gives
    /// warped outputs their corner addresses.
    pub(crate) fn attach_output(&mut self, output: &OutputFile) -> Result<(), String> {
        let number = self.outputs.len() + 1;
        let main = &self.nodes[self.output].id;
        let source_id = output.source.clone().unwrap_or_else(|| main.clone());
        let mut node = self
            .node_index(&source_id)
            .ok_or_else(|| format!("output {number}: '{source_id}' is not a node of scene '{}'", self.name))?;
        if let Some(file) = &output.warp {
            let id = format!("output{number}");
            if self.node_index(&id).is_some() {
                return Err(format!("output {number}: the scene already has a node '{id}'"));
            }
            let (technique, edit) = techniques::stage_output()
                .ok_or_else(|| format!("output {number}: this build has no warp technique"))?;
            let mut params = ParamSet::new((technique.params)());
            let index =
                params.index(edit.file).ok_or_else(|| format!("output {number}: the warp has no file parameter"))?;
            params.set_at(index, ParamValue::Text(crate::params::Text::new(file)));
            params.snap();
            let slots = technique.inputs.iter().map(|s| s.to_string()).collect();
            self.nodes.push(SceneNode { id, technique, params, inputs: vec![node], slots, hears_audio: false });
            node = self.nodes.len() - 1;
        }
        if output.headless && output.ndi.is_none() && output.pipewire.is_none() {
            return Err(format!("output {number} is headless and sends nowhere: give it ndi=NAME or pipewire=NAME"));
        }
        self.outputs.push(SceneOutput {
            node,
            monitor: output.monitor,
            fullscreen: output.fullscreen,
            ndi: output.ndi.clone(),
            pipewire: output.pipewire.clone(),
            headless: output.headless,
        });
        self.osc_aliases.retain(|(a, _)| !a.starts_with("/indra/output/"));
        self.osc_aliases.extend(corner_aliases(&self.outputs, &self.nodes));
        Ok(())
    }

    /// Applies `node.param=value` (value: numbers separated by commas, or true/false), as the
    /// CLI's `--set` does. The value is typed and clamped like any other, and it holds: the
    /// scene's tracks, LFOs and sound mappings on that parameter (or on that component, or on the
    /// whole of the vector it is part of) are dropped. MIDI and OSC can still move it.
    pub fn set_from_str(&mut self, assignment: &str) -> Result<(), String> {
        let (target, value) =
            assignment.split_once('=').ok_or_else(|| format!("'{assignment}' is not of the form node.param=value"))?;
        let t = resolve_target(&self.nodes, target).map_err(|e| format!("scene '{}': {e}", self.name))?;
        let params = &mut self.nodes[t.node].params;
        let accepted = match t.component {
            Some(c) => {
                let x = value
                    .trim()
                    .parse::<f32>()
                    .map_err(|_| format!("'{value}' is not a number (a component takes one)"))?;
                params.set_component(t.param, c, x)
            }
            None => {
                let typed = parse_value_override(value, &params.decls()[t.param])?;
                params.set_at(t.param, typed)
            }
        };
        if !accepted {
            return Err(format!("'{value}' is not a finite number ({target})"));
        }
        params.snap();
        // Otherwise an LFO or a track overwrites the value from the first frame on, silently.
        let moves_it = |node: usize, param: usize, component: Option<usize>| {
            node == t.node
                && param == t.param
                && (component.is_none() || t.component.is_none() || component == t.component)
        };
        self.tracks.retain(|b| !moves_it(b.node, b.param, b.component));
        self.lfos.retain(|l| !moves_it(l.target.node, l.target.param, l.target.component));
        self.audio.retain(|a| !moves_it(a.target.node, a.target.param, a.target.component));
        Ok(())
    }
}

/// Parses a command-line value for `decl`: `1.5`; a vector as `1.0,0.3,0.1` or as the tuple
/// a scene file uses, `(1.0, 0.3, 0.1)` or `[1.0, 0.3, 0.1]`; `true`/`false`; an enum option
/// name (quoted or not); any text for text parameters.
pub fn parse_value_override(text: &str, decl: &ParamDecl) -> Result<ParamValue, String> {
    let ty = decl.ty();
    if ty == ParamType::Text {
        // Text is taken as written (`--set title.text=HELLO WORLD`).
        return Ok(ParamValue::Text(crate::params::Text::new(text)));
    }
    let trimmed = text.trim();
    let unwrapped = [('(', ')'), ('[', ']'), ('"', '"')]
        .iter()
        .find_map(|&(open, close)| trimmed.strip_prefix(open)?.strip_suffix(close))
        .unwrap_or(trimmed)
        .trim();
    let raw = match unwrapped {
        "true" => RawValue::Bool(true),
        "false" => RawValue::Bool(false),
        name if ty == ParamType::Enum && decl.option_index(name).is_some() => RawValue::Text(name.into()),
        name if ty == ParamType::Enum && name.parse::<f64>().is_err() => {
            return Err(format!("'{name}' is not one of {}", decl.options.join(", ")));
        }
        list => RawValue::List(
            list.trim_end_matches(',')
                .split(',')
                .map(|x| {
                    x.trim().parse::<f64>().map_err(|_| {
                        format!("'{}' in '{text}' is not a number (write 0.5, 1,0.5 or (1.0, 0.5))", x.trim())
                    })
                })
                .collect::<Result<_, _>>()?,
        ),
    };
    let raw = match raw {
        RawValue::List(v) if v.len() == 1 => RawValue::Number(v[0]),
        other => other,
    };
    coerce(&raw, ty, &decl.options).ok_or_else(|| match ty {
        ParamType::Enum => format!("'{text}' is not one of {}", decl.options.join(", ")),
        _ => format!("'{text}' is not a {ty}"),
    })
}
