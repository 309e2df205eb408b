//! What `volux render` says after a frame: `--stats` (a line, or one JSON object with
//! `--json`) in the method's own terms, and the file it wrote.
use serde_json::json;
use volux_render::engine::{Frame, MethodStats};
use volux_render::pt::PtStats;
use volux_render::raycast::RenderStats;
use volux_render::scene::{Scene, Volume};
use volux_render::tetray::TetRayStats;

use crate::cli::{value_name, RenderArgs};
use crate::settings::tet_ray_rule;

/// Reports `frame` as `args` asks.
pub fn frame(
    args: &RenderArgs,
    frame: &Frame,
    scene: &Scene,
    volume: &Volume,
) -> std::io::Result<()> {
    let zero_volume = match volume {
        Volume::Mesh(m) => m.report().degenerate,
        _ => 0,
    };
    let size = (scene.view.width, scene.view.height);
    match &frame.stats.method {
        MethodStats::GridRaycast(s) => grid(args, s, size, volume),
        MethodStats::ProjectedTetrahedra(s) => pt(args, s, zero_volume, size),
        MethodStats::TetRaycast(s) => tet_ray(args, s, frame, size),
        _ => Ok(()),
    }
}

/// Grid ray casting.
fn grid(
    args: &RenderArgs,
    s: &RenderStats,
    (w, h): (usize, usize),
    volume: &Volume,
) -> std::io::Result<()> {
    let rate = s.samples as f64 / s.seconds.max(1e-9);
    let cache = match volume {
        Volume::Bricked(b, _) => Some(b.cache_totals()),
        _ => None,
    };
    if args.stats && args.json {
        let mut v = json!({
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "rays": s.rays,
            "samples": s.samples,
            "samples_per_s": rate,
            "rays_over_tolerance": s.rays_over_tolerance,
            "integrator": args.integrator.name(),
        });
        if let Some(c) = cache {
            v["cache"] = json!({
                "hits": c.hits,
                "chunks_read": c.misses,
                "bytes_decoded": c.bytes_read,
                "evictions": c.evictions,
                "rereads": c.rereads,
                "hit_rate": c.hit_rate(),
                "peak_resident_bytes": c.peak_bytes,
            });
        }
        print_json(args, v)?;
        return Ok(());
    }
    if args.stats {
        eprintln!(
            "{}{w}x{h}: {:.1} ms, {} rays, {} samples, {:.1} M samples/s",
            frame_prefix(args),
            s.seconds * 1e3,
            s.rays,
            s.samples,
            rate / 1e6
        );
        if let Some(c) = cache {
            let bytes = volux_core::units::format_bytes;
            // Chunks read again after an eviction say what a hit rate over the rays'
            // lookups hides (it stays near 100 % while the cache thrashes).
            let again = match c.rereads {
                0 => String::new(),
                n => format!(
                    ", {n} of them again after an eviction (the memory budget holds less than \
                     the view needs)"
                ),
            };
            eprintln!(
                "brick cache: {} chunks read{again} ({} decoded), {} evictions, peak {} resident",
                c.misses,
                bytes(c.bytes_read),
                c.evictions,
                bytes(c.peak_bytes)
            );
        }
    }
    Ok(())
}

/// Projected Tetrahedra: the frame's stages add up to its time (`other`: set-up, caches);
/// the violation count is a diagnostic, timed apart.
fn pt(
    args: &RenderArgs,
    s: &PtStats,
    zero_volume: usize,
    (w, h): (usize, usize),
) -> std::io::Result<()> {
    let tets_per_s = s.tets as f64 / s.seconds.max(1e-9);
    let stages = [
        ("discard", s.discard_s),
        ("project", s.project_s),
        ("sort", s.sort_s),
        ("bin", s.bin_s),
        ("raster", s.raster_s),
    ];
    let other = (s.seconds - stages.iter().map(|(_, t)| t).sum::<f64>()).max(0.0);
    if args.stats && args.json {
        let mut v = json!({
            "method": "pt",
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "tets": s.tets,
            "tets_kept": s.tets_kept,
            "tets_drawn": s.tets_drawn,
            "zero_volume": zero_volume,
            "degenerate_projections": s.degenerate,
            "clipped": s.clipped,
            "culled": s.culled,
            "tets_per_s": tets_per_s,
            "fragments": s.fragments,
            "sort": value_name(&args.sort),
            "color": value_name(&args.color),
            "exact_strategy": s.exact_strategy,
            "sort_violations": s.sort_violations,
            "cycles_broken": s.cycles_broken,
            "other_ms": other * 1e3,
            "diagnostics_ms": s.diagnostics_s * 1e3,
            "bytes_per_tet": s.bytes_per_tet,
        });
        for (name, t) in stages {
            v[format!("{name}_ms")] = json!(t * 1e3);
        }
        print_json(args, v)?;
        return Ok(());
    }
    if !args.stats {
        return Ok(());
    }
    // Cells wholly outside a clip plane, named only when there are some.
    let culled = match s.culled {
        0 => String::new(),
        n => format!(" ({n} more culled by clip planes)"),
    };
    eprintln!(
        "{}{w}x{h} PT: {:.1} ms ({:.2} M tets/s), {} tets, {} kept, {} drawn{culled}, \
         {} zero-volume, {} degenerate projections, {} fragments, {:.1} bytes/tet per frame",
        frame_prefix(args),
        s.seconds * 1e3,
        tets_per_s / 1e6,
        s.tets,
        s.tets_kept,
        s.tets_drawn,
        zero_volume,
        s.degenerate,
        s.fragments,
        s.bytes_per_tet
    );
    let parts: Vec<String> = stages
        .iter()
        .chain([("other", other)].iter())
        .map(|(n, t)| format!("{n} {:.1}", t * 1e3))
        .collect();
    let built: Vec<&str> = [
        (s.rebuilt.data, "data structures (e.g. the ψ table)"),
        (s.rebuilt.classification, "the TF's kept cells"),
        (s.rebuilt.view, "the view's projection, order and bins"),
    ]
    .iter()
    .filter(|(b, _)| *b)
    .map(|(_, what)| *what)
    .collect();
    let built = if built.is_empty() {
        "nothing: all cached".to_string()
    } else {
        built.join(", ")
    };
    eprintln!(
        "  stages (ms, adding up to the total; other: set-up and caches): {}; this frame \
         built {built}",
        parts.join(", ")
    );
    if let Some(v) = s.sort_violations {
        eprintln!(
            "  diagnostics, not in the total: {v} face pairs out of the exact order in the \
             centroid order ({:.1} ms to count)",
            s.diagnostics_s * 1e3
        );
    }
    Ok(())
}

/// Tetrahedral ray casting.
fn tet_ray(
    args: &RenderArgs,
    s: &TetRayStats,
    frame: &Frame,
    (w, h): (usize, usize),
) -> std::io::Result<()> {
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
            "skips": s.skips,
            "visible_cells": s.visible_cells,
            "bytes_per_tet": s.bytes_per_tet,
            "color": colour,
            "integrator": mode,
            "isosurfaces": args.view_args.isos.len(),
            "mip": args.mip,
        });
        print_json(args, v)?;
        return Ok(());
    }
    if args.stats {
        eprintln!(
            "{}{w}x{h} tet ray casting ({mode}): {:.1} ms, {} rays, {} segments, {} samples, \
             {reentries_per_ray:.3} re-entries per ray, {} skips over invisible cells ({} \
             visible cells), {} abandoned, {} rays over tolerance \
             (max estimated error {max_error:.2e}), {:.0} bytes/tet of acceleration structures",
            frame_prefix(args),
            s.seconds * 1e3,
            s.rays,
            s.segments,
            s.samples,
            s.skips,
            s.visible_cells,
            s.abandoned,
            s.rays_over_tolerance,
            s.bytes_per_tet
        );
    }
    Ok(())
}

/// Prints the stats object of a frame with what every method shares: the threads and the
/// file written.
fn print_json(args: &RenderArgs, mut v: serde_json::Value) -> std::io::Result<()> {
    v["threads"] = json!(rayon::current_num_threads());
    v["output"] = if args.no_write {
        serde_json::Value::Null
    } else {
        json!(args.output().display().to_string())
    };
    if let Some(k) = args.frame_index {
        v["frame"] = json!(k);
        v["first"] = json!(k == 0);
    }
    outln!("{v}")?;
    Ok(())
}

/// The line prefix of a frame of an --orbit (`frame 3: `; the first says it builds the
/// caches).
fn frame_prefix(args: &RenderArgs) -> String {
    match args.frame_index {
        Some(0) => "frame 0 (first: builds the caches): ".into(),
        Some(k) => format!("frame {k}: "),
        None => String::new(),
    }
}
