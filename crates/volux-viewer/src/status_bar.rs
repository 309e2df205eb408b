//! The status bar along the window's bottom edge: the error (with its dismiss button) or the
//! passing message, and for a bricked volume the level and cache line
//! ([`ViewerApp::lod_status`]). Its height never depends on whether there is a message, so
//! the 3D view and the panels stay put when one appears or goes (a layout that jumps under
//! the pointer turns the next click into a misclick).
use eframe::egui;

use crate::app::ViewerApp;

/// The colour of an error's text.
const ERROR_COLOUR: egui::Color32 = egui::Color32::from_rgb(255, 120, 110);

/// Draws the status bar; call it before the side and central panels so that it spans the
/// window's width.
pub fn show(app: &mut ViewerApp, ctx: &egui::Context) {
    let rows = if app.is_bricked() { 2 } else { 1 };
    egui::TopBottomPanel::bottom("status")
        .exact_height(height(ctx, rows))
        .show(ctx, |ui| {
            message_row(app, ui);
            if let Some(s) = app.lod_status() {
                ui.add(egui::Label::new(s).truncate());
            }
        });
}

/// The bar's height for `rows` rows of one line each.
fn height(ctx: &egui::Context, rows: usize) -> f32 {
    let spacing = ctx.style().spacing.clone();
    let row = spacing.interact_size.y;
    let rows = rows as f32;
    rows * row + (rows - 1.0).max(0.0) * spacing.item_spacing.y
}

/// The error and its dismiss button, or the message, on one line (cut with "…" when longer
/// than the window is wide; the whole text shows when the pointer rests on it).
fn message_row(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        ui.set_min_height(ui.spacing().interact_size.y);
        if let Some(e) = &app.error {
            if ui.small_button("dismiss").clicked() {
                app.error = None;
                return;
            }
            let text = egui::RichText::new(format!("error: {}", one_line(e))).color(ERROR_COLOUR);
            ui.add(egui::Label::new(text).truncate())
                .on_hover_text(e.as_str());
        } else if let Some(s) = &app.status {
            ui.add(egui::Label::new(one_line(s)).truncate())
                .on_hover_text(s.as_str());
        }
    });
}

/// `text` on one line: its line breaks become " · ".
fn one_line(text: &str) -> String {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" · ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_message_of_several_lines_shows_on_one() {
        assert_eq!(one_line("a\n  b\n\nc "), "a · b · c");
        assert_eq!(one_line("plain"), "plain");
    }
}
