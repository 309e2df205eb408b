//! The menu bar and the settings panel: file actions, method and its settings, shading,
//! MIP, isosurfaces, background, sculpting ([`crate::sculpt_panel`]), the TF editor and
//! presets.
use eframe::egui;
use volux_render::integrate::integrator::Integrator;
use volux_render::integrate::segment::SegmentRule;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::sampling::Reconstruction;
use volux_render::scene::{GridRaycast, Method, PtSettings, SlicingSettings, SortMode, Volume};

use crate::app::ViewerApp;
use crate::file_dialog::Purpose;
use crate::lod_status::NEEDS_MEMORY;
use crate::tf_editor::in_value_space;

use volux_core::transfer::PRESETS;

/// Draws the menu bar, the status bar ([`crate::status_bar`]) and the settings panel.
pub fn show(app: &mut ViewerApp, ctx: &egui::Context) {
    egui::TopBottomPanel::top("menu").show(ctx, |ui| menu(app, ui));
    crate::status_bar::show(app, ctx);
    egui::SidePanel::left("settings")
        .default_width(330.0)
        .show(ctx, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| settings(app, ui));
        });
}

fn menu(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        if ui.button("Open…").clicked() {
            app.open_dialog(Purpose::Open);
        }
        let has_data = app.data.is_some();
        ui.add_enabled_ui(has_data, |ui| {
            if ui.button("Save screenshot…").clicked() {
                app.open_dialog(Purpose::SaveScreenshot);
            }
            ui.label("at");
            ui.add(egui::DragValue::new(&mut app.export_size.0).range(16..=16384));
            ui.label("x");
            ui.add(egui::DragValue::new(&mut app.export_size.1).range(16..=16384));
            if ui.small_button("window size").clicked() {
                app.export_size = app.view_size;
            }
            if ui.button("Save session…").clicked() {
                app.open_dialog(Purpose::SaveSession);
            }
        });
        if let Some(job) = &app.load_job {
            match app.load_progress.as_ref().and_then(|p| p.fraction()) {
                Some(f) => {
                    let bar = egui::ProgressBar::new(f as f32).desired_width(160.0);
                    ui.add(bar.show_percentage());
                }
                None => {
                    ui.spinner();
                }
            }
            ui.label(format!(
                "{} ({:.1} s)",
                job.label,
                job.elapsed().as_secs_f64()
            ));
            if ui.button("Cancel").clicked() {
                app.cancel_load();
            }
        }
        if let Some((job, _)) = &app.split_job {
            ui.spinner();
            ui.label(format!(
                "{} ({:.1} s)",
                job.label,
                job.elapsed().as_secs_f64()
            ));
        }
    });
}

fn settings(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let Some(data) = &app.data else {
        ui.label("Open a dataset: the Open… button, drag and drop, or volux-view FILE.");
        return;
    };
    ui.label(data.describe());
    for note in data.notes.iter().take(4) {
        ui.small(note.as_str());
    }
    ui.separator();
    crate::volume_picker::show(app, ui);
    method_settings(app, ui);
    ui.separator();
    appearance_settings(app, ui);
    ui.separator();
    crate::sculpt_panel::show(app, ui);
    ui.separator();
    tf_section(app, ui);
}

/// The methods a dataset can be drawn with.
fn method_choices(volume: &Volume) -> Vec<(&'static str, Method)> {
    let grid = GridRaycast::default();
    match volume {
        Volume::Bricked(..) => vec![("Ray casting (out of core)", Method::GridRaycast(grid))],
        Volume::Grid(_) => vec![
            ("Ray casting", Method::GridRaycast(grid)),
            (
                "Projected Tetrahedra (split)",
                Method::ProjectedTetrahedra(PtSettings::default()),
            ),
            (
                "Tet ray casting (split)",
                Method::TetRaycast(SegmentRule::Psi),
            ),
            (
                "Texture slicing (GPU)",
                Method::Slicing(SlicingSettings::default()),
            ),
        ],
        _ => vec![
            (
                "Projected Tetrahedra",
                Method::ProjectedTetrahedra(PtSettings::default()),
            ),
            ("Tet ray casting", Method::TetRaycast(SegmentRule::Psi)),
            (
                "Resample + ray casting",
                Method::Resample {
                    samples: 256,
                    raycast: grid,
                },
            ),
        ],
    }
}

fn method_settings(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let Some(volume) = app.volume().cloned() else {
        return;
    };
    let current = app.scene.method.name();
    let mut picked = None;
    egui::ComboBox::from_label("method")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for (label, m) in method_choices(&volume) {
                if ui.selectable_label(m.name() == current, label).clicked() && m.name() != current
                {
                    picked = Some(m);
                }
            }
        });
    if let Some(m) = picked {
        pick_method(app, m);
    }
    let bricked = app.is_bricked();
    if bricked {
        let mut full = app.full_resolution;
        ui.checkbox(&mut full, "Full resolution")
            .on_hover_text("refine to level 0 whatever the view (otherwise: the level whose voxels are about a pixel)");
        app.set_full_resolution(full);
    }
    match &mut app.scene.method {
        Method::GridRaycast(g) | Method::Resample { raycast: g, .. } => {
            grid_settings(ui, g, bricked)
        }
        Method::ProjectedTetrahedra(p) => pt_settings(ui, p),
        Method::TetRaycast(rule) => rule_settings(ui, rule, true),
        Method::Slicing(s) => {
            ui.add(egui::Slider::new(&mut s.step, 0.1..=4.0).text("slice distance (voxels)"))
                .on_hover_text("view-aligned slices of the volume of interest, drawn on the GPU");
        }
        _ => {}
    }
}

/// Switches method; a grid is split into tetrahedra first (in the background) for the mesh
/// methods.
fn pick_method(app: &mut ViewerApp, method: Method) {
    app.set_method(method);
}

fn grid_settings(ui: &mut egui::Ui, g: &mut GridRaycast, bricked: bool) {
    let names = [
        "riemann",
        "trapezoid",
        "simpson",
        "preintegrated",
        "adaptive",
        "reference",
    ];
    let step = match g.integrator {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Simpson { step }
        | Integrator::Preintegrated { step } => Some(step),
        _ => None,
    };
    let current = integrator_name(&g.integrator);
    egui::ComboBox::from_label("integrator")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for n in names {
                if ui.selectable_label(n == current, n).clicked() {
                    g.integrator = integrator_named(n, step.unwrap_or(0.5));
                }
            }
        });
    match &mut g.integrator {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Simpson { step }
        | Integrator::Preintegrated { step } => {
            ui.add(
                egui::Slider::new(step, 0.05..=4.0)
                    .logarithmic(true)
                    .text("step (voxels)"),
            );
        }
        Integrator::AdaptiveSimpson(p) => {
            ui.add(
                egui::Slider::new(&mut p.tol, 1e-5..=0.1)
                    .logarithmic(true)
                    .text("tolerance"),
            );
        }
        _ => {}
    }
    let recon = [
        ("trilinear", Reconstruction::Trilinear),
        ("Catmull-Rom", Reconstruction::CatmullRom),
        ("B-spline", Reconstruction::BSpline),
    ];
    ui.horizontal(|ui| {
        for (label, r) in recon {
            let cubic = r != Reconstruction::Trilinear;
            ui.add_enabled_ui(!(bricked && cubic), |ui| {
                ui.radio_value(&mut g.reconstruction, r, label)
                    .on_disabled_hover_text(format!("cubic reconstruction {NEEDS_MEMORY}"));
            });
        }
    });
    if bricked {
        // A session may carry a cubic filter: back to trilinear rather than an error per frame.
        g.reconstruction = Reconstruction::Trilinear;
        ui.small(format!("cubic filters: off; {NEEDS_MEMORY}"));
    }
    ui.checkbox(&mut g.jitter, "jitter");
}

fn integrator_name(i: &Integrator) -> &'static str {
    match i {
        Integrator::Riemann { .. } => "riemann",
        Integrator::Trapezoid { .. } => "trapezoid",
        Integrator::Simpson { .. } => "simpson",
        Integrator::Preintegrated { .. } => "preintegrated",
        Integrator::AdaptiveSimpson(_) => "adaptive",
        Integrator::Reference => "reference",
        _ => "other",
    }
}

fn integrator_named(name: &str, step: f64) -> Integrator {
    match name {
        "trapezoid" => Integrator::Trapezoid { step },
        "simpson" => Integrator::Simpson { step },
        "preintegrated" => Integrator::Preintegrated { step },
        "adaptive" => {
            Integrator::AdaptiveSimpson(volux_render::integrate::adaptive::AdaptiveParams {
                tol: 1e-3,
                ..Integrator::REFERENCE
            })
        }
        "reference" => Integrator::Reference,
        _ => Integrator::Riemann { step },
    }
}

fn pt_settings(ui: &mut egui::Ui, p: &mut PtSettings) {
    ui.horizontal(|ui| {
        ui.label("order");
        ui.radio_value(&mut p.sort, SortMode::Centroid, "centroid");
        ui.radio_value(&mut p.sort, SortMode::Exact, "exact");
    });
    rule_settings(ui, &mut p.color, false);
}

fn rule_settings(ui: &mut egui::Ui, rule: &mut SegmentRule, adaptive: bool) {
    ui.horizontal(|ui| {
        ui.label("colour");
        ui.radio_value(rule, SegmentRule::Average, "average");
        ui.radio_value(rule, SegmentRule::Psi, "ψ");
        ui.radio_value(rule, SegmentRule::Exact, "exact");
        if adaptive
            && ui
                .radio(matches!(rule, SegmentRule::AdaptiveSimpson(_)), "adaptive")
                .clicked()
        {
            *rule =
                SegmentRule::AdaptiveSimpson(volux_render::integrate::adaptive::AdaptiveParams {
                    tol: 1e-3,
                    ..Integrator::REFERENCE
                });
        }
    });
}

fn appearance_settings(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let a = &mut app.scene.appearance;
    let grid_like = matches!(
        app.scene.method,
        Method::GridRaycast(_) | Method::Resample { .. }
    );
    ui.horizontal(|ui| {
        ui.add_enabled(grid_like, egui::Checkbox::new(&mut a.shade_volume, "shade"));
        let pt = matches!(app.scene.method, Method::ProjectedTetrahedra(_));
        ui.add_enabled(!pt, egui::Checkbox::new(&mut a.mip, "MIP"));
        ui.checkbox(&mut app.show_planes, "slice planes");
    });
    ui.add(
        egui::Slider::new(&mut a.opacity_scale, 0.01..=20.0)
            .logarithmic(true)
            .text("opacity scale"),
    );
    ui.horizontal(|ui| {
        ui.label("background");
        ui.color_edit_button_rgb(&mut app.background);
        let mut perspective = matches!(
            app.scene.view.camera.projection,
            volux_core::Projection::Perspective { .. }
        );
        if ui.checkbox(&mut perspective, "perspective").changed() {
            app.scene.view.camera = crate::navigation::toggle_projection(&app.scene.view.camera);
        }
    });
    isosurface_list(app, ui);
}

fn isosurface_list(app: &mut ViewerApp, ui: &mut egui::Ui) {
    let range = app.range();
    let mut values: Vec<Isovalue> = app.scene.appearance.isosurfaces.as_slice().to_vec();
    let mut changed = false;
    let mut remove = None;
    for (i, iso) in values.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            let speed = (range[1] - range[0]) / 500.0;
            changed |= ui
                .add(
                    egui::DragValue::new(&mut iso.value)
                        .speed(speed)
                        .range(range[0]..=range[1]),
                )
                .changed();
            changed |= ui
                .color_edit_button_rgba_unmultiplied(&mut iso.rgba)
                .changed();
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove {
        values.remove(i);
        changed = true;
    }
    if ui.button("add isosurface").clicked() {
        values.push(Isovalue {
            value: ((range[0] + range[1]) * 0.5) as f32,
            rgba: [0.9, 0.85, 0.7, 1.0],
        });
        changed = true;
    }
    if changed {
        if let Ok(iso) = Isosurfaces::new(values) {
            app.scene.appearance.isosurfaces = iso;
        }
    }
}

fn tf_section(app: &mut ViewerApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        ui.label("transfer function");
        egui::ComboBox::from_id_salt("preset")
            .selected_text("preset…")
            .show_ui(ui, |ui| {
                for p in PRESETS {
                    if ui.selectable_label(false, p).clicked() {
                        apply_preset(app, p);
                    }
                }
            });
        if ui.button("Load…").clicked() {
            app.open_dialog(Purpose::LoadTf);
        }
        if ui.button("Save…").clicked() {
            app.open_dialog(Purpose::SaveTf);
        }
    });
    if let Some(editor) = &mut app.editor {
        let mut tf = app.scene.appearance.tf.clone();
        if editor.show(ui, &mut tf) && tf.validate().is_ok() {
            app.scene.appearance.tf = tf;
        }
    }
    ui.small("curve: click adds, drag moves, right click deletes; ctrl+drag: window/level");
    ui.small("colours: click picks, double click adds, right click deletes");
}

/// Replaces the TF with a preset fitted to the data.
pub fn apply_preset(app: &mut ViewerApp, name: &str) {
    let Some(volume) = app.volume().cloned() else {
        return;
    };
    match volume.preset_tf(name) {
        Ok(tf) => {
            app.scene.appearance.tf = in_value_space(&tf, volume.range());
            if let Some(e) = &mut app.editor {
                e.fit_height(&app.scene.appearance.tf);
            }
        }
        Err(e) => app.error = Some(e.to_string()),
    }
}
