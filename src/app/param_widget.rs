//! The widget of one parameter, by its type: sliders, a pad for pairs, a colour button. Both
//! the scene's panel and the show's panel draw parameters with it.

use crate::params::{ParamDecl, ParamValue};

/// The widget of one parameter by its type; whether the performer changed it.
pub(super) fn param_widget(ui: &mut egui::Ui, decl: &ParamDecl, value: &mut ParamValue) -> bool {
    let (lo, hi) = decl.range.unwrap_or((-1e6, 1e6));
    match value {
        // Wide positive ranges (zoom, radius) need a logarithmic slider to be playable.
        ParamValue::Float(x) => {
            ui.add(egui::Slider::new(x, lo..=hi).logarithmic(lo > 0.0 && hi / lo >= 100.0).suffix(&decl.unit)).changed()
        }
        ParamValue::Int(i) => ui.add(egui::Slider::new(i, lo as i32..=hi as i32)).changed(),
        ParamValue::Bool(b) => ui.checkbox(b, "").changed(),
        ParamValue::Trigger(fired) => {
            *fired = ui.button("fire").clicked();
            *fired
        }
        ParamValue::Text(text) => {
            let mut edit = text.as_str().to_string();
            let changed = ui.text_edit_singleline(&mut edit).changed();
            if changed {
                *text = crate::params::Text::new(&edit);
            }
            changed
        }
        ParamValue::Enum(i) => {
            let before = *i;
            let shown = decl.format(&ParamValue::Enum(*i));
            egui::ComboBox::from_id_salt(&decl.name).selected_text(shown).show_ui(ui, |ui| {
                for (k, option) in decl.options.iter().enumerate() {
                    ui.selectable_value(i, k as u32, option);
                }
            });
            *i != before
        }
        ParamValue::Vec2(v) => {
            let pad = vec2_pad(ui, v, (lo, hi));
            let a = ui.add(egui::DragValue::new(&mut v[0]).speed(0.001).range(lo..=hi)).changed();
            let b = ui.add(egui::DragValue::new(&mut v[1]).speed(0.001).range(lo..=hi)).changed();
            pad || a || b
        }
        ParamValue::Vec3(v) => drag_components(ui, v),
        ParamValue::Vec4(v) => drag_components(ui, v),
        ParamValue::Color(c) => {
            // Scene colours are sRGB-encoded, as the picker's bytes are.
            let mut bytes = c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
            let changed = ui.color_edit_button_srgba_unmultiplied(&mut bytes).changed();
            if changed {
                *c = bytes.map(|b| f32::from(b) / 255.0);
            }
            changed
        }
    }
}

/// One drag field per component; every field is drawn even after one changed.
fn drag_components(ui: &mut egui::Ui, components: &mut [f32]) -> bool {
    let mut changed = false;
    for x in components {
        changed |= ui.add(egui::DragValue::new(x).speed(0.01)).changed();
    }
    changed
}

/// A square pad: dragging inside sets both components across the range.
fn vec2_pad(ui: &mut egui::Ui, v: &mut [f32; 2], (lo, hi): (f32, f32)) -> bool {
    let (rect, response) = ui.allocate_exact_size(egui::vec2(48.0, 48.0), egui::Sense::drag());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 3.0, ui.visuals().extreme_bg_color);
    let to_unit = |x: f32| ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    let dot = egui::pos2(rect.left() + to_unit(v[0]) * rect.width(), rect.bottom() - to_unit(v[1]) * rect.height());
    painter.circle_filled(dot, 3.0, ui.visuals().strong_text_color());
    match response.interact_pointer_pos() {
        Some(p) if response.dragged() => {
            v[0] = lo + ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0) * (hi - lo);
            v[1] = lo + ((rect.bottom() - p.y) / rect.height()).clamp(0.0, 1.0) * (hi - lo);
            true
        }
        _ => false,
    }
}
