//! Notes bound to show commands: a clip's trigger (a clip's `note` in the show file, or learned)
//! and effect chain edits (learned on the panel). The learn file names each by its address, as
//! OSC does without `/indra/` and numbered from 1: `layer/<n>/clip/<m>`, `<chain>/fx/add <effect>`,
//! `<chain>/fx/remove <k>`, `<chain>/fx/move <i> <j>`, the chain being `layer/<n>` or `master`.

use crate::params::{EffectEdit, ShowCommand, Text};
use crate::scene::show::chain_edit::{chain_owner, owner_layer};
use crate::scene::{MidiMapping, Scene};

/// A note bound to a show command.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandBinding {
    /// The note and channel, and the command's address as the learn file writes it.
    pub mapping: MidiMapping,
    /// Learned (saved in the learn file), not from the show file.
    pub learned: bool,
    /// What the note does.
    pub command: ShowCommand,
}

/// The learn file's address of `command`, for those a note may be bound to.
pub fn command_address(command: &ShowCommand) -> Option<String> {
    Some(match *command {
        ShowCommand::Trigger { layer, clip: Some(clip) } => format!("layer/{}/clip/{}", layer + 1, clip + 1),
        ShowCommand::Effect { layer, edit } => {
            let chain = chain_owner(layer);
            match edit {
                EffectEdit::Add(effect) => format!("{chain}/fx/add {}", effect.as_str()),
                EffectEdit::Remove(k) => format!("{chain}/fx/remove {}", k + 1),
                EffectEdit::Move { from, to } => format!("{chain}/fx/move {} {}", from + 1, to + 1),
            }
        }
        _ => return None,
    })
}

/// The command at learn file address `address`, if `scene` is a show that has its clip or chain.
pub fn parse_command_address(address: &str, scene: &Scene) -> Option<ShowCommand> {
    let show = scene.show.as_deref()?;
    if let Some((chain, edit)) = address.split_once("/fx/") {
        let layer = owner_layer(chain).filter(|l| l.is_none_or(|l| l < show.layers.len()))?;
        let (verb, args) = edit.split_once(' ')?;
        let numbers: Vec<usize> = args.split(' ').filter_map(|a| a.parse::<usize>().ok()?.checked_sub(1)).collect();
        let edit = match (verb, numbers.as_slice()) {
            ("add", _) if !args.is_empty() => EffectEdit::Add(Text::new(args)),
            ("remove", &[k]) => EffectEdit::Remove(k),
            ("move", &[from, to]) => EffectEdit::Move { from, to },
            _ => return None,
        };
        return Some(ShowCommand::Effect { layer, edit });
    }
    let (layer, clip) = address.strip_prefix("layer/")?.split_once("/clip/")?;
    let (layer, clip) = (layer.parse::<usize>().ok()?.checked_sub(1)?, clip.parse::<usize>().ok()?.checked_sub(1)?);
    show.clip_at(layer, clip).map(|_| ShowCommand::Trigger { layer, clip: Some(clip) })
}

/// The clip notes a show file gives (`note`, `channel`), as bindings.
pub(super) fn show_clip_notes(scene: &Scene) -> Vec<CommandBinding> {
    let Some(show) = &scene.show else { return Vec::new() };
    let mut bindings = Vec::new();
    for (layer, l) in show.layers.iter().enumerate() {
        for (clip, &c) in l.clips.iter().enumerate() {
            let Some((channel, note)) = show.clips[c].note else { continue };
            let command = ShowCommand::Trigger { layer, clip: Some(clip) };
            let Some(address) = command_address(&command) else { continue };
            bindings.push(CommandBinding { mapping: note_mapping(channel, note, address), learned: false, command });
        }
    }
    bindings
}

/// A note mapping to `target` (a command's address).
pub(super) fn note_mapping(channel: Option<u8>, note: u8, target: String) -> MidiMapping {
    MidiMapping {
        channel,
        cc: None,
        note: Some(note),
        target,
        range: None,
        curve: Default::default(),
        invert: false,
        fine: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bindable_command_reads_back_from_its_address() {
        let text = r#"(name: "s", size: (64, 36), layers: [(clips: [(scene: "kleinian_classic"), (scene: "kleinian_classic", id: "b")])])"#;
        let scene = crate::scene::show::parse_show(&crate::assets::Assets::new(None), "s.ron", text, false).unwrap();
        let commands = [
            ShowCommand::Trigger { layer: 0, clip: Some(1) },
            ShowCommand::Effect { layer: Some(0), edit: EffectEdit::Add(Text::new("shaders/isf/Kaleidoscope.fs")) },
            ShowCommand::Effect { layer: None, edit: EffectEdit::Remove(2) },
            ShowCommand::Effect { layer: Some(0), edit: EffectEdit::Move { from: 1, to: 0 } },
        ];
        for command in commands {
            let address = command_address(&command).unwrap();
            assert_eq!(parse_command_address(&address, &scene), Some(command), "{address}");
        }
        assert_eq!(command_address(&ShowCommand::CueGo), None);
        for gone in ["layer/2/fx/remove 1", "layer/1/clip/3", "layer/1/fx/move 1", "master/fx/remove 0", "x"] {
            assert_eq!(parse_command_address(gone, &scene), None, "{gone}");
        }
    }
}
