//! The browser surface's part of the panel: its URL (with the access token) to copy, and a QR
//! code of it for a phone's camera.

use crate::control::web::qr;

/// Pixels per QR module: 33 modules (a typical URL) make a code of about 130 px.
const MODULE: f32 = 4.0;
/// Light modules around the code, as readers need.
const QUIET: f32 = 2.0;

/// Draws the surface's URLs and a QR code of the first (nothing when `--web` is off).
pub fn web_panel(ui: &mut egui::Ui, urls: &[String]) {
    let Some(first) = urls.first() else { return };
    egui::CollapsingHeader::new("browser control").default_open(false).show(ui, |ui| {
        for url in urls {
            ui.horizontal(|ui| {
                if ui.small_button("copy").clicked() {
                    ui.ctx().copy_text(url.clone());
                }
                ui.small(url);
            });
        }
        if let Some(rows) = qr::modules(first) {
            let side = (rows.len() as f32 + 2.0 * QUIET) * MODULE;
            let (rect, _) = ui.allocate_exact_size(egui::vec2(side, side), egui::Sense::hover());
            let painter = ui.painter_at(rect);
            painter.rect_filled(rect, 0.0, egui::Color32::WHITE);
            for (y, row) in rows.iter().enumerate() {
                for (x, _) in row.iter().enumerate().filter(|(_, dark)| **dark) {
                    let at = rect.min + egui::vec2((x as f32 + QUIET) * MODULE, (y as f32 + QUIET) * MODULE);
                    painter.rect_filled(
                        egui::Rect::from_min_size(at, egui::vec2(MODULE, MODULE)),
                        0.0,
                        egui::Color32::BLACK,
                    );
                }
            }
        }
        ui.small("anyone with this URL controls the show: share it like a key");
    });
}
