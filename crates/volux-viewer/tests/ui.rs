//! The viewer's behaviour through egui_kittest (the egui project's harness): the whole
//! window runs headless, pointer events go in, and the app's state is checked.
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use eframe::egui::{self, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use volux_core::synth;
use volux_viewer::app::{Options, ViewerApp};

type App = Option<ViewerApp>;

fn harness(open: Option<PathBuf>) -> Harness<'static, App> {
    let options = Options {
        open,
        ..Default::default()
    };
    Harness::builder()
        .with_size([1100.0, 800.0])
        .with_max_steps(8)
        .build_state(
            move |ctx, app: &mut App| {
                app.get_or_insert_with(|| ViewerApp::new(ctx, options.clone()));
                volux_viewer::window::frame(app.as_mut().unwrap(), ctx)
            },
            None,
        )
}

fn app<'a>(h: &'a Harness<'static, App>) -> &'a ViewerApp {
    h.state()
        .as_ref()
        .expect("the app starts on the first step")
}

/// Steps the window until `done` holds (the render thread and loaders run meanwhile).
fn step_until(h: &mut Harness<'static, App>, what: &str, done: impl Fn(&ViewerApp) -> bool) {
    let start = Instant::now();
    loop {
        h.step();
        if h.state().as_ref().is_some_and(&done) {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what} (error: {:?})",
            h.state().as_ref().and_then(|a| a.error.clone())
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A small grid as raw + JSON sidecar in `dir`.
fn small_grid(dir: &Path) -> PathBuf {
    let path = dir.join("ml.raw");
    volux_io::raw::write(&synth::marschner_lobb(24).unwrap(), &path).unwrap();
    path
}

fn loaded_with_frame(h: &mut Harness<'static, App>) {
    step_until(h, "the dataset and a full frame", |a| {
        a.data.is_some() && a.shown_full()
    });
}

/// Dragging a control point of the opacity curve up raises it.
#[test]
fn dragging_a_tf_control_point_changes_the_tf() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let tf = app(&h).scene.appearance.tf.clone();
    let curve = |tf: &volux_core::TransferFunction| {
        if tf.extinction.is_empty() {
            tf.opacity.clone()
        } else {
            tf.extinction.clone()
        }
    };
    let i = curve(&tf).len() / 2;
    let editor = app(&h).editor.as_ref().unwrap();
    let from = editor.point_position(&tf, i).unwrap();
    let to = Pos2::new(from.x + 12.0, from.y - 40.0);
    drag(
        &mut h,
        from,
        to,
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    let after = curve(&app(&h).scene.appearance.tf);
    assert_eq!(
        after.len(),
        curve(&tf).len(),
        "a drag moves, it does not add"
    );
    assert!(
        after[i][1] > curve(&tf)[i][1],
        "{:?} -> {:?}",
        curve(&tf)[i],
        after[i]
    );
    assert!(after[i][0] > curve(&tf)[i][0] || i + 1 == after.len());
}

/// A quick drag moves a control point at once: by the time egui calls it a drag (a few
/// pixels), the pointer has left the point's grab radius, and the point under the press is
/// the one moved.
#[test]
fn a_quick_drag_moves_a_tf_point_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let tf = app(&h).scene.appearance.tf.clone();
    let curve = |tf: &volux_core::TransferFunction| {
        if tf.extinction.is_empty() {
            tf.opacity.clone()
        } else {
            tf.extinction.clone()
        }
    };
    let i = curve(&tf).len() / 2;
    let from = app(&h)
        .editor
        .as_ref()
        .unwrap()
        .point_position(&tf, i)
        .unwrap();
    // Each move is 20 px: the first frame of the drag is already 20 px from the point.
    let to = Pos2::new(from.x, from.y - 40.0);
    h.hover_at(from);
    h.step();
    let press = |pressed, pos| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    h.event(press(true, from));
    h.step();
    for k in 1..=2 {
        h.hover_at(from + (to - from) * (k as f32 / 2.0));
        h.step();
    }
    h.event(press(false, to));
    h.step();
    h.step();
    let after = curve(&app(&h).scene.appearance.tf);
    assert_eq!(
        after.len(),
        curve(&tf).len(),
        "a drag moves, it does not add"
    );
    assert!(
        after[i][1] > curve(&tf)[i][1],
        "{:?} -> {:?}",
        curve(&tf)[i],
        after[i]
    );
}

/// A press, moves in steps, and a release, one frame each.
fn drag(
    h: &mut Harness<'static, App>,
    from: Pos2,
    to: Pos2,
    button: egui::PointerButton,
    modifiers: egui::Modifiers,
) {
    h.hover_at(from);
    h.step();
    h.event(egui::Event::PointerButton {
        pos: from,
        button,
        pressed: true,
        modifiers,
    });
    h.step();
    for k in 1..=6 {
        h.hover_at(from + (to - from) * (k as f32 / 6.0));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button,
        pressed: false,
        modifiers,
    });
    h.step();
    h.step();
}

/// A malformed file shows its error in the window; the viewer then opens a good file.
#[test]
fn a_malformed_file_shows_an_error_and_the_viewer_lives_on() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.nrrd");
    std::fs::write(&bad, b"NRRD0004\ntype: float\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n\n\x01\x02").unwrap();
    let mut h = harness(Some(bad));
    step_until(&mut h, "the error", |a| a.error.is_some() && !a.busy());
    let message = app(&h).error.clone().unwrap();
    assert!(message.contains("broken.nrrd"), "{message}");
    assert!(app(&h).data.is_none());
    let good = small_grid(dir.path());
    h.state_mut().as_mut().unwrap().open(&good);
    loaded_with_frame(&mut h);
    assert!(app(&h).error.is_none());
    assert!(app(&h).title().starts_with("ml.raw"), "{}", app(&h).title());
}

/// A left drag in the 3D view orbits the camera about its target.
#[test]
fn a_drag_in_the_3d_view_turns_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let before = app(&h).scene.view.camera;
    let c = app(&h).view_rect.center();
    drag(
        &mut h,
        c,
        c + egui::vec2(80.0, 0.0),
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    let after = app(&h).scene.view.camera;
    assert_eq!(after.target, before.target, "an orbit keeps the target");
    let d0 = (before.eye - before.target).length();
    assert!(
        (after.eye - before.eye).length() > 0.1 * d0,
        "{before:?} -> {after:?}"
    );
    assert!(((after.eye - after.target).length() - d0).abs() < 1e-9 * d0);
    // and the full frame of the new view follows
    loaded_with_frame(&mut h);
    assert_eq!(app(&h).shown_scene().unwrap().view.camera, after);
}

/// A saved session reopens to the same camera, TF, method, window and crosshair.
#[test]
fn a_saved_session_reopens_the_same_view() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    {
        let a = h.state_mut().as_mut().unwrap();
        a.scene.view.camera = volux_viewer::navigation::orbit(&a.scene.view.camera, 50.0, 20.0);
        a.scene.appearance.opacity_scale = 2.5;
        a.window = [0.1, 0.7];
        a.crosshair = glam::DVec3::new(0.2, -0.3, 0.1);
    }
    let session = dir.path().join("view.json");
    app(&h).save_session(&session).unwrap();
    let saved = app(&h).session().unwrap();
    let mut h2 = harness(Some(session));
    loaded_with_frame(&mut h2);
    let b = app(&h2);
    assert_eq!(b.scene.view.camera, saved.camera);
    assert_eq!(b.scene.appearance, saved.appearance);
    assert_eq!(b.scene.method, saved.method);
    assert_eq!(b.window, [0.1, 0.7]);
    assert_eq!(b.crosshair, glam::DVec3::new(0.2, -0.3, 0.1));
    // The harness renders on the CPU (the library's default), and the session says so.
    assert_eq!(saved.backend, Some(volux_app::Backend::Cpu));
}

/// A session naming a missing dataset says so, and the viewer stays usable.
#[test]
fn a_session_with_a_missing_dataset_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let session = dir.path().join("s.json");
    app(&h).save_session(&session).unwrap();
    std::fs::remove_file(dir.path().join("ml.raw")).unwrap();
    let mut h2 = harness(Some(session));
    step_until(&mut h2, "the error", |a| a.error.is_some());
    let message = app(&h2).error.clone().unwrap();
    assert!(
        message.contains("ml.raw") && message.contains("no such file"),
        "{message}"
    );
}

/// Cancelling a load frees the window at once; the next file opens.
#[test]
fn a_load_can_be_cancelled() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_grid(dir.path());
    let mut h = harness(None);
    h.step();
    let a = h.state_mut().as_mut().unwrap();
    a.open(&path);
    assert!(a.busy(), "loading runs in the background");
    a.cancel_load();
    h.step();
    let a = h.state_mut().as_mut().unwrap();
    assert!(!a.busy() && a.data.is_none());
    assert_eq!(a.status.as_deref(), Some("loading cancelled"));
    a.open(&path);
    loaded_with_frame(&mut h);
}

/// A session asking for Projected Tetrahedra of a grid that was not split (written by hand)
/// splits it and renders.
#[test]
fn a_session_with_a_mesh_method_on_a_grid_splits_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let session = dir.path().join("pt.json");
    app(&h).save_session(&session).unwrap();
    let text = std::fs::read_to_string(&session).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["method"] = serde_json::json!({"name": "projected-tetrahedra",
        "settings": {"sort": "centroid", "color": {"kind": "psi"}, "count_violations": false}});
    // PT does not shade the volume (a session asking it to is refused, as by the CLI).
    json["appearance"]["shade_volume"] = serde_json::json!(false);
    std::fs::write(&session, json.to_string()).unwrap();
    let mut h2 = harness(Some(session));
    loaded_with_frame(&mut h2);
    assert_eq!(app(&h2).shown_scene().unwrap().method.name(), "pt");
    assert!(app(&h2).data.as_ref().unwrap().tets.is_some());
}

// Sculpting (seed `004` ch. 4-6): the Sculpt panel, the tools in the 3D view, undo, sessions.

fn app_mut<'a>(h: &'a mut Harness<'static, App>) -> &'a mut ViewerApp {
    h.state_mut()
        .as_mut()
        .expect("the app starts on the first step")
}

/// A press and a release at `pos` (one frame each), with `modifiers`.
fn click(h: &mut Harness<'static, App>, pos: Pos2, modifiers: egui::Modifiers) {
    h.hover_at(pos);
    h.step();
    for pressed in [true, false] {
        let event = egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers,
        };
        h.event_modifiers(event, modifiers);
        h.step();
    }
    h.step();
}

/// The number of voxels the sculpt mask removes.
fn removed(h: &Harness<'static, App>) -> u64 {
    app(h).sculpt.as_ref().unwrap().mask().removed_count()
}

/// Waits for the full frame of the newest scene and returns its scene.
fn rendered_scene(h: &mut Harness<'static, App>) -> volux_render::scene::Scene {
    loaded_with_frame(h);
    app(h).shown_scene().unwrap().clone()
}

/// The Add plane button adds a plane facing the camera through the VOI's centre; the render
/// thread gets it; Ctrl+Z takes it away and Ctrl+Shift+Z puts it back.
#[test]
fn adding_a_plane_reaches_the_renderer_and_undo_removes_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    assert!(rendered_scene(&mut h).clip_planes.is_empty());
    h.get_by_label("Add plane").click_accesskit();
    h.step();
    let scene = rendered_scene(&mut h);
    assert_eq!(
        scene.clip_planes.len(),
        1,
        "the rendered scene has the plane"
    );
    let camera = app(&h).scene.view.camera;
    let forward = (camera.target - camera.eye).normalize();
    assert!((scene.clip_planes[0].normal - forward).length() < 1e-9);
    let centre = app(&h).volume().unwrap().bounds().center();
    assert!(scene.clip_planes[0].distance(centre).abs() < 1e-9);
    assert!(h.query_by_label("plane 1").is_some(), "the panel lists it");
    h.key_combination_modifiers(egui::Modifiers::COMMAND, &[egui::Key::Z]);
    h.step();
    assert!(rendered_scene(&mut h).clip_planes.is_empty(), "undone");
    h.key_combination_modifiers(
        egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
        &[egui::Key::Z],
    );
    h.step();
    assert_eq!(rendered_scene(&mut h).clip_planes.len(), 1, "redone");
}

/// A plane that would cut everything away is refused with an error; the window goes on.
#[test]
fn a_plane_removing_everything_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let plane = volux_core::voi::ClipPlane::new(1.0, 0.0, 0.0, -1e6).unwrap();
    let applied = app_mut(&mut h).sculpt_step(volux_render::sculpt::SculptStep::AddPlane { plane });
    assert!(!applied);
    let message = app(&h).error.clone().unwrap();
    assert!(message.contains("whole volume of interest"), "{message}");
    assert!(app(&h).sculpt.as_ref().unwrap().planes().is_empty());
    h.step();
    assert!(
        app(&h).error.is_some(),
        "the error stays until the next action"
    );
}

/// An eraser drag (key E) removes voxels in one undoable step; undo restores the mask bit
/// for bit, and the rendered scene carries the mask.
#[test]
fn an_erase_drag_changes_the_mask_and_undo_restores_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    h.key_press(egui::Key::E);
    h.step();
    assert_eq!(app(&h).tools.tool, volux_viewer::sculpt_state::Tool::Erase);
    let before = app(&h).sculpt.as_ref().unwrap().mask().to_values();
    let camera = app(&h).scene.view.camera;
    let c = app(&h).view_rect.center();
    drag(
        &mut h,
        c - egui::vec2(60.0, 0.0),
        c + egui::vec2(60.0, 0.0),
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    assert_eq!(app(&h).scene.view.camera, camera, "erasing does not turn");
    assert!(removed(&h) > 0, "the stroke removed voxels");
    let steps = app(&h).sculpt.as_ref().unwrap().steps();
    assert_eq!(steps.len(), 1, "one stroke, one step: {steps:?}");
    let volux_render::sculpt::SculptStep::Erase { points, size, .. } = &steps[0] else {
        panic!("{steps:?}")
    };
    assert!(points.len() > 2, "a swept stroke: {points:?}");
    let scene = rendered_scene(&mut h);
    assert_eq!(*size, [scene.view.width, scene.view.height]);
    assert!(scene.mask.is_some(), "the renderer gets the mask");
    h.get_by_label("Undo").click_accesskit();
    h.step();
    assert_eq!(removed(&h), 0);
    assert_eq!(app(&h).sculpt.as_ref().unwrap().mask().to_values(), before);
    assert!(rendered_scene(&mut h).mask.is_none());
}

/// A dig click at the centre of the view removes a ball at the visible surface.
#[test]
fn a_dig_click_removes_voxels() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    app_mut(&mut h).tools.tool = volux_viewer::sculpt_state::Tool::Dig;
    let c = app(&h).view_rect.center();
    click(&mut h, c, egui::Modifiers::NONE);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    assert!(removed(&h) > 0, "the dig removed voxels");
    let steps = app(&h).sculpt.as_ref().unwrap().steps();
    assert!(matches!(
        steps.as_slice(),
        [volux_render::sculpt::SculptStep::Dig { .. }]
    ));
    // A click beside the data hits nothing: an error, nothing removed.
    let count = removed(&h);
    let corner = app(&h).view_rect.left_top() + egui::vec2(3.0, 3.0);
    click(&mut h, corner, egui::Modifiers::NONE);
    assert!(app(&h)
        .error
        .as_deref()
        .unwrap()
        .contains("nothing visible"));
    assert_eq!(removed(&h), count);
}

/// Two measure clicks make a line whose length in mm the panel shows; Shift+click starts a
/// new line.
#[test]
fn two_measure_clicks_show_a_length_in_mm() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    h.key_press(egui::Key::M);
    h.step();
    let c = app(&h).view_rect.center();
    click(&mut h, c - egui::vec2(30.0, 10.0), egui::Modifiers::NONE);
    click(&mut h, c + egui::vec2(30.0, 10.0), egui::Modifiers::NONE);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    let lines = app(&h).sculpt.as_ref().unwrap().measurements();
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].len(), 2);
    let length = volux_render::sculpt::polyline_length(&lines[0]);
    assert!(length > 0.0);
    let text = format!("measurement 1: {length:.2} mm (2 points)");
    assert!(h.query_by_label(&text).is_some(), "the panel shows {text}");
    click(&mut h, c, egui::Modifiers::SHIFT);
    let lines = app(&h).sculpt.as_ref().unwrap().measurements();
    assert_eq!(lines.iter().map(Vec::len).collect::<Vec<_>>(), [2, 1]);
}

/// Label seeds are picked with the panel's label; Compute labels counts the voxels of each.
#[test]
fn label_clicks_and_compute_labels_count_voxels() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    app_mut(&mut h).tools.tool = volux_viewer::sculpt_state::Tool::Label;
    let c = app(&h).view_rect.center();
    click(&mut h, c - egui::vec2(40.0, 0.0), egui::Modifiers::NONE);
    app_mut(&mut h).tools.label = 2;
    click(&mut h, c + egui::vec2(40.0, 0.0), egui::Modifiers::NONE);
    assert_eq!(app(&h).sculpt.as_ref().unwrap().label_seeds().len(), 2);
    h.get_by_label("Compute labels").click_accesskit();
    step_until(&mut h, "the label counts", |a| {
        a.tools.label_counts.is_some()
    });
    let counts = app(&h).tools.label_counts.clone().unwrap();
    assert_eq!(
        counts.iter().map(|c| c.0).collect::<Vec<_>>(),
        [1, 2],
        "{counts:?}"
    );
    h.step();
    let text = format!("label 1: {} voxels", counts[0].1);
    assert!(h.query_by_label(&text).is_some(), "the panel shows {text}");
    // The exported label volume holds the same counts.
    let out = dir.path().join("labels.nrrd");
    app_mut(&mut h).export_labels(&out).unwrap();
    step_until(&mut h, "the export", |a| {
        a.error.is_some() || a.status.as_deref().is_some_and(|s| s.starts_with("saved"))
    });
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    let (data, _) = volux_io::load(&out, &Default::default()).unwrap();
    let volux_io::Dataset::Grid(g) = data else {
        panic!("a grid")
    };
    let d = g.dims();
    let mut exported = [0u64; 3];
    for n in 0..d[0] * d[1] * d[2] {
        let v = g.value(n % d[0], n / d[0] % d[1], n / (d[0] * d[1])) as usize;
        exported[v.min(2)] += 1;
    }
    assert_eq!(exported[1..], [counts[0].1, counts[1].1]);
}

/// The straight (unpremultiplied) colour of the shown image at the screen point `pos`.
fn shown_colour(h: &Harness<'static, App>, pos: Pos2) -> [f32; 3] {
    let a = app(h);
    let [x, y] = volux_viewer::sculpt_tools::image_pixel(a, a.view_rect, pos);
    let image = a.shown_image().expect("a frame on screen");
    let p = image.get(x as usize, y as usize);
    assert!(p[3] > 0.2, "the data shows at {pos:?}: {p:?}");
    [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
}

/// Whether `c` has the hue of `label`: its largest channel is the label's, by a wide margin.
fn has_hue(c: [f32; 3], label: [f32; 3]) -> bool {
    let top = |v: [f32; 3]| (0..3).max_by(|&i, &j| v[i].total_cmp(&v[j])).unwrap();
    let k = top(label);
    k == top(c) && (0..3).all(|i| i == k || c[i] < 0.6 * c[k])
}

/// Label seeds colour the rendering in their labels' colours ("Colour by labels" turns on
/// with the first seed); turning it off brings the transfer function's colours back.
#[test]
fn label_seeds_colour_the_rendering_until_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let before = app(&h).shown_image().unwrap().clone();
    app_mut(&mut h).tools.tool = volux_viewer::sculpt_state::Tool::Label;
    let c = app(&h).view_rect.center();
    let (left, right) = (c - egui::vec2(40.0, 0.0), c + egui::vec2(40.0, 0.0));
    let (red, blue) = ([0.9, 0.1, 0.1], [0.1, 0.2, 0.95]);
    app_mut(&mut h).tools.colour = red;
    click(&mut h, left, egui::Modifiers::NONE);
    assert!(app(&h).tools.label_colours.on, "on with the first seed");
    app_mut(&mut h).tools.label = 2;
    app_mut(&mut h).tools.colour = blue;
    click(&mut h, right, egui::Modifiers::NONE);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    step_until(&mut h, "a frame coloured by two seeds' labels", |a| {
        let seeds = a.sculpt.as_ref().unwrap().label_seeds().len();
        !a.tools.label_colours.computing()
            && a.shown_full()
            && a.shown_scene().and_then(|s| s.labels.as_ref()).is_some()
            && seeds == 2
    });
    let near = |p: Pos2| p + egui::vec2(0.0, 3.0);
    for (pos, colour) in [(left, red), (right, blue)] {
        let tf_colour = {
            let [x, y] =
                volux_viewer::sculpt_tools::image_pixel(app(&h), app(&h).view_rect, near(pos));
            let p = before.get(x as usize, y as usize);
            [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
        };
        assert!(
            !has_hue(tf_colour, colour),
            "the TF alone is not {colour:?}: {tf_colour:?}"
        );
        let shown = shown_colour(&h, near(pos));
        assert!(
            has_hue(shown, colour),
            "near the seed {shown:?}, label {colour:?}"
        );
    }
    // Frames without a change compute nothing again.
    let first = app(&h).render_scene().labels.unwrap();
    for _ in 0..5 {
        h.step();
    }
    assert!(!app(&h).tools.label_colours.computing(), "computed again");
    assert!(std::sync::Arc::ptr_eq(
        &first,
        &app(&h).render_scene().labels.unwrap()
    ));
    // MIP draws no labels, and the panel says so.
    app_mut(&mut h).scene.appearance.mip = true;
    h.step();
    assert!(app(&h).render_scene().labels.is_none());
    let why = "labels colour the composited rendering; MIP shows the TF's colours";
    assert!(h.query_by_label(why).is_some(), "the panel says {why}");
    app_mut(&mut h).scene.appearance.mip = false;
    h.step();
    assert!(app(&h).render_scene().labels.is_some());
    h.get_by_label("Colour by labels").click_accesskit();
    h.step();
    assert!(!app(&h).tools.label_colours.on);
    step_until(&mut h, "a frame without labels", |a| {
        a.shown_full() && a.shown_scene().is_some_and(|s| s.labels.is_none())
    });
    let after = app(&h).shown_image().unwrap();
    let diff = after.compare(&before, 1e-3).unwrap();
    assert!(diff.max_error < 1e-5, "the TF's colours again: {diff:?}");
}

/// A session with sculpt steps reopens to the same mask and planes; the exported mask reads
/// back with the data's geometry.
#[test]
fn a_saved_session_rebuilds_the_same_mask() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    app_mut(&mut h).add_plane();
    app_mut(&mut h).tools.tool = volux_viewer::sculpt_state::Tool::Erase;
    let c = app(&h).view_rect.center();
    drag(
        &mut h,
        c - egui::vec2(50.0, 20.0),
        c + egui::vec2(50.0, 20.0),
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    assert!(removed(&h) > 0);
    let session = dir.path().join("sculpted.json");
    app(&h).save_session(&session).unwrap();
    let a = app(&h).sculpt.as_ref().unwrap();
    let (mask, planes) = (a.mask().to_values(), a.planes().to_vec());
    let mut h2 = harness(Some(session));
    loaded_with_frame(&mut h2);
    let b = app(&h2).sculpt.as_ref().unwrap();
    assert_eq!(b.planes(), planes.as_slice());
    assert_eq!(b.mask().to_values(), mask, "the same mask, bit for bit");
    assert_eq!(b.steps().len(), 2);
    assert!(app(&h2).shown_scene().unwrap().mask.is_some());
    let out = dir.path().join("mask.nrrd");
    app_mut(&mut h2).export_mask(&out).unwrap();
    step_until(&mut h2, "the export", |a| {
        a.error.is_some() || a.status.as_deref().is_some_and(|s| s.starts_with("saved"))
    });
    assert!(app(&h2).error.is_none(), "{:?}", app(&h2).error);
    let (data, _) = volux_io::load(&out, &Default::default()).unwrap();
    let volux_io::Dataset::Grid(g) = data else {
        panic!("a grid")
    };
    let source = app(&h2).sculpt_grid().unwrap();
    assert_eq!(g.dims(), source.dims());
    assert_eq!(g.spacing(), source.spacing());
    assert_eq!(g.origin(), source.origin());
    let values: Vec<u8> = (0..mask.len())
        .map(|n| {
            let d = g.dims();
            g.value(n % d[0], n / d[0] % d[1], n / (d[0] * d[1])) as u8
        })
        .collect();
    assert_eq!(values, mask);
}

/// A mesh gets planes only: Add plane reaches tet ray casting; a session with sculpt steps on
/// the mesh shows the engine's error and opens with its planes.
#[test]
fn a_mesh_gets_planes_and_refuses_sculpt_steps_from_a_session() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("smooth.vtet");
    volux_io::vtet::write(&synth::smooth_tets(3000).unwrap(), &path).unwrap();
    let mut h = harness(Some(path));
    loaded_with_frame(&mut h);
    assert!(app(&h).sculpt_grid().is_none());
    app_mut(&mut h).set_method(volux_render::scene::Method::TetRaycast(
        volux_render::integrate::segment::SegmentRule::Psi,
    ));
    app_mut(&mut h).add_plane();
    assert_eq!(rendered_scene(&mut h).clip_planes.len(), 1);
    let session = dir.path().join("mesh.json");
    app(&h).save_session(&session).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&session).unwrap()).unwrap();
    assert!(
        json.get("sculpt").is_none(),
        "a mesh's planes are saved as planes"
    );
    let plane = app(&h).sculpt.as_ref().unwrap().planes()[0];
    let step = volux_render::sculpt::SculptStep::AddPlane { plane };
    json["sculpt"] = serde_json::json!([serde_json::to_value(step).unwrap()]);
    std::fs::write(&session, json.to_string()).unwrap();
    let mut h2 = harness(Some(session));
    loaded_with_frame(&mut h2);
    let message = app(&h2)
        .error
        .clone()
        .expect("the session's steps are refused");
    assert!(message.contains("tetrahedral mesh"), "{message}");
    assert_eq!(app(&h2).sculpt.as_ref().unwrap().planes(), [plane]);
    assert_eq!(app(&h2).shown_scene().unwrap().clip_planes, [plane]);
}

/// Dragging a plane's offset slider moves the plane in one undo step.
#[test]
fn a_plane_slider_drag_is_one_undo_step() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    app_mut(&mut h).add_plane();
    h.step();
    let added = app(&h).sculpt.as_ref().unwrap().planes()[0];
    let rect = h
        .get_by_role_and_label(egui::accesskit::Role::Slider, "offset")
        .rect();
    assert!(rect.bottom() < 800.0, "the slider is on screen: {rect:?}");
    let from = rect.center() - egui::vec2(rect.width() * 0.1, 0.0);
    drag(
        &mut h,
        from,
        from + egui::vec2(40.0, 0.0),
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    let sculpt = app(&h).sculpt.as_ref().unwrap();
    let moved = sculpt.planes()[0];
    assert!(
        (moved.offset - added.offset).abs() > 1e-6,
        "{added:?} -> {moved:?}"
    );
    assert_eq!(
        moved.normal, added.normal,
        "the offset slider keeps the normal"
    );
    assert_eq!(sculpt.steps().len(), 2, "{:?}", sculpt.steps());
    app_mut(&mut h).undo();
    assert_eq!(app(&h).sculpt.as_ref().unwrap().planes(), [added]);
}

/// Dragging a plane's tilt handle tilts the plane about the data's centre (its distance from
/// the centre kept) in one undo step, without turning the camera.
#[test]
fn dragging_a_tilt_handle_tilts_the_plane() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    app_mut(&mut h).add_plane();
    h.step();
    let added = app(&h).sculpt.as_ref().unwrap().planes()[0];
    let camera = app(&h).scene.view.camera;
    let tip = volux_viewer::plane_handle::tips(app(&h))[0];
    let rect = app(&h).view_rect;
    let at = volux_viewer::sculpt_tools::project(&camera, rect, tip).unwrap();
    drag(
        &mut h,
        at,
        at + egui::vec2(60.0, -40.0),
        egui::PointerButton::Primary,
        egui::Modifiers::NONE,
    );
    assert_eq!(app(&h).scene.view.camera, camera, "the camera stays");
    let sculpt = app(&h).sculpt.as_ref().unwrap();
    let tilted = sculpt.planes()[0];
    assert!(
        tilted.normal.dot(added.normal) < 0.999,
        "{added:?} -> {tilted:?}"
    );
    let centre = app(&h).volume().unwrap().bounds().center();
    assert!((tilted.distance(centre) - added.distance(centre)).abs() < 1e-9);
    assert_eq!(sculpt.steps().len(), 2, "one drag, one step");
    // The tip now sits under the pointer.
    let tip = volux_viewer::plane_handle::tips(app(&h))[0];
    let now = volux_viewer::sculpt_tools::project(&camera, rect, tip).unwrap();
    assert!(now.distance(at + egui::vec2(60.0, -40.0)) < 1.0, "{now:?}");
}

/// The formats of issue 21 open in the viewer as in `volux info`: an ImageJ hyperstack with
/// `--channel`/`--timepoint` (the values of the chosen channel and timepoint), a JPEG
/// Lossless DICOM folder (bit for bit its uncompressed original's range), a bad channel shows
/// an error and the viewer lives on.
#[test]
fn tiff_stacks_and_compressed_dicom_open_with_their_channel() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../volux-io/tests/fixtures");
    let stack = fixtures.join("tiff/imagej_hyperstack.tif");
    let want = |c: Option<usize>, t: Option<usize>| {
        let options = volux_io::LoadOptions {
            channel: c.unwrap_or(0),
            timepoint: t.unwrap_or(0),
            ..Default::default()
        };
        let (data, _) = volux_io::load(&stack, &options).unwrap();
        match data {
            volux_io::Dataset::Grid(g) => g.range(),
            _ => panic!("a grid"),
        }
    };
    assert_ne!(
        want(Some(1), Some(2)),
        want(None, None),
        "the choice matters"
    );
    let open = |path: &Path, channel: Option<usize>, timepoint: Option<usize>| {
        let options = Options {
            open: Some(path.to_path_buf()),
            channel,
            timepoint,
            ..Default::default()
        };
        Harness::builder()
            .with_size([1100.0, 800.0])
            .with_max_steps(8)
            .build_state(
                move |ctx, app: &mut App| {
                    app.get_or_insert_with(|| ViewerApp::new(ctx, options.clone()));
                    volux_viewer::window::frame(app.as_mut().unwrap(), ctx)
                },
                None,
            )
    };
    let mut h = open(&stack, Some(1), Some(2));
    loaded_with_frame(&mut h);
    assert_eq!(app(&h).range(), want(Some(1), Some(2)));
    let mut h = open(&stack, Some(9), None);
    step_until(&mut h, "the error", |a| a.error.is_some() && !a.busy());
    let message = app(&h).error.clone().unwrap();
    assert!(message.contains("channel"), "{message}");
    let native = fixtures.join("dicom_compressed/mr_native");
    let mut h = open(&fixtures.join("dicom_compressed/mr_jpll70"), None, None);
    loaded_with_frame(&mut h);
    let (data, _) = volux_io::load(&native, &Default::default()).unwrap();
    let volux_io::Dataset::Grid(g) = data else {
        panic!("a grid")
    };
    assert_eq!(app(&h).range(), g.range());
}

/// A 4-D file (an fMRI-like time series, here a 4-D NRRD) opens on its first volume; the
/// volume picker reloads another one and keeps the view (camera, transfer function).
#[test]
fn the_volume_picker_shows_another_timepoint_and_keeps_the_view() {
    let dir = tempfile::tempdir().unwrap();
    let n = 6usize;
    let mut bytes = format!(
        "NRRD0004\ntype: uint8\ndimension: 4\nspace: left-posterior-superior\n\
         sizes: {n} {n} {n} 3\nkinds: domain domain domain time\n\
         space directions: (1,0,0) (0,1,0) (0,0,1) none\nspace origin: (0,0,0)\n\
         encoding: raw\n\n"
    )
    .into_bytes();
    // Volume t holds a ramp along x starting at 40 t.
    for t in 0..3u8 {
        for i in 0..n * n * n {
            bytes.push(40 * t + (i % n) as u8);
        }
    }
    let path = dir.path().join("series.nrrd");
    std::fs::write(&path, bytes).unwrap();
    let mut h = harness(Some(path));
    loaded_with_frame(&mut h);
    assert_eq!(app(&h).range(), [0.0, 5.0]);
    let camera = app(&h).scene.view.camera;
    let tf = app(&h).scene.appearance.tf.clone();
    app_mut(&mut h).choose_volume("timepoint", Some(2));
    step_until(&mut h, "timepoint 2", |a| {
        !a.busy()
            && a.data
                .as_ref()
                .is_some_and(|d| d.source.timepoint == Some(2))
    });
    assert_eq!(app(&h).range(), [80.0, 85.0]);
    assert_eq!(app(&h).scene.view.camera, camera, "the view is kept");
    assert_eq!(app(&h).scene.appearance.tf, tf, "the TF is kept");
    // The picker lists the axis, its length and the volume shown.
    h.run();
    assert!(h.query_by_label_contains("time: 3 volumes").is_some());
}

/// The red pixels of the frame on screen (straight colour mostly red), and their mean
/// column as a fraction of the width.
fn red_pixels(h: &Harness<'static, App>) -> (usize, f64) {
    let image = app(h).shown_image().expect("a frame on screen");
    let mut cols = Vec::new();
    for y in 0..image.height() {
        for x in 0..image.width() {
            let p = image.get(x, y);
            if p[3] > 0.5 && p[0] / p[3] > 0.4 && p[1] < 0.4 * p[0] && p[2] < 0.4 * p[0] {
                cols.push(x as f64 / image.width() as f64);
            }
        }
    }
    let mean = cols.iter().sum::<f64>() / cols.len().max(1) as f64;
    (cols.len(), mean)
}

/// The view buttons of a patient scan are the patient's sides (Slicer's convention), the
/// same views as the CLI's `--view`: L shows a marker on the patient's left of a NIfTI head
/// stored as nibabel writes it, R hides it behind the head, and I (the radiological axial
/// view) puts it on the image's right.
#[test]
fn the_view_buttons_show_the_patients_named_side() {
    let dir = tempfile::tempdir().unwrap();
    let head = dir.path().join("head.nii");
    volux_testkit::nifti::write_head_with_left_marker(&head);
    let tf = dir.path().join("marker.json");
    std::fs::write(&tf, volux_testkit::nifti::MARKER_TF).unwrap();
    let mut h = harness(Some(head));
    loaded_with_frame(&mut h);
    app_mut(&mut h).load_tf(&tf).unwrap();
    let shown = |h: &mut Harness<'static, App>, button: &str| {
        h.get_by_label(button).click_accesskit();
        h.step();
        loaded_with_frame(h);
        red_pixels(h)
    };
    let (left, _) = shown(&mut h, "L");
    let (right, _) = shown(&mut h, "R");
    assert!(left > 50 && right == 0, "red pixels: L {left}, R {right}");
    let (count, column) = shown(&mut h, "I");
    assert!(
        count > 10 && column > 0.6,
        "I: {count} red at column {column}"
    );
    let (count, column) = shown(&mut h, "S");
    assert!(
        count > 10 && column < 0.4,
        "S: {count} red at column {column}"
    );
}

/// A grid opens lit; MIP (which shows no light) still renders with the "shade" box ticked,
/// and the frame and the session leave the shading out until MIP is off again.
#[test]
fn mip_renders_while_shading_is_ticked() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    assert!(app(&h).scene.appearance.shade_volume, "a grid opens lit");
    app_mut(&mut h).scene.appearance.mip = true;
    let scene = rendered_scene(&mut h);
    assert!(scene.appearance.mip && !scene.appearance.shade_volume);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    app_mut(&mut h).scene.appearance.mip = false;
    let scene = rendered_scene(&mut h);
    assert!(!scene.appearance.mip && scene.appearance.shade_volume);
}

/// A message or an error appearing (or going) moves nothing: the 3D view and the panels'
/// widgets keep their places, so a click aimed a moment before lands where it was aimed.
#[test]
fn messages_do_not_move_the_layout() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    h.step();
    let places = |h: &Harness<'static, App>| {
        let button = h.get_by_label("Add plane").rect();
        (app(h).view_rect, button)
    };
    let before = places(&h);
    app_mut(&mut h).status = Some("saved /somewhere/screenshot.png".into());
    h.step();
    h.step();
    assert_eq!(places(&h), before, "a message appeared");
    app_mut(&mut h).error = Some("a long error\nover two lines ".repeat(20));
    h.step();
    h.step();
    assert_eq!(places(&h), before, "an error appeared");
    h.get_by_label("dismiss").click_accesskit();
    h.step();
    h.step();
    assert!(app(&h).error.is_none(), "dismissed");
    app_mut(&mut h).status = None;
    h.step();
    h.step();
    assert_eq!(places(&h), before, "the messages went");
}

/// Enter in the file dialog's path field saves, as the Save button does; a save is proposed
/// in the working directory (the dataset's folder may be read-only), then in the folder of
/// the last save.
#[test]
fn the_file_dialog_saves_on_enter_where_the_last_save_went() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let cwd = std::env::current_dir().unwrap();
    app_mut(&mut h).open_dialog(volux_viewer::file_dialog::Purpose::SaveTf);
    h.step();
    let proposed = PathBuf::from(app(&h).file_dialog().path_text());
    assert_eq!(proposed, cwd.join("tf.json"), "not the dataset's folder");
    let out = tempfile::tempdir().unwrap();
    let target = out.path().join("mine.json");
    let field = h.get_by_role(egui::accesskit::Role::TextInput);
    field.focus();
    h.step();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.step();
    h.get_by_role(egui::accesskit::Role::TextInput)
        .type_text(&target.display().to_string());
    h.step();
    h.key_press(egui::Key::Enter);
    h.step();
    h.step();
    assert!(!app(&h).file_dialog().is_open(), "Enter closed the dialog");
    assert!(target.is_file(), "Enter saved {}", target.display());
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    app_mut(&mut h).open_dialog(volux_viewer::file_dialog::Purpose::SaveSession);
    h.step();
    let proposed = PathBuf::from(app(&h).file_dialog().path_text());
    assert_eq!(proposed, out.path().join("session.json"));
    // Reading still starts beside the dataset.
    app_mut(&mut h).open_dialog(volux_viewer::file_dialog::Purpose::LoadTf);
    assert_eq!(PathBuf::from(app(&h).file_dialog().path_text()), dir.path());
}

/// The texts drawn in the last frame, each with the shape drawn just before it.
fn texts_with_what_lies_under(h: &Harness<'static, App>) -> Vec<(String, Option<egui::Shape>)> {
    let shapes: Vec<&egui::Shape> = h.output().shapes.iter().map(|c| &c.shape).collect();
    let mut out = Vec::new();
    for (k, shape) in shapes.iter().enumerate() {
        if let egui::Shape::Text(t) = shape {
            let under = k.checked_sub(1).map(|j| shapes[j].clone());
            out.push((t.galley.text().to_string(), under));
        }
    }
    out
}

/// Whether `under` is a dark filled rectangle holding `text`'s shape.
fn is_dark_backing(under: &Option<egui::Shape>) -> bool {
    match under {
        Some(egui::Shape::Rect(r)) => {
            let [red, green, blue, alpha] = r.fill.to_array();
            alpha >= 128 && red.max(green).max(blue) < 64
        }
        _ => false,
    }
}

/// A measurement's label reads over bright data: it lies on a dark backing. One point asks
/// for a second (never "-0.00 mm"); two say their distance.
#[test]
fn the_measurement_label_is_backed_and_honest() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    let (w, hgt) = app(&h).view_size;
    let centre = [w as f64 * 0.5, hgt as f64 * 0.5];
    app_mut(&mut h).measure_at(centre, true);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    h.step();
    let texts = texts_with_what_lies_under(&h);
    let label = texts
        .iter()
        .find(|(t, _)| t == "no length yet — click a second point")
        .unwrap_or_else(|| panic!("one point asks for a second: {texts:?}"));
    assert!(is_dark_backing(&label.1), "{label:?}");
    assert!(texts.iter().all(|(t, _)| !t.contains("-0.00")), "{texts:?}");
    app_mut(&mut h).measure_at([centre[0] + 30.0, centre[1] + 10.0], false);
    assert!(app(&h).error.is_none(), "{:?}", app(&h).error);
    h.step();
    let texts = texts_with_what_lies_under(&h);
    let label = texts
        .iter()
        .find(|(t, _)| t.ends_with(" mm") && !t.starts_with("measurement"))
        .unwrap_or_else(|| panic!("two points give a length: {texts:?}"));
    assert!(is_dark_backing(&label.1), "{label:?}");
    let length: f64 = label.0.trim_end_matches(" mm").parse().unwrap();
    assert!(length > 0.0, "{label:?}");
}

/// The 3D view's orientation letters (axis names of an unoriented grid) read over bright
/// data: each lies on a dark backing, as the slice views' do.
#[test]
fn the_orientation_letters_are_backed() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    h.step();
    let texts = texts_with_what_lies_under(&h);
    let letters: Vec<_> = texts
        .iter()
        .filter(|(t, _)| ["+X", "-X", "+Y", "-Y", "+Z", "-Z"].contains(&t.as_str()))
        .collect();
    // Four in the 3D view, and the slice views' own.
    assert!(letters.len() >= 4, "one letter per edge: {texts:?}");
    for letter in letters {
        assert!(is_dark_backing(&letter.1), "{letter:?}");
    }
}

/// The slices' captions (plane, voxel, window) lie where no crosshair line crosses them,
/// inside their views (not cut), with the window's values in a few digits.
#[test]
fn slice_captions_are_clear_of_the_crosshair() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(Some(small_grid(dir.path())));
    loaded_with_frame(&mut h);
    h.step();
    let crosshair = volux_viewer::slice_views::CROSSHAIR_COLOUR;
    let mut lines = Vec::new();
    let mut captions = Vec::new();
    for clipped in &h.output().shapes {
        match &clipped.shape {
            egui::Shape::LineSegment { points, stroke } if stroke.color == crosshair => {
                lines.push(egui::Rect::from_two_pos(points[0], points[1]).expand(0.5));
            }
            egui::Shape::Text(t) => {
                let text = t.galley.text().to_string();
                let window = text
                    .strip_prefix("window ")
                    .is_some_and(|v| v.starts_with(|c: char| c.is_ascii_digit() || c == '-'));
                let caption = window
                    || ["axial [", "coronal [", "sagittal ["]
                        .iter()
                        .any(|p| text.starts_with(p));
                if caption {
                    captions.push((text, t.visual_bounding_rect(), clipped.clip_rect));
                }
            }
            _ => {}
        }
    }
    assert_eq!(lines.len(), 6, "two crosshair lines per view");
    assert_eq!(captions.len(), 6, "a caption pair per view: {captions:?}");
    for (text, rect, clip) in &captions {
        assert!(!text.contains('…'), "{text} is cut short");
        assert!(
            clip.contains_rect(*rect),
            "{text} is clipped: {rect:?} in {clip:?}"
        );
        for line in &lines {
            assert!(!line.intersects(*rect), "a crosshair line crosses {text}");
        }
        if let Some(values) = text.strip_prefix("window ") {
            // Marschner-Lobb spans about 0 to 1: three significant digits at most.
            for v in values.split(" – ") {
                let decimals = v.split('.').nth(1).map_or(0, str::len);
                assert!(decimals <= 3, "{text}");
                assert!(v.parse::<f64>().is_ok(), "{text}");
            }
        }
    }
}
