//! The volume picker: for a file that holds several volumes (fMRI time series, DWI b-values,
//! vector components, colour channels), a slider per axis beyond x, y, z that reloads the
//! chosen volume and keeps the view (camera, transfer function, slices, sculpt), as a session
//! reopened on another timepoint would.
use eframe::egui;
use volux_core::volume_axes::{AxisKind, ExtraAxis};
use volux_render::scene::Volume;

use crate::app::ViewerApp;

/// The axes of the loaded grid along which another volume can be chosen.
fn axes(app: &ViewerApp) -> Vec<ExtraAxis> {
    match app.data.as_ref().map(|d| &d.volume.volume) {
        Some(Volume::Grid(g)) => g
            .extra_axes()
            .iter()
            .filter(|a| a.len > 1)
            .cloned()
            .collect(),
        _ => Vec::new(),
    }
}

/// Draws the sliders; a change reloads the file with the new choice.
pub fn show(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let axes = axes(app);
    if axes.is_empty() {
        return;
    }
    for axis in axes {
        ui.label(axis.describe());
        match axis.kind {
            AxisKind::Color => color_choice(app, ui, &axis),
            _ => {
                let Some(mut index) = axis.chosen else {
                    continue;
                };
                let label = axis
                    .values
                    .get(index)
                    .map(|v| format!("{} {index} ({v})", axis.kind.option()))
                    .unwrap_or_else(|| axis.kind.option().to_string());
                let slider = egui::Slider::new(&mut index, 0..=axis.len - 1).text(label);
                if ui.add(slider).changed() {
                    app.choose_volume(axis.kind.option(), Some(index));
                }
            }
        }
    }
    ui.separator();
}

/// Colour, or one channel as the scalar.
fn color_choice(app: &mut ViewerApp, ui: &mut egui::Ui, axis: &ExtraAxis) {
    let names = ["red", "green", "blue", "alpha"];
    let current = axis.chosen;
    ui.horizontal(|ui| {
        if ui.selectable_label(current.is_none(), "colour").clicked() && current.is_some() {
            app.choose_volume("component", None);
        }
        for (c, name) in names.iter().enumerate().take(axis.len) {
            if ui.selectable_label(current == Some(c), *name).clicked() && current != Some(c) {
                app.choose_volume("component", Some(c));
            }
        }
    });
}
