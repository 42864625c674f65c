//! The show's effect chains on the panel: per layer and for the master, each effect with its
//! bypass, its dry/wet mix and buttons to move it up or down or remove it, and a picker that adds
//! one from the library (every ISF filter there is, and the techniques that take an image). Every
//! click is a control event, as OSC sends them; an added effect is built off the render thread.
//! A right-click on a button or a library entry learns a MIDI note for that edit.

use crate::control::hub::ControlHub;
use crate::params::{ControlEvent, EffectEdit, ParamValue, ParamWrite, ShowCommand, Source, Text};
use crate::scene::SceneInstance;
use crate::scene::show::effects::{BYPASS, MIX, library};

/// Draws every chain of `instance`'s show (nothing for a scene); returns what was clicked.
pub fn effects_panel(ui: &mut egui::Ui, instance: &SceneInstance, hub: &mut ControlHub) -> Vec<ControlEvent> {
    let mut events = Vec::new();
    let Some((show, _)) = instance.show() else { return events };
    let chains = show.layers.iter().enumerate().map(|(l, layer)| (Some(l), layer.name.clone(), &layer.effects));
    let chains: Vec<_> = chains.chain([(None, "master".to_string(), &show.master_effects)]).collect();
    if let Some((_, assets, _)) = instance.show_context() {
        library::start(&assets);
    }
    for (layer, name, effects) in chains {
        let command = |edit| ShowCommand::Effect { layer, edit };
        ui.push_id(("effects", layer), |ui| {
            egui::CollapsingHeader::new(format!("effects: {name} ({})", effects.len())).show(ui, |ui| {
                for (k, &node) in effects.iter().enumerate() {
                    let params = instance.params(node);
                    ui.horizontal(|ui| {
                        ui.label(format!("{} {}", k + 1, effect_name(instance, node)));
                        for (p, decl) in
                            params.decls().iter().enumerate().filter(|(_, d)| [BYPASS, MIX].contains(&&*d.name))
                        {
                            let mut value = params.target_at(p);
                            if super::param_widget::param_widget(ui, decl, &mut value) {
                                let write = ParamWrite { node, param: p, component: None, value, source: Source::Ui };
                                events.push(ControlEvent::Write(write));
                            }
                        }
                        let mut button = |label: &str, edit| {
                            let command = command(edit);
                            let clicked = ui.small_button(learn_mark(label, command, hub)).on_hover_text(LEARN_HINT);
                            if clicked.secondary_clicked() {
                                hub.learn_command(command);
                            }
                            clicked.clicked().then_some(ControlEvent::Show(command))
                        };
                        if k > 0 {
                            events.extend(button("up", EffectEdit::Move { from: k, to: k - 1 }));
                        }
                        if k + 1 < effects.len() {
                            events.extend(button("down", EffectEdit::Move { from: k, to: k + 1 }));
                        }
                        events.extend(button("remove", EffectEdit::Remove(k)));
                    });
                }
                let Some(names) = library::names() else {
                    ui.small("reading the effect library…");
                    return;
                };
                egui::ComboBox::from_id_salt("add").selected_text("add an effect").show_ui(ui, |ui| {
                    for effect in names {
                        let command = command(EffectEdit::Add(Text::new(effect)));
                        let entry =
                            ui.selectable_label(false, learn_mark(effect, command, hub)).on_hover_text(LEARN_HINT);
                        if entry.clicked() {
                            events.push(ControlEvent::Show(command));
                        }
                        if entry.secondary_clicked() {
                            hub.learn_command(command);
                        }
                    }
                });
            });
        });
    }
    events
}

/// What a right-click does.
const LEARN_HINT: &str = "right-click, then play a note: MIDI learn";

/// `label` with the mark of its MIDI learn state.
fn learn_mark(label: &str, command: ShowCommand, hub: &ControlHub) -> String {
    format!("{label}{}", hub.mapper.learn_mark(command))
}

/// What effect node `node` plays: its file's name, else its technique's.
fn effect_name(instance: &SceneInstance, node: usize) -> String {
    let params = instance.params(node);
    match params.index("file").map(|i| params.value_at(i)) {
        Some(ParamValue::Text(file)) => {
            std::path::Path::new(file.as_str()).file_stem().map_or_else(String::new, |s| s.to_string_lossy().into())
        }
        _ => instance.scene().nodes[node].technique.name.to_string(),
    }
}
