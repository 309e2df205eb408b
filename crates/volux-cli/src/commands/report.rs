//! What `volux render` says after a frame: `--stats` (a line, or one JSON object with
//! `--json`) in the method's own terms, and the file it wrote.
use serde_json::json;
use volux_render::engine::{Frame, MethodStats};
use volux_render::pt::PtStats;
use volux_render::raycast::RenderStats;
use volux_render::scene::Scene;
use volux_render::tetray::TetRayStats;

use crate::cli::{value_name, RenderArgs};
use crate::settings::tet_ray_rule;

/// Reports `frame` as `args` asks.
pub fn frame(args: &RenderArgs, frame: &Frame, scene: &Scene) {
    let size = (scene.view.width, scene.view.height);
    let printed_json = match &frame.stats.method {
        MethodStats::GridRaycast(s) => grid(args, s, size),
        MethodStats::ProjectedTetrahedra(s) => pt(args, s, size),
        MethodStats::TetRaycast(s) => tet_ray(args, s, frame, size),
        _ => false,
    };
    if !printed_json {
        eprintln!("wrote {}", args.output.display());
    }
}

/// Grid ray casting; returns whether JSON was printed.
fn grid(args: &RenderArgs, s: &RenderStats, (w, h): (usize, usize)) -> bool {
    let rate = s.samples as f64 / s.seconds.max(1e-9);
    if args.stats && args.json {
        let v = json!({
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "rays": s.rays,
            "samples": s.samples,
            "samples_per_s": rate,
            "rays_over_tolerance": s.rays_over_tolerance,
            "integrator": args.integrator.name(),
            "threads": rayon::current_num_threads(),
        });
        println!("{v}");
        return true;
    }
    if args.stats {
        eprintln!(
            "{w}x{h}: {:.1} ms, {} rays, {} samples, {:.1} M samples/s",
            s.seconds * 1e3,
            s.rays,
            s.samples,
            rate / 1e6
        );
    }
    false
}

/// Projected Tetrahedra; returns whether JSON was printed.
fn pt(args: &RenderArgs, s: &PtStats, (w, h): (usize, usize)) -> bool {
    let tets_per_s = s.tets as f64 / s.seconds.max(1e-9);
    if args.stats && args.json {
        let v = json!({
            "method": "pt",
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "tets": s.tets,
            "tets_kept": s.tets_kept,
            "tets_drawn": s.tets_drawn,
            "degenerate": s.degenerate,
            "clipped": s.clipped,
            "tets_per_s": tets_per_s,
            "fragments": s.fragments,
            "sort": value_name(&args.sort),
            "color": value_name(&args.color),
            "exact_strategy": s.exact_strategy,
            "sort_violations": s.sort_violations,
            "cycles_broken": s.cycles_broken,
            "centroid_sort_ms": s.centroid_sort_s * 1e3,
            "exact_sort_ms": s.exact_sort_s * 1e3,
            "project_ms": s.project_s * 1e3,
            "sort_ms": s.sort_s * 1e3,
            "bin_ms": s.bin_s * 1e3,
            "raster_ms": s.raster_s * 1e3,
            "bytes_per_tet": s.bytes_per_tet,
            "threads": rayon::current_num_threads(),
        });
        println!("{v}");
        return true;
    }
    if args.stats {
        eprintln!(
            "{w}x{h} PT: {:.1} ms ({:.2} M tets/s), {} tets, {} kept, {} drawn, {} degenerate, \
             {} fragments, {:.1} bytes/tet per frame",
            s.seconds * 1e3,
            tets_per_s / 1e6,
            s.tets,
            s.tets_kept,
            s.tets_drawn,
            s.degenerate,
            s.fragments,
            s.bytes_per_tet
        );
        eprintln!(
            "  stages: project {:.1} ms, sort {:.1} ms, bin {:.1} ms, raster {:.1} ms; \
             centroid sort {:.1} ms, exact sort {:.1} ms, centroid-order violations {}",
            s.project_s * 1e3,
            s.sort_s * 1e3,
            s.bin_s * 1e3,
            s.raster_s * 1e3,
            s.centroid_sort_s * 1e3,
            s.exact_sort_s * 1e3,
            s.sort_violations
                .map_or_else(|| "-".to_string(), |v| v.to_string())
        );
    }
    false
}

/// Tetrahedral ray casting; returns whether JSON was printed.
fn tet_ray(args: &RenderArgs, s: &TetRayStats, frame: &Frame, (w, h): (usize, usize)) -> bool {
    let colour = tet_ray_rule(args).name();
    let mode = if args.mip { "mip" } else { colour };
    let errors = frame.error_map.as_deref().unwrap_or(&[]);
    let max_error = errors.iter().copied().fold(0.0f32, f32::max);
    let mean_error = errors.iter().map(|&e| e as f64).sum::<f64>() / (w * h).max(1) as f64;
    let reentries_per_ray = s.reentries as f64 / (s.rays.max(1)) as f64;
    if args.stats && args.json {
        let v = json!({
            "method": "raycast",
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "tets": s.tets,
            "tets_per_s": s.tets as f64 / s.seconds.max(1e-9),
            "rays": s.rays,
            "segments": s.segments,
            "samples": s.samples,
            "rays_over_tolerance": s.rays_over_tolerance,
            "max_error": max_error,
            "mean_error": mean_error,
            "reentries": s.reentries,
            "reentries_per_ray": reentries_per_ray,
            "recovered": s.recovered,
            "abandoned": s.abandoned,
            "bytes_per_tet": s.bytes_per_tet,
            "color": colour,
            "integrator": mode,
            "isosurfaces": args.isos.len(),
            "mip": args.mip,
            "threads": rayon::current_num_threads(),
        });
        println!("{v}");
        return true;
    }
    if args.stats {
        eprintln!(
            "{w}x{h} tet ray casting ({mode}): {:.1} ms, {} rays, {} segments, {} samples, \
             {reentries_per_ray:.3} re-entries per ray, {} abandoned, {} rays over tolerance \
             (max estimated error {max_error:.2e}), {:.0} bytes/tet of acceleration structures",
            s.seconds * 1e3,
            s.rays,
            s.segments,
            s.samples,
            s.abandoned,
            s.rays_over_tolerance,
            s.bytes_per_tet
        );
    }
    false
}
