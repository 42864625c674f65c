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
        EffectEdit::Add(_) if entries.len() >= MAX_EFFECTS_PER_CHAIN => {
            return Err(format!("{chain} has {MAX_EFFECTS_PER_CHAIN} effects, the most a chain has"));
        }
        EffectEdit::Add(_) => {}
        EffectEdit::Remove(n) => in_range(n, "remove")?,
        EffectEdit::Move { from, to } => {
            in_range(from, "move")?;
            in_range(to, "move to")?;
        }
    }
    apply_edit(entries, edit, |effect| EffectFile {
        effect: effect.as_str().to_string(),
        params: Default::default(),
        mix: 1.0,
        bypass: false,
    });
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

/// Applies `edit` to `chain` (its positions checked by the caller); an added effect is
/// `added(name)`.
fn apply_edit<T>(chain: &mut Vec<T>, edit: EffectEdit, added: impl FnOnce(Text) -> T) {
    match edit {
        EffectEdit::Add(effect) => chain.push(added(effect)),
        EffectEdit::Remove(n) => {
            chain.remove(n);
        }
        EffectEdit::Move { from, to } => {
            let moved = chain.remove(from);
            chain.insert(to, moved);
        }
    }
}

/// Each layer's chain and the master's as they play now: (owner, effect names in order).
pub fn chains(show: &Show) -> Vec<(String, Vec<String>)> {
    let Some(source) = show.file.as_deref() else { return Vec::new() };
    let names = |effects: &[EffectFile]| effects.iter().map(|e| e.effect.clone()).collect();
    let layers = source.file.layers.iter().enumerate().map(|(l, layer)| (chain_owner(Some(l)), names(&layer.effects)));
    layers.chain([(chain_owner(None), names(&source.file.effects))]).collect()
}

/// The layer a chain owner names (`layer/<n>` → `Some(Some(n − 1))`, `master` → `Some(None)`).
pub fn owner_layer(owner: &str) -> Option<Option<usize>> {
    if owner == "master" {
        return Some(None);
    }
    let n: usize = owner.strip_prefix("layer/")?.parse().ok()?;
    n.checked_sub(1).map(Some)
}

/// The edits that make chain `current` into `target`, fewest moves of the effects both have
/// (those keep their state): removals of what `target` lacks (from the end, so positions hold),
/// additions of what `current` lacks, then moves into `target`'s order. Or the name too long for
/// an edit.
pub fn edits_between(current: &[String], target: &[String]) -> Result<Vec<EffectEdit>, String> {
    if let Some(long) = target.iter().find(|t| t.len() > MAX_EFFECT_NAME) {
        return Err(format!("the effect name '{long}' is longer than {MAX_EFFECT_NAME} bytes"));
    }
    // Which of the current effects stay: for each wanted one, the first unclaimed of its name.
    let mut kept = vec![false; current.len()];
    let mut missing = Vec::new();
    for t in target {
        match (0..current.len()).find(|&i| !kept[i] && current[i] == *t) {
            Some(i) => kept[i] = true,
            None => missing.push(t.clone()),
        }
    }
    let mut edits = Vec::new();
    let mut chain: Vec<String> = Vec::new();
    for i in (0..current.len()).rev() {
        if !kept[i] {
            edits.push(EffectEdit::Remove(i));
        }
    }
    chain.extend(current.iter().zip(&kept).filter(|(_, k)| **k).map(|(c, _)| c.clone()));
    for name in missing {
        edits.push(EffectEdit::Add(Text::new(&name)));
        chain.push(name);
    }
    for (to, wanted) in target.iter().enumerate() {
        let from = (to..chain.len()).find(|&j| chain[j] == *wanted).expect("every wanted effect is in the chain");
        if from != to {
            let edit = EffectEdit::Move { from, to };
            apply_edit(&mut chain, edit, |_| unreachable!("a move adds nothing"));
            edits.push(edit);
        }
    }
    Ok(edits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Applies `edits` to `chain` as `edited_show` does.
    fn apply(chain: &[&str], edits: &[EffectEdit]) -> Vec<String> {
        let mut chain: Vec<String> = chain.iter().map(|s| s.to_string()).collect();
        for &edit in edits {
            apply_edit(&mut chain, edit, |name| name.as_str().to_string());
        }
        chain
    }

    #[test]
    fn the_edits_between_two_chains_make_the_one_into_the_other() {
        let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let cases: [(&[&str], &[&str]); 6] = [
            (&["a", "b"], &["a", "b"]),
            (&[], &["a", "b"]),
            (&["a", "b", "c"], &[]),
            (&["a", "b", "c"], &["c", "a"]),
            (&["a", "x", "b"], &["b", "y", "a", "a"]),
            (&["a", "a", "b"], &["a", "b", "a"]),
        ];
        for (current, target) in cases {
            let edits = edits_between(&s(current), &s(target)).unwrap();
            assert_eq!(apply(current, &edits), s(target), "{current:?} → {target:?} by {edits:?}");
        }
        // Equal chains need nothing; kept effects are moved, never removed and added again.
        assert!(edits_between(&s(&["a", "b"]), &s(&["a", "b"])).unwrap().is_empty());
        let swap = edits_between(&s(&["a", "b"]), &s(&["b", "a"])).unwrap();
        assert_eq!(swap, [EffectEdit::Move { from: 1, to: 0 }]);
        assert!(edits_between(&[], &[("x".repeat(MAX_EFFECT_NAME + 1))]).is_err());
    }

    #[test]
    fn owners_name_layers_from_one_and_the_master() {
        assert_eq!(owner_layer("layer/1"), Some(Some(0)));
        assert_eq!(owner_layer("master"), Some(None));
        assert_eq!(owner_layer("layer/0"), None);
        assert_eq!(owner_layer("clip/2"), None);
        assert_eq!(chain_owner(owner_layer("layer/3").unwrap()), "layer/3");
    }
}
