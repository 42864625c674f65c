//! The show's part of the panel: the clip grid (layers × clips, the playing clip lit, a click
//! triggers it), each layer's fader and blend menu, the columns, the master, and the cue list
//! with GO. Everything it does is a control event, as OSC and MIDI send them.

use crate::control::ControlHub;
use crate::params::{ControlEvent, ParamWrite, ShowCommand, Source};
use crate::scene::SceneInstance;
use crate::scene::show::ClipPolicy;

/// Draws the show controls of `instance` (nothing for a scene); returns what was clicked. A
/// right click on a clip starts MIDI learn for it (the next note triggers it).
pub fn show_panel(ui: &mut egui::Ui, instance: &SceneInstance, hub: &mut ControlHub) -> Vec<ControlEvent> {
    let mut events = Vec::new();
    let Some((show, state)) = instance.show() else { return events };
    let mut trigger = |command| events.push(ControlEvent::Show(command));
    ui.label("clips");
    egui::Grid::new("indra_clip_grid").striped(true).show(ui, |ui| {
        ui.label("");
        for (c, name) in show.columns.iter().enumerate() {
            if ui.small_button(name).on_hover_text("trigger this column on every layer").clicked() {
                trigger(ShowCommand::Column(c));
            }
        }
        ui.end_row();
        for (l, layer) in show.layers.iter().enumerate().rev() {
            let waiting = if state.waiting(l) { " (waits for the beat)" } else { "" };
            if ui.small_button(format!("{}{waiting}", layer.name)).on_hover_text("empty this layer").clicked() {
                trigger(ShowCommand::Trigger { layer: l, clip: None });
            }
            for (c, &clip) in layer.clips.iter().enumerate() {
                let playing = state.playing(l) == Some(clip);
                let info = &show.clips[clip];
                let broken = info.output.is_none();
                let mut hint = format!("{} ({})", info.id, info.scene);
                if info.policy == ClipPolicy::Continue {
                    hint.push_str(" — keeps running while hidden: it costs GPU time");
                }
                if broken {
                    hint.push_str(" — could not be loaded");
                }
                let command = ShowCommand::Trigger { layer: l, clip: Some(c) };
                // ASCII marks: egui's bundled fonts lack the usual dot glyphs.
                let mark = if broken { " !" } else { hub.mapper.learn_mark(command) };
                hint.push_str(" — right-click, then play a note: MIDI learn");
                let cell = ui.selectable_label(playing, format!("{}{mark}", info.id)).on_hover_text(hint);
                if cell.clicked() {
                    trigger(command);
                }
                if cell.secondary_clicked() {
                    hub.learn_clip(l, c);
                }
            }
            ui.end_row();
        }
    });
    events.extend(layer_faders(ui, instance));
    if !show.cues.is_empty() {
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("cues");
            if ui.button("GO").on_hover_text("the next cue (space bar, OSC /indra/cue/go)").clicked() {
                events.push(ControlEvent::Show(ShowCommand::CueGo));
            }
            if ui.button("back").clicked() {
                events.push(ControlEvent::Show(ShowCommand::CueBack));
            }
        });
        for (i, cue) in show.cues.iter().enumerate() {
            let hold = match cue.hold {
                Some(crate::scene::show::Length::Seconds(s)) => format!("{s} s"),
                Some(crate::scene::show::Length::Beats(b)) => format!("{b} beats"),
                None => "GO".into(),
            };
            let label = format!("{} {}  ({hold})", i + 1, cue.name);
            if ui.selectable_label(state.cue() == Some(i), label).clicked() {
                events.push(ControlEvent::Show(ShowCommand::CueGoto(i)));
            }
        }
    }
    ui.separator();
    events
}

/// Each layer's opacity and blend, and the master, as the panel's usual widgets.
fn layer_faders(ui: &mut egui::Ui, instance: &SceneInstance) -> Vec<ControlEvent> {
    let mut events = Vec::new();
    let Some((show, _)) = instance.show() else { return events };
    let nodes = show.layers.iter().map(|l| (l.node, l.name.clone())).chain([(show.master, "master".to_string())]);
    for (node, name) in nodes {
        let params = instance.params(node);
        // One id scope per node: every layer has a `blend` menu.
        ui.push_id(node, |ui| {
            ui.horizontal(|ui| {
                ui.label(name);
                for (p, decl) in params.decls().iter().enumerate() {
                    let mut value = params.target_at(p);
                    if super::param_widget::param_widget(ui, decl, &mut value) {
                        let write = ParamWrite { node, param: p, component: None, value, source: Source::Ui };
                        events.push(ControlEvent::Write(write));
                    }
                }
            })
        });
    }
    events
}
