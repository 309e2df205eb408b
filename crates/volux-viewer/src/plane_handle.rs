//! The clipping planes' tilt handles in the 3D view (seed `004_*.txt` sec. 4.3: the user drags
//! a handle from the centre of the volume to set a plane's normal). Each plane shows a handle
//! from the data's centre along its normal; dragging the tip (with the left button, in any
//! tool mode) moves the tip over the sphere about the centre under the pointer, and the
//! normal points at it; the plane keeps its distance from the centre. One drag is one undo
//! step.
use eframe::egui::{self, Color32, Pos2, Rect, Stroke};
use glam::DVec3;
use volux_core::voi::ClipPlane;

use crate::app::ViewerApp;
use crate::sculpt_tools::project;

/// The handle's length, as a fraction of the data box's diagonal.
const HANDLE_FRACTION: f64 = 0.3;

/// How near the tip a press grabs it, points.
const GRAB_RADIUS: f32 = 9.0;

/// The data's centre and the handles' length.
fn centre_and_length(app: &ViewerApp) -> Option<(DVec3, f64)> {
    let b = app.volume()?.bounds();
    Some((
        (b.min + b.max) * 0.5,
        HANDLE_FRACTION * (b.max - b.min).length(),
    ))
}

/// The handles' tips (world), one per plane.
pub fn tips(app: &ViewerApp) -> Vec<DVec3> {
    let (Some((c, len)), Some(s)) = (centre_and_length(app), &app.sculpt) else {
        return Vec::new();
    };
    s.planes().iter().map(|p| c + p.normal * len).collect()
}

/// Handles a drag on a handle; `true` while one is dragged (the left button is then the
/// handle's: neither the tool nor the camera takes it).
pub fn gesture(app: &mut ViewerApp, ui: &egui::Ui, response: &egui::Response) -> bool {
    let left = egui::PointerButton::Primary;
    if response.drag_started_by(left) {
        let origin = ui.input(|i| i.pointer.press_origin());
        app.tools.handle_drag = origin
            .and_then(|o| grabbed(app, response.rect, o))
            .map(|i| (i, false));
    }
    let Some((index, moved)) = app.tools.handle_drag else {
        return false;
    };
    if response.dragged_by(left) {
        if let Some(pos) = response.interact_pointer_pos() {
            if let Some(plane) = tilted(app, response.rect, index, pos) {
                app.set_plane(index, plane, moved);
                app.tools.handle_drag = Some((index, true));
            }
        }
    }
    if !ui.input(|i| i.pointer.primary_down()) {
        app.tools.handle_drag = None;
    }
    true
}

/// The plane whose tip is under `pos`, if any.
fn grabbed(app: &ViewerApp, rect: Rect, pos: Pos2) -> Option<usize> {
    let camera = app.scene.view.camera;
    tips(app)
        .into_iter()
        .enumerate()
        .filter_map(|(i, t)| Some((i, project(&camera, rect, t)?.distance(pos))))
        .filter(|(_, d)| *d <= GRAB_RADIUS)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Plane `index` with its normal pointing from the centre to the point of the handle's sphere
/// (about the centre, through the tip) under `pos`, on the tip's side (towards or away from
/// the eye); off the sphere, to its silhouette.
fn tilted(app: &ViewerApp, rect: Rect, index: usize, pos: Pos2) -> Option<ClipPlane> {
    let (c, len) = centre_and_length(app)?;
    let plane = *app.sculpt.as_ref()?.planes().get(index)?;
    let camera = app.scene.view.camera;
    let (w, h) = (
        rect.width().max(1.0) as usize,
        rect.height().max(1.0) as usize,
    );
    let rel = pos - rect.min;
    let ray = camera.ray(rel.x as f64, rel.y as f64, w, h);
    // |o + t d - c|^2 = len^2 with |d| = 1.
    let oc = ray.origin - c;
    let mid = -oc.dot(ray.dir);
    let disc = mid * mid - (oc.length_squared() - len * len);
    let far_side = plane.normal.dot(ray.dir) > 0.0;
    let t = match (disc >= 0.0, far_side) {
        (true, true) => mid + disc.sqrt(),
        (true, false) => mid - disc.sqrt(),
        (false, _) => mid,
    };
    let n = (ray.origin + ray.dir * t - c).normalize_or_zero();
    let distance = -(plane.offset + plane.normal.dot(c));
    ClipPlane::new(n.x, n.y, n.z, -(n.dot(c) + distance)).ok()
}

/// Draws the handles: a line from the centre to each tip, the dragged tip filled.
pub fn draw(app: &ViewerApp, painter: &egui::Painter, rect: Rect) {
    let Some((c, _)) = centre_and_length(app) else {
        return;
    };
    let camera = app.scene.view.camera;
    let Some(from) = project(&camera, rect, c) else {
        return;
    };
    let colour = Color32::from_rgb(120, 230, 160);
    for (i, tip) in tips(app).into_iter().enumerate() {
        let Some(to) = project(&camera, rect, tip) else {
            continue;
        };
        painter.line_segment([from, to], Stroke::new(1.5, colour));
        if app.tools.handle_drag.is_some_and(|(d, _)| d == i) {
            painter.circle_filled(to, 6.0, colour);
        } else {
            painter.circle_stroke(to, 6.0, Stroke::new(2.0, colour));
        }
    }
}
