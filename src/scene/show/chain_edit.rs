//! A performer's edit of an effect chain (add, remove, move) as the show it makes: the show file
//! the running show was built from, its chain edited, built again. The edited chain's effects
//! keep the values they have now (they start from them), and the rest of the show is what it
//! was: nodes whose id and technique are unchanged keep their instance when it is installed.

use super::Show;
use super::file::EffectFile;
use super::load::build_show;
use crate::assets::Assets;
use crate::params::{EffectEdit, ParamSet, ParamType, Text, raw_from_value};
use crate::scene::model::Scene;

use super::effects::{BYPASS, MAX_EFFECTS_PER_CHAIN, MIX};

/// The chain's owner in node ids: `layer/<n>` or `master`.
pub fn chain_owner(layer: Option<usize>) -> String {
    layer.map_or_else(|| "master".to_string(), |l| format!("layer/{}", l + 1))
}

/// Whether node id `id` is an effect of `owner`'s chain.
pub fn in_chain(id: &str, owner: &str) -> bool {
    id.strip_prefix(owner).is_some_and(|rest| rest.starts_with("/fx/"))
}

/// The show `scene` with `edit` applied to the chain of `layer` (`None`: the master), its
/// effects starting from their values in `params`; or why it cannot be.
pub fn edited_show(
    assets: &Assets,
    scene: &Scene,
    params: &[ParamSet],
    layer: Option<usize>,
    edit: EffectEdit,
) -> Result<Scene, String> {
    let show: &Show = scene.show.as_deref().ok_or_else(|| format!("'{}' is a scene, not a show", scene.name))?;
    let source = show.file.as_deref().ok_or("the show was not built from a file")?;
    let mut file = source.file.clone();
    let (nodes, entries) = match layer {
        Some(l) => match (show.layers.get(l), file.layers.get_mut(l)) {
            (Some(layer), Some(entry)) => (&layer.effects, &mut entry.effects),
            _ => return Err(format!("the show has no layer {}", l + 1)),
        },
        None => (&show.master_effects, &mut file.effects),
    };
    // The chain as it plays now: every value, bypass and mix where the performer left them.
    for (entry, &node) in entries.iter_mut().zip(nodes) {
        let set = &params[node];
        entry.params.clear();
        for (p, decl) in set.decls().iter().enumerate() {
            let value = set.target_at(p);
            match decl.name.as_str() {
                BYPASS => entry.bypass = matches!(value, crate::params::ParamValue::Bool(true)),
                MIX => entry.mix = raw_from_value(&value, decl).numbers().first().map_or(1.0, |&m| m as f32),
                _ if decl.ty() == ParamType::Trigger => {}
                name => {
                    entry.params.insert(name.to_string(), raw_from_value(&value, decl));
                }
            }
        }
    }
    let chain = chain_owner(layer);
    let in_range = |n: usize, what: &str| {
        (n < entries.len()).then_some(()).ok_or_else(|| format!("{chain} has no effect {} to {what}", n + 1))
    };
    match edit {
        EffectEdit::Add(effect) => {
            if entries.len() >= MAX_EFFECTS_PER_CHAIN {
                return Err(format!("{chain} has {MAX_EFFECTS_PER_CHAIN} effects, the most a chain has"));
            }
            entries.push(EffectFile {
                effect: effect.as_str().to_string(),
                params: Default::default(),
                mix: 1.0,
                bypass: false,
            });
        }
        EffectEdit::Remove(n) => {
            in_range(n, "remove")?;
            entries.remove(n);
        }
        EffectEdit::Move { from, to } => {
            in_range(from, "move")?;
            in_range(to, "move to")?;
            let moved = entries.remove(from);
            entries.insert(to, moved);
        }
    }
    let mut edited = build_show(assets, &scene.origin, &source.text, file, true).map_err(|e| e.to_string())?;
    // Everything but the chain is as it runs, with what the command line changed (`--set`,
    // `--msaa`, `--seed`, `--dt`): an unchanged node keeps its instance and its values.
    (edited.msaa, edited.seed, edited.dt, edited.size) = (scene.msaa, scene.seed, scene.dt, scene.size);
    for node in edited.nodes.iter_mut().filter(|n| !in_chain(&n.id, &chain)) {
        if let Some(old) = scene.nodes.iter().find(|o| o.id == node.id && o.technique.name == node.technique.name) {
            node.params = old.params.clone();
        }
    }
    Ok(edited)
}

/// The longest effect file name an edit carries.
pub const MAX_EFFECT_NAME: usize = Text::CAPACITY;
