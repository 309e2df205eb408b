//! `volux render --method pt`: Projected Tetrahedra of tetrahedral meshes (and of grids split
//! into tetrahedra with `--as-tets`).
use std::borrow::Cow;

use volux_core::histogram::Histogram;
use volux_core::image::PngOptions;
use volux_core::tetrahedralize::grid_to_tets;
use volux_core::{CameraSpec, TetMesh};
use volux_io::Dataset;
use volux_render::integrate::SegmentRule;
use volux_render::pt::{PtOptions, PtRenderer, PtStats, SortMode};
use volux_render::tetray::{TetRayCaster, TetRayOptions};

use super::render::{blinn_phong, isosurfaces, transfer_function};
use super::CmdError;
use crate::cli::RenderArgs;

/// The mesh to render with PT, or `None` when the options ask for another renderer.
pub fn mesh_for_pt<'a>(
    data: &'a Dataset,
    args: &RenderArgs,
) -> Result<Option<Cow<'a, TetMesh>>, CmdError> {
    let method = args.method.as_str();
    match (method, data) {
        ("auto" | "pt", Dataset::Mesh(m)) => Ok(Some(Cow::Borrowed(m))),
        ("auto", Dataset::Grid(_)) if !args.as_tets => Ok(None),
        ("auto" | "pt", Dataset::Grid(g)) => {
            if !args.as_tets {
                return Err(
                    "--method pt renders tetrahedral meshes; add --as-tets to split the \
                            grid's cells into tetrahedra"
                        .into(),
                );
            }
            Ok(Some(Cow::Owned(grid_to_tets(g)?)))
        }
        ("raycast" | "resample", _) => Ok(None),
        ("auto" | "pt", _) => Err("unsupported dataset kind for PT".into()),
        (other, _) => Err(format!("unknown method '{other}' (auto, pt, raycast, resample)").into()),
    }
}

/// Renders `mesh` with PT and writes the PNG.
pub fn run(
    mesh: &TetMesh,
    args: &RenderArgs,
    spec: &CameraSpec,
    (w, h): (usize, usize),
    png: &PngOptions,
) -> Result<(), CmdError> {
    let bounds = mesh.bounds();
    let hist = Histogram::from_values(mesh.scalars(), mesh.range(), 256);
    let tf = transfer_function(&args.tf, &hist, bounds.diagonal() / 256.0)?
        .with_opacity_scale(args.opacity_scale);
    let mut opts = PtOptions::new(spec.resolve(&bounds)?, tf);
    (opts.width, opts.height) = (w, h);
    opts.sort = SortMode::parse(&args.sort)?;
    opts.color = segment_rule(&args.color)?;
    opts.isosurfaces = isosurfaces(args)?;
    opts.shading = blinn_phong(args)?;
    opts.count_violations = args.stats;
    if args.no_early_termination {
        opts.early_termination = None;
    }
    let out = PtRenderer::new(mesh).render(&opts)?;
    out.image
        .write_png(&args.output, png)
        .map_err(|e| format!("{}: {e}", args.output.display()))?;
    report(args, &out.stats, (w, h));
    Ok(())
}

/// Renders `mesh` with the tetrahedral ray caster (`--method raycast`) and writes the PNG:
/// `--integrator exact|psi|adaptive-simpson` (other integrators take the colour of
/// `--color`; the adaptive steps `--h0`, `--hmin`, `--hmax` are in units of the mesh's
/// diagonal / 256, as the TF presets), `--iso` with the lighting options, `--mip`,
/// `--error-map` (the adaptive rule's per-pixel estimate, black to white at `--tol`, magenta
/// above).
pub fn run_raycast(
    mesh: &TetMesh,
    args: &RenderArgs,
    spec: &CameraSpec,
    (w, h): (usize, usize),
    png: &PngOptions,
) -> Result<(), CmdError> {
    use volux_render::integrate::{AdaptiveParams, Integrator};
    let bounds = mesh.bounds();
    let unit = bounds.diagonal() / 256.0;
    let hist = Histogram::from_values(mesh.scalars(), mesh.range(), 256);
    let tf = transfer_function(&args.tf, &hist, unit)?.with_opacity_scale(args.opacity_scale);
    let mut opts = TetRayOptions::new(spec.resolve(&bounds)?, tf);
    (opts.width, opts.height) = (w, h);
    let colour = match args.integrator.as_str() {
        "exact" | "psi" => args.integrator.as_str(),
        "adaptive-simpson" | "adaptive" => "adaptive-simpson",
        _ => args.color.as_str(),
    };
    opts.color = if colour == "adaptive-simpson" {
        let Integrator::AdaptiveSimpson(p) = super::render::integrator(args)? else {
            unreachable!("adaptive-simpson parses as the adaptive integrator")
        };
        SegmentRule::AdaptiveSimpson(AdaptiveParams {
            h0: p.h0 * unit,
            hmin: p.hmin * unit,
            hmax: p.hmax * unit,
            ..p
        })
    } else {
        segment_rule(colour)?
    };
    opts.isosurfaces = isosurfaces(args)?;
    opts.shading = blinn_phong(args)?;
    opts.mip = args.mip;
    if args.no_early_termination {
        opts.early_termination = None;
    }
    let caster = TetRayCaster::new(mesh);
    let out = caster.render(&opts)?;
    out.image
        .write_png(&args.output, png)
        .map_err(|e| format!("{}: {e}", args.output.display()))?;
    if let Some(path) = &args.error_map {
        super::render::error_image(&out.error_map, args.tol, w, h)?
            .write_png(path, &PngOptions::default())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let s = &out.stats;
    let mode = if args.mip { "mip" } else { colour };
    let max_error = out.error_map.iter().copied().fold(0.0f32, f32::max);
    let mean_error =
        out.error_map.iter().map(|&e| e as f64).sum::<f64>() / out.error_map.len().max(1) as f64;
    if args.stats && args.json {
        let v = serde_json::json!({
            "method": "raycast",
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "tets": mesh.tets().len(),
            "tets_per_s": mesh.tets().len() as f64 / s.seconds.max(1e-9),
            "rays": s.rays,
            "segments": s.segments,
            "samples": s.samples,
            "rays_over_tolerance": s.rays_over_tolerance,
            "max_error": max_error,
            "mean_error": mean_error,
            "reentries": s.reentries,
            "reentries_per_ray": s.reentries as f64 / (s.rays.max(1)) as f64,
            "recovered": s.recovered,
            "abandoned": s.abandoned,
            "bytes_per_tet": caster.bytes_per_tet(),
            "color": colour,
            "integrator": mode,
            "isosurfaces": opts.isosurfaces.len(),
            "mip": args.mip,
            "threads": rayon::current_num_threads(),
        });
        println!("{v}");
        return Ok(());
    }
    if args.stats {
        eprintln!(
            "{w}x{h} tet ray casting ({mode}): {:.1} ms, {} rays, {} segments, {} samples, \
             {:.3} re-entries per ray, {} abandoned, {} rays over tolerance (max estimated \
             error {max_error:.2e}), {:.0} bytes/tet of acceleration structures",
            s.seconds * 1e3,
            s.rays,
            s.segments,
            s.samples,
            s.reentries as f64 / (s.rays.max(1)) as f64,
            s.abandoned,
            s.rays_over_tolerance,
            caster.bytes_per_tet()
        );
    }
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

fn report(args: &RenderArgs, s: &PtStats, (w, h): (usize, usize)) {
    if args.stats && args.json {
        let v = serde_json::json!({
            "method": "pt",
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "tets": s.tets,
            "tets_kept": s.tets_kept,
            "tets_drawn": s.tets_drawn,
            "degenerate": s.degenerate,
            "clipped": s.clipped,
            "tets_per_s": s.tets as f64 / s.seconds.max(1e-9),
            "fragments": s.fragments,
            "sort": args.sort,
            "color": args.color,
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
        return;
    }
    if args.stats {
        eprintln!(
            "{w}x{h} PT: {:.1} ms ({:.2} M tets/s), {} tets, {} kept, {} drawn, {} degenerate, \
             {} fragments, {:.1} bytes/tet per frame",
            s.seconds * 1e3,
            s.tets as f64 / s.seconds.max(1e-9) / 1e6,
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
    eprintln!("wrote {}", args.output.display());
}

fn segment_rule(s: &str) -> Result<SegmentRule, CmdError> {
    Ok(match s {
        "average" => SegmentRule::Average,
        "psi" => SegmentRule::Psi,
        "exact" => SegmentRule::Exact,
        other => return Err(format!("unknown colour mode '{other}' (average, psi, exact)").into()),
    })
}
