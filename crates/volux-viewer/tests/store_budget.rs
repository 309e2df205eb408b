//! A store under a brick-cache budget far smaller than the view's image (`volux-view
//! --memory-budget 32M` on a window whose frame needs 42 MiB used to refuse every frame and
//! stay "rendering..."): the budget bounds the cache only, so the coarse level appears first
//! and the view refines to full resolution, reading chunks again as it must. Its own test
//! binary: the cache budget is process-wide.
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use volux_core::bricked::GridChunks;
use volux_core::synth;
use volux_io::omezarr::{write_ome_zarr, Levels, WriteOptions};
use volux_viewer::app::{Options, ViewerApp};

type App = Option<ViewerApp>;

#[test]
fn a_store_under_a_tiny_cache_budget_shows_its_coarse_level_then_refines() {
    let dir = tempfile::tempdir().unwrap();
    let grid = synth::marschner_lobb(64).unwrap();
    let path = dir.path().join("ml.ome.zarr");
    let src = GridChunks::new(Arc::new(grid), [16, 16, 16]).unwrap();
    let opts = WriteOptions {
        levels: Levels::Auto,
        name: "ml".into(),
        ..WriteOptions::default()
    };
    write_ome_zarr(&src, &path, &opts).unwrap();
    // Room for four 16^3 bricks of f32: far less than the 900 x 700 view's image.
    volux_viewer::store::set_cache_budget(4 * 16 * 16 * 16 * 4 + 4096);
    let options = Options {
        open: Some(path),
        ..Default::default()
    };
    let mut h: Harness<'static, App> = Harness::builder()
        .with_size([900.0, 700.0])
        .with_max_steps(8)
        .build_state(
            move |ctx, app: &mut App| {
                app.get_or_insert_with(|| ViewerApp::new(ctx, options.clone()));
                volux_viewer::window::frame(app.as_mut().unwrap(), ctx)
            },
            None,
        );
    let start = Instant::now();
    let mut first = None;
    loop {
        h.step();
        let a = h.state().as_ref().expect("the app starts");
        assert!(a.error.is_none(), "the view shows an error: {:?}", a.error);
        if first.is_none() {
            first = a.shown_level().map(|l| l.level);
        }
        if a.shown_full() {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(180),
            "timed out: shown {:?}",
            a.shown_level()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(first, Some(2), "the coarsest level came first");
    let a = h.state().as_ref().unwrap();
    assert_eq!(a.shown_level().unwrap().level, 0);
    let status = a.lod_status().unwrap();
    assert!(status.contains("cache"), "{status}");
}
