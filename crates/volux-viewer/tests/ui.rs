//! The viewer's behaviour through egui_kittest (the egui project's harness): the whole
//! window runs headless, pointer events go in, and the app's state is checked.
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use eframe::egui::{self, Pos2};
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
            "timed out waiting for {what}"
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
    std::fs::write(&session, json.to_string()).unwrap();
    let mut h2 = harness(Some(session));
    loaded_with_frame(&mut h2);
    assert_eq!(app(&h2).shown_scene().unwrap().method.name(), "pt");
    assert!(app(&h2).data.as_ref().unwrap().tets.is_some());
}
