//! The lights in the panel: the patch's status, its fixtures drawn over the output, and their
//! handles to drag while editing (the next frame samples the moved fixture; "save patch" writes
//! the places back to the file).

use crate::dmx::{LiveLights, Shape};

/// The most LEDs of one strip drawn as dots (a long strip is drawn as its line).
const MAX_DOTS: u32 = 512;

/// The panel's lights section; returns a message for the performer (a save's outcome).
pub(super) fn lights_panel(ui: &mut egui::Ui, lights: &mut LiveLights) -> Option<String> {
    let mut message = None;
    egui::CollapsingHeader::new("lights (DMX)").default_open(false).show(ui, |ui| {
        ui.small(lights.status());
        ui.checkbox(&mut lights.show_fixtures, "show the fixtures over the output");
        ui.add_enabled(lights.show_fixtures, egui::Checkbox::new(&mut lights.editing, "drag the fixtures"));
        if ui.add_enabled(lights.moved, egui::Button::new("save patch")).clicked() {
            message = Some(lights.save().unwrap_or_else(|e| e));
        }
    });
    message
}

/// Draws each fixture over the output (which fills the window) and, while editing, a handle per
/// fixture that moves it when dragged.
pub(super) fn fixture_overlay(ctx: &egui::Context, lights: &mut LiveLights, queue: &wgpu::Queue) {
    if !lights.show_fixtures {
        return;
    }
    let screen = ctx.content_rect();
    let at = |p: (f32, f32)| egui::pos2(screen.left() + p.0 * screen.width(), screen.top() + p.1 * screen.height());
    let painter = ctx.layer_painter(egui::LayerId::new(egui::Order::Foreground, egui::Id::unique("dmx_fixtures")));
    let colour = egui::Color32::from_rgb(255, 200, 40);
    let stroke = egui::Stroke::new(1.5, colour);
    let mut moves = Vec::new();
    for (i, fixture) in lights.patch().fixtures.iter().enumerate() {
        match fixture.shape {
            Shape::Strip { from, to, pixels, .. } => {
                painter.line_segment([at(from), at(to)], stroke);
                if pixels <= MAX_DOTS {
                    let steps = pixels.saturating_sub(1).max(1) as f32;
                    for k in 0..pixels {
                        let t = k as f32 / steps;
                        let p = (from.0 + (to.0 - from.0) * t, from.1 + (to.1 - from.1) * t);
                        painter.circle_filled(at(p), 2.0, colour);
                    }
                }
            }
            Shape::Matrix { at: corner, size, .. } => {
                let rect = egui::Rect::from_two_pos(at(corner), at((corner.0 + size.0, corner.1 + size.1)));
                painter.rect_stroke(rect, 0.0, stroke, egui::StrokeKind::Inside);
            }
            Shape::Point { at: centre, size } => {
                painter.circle_stroke(at(centre), (size * screen.width() / 2.0).max(4.0), stroke);
            }
        }
        let handle = at(fixture.shape.handle());
        if lights.editing {
            let area = egui::Area::new(egui::Id::unique(("dmx_fixture", i))).order(egui::Order::Foreground);
            let response = area
                .fixed_pos(handle - egui::vec2(12.0, 10.0))
                .show(ctx, |ui| ui.add(egui::Button::new(&fixture.name).sense(egui::Sense::drag())))
                .inner;
            if response.dragged() {
                let d = response.drag_delta();
                moves.push((i, d.x / screen.width(), d.y / screen.height()));
            }
        } else {
            let font = egui::FontId::proportional(12.0);
            painter.text(handle, egui::Align2::CENTER_CENTER, &fixture.name, font, colour);
        }
    }
    for (i, dx, dy) in moves {
        lights.move_fixture(queue, i, dx, dy);
    }
}
