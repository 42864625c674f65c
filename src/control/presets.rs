//! Presets: the current value of every parameter saved as `presets/<name>.ron`, recalled at once
//! or morphed over seconds (numbers glide, bools and enums switch at the end). A show's preset
//! also holds each layer's effect chain and the master's — which effects, in which order — and
//! its recall edits the chains to match before the values morph (bypass and mix are values).
//!
//! ```ron
//! (scene: "Kleinian limit set", values: { "limit_set": { "scale": 1.9, "t": [1.94, 0.02] } })
//! (scene: "set", values: { "layer/1/fx/1": { "sides": 6.0, "mix": 0.5, "bypass": false } },
//!  chains: { "layer/1": ["shaders/isf/Kaleidoscope.fs"], "master": [] })
//! ```

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::params::{NodeValues, ParamType, RawValue, ShowCommand, raw_from_value, value_from_raw};
use crate::scene::show::chain_edit::{chains, edits_between, owner_layer};
use crate::scene::{Scene, SceneView};

/// A preset file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PresetFile {
    /// The scene it was saved from (informational).
    #[serde(default)]
    pub scene: String,
    /// node id → parameter → value.
    pub values: BTreeMap<String, BTreeMap<String, RawValue>>,
    /// A show's effect chains: owner (`layer/<n>`, `master`) → effect names in order.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub chains: BTreeMap<String, Vec<String>>,
}

/// The folder of presets.
#[derive(Clone, Debug)]
pub struct PresetStore {
    /// Where the files live.
    pub dir: PathBuf,
}

impl PresetStore {
    /// Saves every parameter's current target as `<name>.ron`; returns the path.
    pub fn save(&self, name: &str, instance: SceneView<'_>) -> Result<PathBuf, String> {
        check_name(name)?;
        let mut values = BTreeMap::new();
        for (n, node) in instance.scene.nodes.iter().enumerate() {
            let params = instance.params(n);
            let entries = params
                .decls()
                .iter()
                .enumerate()
                .filter(|(_, d)| d.ty() != ParamType::Trigger)
                .map(|(p, d)| (d.name.clone(), raw_from_value(&params.target_at(p), d)))
                .collect();
            values.insert(node.id.clone(), entries);
        }
        let chains = instance.scene.show.as_deref().map(chains).unwrap_or_default().into_iter().collect();
        let file = PresetFile { scene: instance.scene.name.clone(), values, chains };
        let text = ron::ser::to_string_pretty(&file, Default::default()).map_err(|e| e.to_string())?;
        std::fs::create_dir_all(&self.dir).map_err(|e| format!("cannot create {}: {e}", self.dir.display()))?;
        let path = self.dir.join(format!("{name}.ron"));
        crate::atomic_file::write(&path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        Ok(path)
    }

    /// Preset `name` as saved.
    pub fn read(&self, name: &str) -> Result<PresetFile, String> {
        check_name(name)?;
        let path = self.dir.join(format!("{name}.ron"));
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("no preset '{name}' ({}: {e})", path.display()))?;
        ron::from_str(&text).map_err(|e| format!("{}:{}", path.display(), e))
    }

    /// Preset names, sorted (MIDI program change n recalls the n-th).
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.dir)
            .map(|entries| {
                entries
                    .flatten()
                    .filter_map(|e| e.file_name().to_str()?.strip_suffix(".ron").map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        names
    }
}

impl PresetFile {
    /// The effect chain edits, in order, that make `scene`'s chains this preset's (none for a
    /// scene, or a preset without chains), and what could not be matched.
    pub fn chain_edits_for(&self, scene: &Scene) -> (Vec<ShowCommand>, Vec<String>) {
        let (mut commands, mut warnings) = (Vec::new(), Vec::new());
        let Some(show) = scene.show.as_deref() else { return (commands, warnings) };
        let current = chains(show);
        for (owner, target) in &self.chains {
            let found = current.iter().find(|(o, _)| o == owner);
            let (Some(layer), Some((_, now))) = (owner_layer(owner), found) else {
                warnings.push(format!("the preset's chain '{owner}' is not in this show"));
                continue;
            };
            match edits_between(now, target) {
                Ok(edits) => commands.extend(edits.into_iter().map(|edit| ShowCommand::Effect { layer, edit })),
                Err(e) => warnings.push(format!("the preset's chain '{owner}': {e}")),
            }
        }
        (commands, warnings)
    }

    /// Its values for `scene`. Nodes or parameters the scene does not have, and values that no
    /// longer fit, are skipped and named in the returned warnings.
    pub fn values_for(&self, name: &str, scene: &Scene) -> (NodeValues, Vec<String>) {
        let (mut values, mut warnings) = (Vec::new(), Vec::new());
        for (node_id, params) in &self.values {
            let Some(n) = scene.node_index(node_id) else {
                warnings.push(format!("preset '{name}': no node '{node_id}' in this scene"));
                continue;
            };
            for (param, raw) in params {
                let decls = scene.nodes[n].params.decls();
                match decls.iter().position(|d| &d.name == param) {
                    None => warnings.push(format!("preset '{name}': node '{node_id}' has no parameter '{param}'")),
                    Some(p) => match value_from_raw(raw, &decls[p]) {
                        Some(v) => values.push((n, p, v)),
                        None => warnings.push(format!("preset '{name}': {node_id}.{param} = {raw:?} does not fit")),
                    },
                }
            }
        }
        (values, warnings)
    }
}

/// Preset names become file names: letters, digits, `-` and `_` only.
fn check_name(name: &str) -> Result<(), String> {
    let ok = !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if ok { Ok(()) } else { Err(format!("preset name '{name}' may use only letters, digits, '-' and '_'")) }
}
