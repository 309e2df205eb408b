//! The sculpting tools in the 3D view (seed `004_*.txt` ch. 4-6): the left button's gestures
//! in the tool modes, the keyboard shortcuts, and the overlay (the outline of the volume of
//! interest, the eraser's and digger's cursor, the measured polylines with their lengths, the
//! labelling seeds). Mouse positions become pixels of the rendered image, the coordinates the
//! engine's steps use.
use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Stroke};
use glam::DVec3;
use volux_core::Camera;
use volux_render::sculpt::polyline_length;

use crate::app::ViewerApp;
use crate::overlay_text::{backed_text, BACKING};
use crate::sculpt_state::Tool;

/// Whether the left button belongs to a tool now (not with Alt held: Alt+drag navigates).
pub fn tool_owns_left_button(app: &ViewerApp, ui: &egui::Ui) -> bool {
    app.tools.tool != Tool::Navigate && !ui.input(|i| i.modifiers.alt)
}

/// Applies the left button's gestures of the current tool.
pub fn gestures(app: &mut ViewerApp, ui: &egui::Ui, response: &egui::Response) {
    let left = egui::PointerButton::Primary;
    let pixel = |app: &ViewerApp, pos: Pos2| image_pixel(app, response.rect, pos);
    let shift = ui.input(|i| i.modifiers.shift);
    let clicked = response.clicked_by(left);
    let click_at = response.interact_pointer_pos().map(|p| pixel(app, p));
    match app.tools.tool {
        Tool::Navigate => {}
        Tool::Erase => erase_gesture(app, ui, response),
        Tool::Dig if clicked => {
            if let Some(p) = click_at {
                app.dig_at(p);
            }
        }
        Tool::Measure if clicked => {
            if let Some(p) = click_at {
                let new_line = shift || app.tools.new_line;
                app.measure_at(p, new_line);
                app.tools.new_line = false;
            }
        }
        Tool::Label if clicked => {
            if let Some(p) = click_at {
                app.label_at(p);
            }
        }
        _ => {}
    }
}

/// The eraser (sec. 4.4): a drag collects the stroke, applied on release as one step; a
/// click erases one disc.
fn erase_gesture(app: &mut ViewerApp, ui: &egui::Ui, response: &egui::Response) {
    let left = egui::PointerButton::Primary;
    let rect = response.rect;
    if response.drag_started_by(left) {
        app.tools.stroke.clear();
        if let Some(origin) = ui.input(|i| i.pointer.press_origin()) {
            app.tools.stroke.push(image_pixel(app, rect, origin));
        }
    }
    if response.dragged_by(left) {
        if let Some(pos) = response.interact_pointer_pos() {
            let p = image_pixel(app, rect, pos);
            let far = app.tools.stroke.last().is_none_or(|q| {
                let d = [p[0] - q[0], p[1] - q[1]];
                d[0].hypot(d[1]) >= 0.5
            });
            if far {
                app.tools.stroke.push(p);
            }
        }
    }
    if response.drag_stopped_by(left) {
        let stroke = std::mem::take(&mut app.tools.stroke);
        app.erase_stroke(stroke);
    } else if response.clicked_by(left) {
        if let Some(pos) = response.interact_pointer_pos() {
            app.erase_stroke(vec![image_pixel(app, rect, pos)]);
        }
    }
}

/// Tool shortcuts (N, E, D, M, L), undo (Ctrl+Z) and redo (Ctrl+Shift+Z, Ctrl+Y), unless a
/// text field has the keyboard.
pub fn shortcuts(app: &mut ViewerApp, ctx: &egui::Context) {
    if app.data.is_none() || ctx.wants_keyboard_input() {
        return;
    }
    let command = egui::Modifiers::COMMAND;
    let redo = ctx.input_mut(|i| {
        i.consume_key(command | egui::Modifiers::SHIFT, egui::Key::Z)
            || i.consume_key(command, egui::Key::Y)
    });
    let undo = ctx.input_mut(|i| i.consume_key(command, egui::Key::Z));
    if redo {
        app.redo();
    } else if undo {
        app.undo();
    }
    let grid = app.sculpt_grid().is_some();
    for tool in Tool::ALL {
        let pressed = ctx.input_mut(|i| i.consume_key(egui::Modifiers::NONE, tool.key()));
        if pressed && (grid || !tool.needs_grid()) {
            app.tools.tool = tool;
        }
    }
}

/// The pixel of the rendered image (x right, y down, continuous) under `pos` in the view
/// `rect`.
pub fn image_pixel(app: &ViewerApp, rect: Rect, pos: Pos2) -> [f64; 2] {
    let scene = app.render_scene();
    let (w, h) = (scene.view.width as f64, scene.view.height as f64);
    let rel = pos - rect.min;
    [
        rel.x as f64 / rect.width().max(1.0) as f64 * w,
        rel.y as f64 / rect.height().max(1.0) as f64 * h,
    ]
}

/// Draws the sculpt overlay over the 3D view.
pub fn overlay(app: &ViewerApp, ui: &egui::Ui, painter: &egui::Painter, rect: Rect) {
    let camera = app.scene.view.camera;
    let project = |p: DVec3| project(&camera, rect, p);
    voi_outline(app, painter, &project);
    measurements(app, painter, &project);
    label_seeds(app, painter, &project);
    cursor(app, ui, painter, rect);
}

/// `p` in the view (points), or `None` behind the camera.
pub fn project(camera: &Camera, rect: Rect, p: DVec3) -> Option<Pos2> {
    let (w, h) = (
        rect.width().max(1.0) as usize,
        rect.height().max(1.0) as usize,
    );
    let (x, y, depth) = camera.project(p, w, h);
    let sx = rect.width() as f64 / w as f64;
    let sy = rect.height() as f64 / h as f64;
    (depth > 0.0).then(|| rect.min + egui::vec2((x * sx) as f32, (y * sy) as f32))
}

/// The edges of the volume of interest (sec. 4.3), once a plane cuts the box.
fn voi_outline(app: &ViewerApp, painter: &egui::Painter, project: &dyn Fn(DVec3) -> Option<Pos2>) {
    let planes = app.sculpt.as_ref().map_or(0, |s| s.planes().len());
    let Some(voi) = app.voi().filter(|_| planes > 0) else {
        return;
    };
    let stroke = Stroke::new(1.2, Color32::from_rgb(90, 200, 230));
    let vertices = voi.vertices();
    for face in voi.faces() {
        let ids = &face.vertices;
        for (k, &a) in ids.iter().enumerate() {
            let b = ids[(k + 1) % ids.len()];
            // Each edge is on two faces: draw it once.
            if a < b {
                let ends = (project(vertices[a as usize]), project(vertices[b as usize]));
                if let (Some(p), Some(q)) = ends {
                    painter.line_segment([p, q], stroke);
                }
            }
        }
    }
}

/// The measured polylines with their lengths in the grid's unit, millimetres for medical
/// data (sec. 6.2): yellow lines on a dark outline, the label on a dark backing
/// ([`backed_text`]) so that both read over bright data; a line of one point asks for the
/// second.
fn measurements(app: &ViewerApp, painter: &egui::Painter, project: &dyn Fn(DVec3) -> Option<Pos2>) {
    let Some(sculpt) = &app.sculpt else { return };
    let unit = unit_of(app);
    let colour = Color32::from_rgb(250, 230, 80);
    for line in sculpt.measurements() {
        let pts: Vec<Pos2> = line.iter().filter_map(|p| project(*p)).collect();
        painter.add(egui::Shape::line(pts.clone(), Stroke::new(4.0, BACKING)));
        painter.add(egui::Shape::line(pts.clone(), Stroke::new(2.0, colour)));
        for p in &pts {
            painter.circle(*p, 3.0, colour, Stroke::new(1.0, BACKING));
        }
        if let Some(last) = pts.last() {
            backed_text(
                painter,
                *last + egui::vec2(8.0, -8.0),
                Align2::LEFT_BOTTOM,
                &length_text(&line, &unit),
                FontId::proportional(14.0),
                colour,
            );
        }
    }
}

/// A polyline's length as the overlay and the panel show it, in the grid's unit ("12.34
/// mm"); a single point has no length yet, and says what to do.
pub fn length_text(line: &[DVec3], unit: &str) -> String {
    if line.len() < 2 {
        return "no length yet — click a second point".to_string();
    }
    // The sum of no segments (or of zero-length ones) may be -0: a length is never negative.
    format!("{:.2} {unit}", polyline_length(line).abs())
}

/// The loaded grid's unit of length (`mm` unless the file says otherwise).
pub fn unit_of(app: &ViewerApp) -> String {
    app.sculpt_grid()
        .map_or_else(|| "mm".to_string(), |g| g.unit().to_string())
}

/// The labelling seeds, in their colours.
fn label_seeds(app: &ViewerApp, painter: &egui::Painter, project: &dyn Fn(DVec3) -> Option<Pos2>) {
    let Some(sculpt) = &app.sculpt else { return };
    for (seed, [r, g, b]) in sculpt.label_seeds() {
        if let Some(p) = project(seed.point) {
            let c = Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8);
            painter.circle(p, 4.0, c, Stroke::new(1.0, Color32::WHITE));
            painter.text(
                p + egui::vec2(6.0, 0.0),
                Align2::LEFT_CENTER,
                seed.label.to_string(),
                FontId::proportional(12.0),
                c,
            );
        }
    }
}

/// The eraser's and digger's disc under the pointer, and the stroke being drawn.
fn cursor(app: &ViewerApp, ui: &egui::Ui, painter: &egui::Painter, rect: Rect) {
    if !matches!(app.tools.tool, Tool::Erase | Tool::Dig) {
        return;
    }
    let scene = app.render_scene();
    let scale = egui::vec2(
        rect.width() / scene.view.width.max(1) as f32,
        rect.height() / scene.view.height.max(1) as f32,
    );
    let radius = app.tools.radius_px as f32 * scale.x;
    let stroke = Stroke::new(1.0, Color32::from_rgb(255, 140, 90));
    if let Some(pos) = ui
        .input(|i| i.pointer.hover_pos())
        .filter(|p| rect.contains(*p))
    {
        painter.circle_stroke(pos, radius, stroke);
    }
    let to_screen = |p: &[f64; 2]| rect.min + egui::vec2(p[0] as f32, p[1] as f32) * scale;
    let pts: Vec<Pos2> = app.tools.stroke.iter().map(to_screen).collect();
    if pts.len() > 1 {
        painter.add(egui::Shape::line(
            pts,
            Stroke::new(2.0 * radius, stroke.color.gamma_multiply(0.3)),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One point asks for the second (no "-0.00"); two give their distance.
    #[test]
    fn a_measurement_says_its_length_or_asks_for_a_second_point() {
        let one = [DVec3::new(1.0, 2.0, 3.0)];
        assert_eq!(
            length_text(&one, "mm"),
            "no length yet — click a second point"
        );
        let two = [DVec3::ZERO, DVec3::new(3.0, 4.0, 0.0)];
        assert_eq!(length_text(&two, "mm"), "5.00 mm");
        let same = [DVec3::ONE, DVec3::ONE];
        assert_eq!(length_text(&same, "µm"), "0.00 µm");
    }
}
