//! Effect chains: an effect on a clip, a layer or the master is a node of the flat scene — an ISF
//! filter or a technique that takes one image — whose parameters end with two of the show's
//! own: `bypass` (the input passes through and the effect draws nothing) and `mix` (dry/wet, a
//! linear-light mix of the input and the effect). So its parameters are addressed, learned,
//! recorded and kept in presets like any node's: `/indra/layer/<n>/fx/<k>/<param>`,
//! `/indra/master/fx/<k>/<param>`, `/indra/<clip>/fx/<k>/<param>`.

use std::collections::BTreeMap;

use super::file::EffectFile;
use crate::assets::Assets;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue, RawValue};
use crate::scene::error::SceneError;
use crate::scene::model::SceneNode;
use crate::scene::schema::NodeFile;
use crate::scene::validate::build_node;
use crate::techniques::{self, Technique};
use crate::time::FrameTime;

pub mod library;

/// The parameter that bypasses an effect.
pub const BYPASS: &str = "bypass";
/// The parameter that mixes an effect's input (0) with its output (1).
pub const MIX: &str = "mix";

/// The most effects in one chain.
pub const MAX_EFFECTS_PER_CHAIN: usize = 16;

/// The node id of effect `k` (from 0) of the chain of `owner` (`layer/1`, `master`, a clip id).
pub fn effect_id(owner: &str, k: usize) -> String {
    format!("{owner}/fx/{}", k + 1)
}

/// The node an effect entry of the show file makes, with id `id`; errors are located in the
/// show file `(origin, source)`. Its one input slot is wired by the show.
fn effect_node(
    file: (&str, &str),
    assets: &Assets,
    effect: &EffectFile,
    id: &str,
) -> Result<SceneNode, Vec<SceneError>> {
    let anchor = format!("\"{}\"", effect.effect);
    let located = |message: String| {
        let (line, column) = crate::scene::error::locate(file.1, &["effects", &anchor]);
        vec![SceneError {
            origin: file.0.into(),
            line,
            column,
            message: format!("effect '{}': {message}", effect.effect),
        }]
    };
    let mut params = effect.params.clone();
    params.remove(BYPASS);
    params.remove(MIX);
    let technique = match techniques::file_technique(&effect.effect) {
        Some((technique, declarer)) => {
            params.insert(declarer.file_param.to_string(), RawValue::Text(effect.effect.clone()));
            technique.name.to_string()
        }
        None if techniques::find(&effect.effect).is_some() => effect.effect.clone(),
        None => {
            let message = "not an ISF filter (.fs), a WGSL effect (.wgsl) nor a technique that takes an image";
            return Err(located(message.into()));
        }
    };
    let node = NodeFile {
        id: id.to_string(),
        technique,
        params,
        ranges: BTreeMap::new(),
        smoothing: BTreeMap::new(),
        inputs: BTreeMap::new(),
    };
    let mut built = build_node(file, assets, &node, &anchor)?;
    if built.slots.len() != 1 {
        return Err(located(format!("it takes {} images ({:?}); an effect takes one", built.slots.len(), built.slots)));
    }
    let mut decls = built.params.decls().to_vec();
    if let Some(clash) = decls.iter().find(|d| d.name == BYPASS || d.name == MIX) {
        return Err(located(format!("its parameter '{}' has the name of the chain's own", clash.name)));
    }
    if !(0.0..=1.0).contains(&effect.mix) {
        return Err(located(format!("mix {} must be 0–1", effect.mix)));
    }
    decls.push(ParamDecl::new(
        BYPASS,
        ParamValue::Bool(effect.bypass),
        None,
        "the input passes through untouched; the effect costs no GPU time",
    ));
    decls.push(ParamDecl::new(
        MIX,
        ParamValue::Float(effect.mix),
        Some((0.0, 1.0)),
        "dry/wet: 0 the input, 1 the effect, between them a mix in linear light",
    ));
    built.params = ParamSet::new(decls);
    Ok(built)
}

/// The nodes of `owner`'s effect chain (each `<owner>/fx/<k>`), to be appended at index
/// `first`: with `input`, each takes the one before it (a clip's chain), else the show wires
/// them as it draws. Entries that cannot be played are left out, and why is in the errors.
pub(super) fn chain_nodes(
    file: (&str, &str),
    assets: &Assets,
    owner: &str,
    effects: &[EffectFile],
    (first, input): (usize, Option<usize>),
) -> (Vec<SceneNode>, Vec<SceneError>) {
    if effects.len() > MAX_EFFECTS_PER_CHAIN {
        let (line, column) = crate::scene::error::locate(file.1, &["effects"]);
        let message = format!("{owner}: {} effects; a chain has at most {MAX_EFFECTS_PER_CHAIN}", effects.len());
        return (Vec::new(), vec![SceneError { origin: file.0.into(), line, column, message }]);
    }
    let (mut nodes, mut errors) = (Vec::new(), Vec::new());
    let mut previous = input;
    for (k, effect) in effects.iter().enumerate() {
        match effect_node(file, assets, effect, &effect_id(owner, k)) {
            Ok(mut node) => {
                node.inputs = previous.into_iter().collect();
                previous = previous.map(|_| first + nodes.len());
                nodes.push(node);
            }
            Err(e) => errors.extend(e),
        }
    }
    (nodes, errors)
}

/// An effect's switches as it is now: bypassed, and its dry/wet mix.
pub fn switches(params: &ParamSet) -> (bool, f32) {
    let n = params.decls().len();
    let bypass = matches!(params.value_at(n - 2), ParamValue::Bool(true));
    let mix = match params.value_at(n - 1) {
        ParamValue::Float(m) => m.clamp(0.0, 1.0),
        _ => 1.0,
    };
    (bypass, mix)
}

/// Declares one effect over `dry`: nothing when it is bypassed or fully dry, the effect's passes
/// when fully wet, and otherwise those and a mix (`mix`: the dry/wet pass, given the dry image,
/// the wet one and the amount). Returns the image after the effect.
pub fn declare<'r>(
    node: &'r mut Box<dyn Technique>,
    graph: &mut FrameGraph<'r>,
    params: &ParamSet,
    time: &FrameTime,
    dry: TextureHandle,
    mix: impl FnOnce(&mut FrameGraph<'r>, TextureHandle, TextureHandle, f32) -> TextureHandle,
) -> TextureHandle {
    let (bypass, amount) = switches(params);
    if bypass || amount <= 0.0 {
        return dry;
    }
    let wet = node.add_passes(graph, params, time, &[dry]);
    if amount >= 1.0 { wet } else { mix(graph, dry, wet, amount) }
}
