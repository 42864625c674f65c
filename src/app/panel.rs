//! The egui overlay: a parameter panel generated from the scene's declarations, the pass timing
//! list, and the error overlay.

use crate::control::ControlHub;
use crate::graph::{FrameStats, PassTiming};
use crate::params::{ControlEvent, Target};
use crate::params::{ParamWrite, Source};
use crate::scene::{AUDIO_BANDS, AudioSource, SceneInstance};
use crate::time::FrameTime;

use super::param_widget::param_widget;

/// egui's fonts, with Hack (monospace) behind the proportional font: Ubuntu Light has no
/// ●, ■ or ▶, which showed as a missing glyph on the record button.
pub fn panel_fonts() -> egui::FontDefinitions {
    let mut fonts = egui::FontDefinitions::default();
    if let Some(family) = fonts.families.get_mut(&egui::FontFamily::Proportional) {
        family.push("Hack".to_owned());
    }
    fonts
}

/// What the overlay shows besides parameters.
pub struct Overlay {
    /// Whether the side panel is shown (F1 toggles).
    pub panel_visible: bool,
    /// Last frame's graph stats.
    pub stats: Option<FrameStats>,
    /// Rolling per-pass GPU medians.
    pub timings: Vec<PassTiming>,
    /// Distinct errors with how often each happened; each is logged once. At most
    /// [`MAX_SHOWN_ERRORS`], newest kept: a flood of distinct failures cannot grow memory.
    errors: Vec<(String, u32)>,
    /// Errors pushed out of the list, and distinct errors logged so far.
    errors_dropped: u64,
    errors_logged: u64,
    /// Name typed for saving a preset.
    pub preset_name: String,
    /// Seconds a preset recall morphs over (0: instant).
    pub morph_seconds: f32,
    /// The video recording's status line, while one runs.
    pub recording: Option<String>,
    /// A status line per send (`run --stream`, `run --ndi-out`), while they run.
    pub sending: Vec<String>,
    /// The record button was clicked (the window starts or stops the recording).
    pub record_clicked: bool,
    /// How the last take ended.
    pub last_take: Option<String>,
    /// The show's timeline under the clip grid.
    pub lanes: super::lane_view::LaneView,
    /// What `auto` parameters take on this adapter (`Tuning::summary`).
    pub tuning: String,
}

impl Default for Overlay {
    fn default() -> Self {
        Self {
            panel_visible: true,
            stats: None,
            timings: Vec::new(),
            errors: Vec::new(),
            errors_dropped: 0,
            errors_logged: 0,
            preset_name: "preset-1".into(),
            morph_seconds: 0.0,
            recording: None,
            sending: Vec::new(),
            record_clicked: false,
            last_take: None,
            lanes: Default::default(),
            tuning: String::new(),
        }
    }
}

impl Overlay {
    /// Forgets shown errors (after a fix was picked up).
    pub fn clear_errors(&mut self) {
        self.errors.clear();
        self.errors_dropped = 0;
    }

    /// Records an error: logged the first time, counted after that, shown until dismissed.
    /// Long messages are cut; past [`MAX_SHOWN_ERRORS`] the oldest make room (and are counted),
    /// and past [`MAX_LOGGED_ERRORS`] distinct ones are no longer logged.
    pub fn report(&mut self, message: String) {
        let message = match message.char_indices().nth(MAX_ERROR_CHARS) {
            Some((cut, _)) => format!("{}…", &message[..cut]),
            None => message,
        };
        if let Some((_, count)) = self.errors.iter_mut().find(|(m, _)| *m == message) {
            *count = count.saturating_add(1);
            return;
        }
        self.errors_logged += 1;
        if self.errors_logged <= MAX_LOGGED_ERRORS {
            log::error!("{message}");
        } else if self.errors_logged == MAX_LOGGED_ERRORS + 1 {
            log::error!("{MAX_LOGGED_ERRORS} distinct errors logged; further ones are only shown");
        }
        if self.errors.len() == MAX_SHOWN_ERRORS {
            self.errors.remove(0);
            self.errors_dropped += 1;
        }
        self.errors.push((message, 1));
    }
}

/// Distinct errors the overlay lists at once.
pub const MAX_SHOWN_ERRORS: usize = 20;
/// Distinct errors logged before the log only gets a count.
pub const MAX_LOGGED_ERRORS: u64 = 200;
/// Longest error shown, in characters.
pub const MAX_ERROR_CHARS: usize = 400;

/// The live input's level meter and spectrum, and its tempo estimate with a button to take it.
fn audio_panel(ui: &mut egui::Ui, frame: &crate::control::audio::AudioFrame) -> Option<ControlEvent> {
    ui.add(egui::ProgressBar::new(frame.level.clamp(0.0, 1.0)).desired_height(6.0).text("level"));
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width().min(240.0), 36.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    let width = rect.width() / frame.bands.len().max(1) as f32;
    for (i, band) in frame.bands.iter().enumerate() {
        let x = rect.left() + i as f32 * width;
        let top = rect.bottom() - band.clamp(0.0, 1.0) * rect.height();
        let bar = egui::Rect::from_min_max(egui::pos2(x + 1.0, top), egui::pos2(x + width - 1.0, rect.bottom()));
        painter.rect_filled(bar, 0.0, if frame.onset { egui::Color32::WHITE } else { egui::Color32::LIGHT_BLUE });
    }
    let bpm = frame.bpm?;
    let mut take = None;
    ui.horizontal(|ui| {
        ui.small(format!("the audio suggests {bpm:.1} BPM"));
        if ui.small_button("use").clicked() {
            take = Some(ControlEvent::Tempo { bpm, resync: false });
        }
    });
    take
}

/// The record button and, while recording, the file, length and lost frames.
fn record_panel(ui: &mut egui::Ui, overlay: &mut Overlay) {
    ui.horizontal(|ui| {
        let (label, hint) = match overlay.recording {
            Some(_) => ("■ stop recording", "finish the video file"),
            None => ("● record video", "record the output as shown (also OSC /indra/record/start, /stop)"),
        };
        if ui.button(label).on_hover_text(hint).clicked() {
            overlay.record_clicked = true;
        }
    });
    if let Some(status) = overlay.recording.as_ref().or(overlay.last_take.as_ref()) {
        ui.small(status);
    }
    for status in &overlay.sending {
        ui.small(status);
    }
}

/// Draws the whole overlay for one frame; returns the control events the performer made.
pub fn draw_ui(
    ui: &mut egui::Ui,
    instance: &mut SceneInstance,
    overlay: &mut Overlay,
    hub: &mut ControlHub,
    time: FrameTime,
    mut lights: Option<(&mut crate::dmx::LiveLights, &wgpu::Queue)>,
) -> Vec<ControlEvent> {
    let mut events = Vec::new();
    if let Some((lights, queue)) = lights.as_mut() {
        super::lights_panel::fixture_overlay(ui.ctx(), lights, queue);
    }
    if overlay.panel_visible {
        egui::Panel::left("indra_params").resizable(true).default_size(300.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.heading(&instance.scene().name);
                ui.label(format!("t = {:.2} s   frame {}", time.seconds, time.frame));
                ui.horizontal(|ui| {
                    ui.checkbox(&mut instance.animate, "play animation tracks");
                    if ui
                        .button("resume tracks")
                        .on_hover_text("give taken-over parameters back to their tracks")
                        .clicked()
                    {
                        events.push(ControlEvent::ResumeTracks);
                    }
                });
                let tempo = instance.tempo();
                ui.horizontal(|ui| {
                    // The beat within the bar of four, so the performer sees the phase.
                    let beat = tempo.beats.rem_euclid(4.0).floor() as u32 + 1;
                    ui.label(format!("{:.1} BPM  beat {beat}/4", tempo.bpm));
                    if ui.button("tap").on_hover_text("tap tempo (key T, OSC /indra/tempo/tap)").clicked() {
                        events.extend(hub.tap_tempo());
                    }
                });
                if let Some(frame) = hub.audio_frame.clone() {
                    events.extend(audio_panel(ui, &frame));
                }
                ui.small(hub.status());
                super::web_panel::web_panel(ui, &hub.web_urls);
                events.extend(super::show_panel::show_panel(ui, instance, hub));
                events.extend(overlay.lanes.draw(ui, instance, time));
                events.extend(super::effects_panel::effects_panel(ui, instance, hub));
                if let Some((lights, _)) = lights.as_mut()
                    && let Some(message) = super::lights_panel::lights_panel(ui, lights)
                {
                    overlay.report(message);
                }
                events.extend(param_panel(ui, instance, hub).into_iter().map(ControlEvent::Write));
                ui.separator();
                events.extend(preset_panel(ui, instance, overlay, hub));
                ui.separator();
                record_panel(ui, overlay);
                ui.separator();
                timing_panel(ui, overlay);
                ui.small("F1: hide panel · F2: resume tracks · 1–9: presets · space: GO (shows) · F11: fullscreen · Esc: leave fullscreen");
            });
        });
    }
    if !overlay.errors.is_empty() {
        let mut dismiss = false;
        egui::Window::new("errors").anchor(egui::Align2::RIGHT_BOTTOM, [-8.0, -8.0]).show(ui.ctx(), |ui| {
            if overlay.errors_dropped > 0 {
                ui.label(format!("({} older errors not shown)", overlay.errors_dropped));
            }
            for (message, count) in &overlay.errors {
                let suffix = if *count > 1 { format!("  (×{count})") } else { String::new() };
                ui.colored_label(egui::Color32::from_rgb(255, 110, 110), format!("{message}{suffix}"));
            }
            dismiss = ui.button("dismiss").clicked();
        });
        if dismiss {
            overlay.clear_errors();
        }
    }
    events
}

/// Save the current values under a name; recall saved presets (1–9 on the keyboard too).
fn preset_panel(
    ui: &mut egui::Ui,
    instance: &SceneInstance,
    overlay: &mut Overlay,
    hub: &mut ControlHub,
) -> Vec<ControlEvent> {
    let mut events = Vec::new();
    ui.label("presets");
    ui.horizontal(|ui| {
        ui.text_edit_singleline(&mut overlay.preset_name);
        if ui.button("save").clicked() {
            let name = overlay.preset_name.clone();
            hub.save_preset(&name, instance.view());
        }
    });
    ui.add(egui::Slider::new(&mut overlay.morph_seconds, 0.0..=10.0).text("morph s"));
    ui.horizontal_wrapped(|ui| {
        for (i, name) in hub.preset_names().to_vec().iter().enumerate() {
            let label = if i < 9 { format!("{} {name}", i + 1) } else { name.clone() };
            if ui.button(label).clicked() {
                events.extend(hub.recall(name, f64::from(overlay.morph_seconds), instance.scene()));
            }
        }
    });
    events
}

/// The parameter panel; returns the writes the performer made this frame. Each parameter has a
/// MIDI learn button: click it, move a control; right-click unlearns. Numbers, bools and triggers
/// also have an audio button: click it, pick a source (shown with its live value); right-click
/// unlearns. With DMX in, a DMX learn button: click it, move a channel on the desk.
fn param_panel(ui: &mut egui::Ui, instance: &SceneInstance, hub: &mut ControlHub) -> Vec<ParamWrite> {
    let mut writes = Vec::new();
    for node in 0..instance.scene().nodes.len() {
        // A show lists the nodes of the clips on screen (and its layers and master, to learn).
        if let Some((show, state)) = instance.show()
            && show.clip_of(node).is_some_and(|c| !state.visible(c))
        {
            continue;
        }
        let header = format!("{} ({})", instance.scene().nodes[node].id, instance.scene().nodes[node].technique.name);
        egui::CollapsingHeader::new(header).default_open(true).show(ui, |ui| {
            if let Some(status) = instance.status(node) {
                ui.label(egui::RichText::new(status).small());
            }
            for (p, decl) in instance.params(node).decls().iter().enumerate() {
                let animated = instance.is_animated(node, p);
                let mut value = instance.params(node).target_at(p);
                let changed = ui
                    .horizontal(|ui| {
                        let target = Target { node, param: p, component: None };
                        let learning = hub.mapper.learning == Some(target);
                        // ASCII: egui's bundled fonts lack the usual dot glyphs.
                        let mark = if learning {
                            "?"
                        } else if hub.mapper.is_mapped(node, p) {
                            "M"
                        } else {
                            "m"
                        };
                        let hint = "MIDI learn: click, then move a control; right-click to unlearn";
                        let learn = ui.small_button(mark).on_hover_text(hint);
                        if learn.clicked() {
                            hub.learn(target);
                        }
                        if learn.secondary_clicked() {
                            hub.unlearn(node, p, instance.scene());
                        }
                        if decl.ty().is_scalar() {
                            audio_learn_button(ui, instance, hub, target);
                        }
                        if let Some(dmx) = hub.dmx.as_mut() {
                            let mark = match (dmx.learning() == Some(target), dmx.maps(target)) {
                                (true, _) => "?",
                                (false, true) => "D",
                                (false, false) => "d",
                            };
                            let hint = "DMX learn: click, then move a channel on the desk";
                            if ui.small_button(mark).on_hover_text(hint).clicked() {
                                let id = &instance.scene().nodes[node].id;
                                dmx.learn(target, format!("{id}.{}", decl.name));
                            }
                        }
                        let label = ui.label(&decl.name).on_hover_text(&decl.doc);
                        if animated {
                            label.on_hover_text("driven by a track: moving it takes over until 'resume tracks'");
                        } else if instance.is_overridden(node, p) {
                            ui.small("(live)");
                        }
                        param_widget(ui, decl, &mut value)
                    })
                    .inner;
                if changed {
                    writes.push(ParamWrite { node, param: p, component: None, value, source: Source::Ui });
                }
            }
        });
    }
    writes
}

/// The audio learn menu of one parameter: "a", "A" when audio moves it (learned or from the
/// scene), "A*" when the mapping was learned here.
fn audio_learn_button(ui: &mut egui::Ui, instance: &SceneInstance, hub: &mut ControlHub, target: Target) {
    let scene = instance.scene();
    let (mapped, learned) = hub.audio_mapped(target.node, target.param);
    let mark = match (mapped, learned) {
        (_, true) => "A*",
        (true, false) => "A",
        _ => "a",
    };
    let mut picked = None;
    let menu = ui.menu_button(mark, |ui| {
        // Read only while the menu is open: this button is drawn for every parameter each frame.
        if hub.audio_frame.is_none() {
            ui.small("no sound heard yet (an input opens once something is mapped, unless --no-audio)");
        }
        let frame = hub.audio_frame.clone().unwrap_or_default();
        let pulse = |on: bool| if on { "HIT" } else { "-" };
        let band = |b: usize| frame.bands.get(b).copied().unwrap_or(0.0);
        let mut sources = vec![
            (AudioSource::Level, format!("level {:.2}", frame.level)),
            (AudioSource::Peak, format!("peak {:.2}", frame.peak)),
            (AudioSource::Low, format!("low {:.2}", frame.low)),
            (AudioSource::Mid, format!("mid {:.2}", frame.mid)),
            (AudioSource::High, format!("high {:.2}", frame.high)),
            (AudioSource::Onset, format!("onset {}", pulse(frame.onset))),
            (AudioSource::Beat, format!("beat {}", pulse(frame.beat))),
        ];
        let mut choose = |ui: &mut egui::Ui, source: AudioSource, label: String| {
            if ui.button(label).clicked() {
                picked = Some(source);
                ui.close();
            }
        };
        for (source, label) in sources.drain(..) {
            choose(ui, source, label);
        }
        ui.menu_button("bands (30 Hz - 16 kHz)", |ui| {
            for b in 0..AUDIO_BANDS {
                choose(ui, AudioSource::Band(b as u8), format!("band {b} {:.2}", band(b)));
            }
        });
    });
    let menu = menu.response.on_hover_text("audio learn: click, pick a source; right-click to unlearn");
    if menu.secondary_clicked() {
        hub.unlearn_audio(target.node, target.param, scene);
    }
    if let Some(source) = picked {
        hub.learn_audio(target, source, instance.view());
    }
}

fn timing_panel(ui: &mut egui::Ui, overlay: &Overlay) {
    ui.small(&overlay.tuning);
    ui.label("GPU time per pass (rolling median)");
    if overlay.timings.is_empty() {
        ui.small("no timestamps on this adapter, or none yet");
    }
    for t in &overlay.timings {
        ui.monospace(format!("{:<24} {:>7.3} ms", t.name, t.median_ms));
    }
    if let Some(s) = &overlay.stats {
        ui.small(format!(
            "passes {}/{} · transient {} / {} KiB · compile {:.0} µs",
            s.passes_executed,
            s.passes_declared,
            s.transient_bytes_allocated / 1024,
            s.transient_bytes_requested / 1024,
            s.compile_time.as_secs_f64() * 1e6
        ));
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_character_the_panel_can_show_is_in_its_proportional_fonts() {
        let fonts = panel_fonts();
        let family = &fonts.families[&egui::FontFamily::Proportional];
        // The panel's labels, the recording line and the status lines come from these files.
        let sources = [
            include_str!("panel.rs"),
            include_str!("window.rs"),
            include_str!("lane_view.rs"),
            include_str!("../control/hub.rs"),
        ];
        let mut symbols: Vec<char> = sources.iter().flat_map(|s| s.chars()).filter(|c| !c.is_ascii()).collect();
        symbols.sort_unstable();
        symbols.dedup();
        assert!(symbols.contains(&'●'), "the record symbol is among them");
        for symbol in symbols {
            let covered = family.iter().any(|name| {
                let data = &fonts.font_data[name];
                let bytes: &[u8] = (*data.font).as_ref();
                ttf_parser::Face::parse(bytes, data.index).is_ok_and(|f| f.glyph_index(symbol).is_some())
            });
            assert!(covered, "no proportional font draws {symbol}");
        }
    }

    use super::*;

    #[test]
    fn a_flood_of_distinct_errors_keeps_the_overlay_bounded() {
        let mut overlay = Overlay::default();
        for i in 0..10_000 {
            overlay.report(format!("preset '{i}' not found {}", "x".repeat(1000)));
            overlay.report(format!("preset '{i}' not found {}", "x".repeat(1000)));
        }
        assert_eq!(overlay.errors.len(), MAX_SHOWN_ERRORS);
        assert_eq!(overlay.errors_dropped, 10_000 - MAX_SHOWN_ERRORS as u64);
        assert!(overlay.errors.iter().all(|(m, n)| m.chars().count() <= MAX_ERROR_CHARS + 1 && *n == 2));
        assert!(overlay.errors.last().unwrap().0.starts_with("preset '9999'"), "the newest are kept");
    }
}
