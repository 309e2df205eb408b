//! The three slice views under the 3D view: a click or drag moves the crosshair (shared
//! with the 3D view's plane outlines), a right drag sets the window (horizontal: level,
//! vertical: width), the patient or axis letters on the edges (on a dark backing), and a
//! caption strip under each image (plane, voxel, window) where the crosshair never crosses.
use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Sense, Stroke};

use crate::app::ViewerApp;
use crate::overlay_text::backed_text;
use crate::slices::{direction_name, Plane};

/// Height of the slice strip (points).
pub const STRIP_HEIGHT: f32 = 220.0;

/// Height of the caption strip under each slice's image (points).
const CAPTION_HEIGHT: f32 = 16.0;

/// The crosshair's colour in the slice views.
pub const CROSSHAIR_COLOUR: Color32 = Color32::from_rgba_unmultiplied_const(80, 220, 255, 160);

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
    let area = fitted(image_rect(rect), data.slices.world_size(plane));
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
    let font = FontId::proportional(13.0);
    let colour = Color32::from_rgb(240, 200, 90);
    let image = image_rect(rect);
    backed_text(
        &painter,
        Pos2::new(image.right() - 3.0, image.center().y),
        Align2::RIGHT_CENTER,
        &direction_name(right, medical),
        font.clone(),
        colour,
    );
    backed_text(
        &painter,
        Pos2::new(image.center().x, image.top() + 3.0),
        Align2::CENTER_TOP,
        &direction_name(top, medical),
        font,
        colour,
    );
    let idx = data.slices.index_of(app.crosshair);
    let [i, j, l] = idx;
    let window = window_caption(app.window, app.range());
    caption(
        &painter,
        caption_rect(rect),
        &format!("{} [{i}, {j}, {l}]", plane.name()),
        &window,
    );
}

/// The part of a slice's cell the image is fitted in: all but the caption strip.
fn image_rect(cell: Rect) -> Rect {
    let mut image = cell;
    image.max.y -= CAPTION_HEIGHT;
    image
}

/// The caption strip under a slice's image, where no crosshair line reaches.
fn caption_rect(cell: Rect) -> Rect {
    Rect::from_min_max(
        Pos2::new(cell.left(), cell.bottom() - CAPTION_HEIGHT),
        cell.max,
    )
}

/// Draws `left` and `right` in the caption strip `rect`, each on one line; a text longer
/// than its room ends in "…" rather than running out of the strip.
fn caption(painter: &egui::Painter, rect: Rect, left: &str, right: &str) {
    let font = FontId::proportional(11.0);
    let colour = Color32::LIGHT_GRAY;
    let room = (rect.width() - 8.0).max(8.0);
    let right = one_line(painter, right, font.clone(), colour, room * 0.6);
    let left_room = (room - right.size().x - 8.0).max(8.0);
    let left = one_line(painter, left, font, colour, left_room);
    let y = rect.center().y;
    let left_at = Align2::LEFT_CENTER.anchor_size(Pos2::new(rect.left() + 4.0, y), left.size());
    let right_at = Align2::RIGHT_CENTER.anchor_size(Pos2::new(rect.right() - 4.0, y), right.size());
    painter.galley(left_at.min, left, colour);
    painter.galley(right_at.min, right, colour);
}

/// `text` laid out on one line at most `width` wide, cut with "…".
fn one_line(
    painter: &egui::Painter,
    text: &str,
    font: FontId,
    colour: Color32,
    width: f32,
) -> std::sync::Arc<egui::Galley> {
    let mut job = egui::text::LayoutJob::simple_singleline(text.to_string(), font, colour);
    job.wrap = egui::text::TextWrapping::truncate_at_width(width);
    painter.layout_job(job)
}

/// The caption of window `[lo, hi]` over data spanning `range`: "window 40 – 400" for a
/// CT, "window 0.125 – 0.750" for data between 0 and 1.
pub fn window_caption(window: [f64; 2], range: [f64; 2]) -> String {
    let span = range[1] - range[0];
    format!(
        "window {} – {}",
        value_text(window[0], span),
        value_text(window[1], span)
    )
}

/// `v` with the decimals that give a value of the data's `span` three significant digits
/// (none for spans of 100 and more, as CT's Hounsfield units), and never "-0".
pub fn value_text(v: f64, span: f64) -> String {
    let magnitude = if span.is_finite() && span > 0.0 {
        span.log10().floor()
    } else {
        0.0
    };
    let decimals = (2.0 - magnitude).clamp(0.0, 9.0) as usize;
    let scale = 10f64.powi(decimals as i32);
    let rounded = (v * scale).round() / scale;
    // Rounding a small negative value gives -0.
    let rounded = if rounded == 0.0 { 0.0 } else { rounded };
    format!("{rounded:.decimals$}")
}

fn crosshair_lines(app: &ViewerApp, painter: &egui::Painter, plane: Plane, area: Rect) {
    let Some(data) = &app.data else { return };
    let (u, v) = data.slices.crosshair_fraction(plane, app.crosshair);
    let (u, v) = (u as f32, v as f32);
    let x = area.left() + u * area.width();
    let y = area.top() + v * area.height();
    let stroke = Stroke::new(1.0, CROSSHAIR_COLOUR);
    painter.line_segment(
        [Pos2::new(x, area.top()), Pos2::new(x, area.bottom())],
        stroke,
    );
    painter.line_segment(
        [Pos2::new(area.left(), y), Pos2::new(area.right(), y)],
        stroke,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Window values: integers for CT's Hounsfield units, three significant digits of the
    /// data's range otherwise, no "-0".
    #[test]
    fn window_values_have_sensible_precision() {
        let ct = [-1024.0, 3071.0];
        assert_eq!(
            window_caption([-160.0001, 240.4999], ct),
            "window -160 – 240"
        );
        assert_eq!(
            window_caption([0.123456, 0.75], [0.0, 1.0]),
            "window 0.12 – 0.75"
        );
        assert_eq!(value_text(12.3456, 50.0), "12.3");
        assert_eq!(value_text(0.000123456, 0.001), "0.00012");
        assert_eq!(value_text(-0.001, 1.0), "0.00");
        assert_eq!(value_text(-0.4, 4000.0), "0");
        assert_eq!(value_text(7.0, 0.0), "7.00", "a constant volume");
    }

    /// The caption strip and the image share no point: a crosshair line (drawn inside the
    /// image) never crosses the caption.
    #[test]
    fn the_caption_lies_outside_the_image() {
        let cell = Rect::from_min_size(Pos2::new(10.0, 20.0), egui::vec2(250.0, 208.0));
        let (image, caption) = (image_rect(cell), caption_rect(cell));
        assert!(image.max.y <= caption.min.y, "{image:?} {caption:?}");
        assert!(cell.contains_rect(caption) && cell.contains_rect(image));
        assert_eq!(caption.height(), CAPTION_HEIGHT);
    }
}
