//! OME-Zarr stores in the viewer (issue 19), through egui_kittest like `ui.rs`: a store
//! opens out of core, shows its coarsest level first and refines to level 0 (the picture
//! then equals the engine's level-0 render and the in-core render of the same data); a view
//! change during refinement restarts from the coarsest level; a damaged store shows its
//! error and the viewer lives on.
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use volux_core::bricked::GridChunks;
use volux_core::synth;
use volux_io::omezarr::{write_ome_zarr, Levels, WriteOptions};
use volux_render::bricked::Lod;
use volux_render::engine::render_once;
use volux_render::scene::Volume;
use volux_render::tiles::Control;
use volux_testkit::images::{assert_images_close, Tolerance};
use volux_viewer::app::{Options, ViewerApp};

type App = Option<ViewerApp>;

fn harness(open: Option<PathBuf>) -> Harness<'static, App> {
    let options = Options {
        open,
        ..Default::default()
    };
    Harness::builder()
        .with_size([900.0, 700.0])
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

fn app_mut<'a>(h: &'a mut Harness<'static, App>) -> &'a mut ViewerApp {
    h.state_mut()
        .as_mut()
        .expect("the app starts on the first step")
}

fn step_until(h: &mut Harness<'static, App>, what: &str, done: impl Fn(&ViewerApp) -> bool) {
    let start = Instant::now();
    loop {
        h.step();
        if h.state().as_ref().is_some_and(&done) {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The Marschner-Lobb field at `n`^3 written as a store with 16^3 chunks and a pyramid
/// down to one chunk (levels of n, n/2, ..., 16).
fn store(dir: &Path, n: usize) -> (PathBuf, volux_core::Grid) {
    let grid = synth::marschner_lobb(n).unwrap();
    let out = dir.join(format!("ml{n}.ome.zarr"));
    let src = GridChunks::new(Arc::new(grid.clone()), [16, 16, 16]).unwrap();
    let opts = WriteOptions {
        levels: Levels::Auto,
        name: "ml".into(),
        ..WriteOptions::default()
    };
    write_ome_zarr(&src, &out, &opts).unwrap();
    (out, grid)
}

/// The levels shown for request `generation`, in the order they came.
fn levels_of(a: &ViewerApp, generation: u64) -> Vec<usize> {
    a.level_log()
        .into_iter()
        .filter(|(g, _)| *g == generation)
        .map(|(_, l)| l.level)
        .collect()
}

fn newest_generation(a: &ViewerApp) -> u64 {
    a.level_log().last().map_or(0, |(g, _)| *g)
}

#[test]
fn a_store_shows_its_coarsest_level_first_and_refines_to_level_0() {
    let dir = tempfile::tempdir().unwrap();
    let (path, grid) = store(dir.path(), 64);
    let mut h = harness(Some(path));
    step_until(&mut h, "a first picture", |a| a.shown_level().is_some());
    let a = app(&h);
    assert!(a.is_bricked());
    let first = a.level_log()[0].1;
    assert_eq!((first.level, first.levels), (2, 3), "{first:?}");
    assert_eq!(first.dims, [16, 16, 16]);
    let status = a.lod_status().unwrap();
    assert!(status.contains("cache"), "{status}");
    step_until(&mut h, "the refined frame", |a| a.shown_full());
    let a = app(&h);
    let shown = a.shown_level().unwrap();
    assert_eq!((shown.level, shown.target), (0, 0), "{shown:?}");
    let status = a.lod_status().unwrap();
    assert!(
        status.contains("level 0") && status.contains("full resolution"),
        "{status}"
    );
    let levels = levels_of(a, newest_generation(a));
    assert_eq!(levels.first(), Some(&2), "{levels:?}");
    assert_eq!(levels.last(), Some(&0), "{levels:?}");
    assert!(levels.windows(2).all(|w| w[0] > w[1]), "{levels:?}");
    // The refined picture is the engine's level-0 render of the same scene, and the
    // in-core render of the same data.
    let scene = a.shown_scene().unwrap().clone();
    let image = a.shown_image().unwrap().clone();
    let Some(Volume::Bricked(b, _)) = a.volume() else {
        panic!("not bricked")
    };
    let level0 = Volume::Bricked(b.clone(), Lod::Level(0));
    let engine = render_once(&level0, &scene, &Control::default()).unwrap();
    assert_images_close(
        "viewer-store-level0",
        &image,
        &engine.image,
        Tolerance::max(1e-6),
    );
    let in_core = render_once(&Volume::from(grid), &scene, &Control::default()).unwrap();
    assert_images_close(
        "viewer-store-in-core",
        &image,
        &in_core.image,
        Tolerance::max(1e-5),
    );
}

#[test]
fn a_view_change_during_refinement_restarts_from_the_coarsest_level() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = store(dir.path(), 128);
    let mut h = harness(Some(path));
    step_until(&mut h, "a first picture", |a| a.shown_level().is_some());
    let before = newest_generation(app(&h));
    let caught_refining = !app(&h).shown_full();
    // Turn the camera (as a finished drag does): a new request.
    let a = app_mut(&mut h);
    a.scene.view.camera = volux_viewer::navigation::orbit(&a.scene.view.camera, 40.0, 10.0);
    step_until(&mut h, "a frame of the new view", |a| {
        newest_generation(a) > before
    });
    let after = newest_generation(app(&h));
    assert_eq!(levels_of(app(&h), after).first(), Some(&3));
    step_until(&mut h, "the refined frame of the new view", |a| {
        a.shown_full()
    });
    let a = app(&h);
    let levels = levels_of(a, after);
    assert_eq!(levels.first(), Some(&3), "{levels:?}");
    assert_eq!(levels.last(), Some(&0), "{levels:?}");
    if caught_refining {
        // The first view's refinement was superseded before it reached level 0.
        let old = levels_of(a, before);
        eprintln!("first view's levels before the change: {old:?}");
        assert!(!old.is_empty());
    }
}

#[test]
fn full_resolution_refines_to_level_0_when_auto_stops_coarser() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = store(dir.path(), 64);
    let mut h = harness(Some(path));
    step_until(&mut h, "the refined frame", |a| a.shown_full());
    // Far away, a pixel covers several voxels: the automatic level is coarser than 0.
    let a = app_mut(&mut h);
    a.scene.view.camera = volux_viewer::navigation::zoom(&a.scene.view.camera, 0.05);
    step_until(&mut h, "the refined far view", |a| {
        a.shown_full() && a.shown_scene() == Some(&a.render_scene())
    });
    let far = app(&h).shown_level().unwrap();
    assert!(far.level > 0 && far.is_final(), "{far:?}");
    assert!(
        app(&h)
            .lod_status()
            .unwrap()
            .contains("as fine as the view needs"),
        "{:?}",
        app(&h).lod_status()
    );
    app_mut(&mut h).set_full_resolution(true);
    step_until(&mut h, "level 0", |a| {
        a.shown_full() && a.shown_level().is_some_and(|l| l.level == 0)
    });
}

#[test]
fn a_damaged_store_shows_its_error_and_the_viewer_lives_on() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = store(dir.path(), 32);
    // A corrupt chunk of the full level.
    let chunk = path.join("0/c/0/0/1");
    assert!(chunk.is_file(), "{chunk:?}");
    std::fs::write(&chunk, [0xA5u8; 40]).unwrap();
    let mut h = harness(Some(path.clone()));
    step_until(&mut h, "the error", |a| a.error.is_some() && !a.busy());
    let message = app(&h).error.clone().unwrap();
    assert!(message.contains("ml32.ome.zarr"), "{message}");
    assert!(app(&h).data.is_none());
    // Missing metadata.
    let (other, _) = store(&dir.path().join("b"), 32);
    std::fs::remove_file(other.join("zarr.json")).unwrap();
    app_mut(&mut h).open(&other);
    step_until(&mut h, "the second error", |a| {
        a.error.is_some() && !a.busy()
    });
    assert!(app(&h).data.is_none());
    // A good store still opens and renders.
    let (good, _) = store(&dir.path().join("c"), 32);
    app_mut(&mut h).open(&good);
    step_until(&mut h, "the good store's refined frame", |a| a.shown_full());
    assert!(app(&h).error.is_none());
}
