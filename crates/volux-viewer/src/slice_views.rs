//! The three slice views under the 3D view: a click or drag moves the crosshair (shared
//! with the 3D view's plane outlines), a right drag sets the window (horizontal: level,
//! vertical: width), the patient or axis letters on the edges.
use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Sense, Stroke};

use crate::app::ViewerApp;
use crate::slices::{direction_name, Plane};

/// Height of the slice strip (points).
pub const STRIP_HEIGHT: f32 = 220.0;

/// Draws the slice strip when a dataset is open.
pub fn show(app: &mut ViewerApp, ctx: &egui::Context) {
    if app.data.is_none() {
        return;
    }
    refresh_textures(app, ctx);
    egui::TopBottomPanel::bottom("slices")
        .exact_height(STRIP_HEIGHT)
        .show(ctx, |ui| {
            ui.horizontal(|ui| {
                let w = (ui.available_width() / 3.0 - 6.0).max(40.0);
                for (k, plane) in Plane::ALL.into_iter().enumerate() {
                    let (rect, response) = ui.allocate_exact_size(
                        egui::vec2(w, STRIP_HEIGHT - 12.0),
                        Sense::click_and_drag(),
                    );
                    slice_view(app, ui, k, plane, rect, &response);
                }
            });
        });
}

/// Re-cuts the slices when the crosshair's sample or the window changed.
fn refresh_textures(app: &mut ViewerApp, ctx: &egui::Context) {
    let Some(data) = &app.data else { return };
    let key = (
        data.volume.id,
        app.window,
        data.slices.index_of(app.crosshair),
    );
    if app.slices_key == Some(key) {
        return;
    }
    for (k, plane) in Plane::ALL.into_iter().enumerate() {
        let img = data.slices.slice(plane, app.crosshair, app.window);
        let colour = egui::ColorImage::from_rgba_unmultiplied([img.width, img.height], &img.rgba);
        app.slice_textures[k] = Some(ctx.load_texture(
            format!("slice-{}", plane.name()),
            colour,
            egui::TextureOptions::NEAREST,
        ));
    }
    app.slices_key = Some(key);
}

/// Where a slice of world size `size` sits in `rect`, aspect kept.
fn fitted(rect: Rect, size: [f64; 2]) -> Rect {
    let [w, h] = size;
    let s = (rect.width() as f64 / w.max(1e-12)).min(rect.height() as f64 / h.max(1e-12));
    Rect::from_center_size(rect.center(), egui::vec2((w * s) as f32, (h * s) as f32))
}

fn slice_view(
    app: &mut ViewerApp,
    ui: &egui::Ui,
    k: usize,
    plane: Plane,
    rect: Rect,
    response: &egui::Response,
) {
    let Some(data) = app.data.clone() else { return };
    let area = fitted(rect, data.slices.world_size(plane));
    if response.dragged_by(egui::PointerButton::Secondary) {
        let d = response.drag_delta();
        let [lo, hi] = app.window;
        let range = app.range();
        let span = (range[1] - range[0]).max(1e-12);
        let level = (lo + hi) * 0.5 + d.x as f64 / area.width().max(1.0) as f64 * span;
        let width = ((hi - lo) * (d.y as f64 / 100.0).exp()).max(span * 1e-4);
        app.window = [level - width * 0.5, level + width * 0.5];
    } else if let Some(p) = response.interact_pointer_pos() {
        if response.dragged_by(egui::PointerButton::Primary) || response.clicked() {
            let u = ((p.x - area.left()) / area.width().max(1.0)) as f64;
            let v = ((p.y - area.top()) / area.height().max(1.0)) as f64;
            app.crosshair = data.slices.pick(plane, app.crosshair, u, v);
        }
    }
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::BLACK);
    if let Some(t) = &app.slice_textures[k] {
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(t.id(), area, uv, Color32::WHITE);
    }
    crosshair_lines(app, &painter, plane, area);
    let (right, top) = data.slices.edge_directions(plane);
    let medical = data.is_medical();
    let letters = (direction_name(right, medical), direction_name(top, medical));
    let font = FontId::proportional(13.0);
    let colour = Color32::from_rgb(240, 200, 90);
    painter.text(
        Pos2::new(rect.right() - 4.0, rect.center().y),
        Align2::RIGHT_CENTER,
        letters.0,
        font.clone(),
        colour,
    );
    painter.text(
        Pos2::new(rect.center().x, rect.top() + 2.0),
        Align2::CENTER_TOP,
        letters.1,
        font.clone(),
        colour,
    );
    let idx = data.slices.index_of(app.crosshair);
    painter.text(
        rect.left_bottom() + egui::vec2(4.0, -4.0),
        Align2::LEFT_BOTTOM,
        format!(
            "{} · {:?} · window [{:.4}, {:.4}]",
            plane.name(),
            idx,
            app.window[0],
            app.window[1]
        ),
        FontId::monospace(10.0),
        Color32::LIGHT_GRAY,
    );
}

fn crosshair_lines(app: &ViewerApp, painter: &egui::Painter, plane: Plane, area: Rect) {
    let Some(data) = &app.data else { return };
    let (u, v) = data.slices.crosshair_fraction(plane, app.crosshair);
    let (u, v) = (u as f32, v as f32);
    let x = area.left() + u * area.width();
    let y = area.top() + v * area.height();
    let stroke = Stroke::new(1.0, Color32::from_rgba_unmultiplied(80, 220, 255, 160));
    painter.line_segment(
        [Pos2::new(x, area.top()), Pos2::new(x, area.bottom())],
        stroke,
    );
    painter.line_segment(
        [Pos2::new(area.left(), y), Pos2::new(area.right(), y)],
        stroke,
    );
}
