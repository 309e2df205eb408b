//! The 3D view: the render thread's latest frame, the camera gestures, the overlay
//! (ms/frame, fps, the method's figure), the orientation letters on the edges, and the
//! slice planes' outlines. In a sculpting tool's mode ([`crate::sculpt_tools`]) the left
//! button is the tool's; the right button orbits, the middle button pans, Alt+left navigates.
//! A clipping plane's tilt handle ([`crate::plane_handle`]) takes a left drag in any mode.
use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Sense, Stroke};
use glam::DVec3;
use volux_render::engine::{FrameStats, MethodStats};

use crate::app::ViewerApp;
use crate::navigation;
use crate::overlay_text::backed_text;
use crate::render_service::FinishedFrame;
use crate::slices::{direction_name, Plane};
use crate::{plane_handle, sculpt_tools};
use volux_core::NamedView;

/// Draws the 3D view in the central panel and applies the gestures to the camera.
pub fn show(app: &mut ViewerApp, ctx: &egui::Context) {
    egui::CentralPanel::default()
        .frame(egui::Frame::NONE.fill(Color32::from_gray(12)))
        .show(ctx, |ui| {
            if app.data.is_some() {
                toolbar(app, ui);
            }
            let rect = ui.available_rect_before_wrap();
            let response = ui.allocate_rect(rect, Sense::click_and_drag());
            app.view_rect = rect;
            let ppp = ctx.pixels_per_point();
            app.view_size = (
                ((rect.width() * ppp) as usize).max(16),
                ((rect.height() * ppp) as usize).max(16),
            );
            gestures(app, ui, &response);
            paint(app, ui, rect);
        });
}

fn toolbar(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let medical = app.data.as_ref().is_some_and(|d| d.is_medical());
    ui.horizontal(|ui| {
        if ui.button("reset").clicked() {
            reset_camera(app);
        }
        let views = if medical {
            NamedView::ANATOMICAL
        } else {
            NamedView::AXES
        };
        for v in views {
            if ui.button(v.label()).on_hover_text(view_hint(v)).clicked() {
                if let Some(b) = app.volume().map(|v| v.bounds()) {
                    let aspect = app.view_size.0 as f64 / app.view_size.1.max(1) as f64;
                    app.scene.view.camera =
                        navigation::standard_view(&app.scene.view.camera, v, &b, aspect);
                }
            }
        }
    });
}

/// The tooltip of a view button.
fn view_hint(v: NamedView) -> &'static str {
    match v {
        NamedView::Left => "from the patient's left: shows the left side",
        NamedView::Right => "from the patient's right: shows the right side",
        NamedView::Anterior => "from the front",
        NamedView::Posterior => "from behind",
        NamedView::Superior => "from above the head, anterior up",
        NamedView::Inferior => "from the feet, anterior up: the radiological axial view",
        _ => "look from this side",
    }
}

/// The home camera on the dataset.
pub fn reset_camera(app: &mut ViewerApp) {
    if let Some(volume) = app.volume().cloned() {
        app.scene.view.camera = app.home_camera(&volume);
    }
}

fn gestures(app: &mut ViewerApp, ui: &egui::Ui, response: &egui::Response) {
    if app.data.is_none() {
        return;
    }
    let camera = app.scene.view.camera;
    let delta = response.drag_delta();
    let (dx, dy) = (delta.x as f64, delta.y as f64);
    let shift = ui.input(|i| i.modifiers.shift);
    let handle = plane_handle::gesture(app, ui, response);
    let tool = !handle && sculpt_tools::tool_owns_left_button(app, ui);
    if tool {
        sculpt_tools::gestures(app, ui, response);
    }
    let left = response.dragged_by(egui::PointerButton::Primary) && !tool && !handle;
    if response.dragged_by(egui::PointerButton::Middle) || (left && shift) {
        app.scene.view.camera = navigation::pan(&camera, dx, dy, response.rect.height() as f64);
    } else if left || response.dragged_by(egui::PointerButton::Secondary) {
        app.scene.view.camera = navigation::orbit(&camera, dx, dy);
    }
    let scroll = if response.hovered() {
        ui.input(|i| i.smooth_scroll_delta.y)
    } else {
        0.0
    };
    if scroll != 0.0 {
        let factor = (scroll as f64 * 0.0025).exp();
        app.scene.view.camera = navigation::zoom(&app.scene.view.camera, factor);
    }
    if response.double_clicked() && !tool {
        reset_camera(app);
    }
    // A tool's left button changes the scene once, on release: no previews meanwhile.
    let navigating = |i: &egui::InputState| {
        let other = i.pointer.middle_down() || i.pointer.secondary_down();
        other || (i.pointer.primary_down() && !tool)
    };
    let pointer_down = ui.input(navigating);
    app.interacting = (response.dragged() && pointer_down)
        || (scroll != 0.0)
        || (pointer_down && response.is_pointer_button_down_on());
}

fn paint(app: &ViewerApp, ui: &egui::Ui, rect: Rect) {
    let painter = ui.painter_at(rect);
    if let Some(shown) = &app.shown {
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(shown.texture.id(), rect, uv, Color32::WHITE);
        overlay(app, &painter, rect, &shown.frame);
    } else if app.data.is_some() {
        painter.text(
            rect.center(),
            Align2::CENTER_CENTER,
            "rendering…",
            FontId::proportional(16.0),
            Color32::GRAY,
        );
    } else {
        painter.text(
            rect.center(),
            Align2::CENTER_CENTER,
            "Open a dataset (Open…, or drop a file here)",
            FontId::proportional(16.0),
            Color32::GRAY,
        );
    }
    if app.data.is_some() {
        orientation_letters(app, &painter, rect);
        if app.show_planes {
            plane_outlines(app, &painter, rect);
        }
        sculpt_tools::overlay(app, ui, &painter, rect);
        plane_handle::draw(app, &painter, rect);
    }
}

fn overlay(app: &ViewerApp, painter: &egui::Painter, rect: Rect, frame: &FinishedFrame) {
    let (stats, divisor, device) = (&frame.stats, frame.divisor, &frame.device);
    let kind = if frame.full {
        "full".to_string()
    } else {
        format!("preview 1/{divisor}")
    };
    let text = format!(
        "{:.1} ms/frame · {:.1} fps · {kind}\n{}\n{device}",
        stats.ms,
        app.fps(),
        method_figure(stats)
    );
    painter.text(
        rect.left_top() + egui::vec2(8.0, 8.0),
        Align2::LEFT_TOP,
        text,
        FontId::monospace(12.0),
        Color32::from_rgb(200, 220, 200),
    );
}

/// The method's figure for the overlay: samples/s for ray casting (and rays over the
/// tolerance when adaptive), tets/s for PT.
pub fn method_figure(stats: &FrameStats) -> String {
    let per_s = |n: f64| n / (stats.ms * 1e-3).max(1e-9);
    match &stats.method {
        MethodStats::GridRaycast(r) => {
            let mut s = format!("{:.1} M samples/s", per_s(r.samples as f64) * 1e-6);
            if r.rays_over_tolerance > 0 {
                s += &format!(" · {} rays over tolerance", r.rays_over_tolerance);
            }
            s
        }
        MethodStats::ProjectedTetrahedra(p) => format!(
            "{:.2} M tets/s · {} of {} tets drawn",
            per_s(p.tets as f64) * 1e-6,
            p.tets_drawn,
            p.tets
        ),
        MethodStats::TetRaycast(t) => {
            let mut s = format!("{:.1} M segments/s", per_s(t.segments as f64) * 1e-6);
            if t.rays_over_tolerance > 0 {
                s += &format!(" · {} rays over tolerance", t.rays_over_tolerance);
            }
            s
        }
        _ => String::new(),
    }
}

/// The letters of the sides the screen's edges face: patient sides (LPS) for medical data,
/// axis names otherwise; on a dark backing, as the slice views' letters, so they read over
/// bright tissue.
fn orientation_letters(app: &ViewerApp, painter: &egui::Painter, rect: Rect) {
    let medical = app.data.as_ref().is_some_and(|d| d.is_medical());
    let (right, up, _) = app.scene.view.camera.basis();
    let name = |d: DVec3| direction_name(d, medical);
    let font = FontId::proportional(15.0);
    let colour = Color32::from_rgb(240, 200, 90);
    let m = 14.0;
    let c = rect.center();
    for (d, pos, align) in [
        (
            right,
            Pos2::new(rect.right() - m, c.y),
            Align2::RIGHT_CENTER,
        ),
        (-right, Pos2::new(rect.left() + m, c.y), Align2::LEFT_CENTER),
        (up, Pos2::new(c.x, rect.top() + m), Align2::CENTER_TOP),
        (
            -up,
            Pos2::new(c.x, rect.bottom() - m),
            Align2::CENTER_BOTTOM,
        ),
    ] {
        backed_text(painter, pos, align, &name(d), font.clone(), colour);
    }
}

fn plane_outlines(app: &ViewerApp, painter: &egui::Painter, rect: Rect) {
    let Some(data) = &app.data else { return };
    let camera = &app.scene.view.camera;
    let (w, h) = (rect.width() as usize, rect.height() as usize);
    let colours = [
        Color32::from_rgb(230, 80, 80),
        Color32::from_rgb(80, 200, 80),
        Color32::from_rgb(230, 200, 60),
    ];
    for (plane, colour) in Plane::ALL.into_iter().zip(colours) {
        let corners = data.slices.plane_corners(plane, app.crosshair);
        let pts: Vec<Pos2> = corners
            .iter()
            .filter_map(|p| {
                let (x, y, depth) = camera.project(*p, w.max(1), h.max(1));
                (depth > 0.0).then(|| rect.left_top() + egui::vec2(x as f32, y as f32))
            })
            .collect();
        if pts.len() == 4 {
            painter.add(egui::Shape::closed_line(pts, Stroke::new(1.5, colour)));
        }
    }
}
