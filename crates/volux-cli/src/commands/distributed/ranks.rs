//! One rank of a distributed render: rank 0 plans the frame (the scene of `volux render`,
//! as the single-process render would draw it) and broadcasts it; every rank opens the
//! store, renders its k-d region reading only its chunks and their face neighbours, the
//! ranks agree that every region rendered, composite by binary swap, and rank 0 writes the
//! PNG (a temporary name renamed into place) and the per-rank figures. Adaptive Simpson
//! instead passes its rays' states from region to region in visibility order (the state
//! pipeline of `volux_render::distributed::pipeline`, exact), its regions rendered as the
//! states arrive; the ranks then agree that it succeeded. An error on any rank is reported
//! once, by rank 0, as one line; nothing is written then.
use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use volux_app::session::DatasetRef;
use volux_core::Image;
use volux_io::omezarr;
use volux_mpi::stats::RankStats;
use volux_mpi::{Mpi, World};
use volux_render::bricked::{
    level_placement, render_cache_frame, render_cache_region, BrickCache, BrickedRenderer, Lod,
};
use volux_render::distributed::exchange::Exchange;
use volux_render::distributed::job::RegionJob;
use volux_render::distributed::kdtree::{KdSplit, ViewPoint};
use volux_render::distributed::part::Part;
use volux_render::distributed::reads::CountedChunks;
use volux_render::distributed::region::is_pipelined;
use volux_render::scene::Volume;

use crate::cli::RenderArgs;
use crate::commands::common::CmdError;
use crate::settings::RenderPlan;

/// What rank 0 sends every rank.
#[derive(Serialize, Deserialize)]
struct Plan {
    /// The store and its array, channel and timepoint.
    dataset: DatasetRef,
    budget: u64,
    job: RegionJob,
}

/// Runs this rank's part.
pub fn run(args: &RenderArgs) -> Result<(), CmdError> {
    let mpi = Mpi::init()?;
    let mut world = mpi.world();
    let rank = world.rank();
    let started = Instant::now();
    let planned = (rank == 0).then(|| {
        let p: Result<Plan, String> = plan(args).map_err(|e| e.to_string());
        serde_json::to_vec(&p).unwrap_or_default()
    });
    let bytes = world.broadcast_bytes(0, planned);
    let plan = match serde_json::from_slice::<Result<Plan, String>>(&bytes) {
        Ok(Ok(p)) => p,
        Ok(Err(e)) => return failed(rank, e),
        Err(e) => return failed(rank, format!("the plan of the render: {e}")),
    };
    let (image, stats) = if is_pipelined(&plan.job.options()) {
        let region = open_region(&plan, rank, world.size());
        let Some(region) = agree(&world, rank, region)? else {
            return Ok(());
        };
        let piped = pipelined(&plan, region, &mut world);
        match agree(&world, rank, piped)? {
            Some(done) => done,
            None => return Ok(()),
        }
    } else {
        let rendered = render(&plan, rank, world.size());
        let Some((part, order, mut stats)) = agree(&world, rank, rendered)? else {
            return Ok(());
        };
        let t = Instant::now();
        let composited = part.combine(&mut world, &order);
        let (image, cstats) = match composited {
            Ok(c) => c,
            Err(e) => return failed(rank, format!("rank {rank}: compositing: {e}")),
        };
        stats.composite_ms = t.elapsed().as_secs_f64() * 1e3;
        stats.composite = cstats;
        (image, stats)
    };
    let json = serde_json::to_vec(&stats).unwrap_or_default();
    let gathered = world.gather_bytes(0, &json);
    let (Some(image), Some(gathered)) = (image, gathered) else {
        return Ok(());
    };
    let all: Vec<RankStats> = gathered
        .iter()
        .map(|b| serde_json::from_slice(b))
        .collect::<Result<_, _>>()
        .map_err(|e| format!("the figures of a rank: {e}"))?;
    write(args, &image)?;
    if args.stats {
        report(args, &plan, &all, started.elapsed().as_secs_f64() * 1e3)?;
    }
    Ok(())
}

/// Whether `result` is good on every rank: its value (`Some`), or, where some rank failed,
/// rank 0's error naming the first failed rank, the others `Ok(None)`.
fn agree<T, E: std::fmt::Display>(
    world: &World,
    rank: usize,
    result: Result<T, E>,
) -> Result<Option<T>, CmdError> {
    if world.all(result.is_ok()) {
        return Ok(result.ok());
    }
    let mine = result
        .as_ref()
        .err()
        .map(|e| format!("rank {rank}: {e}"))
        .unwrap_or_default();
    let first = world.gather_bytes(0, mine.as_bytes()).and_then(|all| {
        all.into_iter()
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .find(|m| !m.is_empty())
    });
    failed(rank, first.unwrap_or_default()).map(|()| None)
}

/// This rank's region of the level, opened: the split, the counted chunks, the cache.
struct Region {
    split: KdSplit,
    counted: Arc<CountedChunks>,
    cache: BrickCache,
}

/// Opens this rank's region of the plan's level.
fn open_region(plan: &Plan, rank: usize, size: usize) -> Result<Region, CmdError> {
    let store = &plan.dataset.path;
    let ms = omezarr::open_multiscale(store, &volux_app::store::zarr_options(&plan.dataset))
        .map_err(|e| format!("{}: {e}", store.display()))?;
    let level = ms.levels().get(plan.job.level).cloned().ok_or_else(|| {
        format!(
            "{}: level {} does not exist",
            store.display(),
            plan.job.level
        )
    })?;
    let split = KdSplit::new(level.layout(), size)?;
    let counted = Arc::new(CountedChunks::new(level, split.regions()[rank]));
    let cache = BrickCache::new(counted.clone(), plan.budget);
    Ok(Region {
        split,
        counted,
        cache,
    })
}

/// Adaptive Simpson: this rank's region rendered band by band in the state pipeline; rank
/// 0 gets the image. Its figures: render time, and the rest as compositing.
fn pipelined(
    plan: &Plan,
    region: Region,
    world: &mut World,
) -> Result<(Option<Image>, RankStats), CmdError> {
    let rank = world.rank();
    let opts = plan.job.options();
    let view = ViewPoint::of(&opts.camera, &level_placement(&region.cache));
    let order = region.split.visibility_order(view);
    let (cache, split) = (&region.cache, &region.split);
    let (image, frame) =
        render_cache_frame(cache, plan.job.range, (split, rank), &opts, world, &order)?;
    let b = split.regions()[rank];
    let stats = RankStats {
        rank,
        region_chunks: b.count(),
        region: [b.lo, b.hi],
        reads: region.counted.stats(),
        render_ms: frame.render_seconds * 1e3,
        composite_ms: frame.composite.seconds * 1e3,
        composite: frame.composite,
    };
    Ok((image, stats))
}

/// Rank 0 returns the error (printed as one line); the others end quietly (rank 0's exit
/// status fails the run).
fn failed(rank: usize, message: String) -> Result<(), CmdError> {
    if rank == 0 {
        return Err(message.into());
    }
    Ok(())
}

/// Rank 0: the frame of `args`, as `volux render STORE --lod N --no-early-termination`
/// draws it (level 0 unless --lod says otherwise; adaptive Simpson keeps the scene's early
/// termination: `volux render STORE --lod N`).
fn plan(args: &RenderArgs) -> Result<Plan, CmdError> {
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
    let level = BrickedRenderer::new(volume.clone(), lod).level_for(&scene);
    let job = RegionJob::from_scene(&scene, level, volume.range())?;
    Ok(Plan {
        dataset,
        budget,
        job,
    })
}

/// This rank's part (a partial image, or MIP maxima), the visibility order, and its figures so far.
fn render(
    plan: &Plan,
    rank: usize,
    size: usize,
) -> Result<(Part, Vec<usize>, RankStats), CmdError> {
    let Region {
        split,
        counted,
        cache,
    } = open_region(plan, rank, size)?;
    let region = split.regions()[rank];
    let opts = plan.job.options();
    let t = Instant::now();
    let part = render_cache_region(&cache, plan.job.range, &split, rank, &opts)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let order = split.visibility_order(ViewPoint::of(&opts.camera, &level_placement(&cache)));
    let stats = RankStats {
        rank,
        region_chunks: region.count(),
        region: [region.lo, region.hi],
        reads: counted.stats(),
        render_ms,
        ..Default::default()
    };
    Ok((part, order, stats))
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
fn report(args: &RenderArgs, plan: &Plan, all: &[RankStats], total_ms: f64) -> std::io::Result<()> {
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
