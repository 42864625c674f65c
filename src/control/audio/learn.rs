//! Audio mappings learned from the panel: a parameter's audio button offers the sources with
//! their live values; the one picked is mapped and saved by name in a RON file (the same entries
//! a scene's `controls.audio` takes, so one can be pasted into a scene). Entries for parameters
//! of other scenes stay in the file and apply when their scene runs.

use std::path::PathBuf;

use crate::params::{ParamType, ParamValue, Target};
use crate::scene::{AudioFile, AudioMapping, AudioSource, Scene, check_audio, resolve_target, ron_options};

/// Attack and release a learned mapping starts with (seconds): quick to rise, a short tail.
const LEARNED_ATTACK: f32 = 0.01;
const LEARNED_RELEASE: f32 = 0.3;
/// The share of a number's range a learned mapping sweeps.
const LEARNED_SPAN: f32 = 0.25;

/// The learned audio mappings and their file.
#[derive(Debug, Default)]
pub struct AudioLearn {
    /// The file.
    pub path: PathBuf,
    entries: Vec<AudioFile>,
}

impl AudioLearn {
    /// The mappings saved in `path` (none if it does not exist), and one sentence if it could
    /// not be read: a broken file is ignored, never fatal.
    pub fn load(path: PathBuf) -> (Self, Option<String>) {
        let Ok(text) = std::fs::read_to_string(&path) else { return (Self { path, entries: Vec::new() }, None) };
        match ron_options().from_str::<Vec<AudioFile>>(&text) {
            Ok(entries) => (Self { path, entries }, None),
            Err(e) => {
                let problem = format!(
                    "ignoring audio learn file {}:{}:{}: {}",
                    path.display(),
                    e.span.start.line,
                    e.span.start.col,
                    e.code
                );
                (Self { path, entries: Vec::new() }, Some(problem))
            }
        }
    }

    /// The learned mappings that bind in `scene` (entries naming parameters it lacks belong to
    /// other scenes; an entry that names one of its parameters wrongly is logged and skipped).
    pub fn bound(&self, scene: &Scene) -> Vec<AudioMapping> {
        let mut out = Vec::new();
        for entry in &self.entries {
            let Ok(target) = resolve_target(&scene.nodes, &entry.target) else { continue };
            match check_audio(&scene.nodes, entry, target) {
                Ok(m) => out.push(m),
                Err(e) => {
                    log::warn!("{}: learned audio mapping to '{}' left out: {e}", self.path.display(), entry.target)
                }
            }
        }
        out
    }

    /// Maps `source` to the whole parameter `target` (replacing a learned mapping it had) and
    /// saves the file. A number sweeps from its value `now` up a quarter of its range (down, if it
    /// is at the top): silence leaves it where the performer set it. Edit the file for others.
    pub fn learn(
        &mut self,
        scene: &Scene,
        target: Target,
        source: AudioSource,
        now: &ParamValue,
    ) -> Result<(), String> {
        let decl = &scene.nodes[target.node].params.decls()[target.param];
        let range = match (decl.ty(), now, decl.range) {
            (ParamType::Float | ParamType::Int, value, Some((lo, hi))) => {
                let at = match value {
                    ParamValue::Float(f) => *f,
                    ParamValue::Int(i) => *i as f32,
                    _ => lo,
                };
                // A quarter of the range above the value (below it, at the top): enough to see,
                // not enough to push a costly parameter (iterations, samples) to its maximum.
                let span = LEARNED_SPAN * (hi - lo);
                if at < hi { (at, (at + span).min(hi)) } else { ((at - span).max(lo), at) }
            }
            (ParamType::Float | ParamType::Int, _, None) => (0.0, 1.0),
            (ParamType::Bool | ParamType::Trigger, _, _) => (0.0, 1.0),
            (ty, _, _) => return Err(format!("'{}' is a {ty}: audio maps numbers, bools and triggers", decl.name)),
        };
        let name = target_name(scene, target.node, target.param);
        let entry = AudioFile { source, target: name.clone(), range, attack: LEARNED_ATTACK, release: LEARNED_RELEASE };
        check_audio(&scene.nodes, &entry, Target { component: None, ..target })?;
        self.entries.retain(|e| e.target != name);
        self.entries.push(entry);
        self.save()
    }

    /// Removes the learned mapping of `node`'s parameter `param` and saves the file.
    pub fn unlearn(&mut self, scene: &Scene, node: usize, param: usize) -> Result<(), String> {
        let name = target_name(scene, node, param);
        self.entries.retain(|e| e.target != name);
        self.save()
    }

    fn save(&self) -> Result<(), String> {
        let text = ron::ser::to_string_pretty(&self.entries, Default::default()).map_err(|e| e.to_string())?;
        crate::atomic_file::write(&self.path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", self.path.display()))
    }
}

/// `node.param`, the name a mapping is saved under.
fn target_name(scene: &Scene, node: usize, param: usize) -> String {
    format!("{}.{}", scene.nodes[node].id, scene.nodes[node].params.decls()[param].name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::parse_scene;

    fn scene(id: &str) -> Scene {
        let src = format!(
            r#"(name: "t", size: (8, 8), dt: 0.1, nodes: [(id: "{id}", technique: "grid_fluid")], output: "{id}")"#
        );
        parse_scene("t.ron", &src).unwrap()
    }

    #[test]
    fn learned_mappings_persist_by_name_and_belong_to_their_scene() {
        let path = std::env::temp_dir().join(format!("indra-audio-learn-{}.ron", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let (fluid, other) = (scene("fluid"), scene("elsewhere"));
        let (mut learn, problem) = AudioLearn::load(path.clone());
        assert!(problem.is_none() && learn.bound(&fluid).is_empty());
        let param = fluid.nodes[0].params.index("velocity_coef").unwrap();
        let target = Target { node: 0, param, component: None };
        learn.learn(&fluid, target, AudioSource::Low, &ParamValue::Float(4.0)).unwrap();
        learn.learn(&fluid, target, AudioSource::Band(3), &ParamValue::Float(4.0)).unwrap();
        // Saved, reloaded: one mapping (the second replaced the first), from the value set up a
        // quarter of the range (0–50).
        let (learn, _) = AudioLearn::load(path.clone());
        let bound = learn.bound(&fluid);
        assert_eq!(bound.len(), 1);
        assert_eq!((bound[0].source, bound[0].range), (AudioSource::Band(3), (4.0, 16.5)));
        assert_eq!((bound[0].target.node, bound[0].target.param), (0, param), "learned for that parameter");
        assert!(learn.bound(&other).is_empty(), "another scene's nodes are not touched");
        // A broken file is one sentence and no mappings.
        std::fs::write(&path, "[(source: Nope").unwrap();
        let (broken, problem) = AudioLearn::load(path.clone());
        assert!(broken.bound(&fluid).is_empty() && problem.unwrap().contains("ignoring audio learn file"));
        let _ = std::fs::remove_file(&path);
    }
}
