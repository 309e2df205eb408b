//! The Sculpt section of the settings panel (seed `004_*.txt` ch. 4-6): undo and redo, the
//! tool modes and their radius, the clipping planes (sec. 4.3: offset from the data's centre,
//! the normal's azimuth and elevation, remove, add), the measured lengths (sec. 6.2), the
//! labelling seeds' label, colour and rule (connected or nearest, issue 41) with their counts
//! and "Colour by labels" (sec. 6.2), and the exports.
use eframe::egui;
use glam::DVec3;
use volux_core::sculpt::RegionRule;
use volux_core::voi::ClipPlane;

use crate::app::ViewerApp;
use crate::file_dialog::Purpose;
use crate::label_colours::LabelColours;
use crate::sculpt_state::Tool;

/// Draws the section.
pub fn show(app: &mut ViewerApp, ui: &mut egui::Ui) {
    if app.sculpt.is_none() {
        return;
    }
    let grid = app.sculpt_grid().is_some();
    ui.horizontal(|ui| {
        ui.strong("Sculpt");
        undo_buttons(app, ui);
    });
    if grid {
        tools(app, ui);
    } else if app.is_bricked() {
        ui.small(format!(
            "erase, dig, measure and labels: off; sculpting {}; clipping planes work",
            crate::lod_status::NEEDS_MEMORY
        ));
    }
    planes(app, ui);
    if grid {
        measurements(app, ui);
        labels(app, ui);
        exports(app, ui);
    }
}

fn undo_buttons(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let (undo, redo) = app
        .sculpt
        .as_ref()
        .map_or((false, false), |s| s.can_undo_redo());
    if ui
        .add_enabled(undo, egui::Button::new("Undo"))
        .on_hover_text("Ctrl+Z")
        .clicked()
    {
        app.undo();
    }
    if ui
        .add_enabled(redo, egui::Button::new("Redo"))
        .on_hover_text("Ctrl+Shift+Z, Ctrl+Y")
        .clicked()
    {
        app.redo();
    }
}

fn tools(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal_wrapped(|ui| {
        for tool in Tool::ALL {
            let key = format!("{:?}", tool.key());
            ui.radio_value(&mut app.tools.tool, tool, tool.label())
                .on_hover_text(format!("key {key}"));
        }
    });
    if matches!(app.tools.tool, Tool::Erase | Tool::Dig) {
        ui.add(
            egui::Slider::new(&mut app.tools.radius_px, 1.0..=100.0)
                .logarithmic(true)
                .text("radius (pixels)"),
        );
    }
    if app.tools.tool != Tool::Navigate {
        ui.small("right drag: orbit · middle drag: pan · Alt+left drag: navigate");
    }
    if let Some(s) = &app.sculpt {
        let removed = s.mask().removed_count();
        if removed > 0 {
            ui.small(format!("{removed} voxels removed"));
        }
    }
}

fn planes(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let Some(volume) = app.volume() else { return };
    let bounds = volume.bounds();
    let centre = (bounds.min + bounds.max) * 0.5;
    let reach = 0.5 * (bounds.max - bounds.min).length();
    if !ui.input(|i| i.pointer.any_down()) {
        app.tools.plane_gesture = None;
    }
    let planes = app
        .sculpt
        .as_ref()
        .map_or(Vec::new(), |s| s.planes().to_vec());
    let mut remove = None;
    for (i, plane) in planes.iter().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("plane {}", i + 1));
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
        let mut pose = PlanePose::of(plane, centre);
        let mut changed = false;
        ui.push_id(i, |ui| {
            changed |= slider(ui, &mut pose.distance, -reach..=reach, "offset");
            changed |= slider(ui, &mut pose.azimuth, -180.0..=180.0, "azimuth °");
            changed |= slider(ui, &mut pose.elevation, -90.0..=90.0, "elevation °");
        });
        if changed {
            if let Ok(p) = pose.plane(plane, centre) {
                let continuing = app.tools.plane_gesture == Some(i);
                app.set_plane(i, p, continuing);
                app.tools.plane_gesture = ui.input(|i| i.pointer.any_down()).then_some(i);
            }
        }
    }
    if let Some(i) = remove {
        app.remove_plane(i);
    }
    if ui
        .button("Add plane")
        .on_hover_text("through the centre of the kept volume, facing you: keeps the far half")
        .clicked()
    {
        app.add_plane();
    }
}

fn slider(
    ui: &mut egui::Ui,
    value: &mut f64,
    range: std::ops::RangeInclusive<f64>,
    text: &str,
) -> bool {
    ui.add(egui::Slider::new(value, range).text(text)).changed()
}

/// A plane as the panel edits it: its signed distance from the data's centre along its
/// normal, and the normal's azimuth (about z, from x) and elevation (from the xy plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanePose {
    /// World units, positive along the normal.
    pub distance: f64,
    /// Degrees.
    pub azimuth: f64,
    /// Degrees.
    pub elevation: f64,
}

impl PlanePose {
    /// The pose of `plane` about `centre`.
    pub fn of(plane: &ClipPlane, centre: DVec3) -> Self {
        let n = plane.normal;
        Self {
            distance: -(plane.offset + n.dot(centre)),
            azimuth: n.y.atan2(n.x).to_degrees(),
            elevation: n.z.clamp(-1.0, 1.0).asin().to_degrees(),
        }
    }

    /// `old` moved to this pose about `centre`: through `centre + distance * normal`, keeping
    /// the side the normal points to; `old`'s normal exactly while the angles are its own.
    pub fn plane(&self, old: &ClipPlane, centre: DVec3) -> Result<ClipPlane, String> {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        let tilted = Self::of(old, centre);
        let n = if (tilted.azimuth, tilted.elevation) == (self.azimuth, self.elevation) {
            old.normal
        } else {
            DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
        };
        let d = -(n.dot(centre) + self.distance);
        ClipPlane::new(n.x, n.y, n.z, d).map_err(|e| e.to_string())
    }
}

fn measurements(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let lines = app.sculpt.as_ref().map_or(Vec::new(), |s| s.measurements());
    let unit = crate::sculpt_tools::unit_of(app);
    for (i, line) in lines.iter().enumerate() {
        let points = match line.len() {
            1 => String::new(),
            n => format!(" ({n} points)"),
        };
        ui.label(format!(
            "measurement {}: {}{points}",
            i + 1,
            crate::sculpt_tools::length_text(line, &unit),
        ));
    }
    if app.tools.tool == Tool::Measure {
        let text = if app.tools.new_line {
            "the next point starts a new line"
        } else {
            "New line"
        };
        if ui
            .add_enabled(!app.tools.new_line, egui::Button::new(text))
            .on_hover_text("or Shift+click")
            .clicked()
        {
            app.tools.new_line = true;
        }
    }
}

fn labels(app: &mut ViewerApp, ui: &mut egui::Ui) {
    if app.tools.tool == Tool::Label {
        ui.horizontal(|ui| {
            ui.label("label");
            ui.add(egui::DragValue::new(&mut app.tools.label).range(1..=255));
            ui.color_edit_button_rgb(&mut app.tools.colour);
        });
        ui.horizontal(|ui| {
            ui.label("grows");
            for rule in RegionRule::ALL {
                ui.radio_value(&mut app.tools.rule, rule, rule.name())
                    .on_hover_text(rule_hint(rule));
            }
        });
    }
    let seeds = app.sculpt.as_ref().map_or(0, |s| s.label_seeds().len());
    if seeds == 0 {
        return;
    }
    ui.horizontal(|ui| {
        ui.label(format!("{seeds} labelling seeds"));
        let busy = app.tools.labels_job.is_some();
        if ui
            .add_enabled(!busy, egui::Button::new("Compute labels"))
            .clicked()
        {
            app.compute_labels();
        }
        if busy {
            ui.spinner();
        }
    });
    colour_by_labels(app, ui);
    if let Some(counts) = &app.tools.label_counts {
        for (label, count) in counts {
            ui.small(format!("label {label}: {count} voxels"));
        }
        if counts.is_empty() {
            ui.small("no visible voxel is labelled");
        }
    }
}

/// What a seed placed with `rule` labels (the panel's hover text).
fn rule_hint(rule: RegionRule) -> &'static str {
    match rule {
        RegionRule::Connected => {
            "the next seeds label the visible voxels connected to them; parts no seed \
             touches stay unlabelled"
        }
        RegionRule::Nearest => {
            "the next seeds label every visible voxel nearer to them than to other nearest \
             seeds, parts they do not touch included"
        }
    }
}

/// The "Colour by labels" checkbox, and why the rendering shows no labels when it cannot.
fn colour_by_labels(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        ui.checkbox(&mut app.tools.label_colours.on, "Colour by labels")
            .on_hover_text("the visible voxels take the colour of their nearest seed");
        if app.tools.label_colours.on && app.tools.label_colours.computing() {
            ui.spinner();
        }
    });
    if app.tools.label_colours.on {
        if let Some(why) = LabelColours::not_drawn(&app.render_scene()) {
            ui.small(why);
        }
    }
}

fn exports(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        if ui.button("Export mask…").clicked() {
            app.open_dialog(Purpose::ExportMask);
        }
        let seeds = app
            .sculpt
            .as_ref()
            .is_some_and(|s| !s.label_seeds().is_empty());
        if ui
            .add_enabled(seeds, egui::Button::new("Export labels…"))
            .clicked()
        {
            app.open_dialog(Purpose::ExportLabels);
        }
    });
}
