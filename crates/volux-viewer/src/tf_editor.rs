//! The transfer-function editor: the data's histogram (linear or log counts) under the
//! opacity curve, whose control points are added (click on empty space), dragged, and
//! deleted (right click); colour stops under it, each with a colour picker (click), dragged
//! along the values, added (double click on the strip) and deleted (right click); window
//! and level for the whole TF (ctrl + drag or middle drag: horizontal shifts it, vertical
//! widens or narrows it about its centre, the gesture CT readers know).
//!
//! The curve is the TF's own list: its extinction (per unit length) or its opacity (per
//! `opacity_step`), whichever it holds, so an edited TF saves in the CLI's format unchanged
//! in kind. The pure edits ([`add_point`], [`move_point`], [`delete_point`],
//! [`window_level`]) are separate from the drawing, for tests.
use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2};
use volux_core::histogram::Histogram;
use volux_core::transfer::Space;
use volux_core::TransferFunction;

/// Pixels within which the pointer grabs a control point.
pub const GRAB_RADIUS: f32 = 7.0;

/// Which list of the TF the curve edits.
fn curve(tf: &TransferFunction) -> &Vec<[f64; 2]> {
    if tf.extinction.is_empty() {
        &tf.opacity
    } else {
        &tf.extinction
    }
}

fn curve_mut(tf: &mut TransferFunction) -> &mut Vec<[f64; 2]> {
    if tf.extinction.is_empty() {
        &mut tf.opacity
    } else {
        &mut tf.extinction
    }
}

/// `tf` with its positions in data values (a normalized TF mapped onto `range`); the
/// heights are unchanged.
pub fn in_value_space(tf: &TransferFunction, range: [f64; 2]) -> TransferFunction {
    let mut out = tf.clone();
    if tf.space == Space::Normalized {
        let map = |s: f64| range[0] + s * (range[1] - range[0]);
        out.color.iter_mut().for_each(|p| p[0] = map(p[0]));
        out.extinction.iter_mut().for_each(|p| p[0] = map(p[0]));
        out.opacity.iter_mut().for_each(|p| p[0] = map(p[0]));
        out.space = Space::Value;
    }
    out
}

/// Inserts a point at `x` (kept sorted); returns its index.
pub fn add_point(points: &mut Vec<[f64; 2]>, x: f64, y: f64) -> usize {
    let i = points.partition_point(|p| p[0] <= x);
    points.insert(i, [x, y.max(0.0)]);
    i
}

/// Moves point `i` to (`x`, `y`), `x` kept between its neighbours so the order holds.
pub fn move_point(points: &mut [[f64; 2]], i: usize, x: f64, y: f64) {
    let lo = if i > 0 { points[i - 1][0] } else { f64::MIN };
    let hi = points.get(i + 1).map_or(f64::MAX, |p| p[0]);
    points[i] = [x.clamp(lo, hi), y.max(0.0)];
}

/// Deletes point `i` unless only two are left (a curve needs two ends).
pub fn delete_point<T>(points: &mut Vec<T>, i: usize) -> bool {
    if points.len() <= 2 || i >= points.len() {
        return false;
    }
    points.remove(i);
    true
}

/// Window/level of the whole TF (colour and curve): positions shifted by `shift` and
/// scaled by `scale` about `centre`.
pub fn window_level(
    tf: &TransferFunction,
    centre: f64,
    shift: f64,
    scale: f64,
) -> TransferFunction {
    let map = |s: f64| centre + (s - centre) * scale + shift;
    let mut out = tf.clone();
    out.color.iter_mut().for_each(|p| p[0] = map(p[0]));
    out.extinction.iter_mut().for_each(|p| p[0] = map(p[0]));
    out.opacity.iter_mut().for_each(|p| p[0] = map(p[0]));
    out
}

/// The editor's state besides the TF itself.
#[derive(Clone, Debug)]
pub struct TfEditor {
    /// Counts per bin over the data's range.
    pub histogram: Histogram,
    /// Log-scale counts.
    pub log_scale: bool,
    /// Curve height drawn at the top of the editor.
    pub y_max: f64,
    /// The colour stop whose picker is open.
    pub selected_color: Option<usize>,
    dragging: Option<Drag>,
    /// Where the curve was last drawn (tests aim the pointer with it).
    pub rect: Rect,
}

#[derive(Clone, Debug)]
enum Drag {
    Point(usize),
    Color(usize),
    Window { start: Pos2, tf: TransferFunction },
}

impl TfEditor {
    /// An editor over `histogram`, its height fitted to `tf`'s curve.
    pub fn new(histogram: Histogram, tf: &TransferFunction) -> Self {
        let mut e = Self {
            histogram,
            log_scale: true,
            y_max: 1.0,
            selected_color: None,
            dragging: None,
            rect: Rect::NOTHING,
        };
        e.fit_height(tf);
        e
    }

    /// Makes the curve's highest point reach 90 % of the editor's height.
    pub fn fit_height(&mut self, tf: &TransferFunction) {
        let top = curve(tf).iter().map(|p| p[1]).fold(0.0, f64::max);
        self.y_max = if top > 0.0 { top / 0.9 } else { 1.0 };
        if tf.extinction.is_empty() {
            self.y_max = self.y_max.clamp(1.0, 1.0 / 0.9);
        }
    }

    /// Screen position of curve point `p` in `rect`.
    pub fn to_screen(&self, rect: Rect, p: [f64; 2]) -> Pos2 {
        let (lo, hi) = (self.histogram.min, self.histogram.max);
        let t = ((p[0] - lo) / (hi - lo).max(1e-300)) as f32;
        let u = (p[1] / self.y_max) as f32;
        Pos2::new(
            rect.left() + t * rect.width(),
            rect.bottom() - u.clamp(0.0, 1.0) * rect.height(),
        )
    }

    fn to_data(&self, rect: Rect, pos: Pos2) -> [f64; 2] {
        let (lo, hi) = (self.histogram.min, self.histogram.max);
        let t = ((pos.x - rect.left()) / rect.width().max(1.0)).clamp(0.0, 1.0) as f64;
        let u = ((rect.bottom() - pos.y) / rect.height().max(1.0)).clamp(0.0, 1.0) as f64;
        [lo + t * (hi - lo), u * self.y_max]
    }

    /// The screen position of curve point `i` where the editor was last drawn.
    pub fn point_position(&self, tf: &TransferFunction, i: usize) -> Option<Pos2> {
        curve(tf).get(i).map(|p| self.to_screen(self.rect, *p))
    }

    /// Draws the editor and applies the pointer's edits to `tf`; returns whether it changed.
    pub fn show(&mut self, ui: &mut egui::Ui, tf: &mut TransferFunction) -> bool {
        let width = ui.available_width().max(120.0);
        let (rect, response) =
            ui.allocate_exact_size(Vec2::new(width, 150.0), Sense::click_and_drag());
        self.rect = rect;
        let (strip, strip_response) =
            ui.allocate_exact_size(Vec2::new(width, 22.0), Sense::click_and_drag());
        let mut changed = self.curve_input(ui, &response, rect, tf);
        changed |= self.strip_input(ui, &strip_response, strip, tf);
        self.paint(ui, rect, strip, tf);
        changed |= self.color_picker(ui, tf);
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.log_scale, "log counts");
            if ui.button("fit height").clicked() {
                self.fit_height(tf);
            }
        });
        changed
    }

    fn nearest_point(&self, rect: Rect, tf: &TransferFunction, pos: Pos2) -> Option<usize> {
        curve(tf)
            .iter()
            .enumerate()
            .map(|(i, p)| (i, self.to_screen(rect, *p).distance(pos)))
            .filter(|(_, d)| *d <= GRAB_RADIUS)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    fn curve_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: Rect,
        tf: &mut TransferFunction,
    ) -> bool {
        let pos = response.interact_pointer_pos().or(response.hover_pos());
        let Some(pos) = pos else { return false };
        let window_gesture = ui.input(|i| i.modifiers.ctrl || i.modifiers.command)
            || response.dragged_by(egui::PointerButton::Middle);
        if response.drag_started() {
            // egui starts a drag only once the pointer has moved a few pixels: the point
            // grabbed is the one under the press, not under the pointer now.
            let press = press_origin(ui).unwrap_or(pos);
            self.dragging = if window_gesture {
                Some(Drag::Window {
                    start: press,
                    tf: tf.clone(),
                })
            } else {
                self.nearest_point(rect, tf, press).map(Drag::Point)
            };
        }
        if response.drag_stopped() {
            self.dragging = None;
        }
        if response.dragged() {
            match self.dragging.clone() {
                Some(Drag::Point(i)) if i < curve(tf).len() => {
                    let [x, y] = self.to_data(rect, pos);
                    move_point(curve_mut(tf), i, x, y);
                    return true;
                }
                Some(Drag::Window {
                    start,
                    tf: original,
                }) => {
                    *tf = self.window_drag(rect, start, pos, &original);
                    return true;
                }
                _ => {}
            }
        }
        if response.clicked() && self.nearest_point(rect, tf, pos).is_none() {
            let [x, y] = self.to_data(rect, pos);
            add_point(curve_mut(tf), x, y);
            return true;
        }
        if response.secondary_clicked() {
            if let Some(i) = self.nearest_point(rect, tf, pos) {
                return delete_point(curve_mut(tf), i);
            }
        }
        false
    }

    /// A window/level drag from `start` to `pos`: right shifts the TF up the values, up
    /// narrows it (doubling per editor height).
    fn window_drag(
        &self,
        rect: Rect,
        start: Pos2,
        pos: Pos2,
        original: &TransferFunction,
    ) -> TransferFunction {
        let span = self.histogram.max - self.histogram.min;
        let shift = (pos.x - start.x) as f64 / rect.width().max(1.0) as f64 * span;
        let scale = 2f64.powf((pos.y - start.y) as f64 / rect.height().max(1.0) as f64);
        let xs = original.color.iter().map(|p| p[0]);
        let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
        window_level(original, (lo + hi) * 0.5, shift, scale)
    }

    fn strip_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        strip: Rect,
        tf: &mut TransferFunction,
    ) -> bool {
        let Some(pos) = response.interact_pointer_pos().or(response.hover_pos()) else {
            return false;
        };
        let near_x = |x: f32| {
            tf.color
                .iter()
                .enumerate()
                .map(|(i, p)| (i, (self.to_screen(strip, [p[0], 0.0]).x - x).abs()))
                .filter(|(_, d)| *d <= GRAB_RADIUS)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| i)
        };
        let near = near_x(pos.x);
        let x = self.to_data(strip, pos)[0];
        if response.drag_started() {
            let press = press_origin(ui).unwrap_or(pos);
            self.dragging = near_x(press.x).map(Drag::Color);
        }
        if response.drag_stopped() {
            self.dragging = None;
        }
        if let (true, Some(Drag::Color(i))) = (response.dragged(), self.dragging.clone()) {
            let lo = if i > 0 { tf.color[i - 1][0] } else { f64::MIN };
            let hi = tf.color.get(i + 1).map_or(f64::MAX, |p| p[0]);
            tf.color[i][0] = x.clamp(lo, hi);
            return true;
        }
        if response.double_clicked() {
            let c = tf
                .resolved([self.histogram.min, self.histogram.max])
                .color_at(x);
            let i = tf.color.partition_point(|p| p[0] <= x);
            tf.color.insert(i, [x, c[0], c[1], c[2]]);
            self.selected_color = Some(i);
            return true;
        }
        if response.clicked() {
            self.selected_color = near;
        }
        if response.secondary_clicked() {
            if let Some(i) = near {
                self.selected_color = None;
                return delete_point(&mut tf.color, i);
            }
        }
        false
    }

    fn color_picker(&mut self, ui: &mut egui::Ui, tf: &mut TransferFunction) -> bool {
        let Some(i) = self.selected_color.filter(|i| *i < tf.color.len()) else {
            return false;
        };
        let mut rgb = [
            tf.color[i][1] as f32,
            tf.color[i][2] as f32,
            tf.color[i][3] as f32,
        ];
        let mut changed = false;
        ui.horizontal(|ui| {
            ui.label(format!("colour at {:.4}", tf.color[i][0]));
            changed = egui::color_picker::color_edit_button_rgb(ui, &mut rgb).changed();
        });
        if changed {
            for (k, c) in rgb.iter().enumerate() {
                tf.color[i][k + 1] = (*c as f64).clamp(0.0, 1.0);
            }
        }
        changed
    }

    fn paint(&self, ui: &egui::Ui, rect: Rect, strip: Rect, tf: &TransferFunction) {
        let painter = ui.painter();
        painter.rect_filled(rect, 2.0, Color32::from_gray(24));
        self.paint_histogram(painter, rect);
        let range = [self.histogram.min, self.histogram.max];
        let resolved = tf.resolved(range);
        let columns = strip.width().max(1.0) as usize;
        for c in 0..columns {
            let s = range[0] + (c as f64 + 0.5) / columns as f64 * (range[1] - range[0]);
            let rgb = resolved
                .color_at(s)
                .map(|v| (linear_to_srgb(v) * 255.0) as u8);
            let x = strip.left() + c as f32;
            painter.line_segment(
                [Pos2::new(x, strip.top()), Pos2::new(x, strip.bottom())],
                Stroke::new(1.0, Color32::from_rgb(rgb[0], rgb[1], rgb[2])),
            );
        }
        for p in &tf.color {
            let x = self.to_screen(strip, [p[0], 0.0]).x;
            let tri = vec![
                Pos2::new(x, strip.bottom() - 8.0),
                Pos2::new(x - 5.0, strip.bottom()),
                Pos2::new(x + 5.0, strip.bottom()),
            ];
            painter.add(egui::Shape::convex_polygon(
                tri,
                Color32::WHITE,
                Stroke::new(1.0, Color32::BLACK),
            ));
        }
        let points: Vec<Pos2> = curve(tf).iter().map(|p| self.to_screen(rect, *p)).collect();
        painter.add(egui::Shape::line(
            points.clone(),
            Stroke::new(1.5, Color32::from_rgb(255, 210, 80)),
        ));
        for p in points {
            painter.circle(
                p,
                4.0,
                Color32::from_rgb(255, 210, 80),
                Stroke::new(1.0, Color32::BLACK),
            );
        }
    }

    fn paint_histogram(&self, painter: &egui::Painter, rect: Rect) {
        let counts = &self.histogram.counts;
        let f = |c: u64| {
            if self.log_scale {
                (c as f64 + 1.0).ln()
            } else {
                c as f64
            }
        };
        let top = counts.iter().map(|c| f(*c)).fold(0.0, f64::max).max(1e-9);
        let w = rect.width() / counts.len().max(1) as f32;
        for (i, c) in counts.iter().enumerate() {
            let h = (f(*c) / top) as f32 * rect.height();
            let x = rect.left() + i as f32 * w;
            painter.rect_filled(
                Rect::from_min_max(
                    Pos2::new(x, rect.bottom() - h),
                    Pos2::new(x + w, rect.bottom()),
                ),
                0.0,
                Color32::from_gray(70),
            );
        }
    }
}

/// Where the pointer was when its button went down (`None` while no button is down).
fn press_origin(ui: &egui::Ui) -> Option<Pos2> {
    ui.input(|i| i.pointer.press_origin())
}

fn linear_to_srgb(v: f64) -> f32 {
    volux_core::image::linear_to_srgb(v as f32).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points stay sorted whatever the edits; a curve keeps its two ends.
    #[test]
    fn edits_keep_the_curve_valid() {
        let mut pts = vec![[0.0, 0.0], [1.0, 1.0]];
        let i = add_point(&mut pts, 0.5, 0.3);
        assert_eq!((i, pts[1]), (1, [0.5, 0.3]));
        move_point(&mut pts, 1, 2.0, -1.0);
        assert_eq!(pts[1], [1.0, 0.0], "clamped to its neighbour and to >= 0");
        assert!(delete_point(&mut pts, 1));
        assert!(!delete_point(&mut pts, 0), "two points stay");
    }

    /// Window/level shifts and scales every position about the centre, heights unchanged.
    #[test]
    fn window_level_moves_positions_only() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0, 0, 0, 0], [10, 1, 1, 1]], "extinction": [[0, 0], [10, 2]]}"#,
        )
        .unwrap();
        let w = window_level(&tf, 5.0, 1.0, 0.5);
        assert_eq!(w.color[0][0], 3.5);
        assert_eq!(w.color[1][0], 8.5);
        assert_eq!(w.extinction[1], [8.5, 2.0]);
        w.validate().unwrap();
    }

    /// A normalized TF is mapped onto the range, heights unchanged.
    #[test]
    fn normalized_positions_become_values() {
        let tf = TransferFunction::from_json(
            r#"{"space": "normalized", "color": [[0, 0, 0, 0], [1, 1, 1, 1]], "opacity": [[0, 0], [0.5, 0.5]]}"#,
        )
        .unwrap();
        let v = in_value_space(&tf, [100.0, 300.0]);
        assert_eq!(v.opacity[1], [200.0, 0.5]);
        assert_eq!(v.color[1][0], 300.0);
        assert_eq!(v.space, Space::Value);
    }
}
