//! One rank of a distributed render, driven from the command line: rank 0 plans the frame
//! (the scene of `volux render`, as the single-process render would draw it), and every
//! rank renders it through the application layer's distributed frame
//! ([`volux_app::distributed::render_frame`] over MPI's `World`): regions, compositing or
//! the state pipeline, agreement that every rank succeeded, the figures gathered. Rank 0
//! then writes the PNG (a temporary name renamed into place) and the per-rank figures. An
//! error on any rank is reported once, by rank 0, as one line; nothing is written then.
use volux_app::distributed::{render_frame, DistributedFrame, DistributedPlan, RankStats};
use volux_core::Image;
use volux_mpi::Mpi;
use volux_render::bricked::Lod;
use volux_render::distributed::exchange::Exchange;
use volux_render::scene::Volume;

use crate::cli::RenderArgs;
use crate::commands::common::CmdError;
use crate::settings::RenderPlan;

/// Runs this rank's part.
pub fn run(args: &RenderArgs) -> Result<(), CmdError> {
    let mpi = Mpi::init()?;
    let mut world = mpi.world();
    let planned =
        (world.rank() == 0).then(|| plan(args).map_err(|e| crate::phrase::phrase(e.as_ref())));
    let Some(frame) = render_frame(&mut world, planned)? else {
        return Ok(());
    };
    write(args, &frame.image)?;
    if args.stats {
        report(args, &frame)?;
    }
    Ok(())
}

/// Rank 0: the frame of `args`, as `volux render STORE --lod N --no-early-termination`
/// draws it (level 0 unless --lod says otherwise; adaptive Simpson keeps the scene's early
/// termination: `volux render STORE --lod N`).
fn plan(args: &RenderArgs) -> Result<DistributedPlan, CmdError> {
    RenderPlan::new(args)?;
    let file = args
        .file
        .as_deref()
        .ok_or("--distributed renders a store: give STORE.ome.zarr")?;
    if volux_io::detect(file).ok() != Some(volux_io::Format::OmeZarr) {
        return Err(format!(
            "{}: --distributed renders OME-Zarr stores (write one with `volux convert IN OUT.ome.zarr`)",
            file.display()
        )
        .into());
    }
    let dataset = args.load.dataset(file);
    let budget = volux_core::limits::memory_budget();
    let volume = volux_app::store::open_store(&dataset, budget)?.volume;
    let lod = match args.lod.as_deref() {
        Some(s) => crate::commands::bricked::parse_lod(s)?,
        None => Lod::Level(0),
    };
    let scene = RenderPlan::new(args)?.scene(args, &Volume::Bricked(volume.clone(), lod), false)?;
    Ok(DistributedPlan::new(dataset, &volume, &scene, lod, budget)?)
}

/// Rank 0 writes the PNG (and the raw image), each through a temporary name.
fn write(args: &RenderArgs, image: &Image) -> Result<(), CmdError> {
    let png = RenderPlan::new(args)?.png;
    let output = args.output();
    image
        .write_png(&output, &png)
        .map_err(|e| format!("{}: {e}", output.display()))?;
    if let Some(path) = &args.raw_out {
        crate::commands::raw::write_raw(image, path)?;
    }
    eprintln!("wrote {}", output.display());
    Ok(())
}

/// The figures of every rank: JSON on stdout with --json, else a line per rank.
fn report(args: &RenderArgs, frame: &DistributedFrame) -> std::io::Result<()> {
    let (plan, all, total_ms) = (&frame.plan, &frame.ranks[..], frame.total_ms);
    let max = |f: fn(&RankStats) -> f64| all.iter().map(f).fold(0.0, f64::max);
    if args.json {
        let v = serde_json::json!({
            "ranks": all.len(),
            "level": plan.job.level,
            "width": plan.job.width,
            "height": plan.job.height,
            "integrator": plan.job.integrator.name(),
            "total_ms": total_ms,
            "render_ms_max": max(|s| s.render_ms),
            "composite_ms_max": max(|s| s.composite_ms),
            "per_rank": all,
        });
        outln!("{v}")?;
        return Ok(());
    }
    outln!(
        "{} ranks, level {}, {}x{}: {total_ms:.1} ms in all",
        all.len(),
        plan.job.level,
        plan.job.width,
        plan.job.height
    )?;
    for s in all {
        outln!(
            "rank {}: {} chunks in its region; read {} own, {} neighbour, {} other ({} bytes); render {:.1} ms, compositing {:.1} ms ({} messages, {} bytes sent)",
            s.rank,
            s.region_chunks,
            s.reads.own,
            s.reads.neighbours,
            s.reads.other,
            s.reads.bytes,
            s.render_ms,
            s.composite_ms,
            s.composite.messages,
            s.composite.bytes_sent
        )?;
    }
    Ok(())
}
