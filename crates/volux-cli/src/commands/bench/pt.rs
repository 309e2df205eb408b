//! `volux bench --suite pt`: tets/s and ms/frame of Projected Tetrahedra at 512x512 for the
//! basic (average), ψ and ψ + isosurfaces modes (seed `002` table 2), on generated meshes of
//! about 200K and 1.25M tetrahedra and on the shared Blunt Fin and LOx Post; and PT's
//! accuracy against the brute-force reference.
//!
//! Every timed frame uses a new view (the camera turns one degree per frame), so the whole
//! pipeline runs: per-tetrahedron pass, sort, binning, rasterization. A recolour-only frame
//! (same view, new TF) is timed too. Early termination stays at 0.999, the figure of the
//! earlier measurements.
use serde_json::json;
use volux_core::{CameraSpec, TransferFunction};
use volux_render::engine::{create_renderer, MethodStats};
use volux_render::integrate::SegmentRule;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::pt::{PtStats, SortMode};
use volux_render::scene::{Method, PtSettings, Scene, Volume};

use super::common::{frame, median, meshes, shared, EARLY_TERMINATION};
use crate::commands::common::CmdError;

/// Non-zero extinction over the whole range (normalized), up to 3 optical depths across the
/// mesh's diagonal.
const DENSE_TF: &str = r#"{"space": "normalized",
  "color": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.5, 0.1], [1, 1, 1, 1]],
  "extinction": [[0, 0.05], [0.5, 0.3], [1, 1.5]]}"#;

/// Two isosurfaces at a third and two thirds of the range.
fn isos(range: [f64; 2]) -> Result<Isosurfaces, CmdError> {
    let at = |f: f64| (range[0] + f * (range[1] - range[0])) as f32;
    Ok(Isosurfaces::new(vec![
        Isovalue {
            value: at(1.0 / 3.0),
            rgba: [0.9, 0.8, 0.3, 0.6],
        },
        Isovalue {
            value: at(2.0 / 3.0),
            rgba: [0.3, 0.6, 0.9, 0.8],
        },
    ])?)
}

/// The camera of frame `f`: azimuth 30 + f degrees, elevation 20.
fn orbit(f: usize) -> CameraSpec {
    CameraSpec {
        azimuth: Some(30.0 + f as f64),
        elevation: Some(20.0),
        ..Default::default()
    }
}

fn pt_stats(m: &MethodStats) -> PtStats {
    match m {
        MethodStats::ProjectedTetrahedra(s) => s.clone(),
        _ => PtStats::default(),
    }
}

/// Runs the PT benchmark; returns the JSON rows.
pub fn run(quick: bool, frames: usize, as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let frames = if quick { 1 } else { frames.max(1) };
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    if !as_json {
        outln!("PT, 512x512, centroid order; threads: {threads}; frames per case: {frames} (median), new view each frame")?;
        outln!(
            "{:<14} {:>9} {:<14} {:>9} {:>9} {:>11} {:>12} {:>10} {:>9}",
            "mesh",
            "tets",
            "mode",
            "ms/frame",
            "M tets/s",
            "recolour ms",
            "fragments",
            "bytes/tet",
            "drawn"
        )?;
    }
    for (name, volume) in meshes(quick)? {
        let tf = volume.preset_tf("auto")?;
        let mut renderer =
            create_renderer(&volume, &Method::ProjectedTetrahedra(PtSettings::default()))?;
        // The automatic TF (most tetrahedra discarded on these meshes) and a dense one whose
        // extinction is non-zero over the whole range (every tetrahedron drawn).
        let dense = TransferFunction::from_json(DENSE_TF)?
            .with_unit_length(volume.bounds().diagonal() / 2.0);
        let modes = [
            ("average", SegmentRule::Average, false, &tf),
            ("psi", SegmentRule::Psi, false, &tf),
            ("psi+iso", SegmentRule::Psi, true, &tf),
            ("average-dense", SegmentRule::Average, false, &dense),
            ("psi-dense", SegmentRule::Psi, false, &dense),
        ];
        for (label, color, with_iso, tf) in modes {
            let mut times = Vec::new();
            let mut last = None;
            for f in 0..frames + 1 {
                let camera = orbit(f).resolve(&volume.bounds())?;
                let mut scene = Scene::new(camera, 512, 512, tf.clone());
                scene.method = Method::ProjectedTetrahedra(PtSettings {
                    sort: SortMode::Centroid,
                    color,
                    count_violations: false,
                });
                scene.early_termination = Some(EARLY_TERMINATION);
                if with_iso {
                    scene.appearance.isosurfaces = isos(volume.range())?;
                }
                let r = frame(renderer.as_mut(), &scene)?;
                if f > 0 {
                    // The first frame builds the per-mesh caches (ψ table, gradients).
                    times.push(r.stats.ms / 1e3);
                }
                last = Some((pt_stats(&r.stats.method), scene));
            }
            let (stats, mut scene) = last.expect("at least one frame");
            scene.appearance.opacity_scale = 1.5;
            let recolour = frame(renderer.as_mut(), &scene)?.stats.ms / 1e3;
            let s = median(&mut times);
            let rate = stats.tets as f64 / s / 1e6;
            if !as_json {
                outln!(
                    "{:<14} {:>9} {:<14} {:>9.1} {:>9.2} {:>11.1} {:>12} {:>10.1} {:>9}",
                    name,
                    stats.tets,
                    label,
                    s * 1e3,
                    rate,
                    recolour * 1e3,
                    stats.fragments,
                    stats.bytes_per_tet,
                    stats.tets_drawn
                )?;
            }
            rows.push(json!({
                "suite": "pt", "dataset": name, "width": 512, "height": 512, "mode": label,
                "tets": stats.tets, "tets_drawn": stats.tets_drawn, "ms": s * 1e3,
                "tets_per_s": rate * 1e6, "recolour_ms": recolour * 1e3,
                "fragments": stats.fragments, "bytes_per_tet": stats.bytes_per_tet,
            }));
        }
    }
    if !quick {
        rows.extend(accuracy(as_json)?);
    }
    Ok(rows)
}

/// PT against the brute-force per-pixel reference at 128x128 (exact colour, exact order):
/// how wrong the seeds' fast modes (centroid order, average or ψ colour) are, in numbers.
fn accuracy(as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let (w, h) = (128, 128);
    let mut rows = Vec::new();
    if !as_json {
        outln!("\nPT accuracy against the brute-force reference, {w}x{h}, automatic TF, no early termination")?;
        outln!(
            "{:<14} {:<10} {:<8} {:>14} {:>12} {:>12}",
            "mesh",
            "sort",
            "colour",
            "mean |err|",
            "max |err|",
            "violations"
        )?;
    }
    let mut all = meshes(true)?;
    if let Some(v @ Volume::Mesh(_)) = shared("vtk_post_tets/post.vtk")? {
        all.push(("post-vtk".to_string(), v));
    }
    for (name, volume) in all {
        let camera = orbit(0).resolve(&volume.bounds())?;
        let mut scene = Scene::new(camera, w, h, volume.preset_tf("auto")?);
        scene.early_termination = None;
        scene.method = Method::MeshReference;
        let reference = create_renderer(&volume, &scene.method)?;
        let reference = frame_of(reference, &scene)?.image;
        let mut renderer =
            create_renderer(&volume, &Method::ProjectedTetrahedra(PtSettings::default()))?;
        for sort in [SortMode::Centroid, SortMode::Exact] {
            for color in [SegmentRule::Average, SegmentRule::Psi, SegmentRule::Exact] {
                scene.method = Method::ProjectedTetrahedra(PtSettings {
                    sort,
                    color,
                    count_violations: sort == SortMode::Centroid,
                });
                let r = frame(renderer.as_mut(), &scene)?;
                let d = r.image.compare(&reference, 0.0)?;
                let stats = pt_stats(&r.stats.method);
                let sort_name = if sort == SortMode::Centroid {
                    "centroid"
                } else {
                    "exact"
                };
                let violations = stats.sort_violations.map_or("-".into(), |v| v.to_string());
                if !as_json {
                    outln!(
                        "{:<14} {:<10} {:<8} {:>14.2e} {:>12.2e} {:>12}",
                        name,
                        sort_name,
                        color.name(),
                        d.mean_error,
                        d.max_error,
                        violations
                    )?;
                }
                rows.push(json!({
                    "suite": "pt-accuracy", "dataset": name, "width": w, "height": h,
                    "sort": sort_name, "color": color.name(), "mean_abs_error": d.mean_error,
                    "max_abs_error": d.max_error, "sort_violations": stats.sort_violations,
                }));
            }
        }
    }
    Ok(rows)
}

/// One frame of a renderer used once.
fn frame_of(
    mut renderer: Box<dyn volux_render::engine::Renderer>,
    scene: &Scene,
) -> Result<volux_render::engine::Frame, CmdError> {
    frame(renderer.as_mut(), scene)
}
