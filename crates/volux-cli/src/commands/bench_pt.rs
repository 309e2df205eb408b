//! `volux bench --suite pt`: tets/s and ms/frame of Projected Tetrahedra at 512x512 for the
//! basic (average), ψ and ψ + isosurfaces modes (seed `002` table 2), on generated meshes of
//! about 200K and 1.25M tetrahedra and on the shared Blunt Fin and LOx Post.
//!
//! Every timed frame uses a new view (the camera turns one degree per frame), so the whole
//! pipeline runs: per-tetrahedron pass, sort, binning, rasterization. A recolour-only frame
//! (same view, new TF) is timed too.
use std::path::Path;

use serde_json::json;
use volux_core::histogram::Histogram;
use volux_core::Image;
use volux_core::{synth, CameraSpec, TetMesh, TransferFunction};
use volux_io::{Dataset, LoadOptions};
use volux_render::integrate::SegmentRule;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::pt::reference::{render_mesh_reference, ReferenceOptions};
use volux_render::pt::{PtOptions, PtRenderer, SortMode};
use volux_render::tetray::{TetRayCaster, TetRayOptions};

use super::CmdError;

/// Non-zero extinction over the whole range (normalized), up to 3 optical depths across the
/// mesh's diagonal.
const DENSE_TF: &str = r#"{"space": "normalized",
  "color": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.5, 0.1], [1, 1, 1, 1]],
  "extinction": [[0, 0.05], [0.5, 0.3], [1, 1.5]]}"#;

const SHARED: [(&str, &str); 2] = [
    ("blunt-fin", "nasa_blunt_fin/blunt_fin_tets_density.off.gz"),
    ("lox-post", "nasa_lox_post/lox_post_tets_velmag.off.gz"),
];

fn meshes(quick: bool) -> Result<Vec<(String, TetMesh)>, CmdError> {
    let mut out = vec![("smooth-200k".to_string(), synth::smooth_tets(200_000)?)];
    if !quick {
        out.push(("smooth-1.25m".to_string(), synth::smooth_tets(1_250_000)?));
    }
    let root = Path::new("../shared/data");
    for (name, rel) in SHARED {
        let p = root.join(rel);
        if !p.exists() {
            eprintln!("bench: {} absent, skipped", p.display());
            continue;
        }
        if let (Dataset::Mesh(m), _) = volux_io::load(&p, &LoadOptions::default())? {
            out.push((name.to_string(), m));
        }
    }
    Ok(out)
}

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

/// Runs the PT benchmark; returns the JSON rows.
pub fn run(quick: bool, frames: usize, as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let frames = if quick { 1 } else { frames.max(1) };
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    if !as_json {
        println!("PT, 512x512, centroid order; threads: {threads}; frames per case: {frames} (median), new view each frame");
        println!(
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
        );
    }
    for (name, mesh) in meshes(quick)? {
        let hist = Histogram::from_values(mesh.scalars(), mesh.range(), 256);
        let tf = TransferFunction::preset("auto", &hist)?
            .with_unit_length(mesh.bounds().diagonal() / 256.0);
        let mut renderer = PtRenderer::new(&mesh);
        // The automatic TF (most tetrahedra discarded on these meshes) and a dense one whose
        // extinction is non-zero over the whole range (every tetrahedron drawn).
        let dense =
            TransferFunction::from_json(DENSE_TF)?.with_unit_length(mesh.bounds().diagonal() / 2.0);
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
                let spec = CameraSpec {
                    azimuth: Some(30.0 + f as f64),
                    elevation: Some(20.0),
                    ..Default::default()
                };
                let mut opts = PtOptions::new(spec.resolve(&mesh.bounds())?, tf.clone());
                opts.color = color;
                opts.sort = SortMode::Centroid;
                if with_iso {
                    opts.isosurfaces = isos(mesh.range())?;
                }
                let r = renderer.render(&opts)?;
                if f > 0 {
                    // The first frame builds the per-mesh caches (ψ table, gradients).
                    times.push(r.stats.seconds);
                }
                last = Some((r.stats, opts));
            }
            let (stats, mut opts) = last.expect("at least one frame");
            opts.tf = opts.tf.with_opacity_scale(1.5);
            let recolour = renderer.render(&opts)?.stats.seconds;
            times.sort_by(f64::total_cmp);
            let s = times[times.len() / 2];
            let rate = stats.tets as f64 / s / 1e6;
            if !as_json {
                println!(
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
                );
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

/// Mean and largest absolute difference per channel.
fn image_error(a: &Image, b: &Image) -> (f64, f64) {
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels().iter().zip(b.pixels()) {
        for c in 0..4 {
            let d = f64::from((p[c] - q[c]).abs());
            sum += d;
            max = max.max(d);
        }
    }
    (sum / (4 * a.pixels().len()).max(1) as f64, max)
}

/// PT against the brute-force per-pixel reference at 128x128 (exact colour, exact order):
/// how wrong the seeds' fast modes (centroid order, average or ψ colour) are, in numbers.
fn accuracy(as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let (w, h) = (128, 128);
    let mut rows = Vec::new();
    if !as_json {
        println!("\nPT accuracy against the brute-force reference, {w}x{h}, automatic TF, no early termination");
        println!(
            "{:<14} {:<10} {:<8} {:>14} {:>12} {:>12}",
            "mesh", "sort", "colour", "mean |err|", "max |err|", "violations"
        );
    }
    let mut all = meshes(true)?;
    let post = Path::new("../shared/data/vtk_post_tets/post.vtk");
    if post.exists() {
        if let (Dataset::Mesh(m), _) = volux_io::load(post, &LoadOptions::default())? {
            all.push(("post-vtk".to_string(), m));
        }
    }
    for (name, mesh) in all {
        let hist = Histogram::from_values(mesh.scalars(), mesh.range(), 256);
        let tf = TransferFunction::preset("auto", &hist)?
            .with_unit_length(mesh.bounds().diagonal() / 256.0);
        let spec = CameraSpec {
            azimuth: Some(30.0),
            elevation: Some(20.0),
            ..Default::default()
        };
        let camera = spec.resolve(&mesh.bounds())?;
        let reference = render_mesh_reference(
            &mesh,
            &ReferenceOptions {
                width: w,
                height: h,
                camera,
                tf: tf.clone(),
            },
        )?;
        let mut renderer = PtRenderer::new(&mesh);
        for sort in [SortMode::Centroid, SortMode::Exact] {
            for color in [SegmentRule::Average, SegmentRule::Psi, SegmentRule::Exact] {
                let mut opts = PtOptions::new(camera, tf.clone());
                (opts.width, opts.height) = (w, h);
                (opts.sort, opts.color) = (sort, color);
                opts.early_termination = None;
                opts.count_violations = sort == SortMode::Centroid;
                let r = renderer.render(&opts)?;
                let (mean, max) = image_error(&r.image, &reference);
                let sort_name = if sort == SortMode::Centroid {
                    "centroid"
                } else {
                    "exact"
                };
                let violations = r
                    .stats
                    .sort_violations
                    .map_or("-".into(), |v| v.to_string());
                if !as_json {
                    println!(
                        "{:<14} {:<10} {:<8} {:>14.2e} {:>12.2e} {:>12}",
                        name,
                        sort_name,
                        color.name(),
                        mean,
                        max,
                        violations
                    );
                }
                rows.push(json!({
                    "suite": "pt-accuracy", "dataset": name, "width": w, "height": h,
                    "sort": sort_name, "color": color.name(), "mean_abs_error": mean,
                    "max_abs_error": max, "sort_violations": r.stats.sort_violations,
                }));
            }
        }
    }
    Ok(rows)
}

/// The tetrahedral ray caster on the same meshes: ms/frame at 512x512 for exact and ψ colour,
/// automatic TF, early termination at 0.999, and the bytes per tet of its acceleration
/// structures (boundary BVH, face planes, adjacency).
pub fn run_tetray(
    quick: bool,
    frames: usize,
    as_json: bool,
) -> Result<Vec<serde_json::Value>, CmdError> {
    let frames = if quick { 1 } else { frames.max(1) };
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    if !as_json {
        println!("\nTet ray casting, 512x512, automatic TF; threads: {threads}; frames per case: {frames} (median)");
        println!(
            "{:<14} {:>9} {:<8} {:>9} {:>9} {:>11} {:>10} {:>10} {:>9}",
            "mesh",
            "tets",
            "colour",
            "ms/frame",
            "M tets/s",
            "segments",
            "reentries",
            "abandoned",
            "bytes/tet"
        );
    }
    for (name, mesh) in meshes(quick)? {
        let hist = Histogram::from_values(mesh.scalars(), mesh.range(), 256);
        let tf = TransferFunction::preset("auto", &hist)?
            .with_unit_length(mesh.bounds().diagonal() / 256.0);
        let caster = TetRayCaster::new(&mesh);
        let spec = CameraSpec {
            azimuth: Some(30.0),
            elevation: Some(20.0),
            ..Default::default()
        };
        for (label, color) in [("exact", SegmentRule::Exact), ("psi", SegmentRule::Psi)] {
            let mut opts = TetRayOptions::new(spec.resolve(&mesh.bounds())?, tf.clone());
            opts.color = color;
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..frames {
                let r = caster.render(&opts)?;
                times.push(r.stats.seconds);
                last = Some(r.stats);
            }
            let stats = last.expect("one frame");
            times.sort_by(f64::total_cmp);
            let s = times[times.len() / 2];
            let tets = mesh.tets().len();
            if !as_json {
                println!(
                    "{:<14} {:>9} {:<8} {:>9.1} {:>9.2} {:>11} {:>10} {:>10} {:>9.1}",
                    name,
                    tets,
                    label,
                    s * 1e3,
                    tets as f64 / s / 1e6,
                    stats.segments,
                    stats.reentries,
                    stats.abandoned,
                    caster.bytes_per_tet()
                );
            }
            rows.push(json!({
                "suite": "tetray", "dataset": name, "width": 512, "height": 512, "color": label,
                "tets": tets, "ms": s * 1e3, "tets_per_s": tets as f64 / s,
                "segments": stats.segments, "reentries": stats.reentries,
                "abandoned": stats.abandoned, "bytes_per_tet": caster.bytes_per_tet(),
            }));
        }
    }
    Ok(rows)
}
