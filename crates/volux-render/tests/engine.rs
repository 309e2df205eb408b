//! The engine API as a front end uses it: caches keyed on what changed (a camera change
//! re-projects, a TF change re-classifies, nothing else is rebuilt), previews, cancellation,
//! progress, and errors for scenes a renderer cannot draw, for every method.
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use volux_core::{synth, CameraSpec};
use volux_render::engine::{create_renderer, Rebuilt, Renderer};
use volux_render::integrate::SegmentRule;
use volux_render::scene::{GridRaycast, Method, PtSettings, Scene, Volume};
use volux_render::tiles::Control;
use volux_render::RenderError;

fn volumes() -> (Volume, Volume) {
    let grid = Volume::from(synth::marschner_lobb(24).unwrap());
    let mesh = Volume::from(synth::smooth_tets(3000).unwrap());
    (grid, mesh)
}

fn scene(volume: &Volume, method: Method, azimuth: f64) -> Scene {
    let spec = CameraSpec {
        azimuth: Some(azimuth),
        elevation: Some(20.0),
        ..Default::default()
    };
    let camera = spec.resolve(&volume.bounds()).unwrap();
    let mut s = Scene::new(camera, 48, 40, volume.preset_tf("auto").unwrap());
    s.method = method;
    s
}

/// Every method with the volume it draws.
fn cases() -> Vec<(Volume, Method)> {
    let (grid, mesh) = volumes();
    vec![
        (grid.clone(), Method::Auto),
        (grid, Method::GridRaycast(GridRaycast::default())),
        (mesh.clone(), Method::Auto),
        (
            mesh.clone(),
            Method::ProjectedTetrahedra(PtSettings::default()),
        ),
        (mesh.clone(), Method::TetRaycast(SegmentRule::Psi)),
        (mesh.clone(), Method::MeshReference),
        (
            mesh,
            Method::Resample {
                samples: 24,
                raycast: GridRaycast::default(),
            },
        ),
    ]
}

fn rebuilt(r: &mut dyn Renderer, s: &Scene) -> Rebuilt {
    r.render(s, &Control::default()).unwrap().stats.rebuilt
}

const NOTHING: Rebuilt = Rebuilt {
    data: false,
    classification: false,
    view: false,
};

#[test]
fn renderers_rebuild_only_what_changed() {
    let (grid, mesh) = volumes();
    // Grid ray casting: the view is recomputed every frame (rays), data and classification
    // are kept.
    let mut r = create_renderer(&grid, &Method::Auto).unwrap();
    let s = scene(&grid, Method::Auto, 30.0);
    assert_eq!(rebuilt(r.as_mut(), &s), Rebuilt::ALL);
    let same = rebuilt(r.as_mut(), &s);
    assert!(!same.data && !same.classification, "{same:?}");
    let turned = rebuilt(r.as_mut(), &scene(&grid, Method::Auto, 60.0));
    assert!(!turned.data && !turned.classification, "{turned:?}");
    let mut recoloured = s.clone();
    recoloured.appearance.opacity_scale = 2.0;
    let r2 = rebuilt(r.as_mut(), &recoloured);
    assert!(!r2.data && r2.classification, "{r2:?}");
    let mut shaded = s.clone();
    shaded.appearance.shade_volume = true;
    assert!(
        rebuilt(r.as_mut(), &shaded).data,
        "the gradient volume is built once"
    );
    assert!(!rebuilt(r.as_mut(), &shaded).data);

    // Projected Tetrahedra and tet ray casting keep view-dependent data too.
    for method in [
        Method::ProjectedTetrahedra(PtSettings::default()),
        Method::TetRaycast(SegmentRule::Psi),
    ] {
        let mut r = create_renderer(&mesh, &method).unwrap();
        let s = scene(&mesh, method, 30.0);
        let first = rebuilt(r.as_mut(), &s);
        assert!(
            first.data && first.classification && first.view,
            "{first:?}"
        );
        assert_eq!(rebuilt(r.as_mut(), &s), NOTHING, "{}", method.name());
        let turned = rebuilt(r.as_mut(), &scene(&mesh, method, 60.0));
        assert_eq!(
            turned,
            Rebuilt {
                view: true,
                ..NOTHING
            },
            "{}",
            method.name()
        );
        let mut other_tf = scene(&mesh, method, 60.0);
        other_tf.appearance.tf = mesh.preset_tf("viridis").unwrap();
        assert_eq!(
            rebuilt(r.as_mut(), &other_tf),
            Rebuilt {
                classification: true,
                // PT's order and bins hold the kept cells, which the TF chose.
                view: matches!(method, Method::ProjectedTetrahedra(_)),
                ..NOTHING
            },
            "{}",
            method.name()
        );
    }
}

#[test]
fn previews_are_smaller_and_alternate_with_full_frames_without_rebuilding() {
    for (volume, method) in cases() {
        let mut r = create_renderer(&volume, &method).unwrap();
        let s = scene(&volume, method, 30.0);
        let preview = r.render_preview(&s, &Control::default(), 4).unwrap();
        assert_eq!(
            (preview.image.width(), preview.image.height()),
            (12, 10),
            "{}",
            method.name()
        );
        let full = r.render(&s, &Control::default()).unwrap();
        assert_eq!(full.stats.pixels, 48 * 40);
        if let Method::ProjectedTetrahedra(_) = method {
            // The preview's view is kept beside the full frame's: switching costs nothing.
            let again = r.render_preview(&s, &Control::default(), 4).unwrap();
            assert_eq!(again.stats.rebuilt, NOTHING);
            assert_eq!(again.image, preview.image);
        }
    }
}

#[test]
fn every_renderer_can_be_cancelled_and_reports_progress() {
    for (volume, method) in cases() {
        let mut r = create_renderer(&volume, &method).unwrap();
        let s = scene(&volume, method, 30.0);
        let cancel = Arc::new(AtomicBool::new(true));
        let e = r.render(&s, &Control::with_cancel(cancel)).unwrap_err();
        assert!(
            matches!(e, RenderError::Cancelled),
            "{}: {e}",
            method.name()
        );
        let rows = Arc::new(AtomicUsize::new(0));
        let seen = rows.clone();
        let control = Control {
            cancel: None,
            progress: Some(Arc::new(move |done, total| {
                assert_eq!(total, 40);
                seen.fetch_max(done, Ordering::Relaxed);
            })),
        };
        r.render(&s, &control).unwrap();
        assert_eq!(rows.load(Ordering::Relaxed), 40, "{}", method.name());
    }
}

#[test]
fn scenes_a_renderer_cannot_draw_are_errors() {
    let (grid, mesh) = volumes();
    // Methods that do not apply to the volume.
    for (volume, method) in [
        (&grid, Method::ProjectedTetrahedra(PtSettings::default())),
        (&grid, Method::TetRaycast(SegmentRule::Exact)),
        (&grid, Method::MeshReference),
        (&mesh, Method::GridRaycast(GridRaycast::default())),
    ] {
        assert!(
            create_renderer(volume, &method).is_err(),
            "{}",
            method.name()
        );
    }
    // A renderer handed another method's scene, a bad image size, a bad early termination.
    let mut r = create_renderer(&mesh, &Method::Auto).unwrap();
    let tet = scene(&mesh, Method::TetRaycast(SegmentRule::Exact), 30.0);
    assert!(r.render(&tet, &Control::default()).is_err());
    let mut bad = scene(&mesh, Method::Auto, 30.0);
    bad.view.width = 0;
    assert!(r.render(&bad, &Control::default()).is_err());
    let mut bad = scene(&mesh, Method::Auto, 30.0);
    bad.early_termination = Some(f32::NAN);
    assert!(r.render(&bad, &Control::default()).is_err());
    // PT composites fragments: adaptive Simpson is the ray caster's.
    let pt = Method::ProjectedTetrahedra(PtSettings {
        color: SegmentRule::AdaptiveSimpson(volux_render::integrate::Integrator::REFERENCE),
        ..PtSettings::default()
    });
    let mut r = create_renderer(&mesh, &pt).unwrap();
    assert!(r
        .render(&scene(&mesh, pt, 30.0), &Control::default())
        .is_err());
}
