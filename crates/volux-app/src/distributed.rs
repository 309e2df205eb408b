//! A distributed frame (seed `003`, sort-last): every rank renders its k-d region of a
//! store's level reading only its chunks and their face neighbours, and the ranks composite
//! by binary swap in visibility order (adaptive Simpson passes its rays' states from region
//! to region instead); rank 0 gets the image, equal to the single-process render, and every
//! rank's figures. Written once over the engine's message passing
//! ([`Collective`]), so that any front end (the CLI's `mpirun ... --distributed`, a Python
//! script on MPI) drives it, and a test drives it over threads.
//!
//! The front end only plans the frame on rank 0 ([`DistributedPlan::new`], from the scene it
//! built as for a single-process render) and does something with rank 0's
//! [`DistributedFrame`]; [`render_frame`] does the rest on every rank.
use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use volux_core::Image;
use volux_io::omezarr;
use volux_render::bricked::{
    level_placement, render_cache_frame, render_cache_region, BrickCache, BrickedRenderer,
    BrickedVolume, Lod,
};
use volux_render::distributed::error::DistributedError;
use volux_render::distributed::exchange::Collective;
use volux_render::distributed::job::RegionJob;
use volux_render::distributed::kdtree::{KdSplit, ViewPoint};
use volux_render::distributed::part::Part;
use volux_render::distributed::reads::{CountedChunks, ReadStats};
use volux_render::distributed::region::is_pipelined;
use volux_render::distributed::swap::CompositeStats;
use volux_render::scene::Scene;

use crate::error::AppError;
use crate::session::DatasetRef;

/// What rank 0 sends every rank: the store (with its array, channel and timepoint), the
/// brick cache's budget, and the frame's job (level, view, classification, integrator).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DistributedPlan {
    /// The store.
    pub dataset: DatasetRef,
    /// Each rank's brick cache budget, in bytes.
    pub budget: u64,
    /// The frame.
    pub job: RegionJob,
}

impl DistributedPlan {
    /// The plan of `scene` of the store `dataset`, opened as `volume`, at the level `lod`
    /// picks for the view; each rank's cache gets `budget` bytes.
    pub fn new(
        dataset: DatasetRef,
        volume: &Arc<BrickedVolume>,
        scene: &Scene,
        lod: Lod,
        budget: u64,
    ) -> Result<Self, AppError> {
        let level = BrickedRenderer::new(volume.clone(), lod).level_for(scene);
        let job = RegionJob::from_scene(scene, level, volume.range()).map_err(|e| {
            AppError::Distributed {
                rank: 0,
                reason: e.to_string(),
            }
        })?;
        Ok(Self {
            dataset,
            budget,
            job,
        })
    }
}

/// What one rank did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RankStats {
    /// The rank.
    pub rank: usize,
    /// The chunks of its region.
    pub region_chunks: usize,
    /// Its region, chunk coordinates `[lo, hi)`.
    pub region: [[usize; 3]; 2],
    /// Chunks it read: its own, its neighbours' next to its faces, others.
    pub reads: ReadStats,
    /// Wall time of its region's render, milliseconds.
    pub render_ms: f64,
    /// Wall time of its part of the compositing (swap and gather), milliseconds.
    pub composite_ms: f64,
    /// Its messages and bytes while compositing.
    pub composite: CompositeStats,
}

/// Rank 0's result: the plan every rank rendered, the image, every rank's figures.
#[derive(Clone, Debug)]
pub struct DistributedFrame {
    /// The plan.
    pub plan: DistributedPlan,
    /// The image, equal to the single-process render of the plan's level.
    pub image: Image,
    /// Every rank's figures, in rank order.
    pub ranks: Vec<RankStats>,
    /// Wall time of the whole frame on rank 0 (from the plan's broadcast), milliseconds.
    pub total_ms: f64,
}

/// Renders the frame of rank 0's `plan` on this rank of `world` (every rank calls it; the
/// others pass `None`, rank 0 its plan or why it has none). Rank 0 returns the frame; the
/// others return `Ok(None)`. An error on any rank stops every rank: rank 0 returns it,
/// naming the first rank that failed, and the others return `Ok(None)`.
pub fn render_frame<C: Collective>(
    world: &mut C,
    plan: Option<Result<DistributedPlan, String>>,
) -> Result<Option<DistributedFrame>, AppError> {
    let rank = world.rank();
    let started = Instant::now();
    let link = |e: DistributedError| AppError::Distributed {
        rank,
        reason: e.to_string(),
    };
    let planned = (rank == 0).then(|| serde_json::to_vec(&plan).unwrap_or_default());
    let bytes = world.broadcast_bytes(0, planned).map_err(link)?;
    let plan = match serde_json::from_slice::<Option<Result<DistributedPlan, String>>>(&bytes) {
        Ok(Some(Ok(p))) => p,
        Ok(Some(Err(e))) => return failed(rank, 0, e),
        Ok(None) => return failed(rank, 0, "rank 0 had no plan".into()),
        Err(e) => return failed(rank, 0, format!("the plan of the render: {e}")),
    };
    let (image, stats) = if is_pipelined(&plan.job.options()) {
        let region = open_region(&plan, rank, world.size());
        let Some(region) = agree(world, region)? else {
            return Ok(None);
        };
        let piped = pipelined(&plan, region, world);
        match agree(world, piped)? {
            Some(done) => done,
            None => return Ok(None),
        }
    } else {
        let rendered = render(&plan, rank, world.size());
        let Some((part, order, mut stats)) = agree(world, rendered)? else {
            return Ok(None);
        };
        let t = Instant::now();
        let (image, composite) = match part.combine(world, &order) {
            Ok(c) => c,
            Err(e) => return failed(rank, rank, format!("compositing: {e}")),
        };
        stats.composite_ms = t.elapsed().as_secs_f64() * 1e3;
        stats.composite = composite;
        (image, stats)
    };
    let json = serde_json::to_vec(&stats).unwrap_or_default();
    let gathered = world.gather_bytes(0, &json).map_err(link)?;
    let (Some(image), Some(gathered)) = (image, gathered) else {
        return Ok(None);
    };
    let ranks = gathered
        .iter()
        .map(|b| serde_json::from_slice(b))
        .collect::<Result<Vec<RankStats>, _>>()
        .map_err(|e| AppError::Distributed {
            rank,
            reason: format!("the figures of a rank: {e}"),
        })?;
    Ok(Some(DistributedFrame {
        plan,
        image,
        ranks,
        total_ms: started.elapsed().as_secs_f64() * 1e3,
    }))
}

/// Whether `result` is good on every rank: its value (`Some`), or, where some rank failed,
/// on rank 0 the error of the first rank that failed, on the others `Ok(None)`.
fn agree<C: Collective, T>(
    world: &mut C,
    result: Result<T, AppError>,
) -> Result<Option<T>, AppError> {
    let rank = world.rank();
    let link = |e: DistributedError| AppError::Distributed {
        rank,
        reason: e.to_string(),
    };
    if world.all(result.is_ok()).map_err(link)? {
        return Ok(result.ok());
    }
    let mine = result
        .as_ref()
        .err()
        .map(|e| match e {
            // Already this rank's error: its reason, not "rank N: " twice.
            AppError::Distributed { reason, .. } => format!("{rank}\n{reason}"),
            other => format!("{rank}\n{other}"),
        })
        .unwrap_or_default();
    let first = world
        .gather_bytes(0, mine.as_bytes())
        .map_err(link)?
        .and_then(|all| {
            all.into_iter()
                .map(|b| String::from_utf8_lossy(&b).into_owned())
                .find(|m| !m.is_empty())
        })
        .unwrap_or_default();
    let (who, why) = first.split_once('\n').unwrap_or(("0", first.as_str()));
    failed(rank, who.parse().unwrap_or(0), why.to_string())
}

/// Rank 0 returns the error of rank `who`; the others end quietly (rank 0 reports it).
fn failed<T>(rank: usize, who: usize, reason: String) -> Result<Option<T>, AppError> {
    if rank == 0 {
        return Err(AppError::Distributed { rank: who, reason });
    }
    Ok(None)
}

/// This rank's region of the plan's level, opened: the split, the counted chunks, the cache.
struct Region {
    split: KdSplit,
    counted: Arc<CountedChunks>,
    cache: BrickCache,
}

/// Opens this rank's region of the plan's level.
fn open_region(plan: &DistributedPlan, rank: usize, size: usize) -> Result<Region, AppError> {
    let store = &plan.dataset.path;
    let fail = |reason: String| AppError::Store {
        path: store.clone(),
        reason,
    };
    let ms = omezarr::open_multiscale(store, &crate::store::zarr_options(&plan.dataset))
        .map_err(|e| fail(e.to_string()))?;
    let level = ms
        .levels()
        .get(plan.job.level)
        .cloned()
        .ok_or_else(|| AppError::NoSuchLevel {
            store: store.clone(),
            level: plan.job.level,
            levels: ms.levels().len(),
        })?;
    let split = KdSplit::new(level.layout(), size).map_err(|e| fail(e.to_string()))?;
    let counted = Arc::new(CountedChunks::new(level, split.regions()[rank]));
    let cache = BrickCache::new(counted.clone(), plan.budget);
    Ok(Region {
        split,
        counted,
        cache,
    })
}

/// This rank's figures so far.
fn stats_of(region: &Region, rank: usize, render_ms: f64) -> RankStats {
    let b = region.split.regions()[rank];
    RankStats {
        rank,
        region_chunks: b.count(),
        region: [b.lo, b.hi],
        reads: region.counted.stats(),
        render_ms,
        ..Default::default()
    }
}

/// Adaptive Simpson: this rank's region rendered band by band in the state pipeline; rank
/// 0 gets the image. Its figures: render time, and the rest as compositing.
fn pipelined<C: Collective>(
    plan: &DistributedPlan,
    region: Region,
    world: &mut C,
) -> Result<(Option<Image>, RankStats), AppError> {
    let rank = world.rank();
    let opts = plan.job.options();
    let view = ViewPoint::of(&opts.camera, &level_placement(&region.cache));
    let order = region.split.visibility_order(view);
    let (image, times) = render_cache_frame(
        &region.cache,
        plan.job.range,
        (&region.split, rank),
        &opts,
        world,
        &order,
    )
    .map_err(|e| AppError::Distributed {
        rank,
        reason: e.to_string(),
    })?;
    let mut stats = stats_of(&region, rank, times.render_seconds * 1e3);
    stats.composite_ms = times.composite.seconds * 1e3;
    stats.composite = times.composite;
    Ok((image, stats))
}

/// This rank's part (a partial image, or MIP maxima), the visibility order, and its figures
/// so far.
fn render(
    plan: &DistributedPlan,
    rank: usize,
    size: usize,
) -> Result<(Part, Vec<usize>, RankStats), AppError> {
    let region = open_region(plan, rank, size)?;
    let opts = plan.job.options();
    let t = Instant::now();
    let part = render_cache_region(&region.cache, plan.job.range, &region.split, rank, &opts)
        .map_err(|e| AppError::Distributed {
            rank,
            reason: e.to_string(),
        })?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let view = ViewPoint::of(&opts.camera, &level_placement(&region.cache));
    let order = region.split.visibility_order(view);
    Ok((part, order, stats_of(&region, rank, render_ms)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::bricked::GridChunks;
    use volux_io::omezarr::{write_ome_zarr, Levels, WriteOptions};
    use volux_render::distributed::exchange::{Exchange, ThreadExchange};
    use volux_render::engine::Renderer;
    use volux_render::scene::Volume;
    use volux_render::tiles::Control;

    /// A store of a Marschner-Lobb grid in 8³ chunks, one level.
    fn store(dir: &std::path::Path) -> (DatasetRef, Arc<BrickedVolume>) {
        let path = dir.join("ml.ome.zarr");
        let grid = Arc::new(volux_core::synth::marschner_lobb(24).unwrap());
        let chunks = GridChunks::new(grid, [8, 8, 8]).unwrap();
        let opts = WriteOptions {
            levels: Levels::Count(1),
            name: "ml".into(),
            ..WriteOptions::default()
        };
        write_ome_zarr(&chunks, &path, &opts).unwrap();
        let dataset = DatasetRef::at(&path);
        let volume = crate::store::open_store(&dataset, 64 << 20).unwrap().volume;
        (dataset, volume)
    }

    /// `ranks` threads render the plan of `scene`; rank 0's frame.
    fn over_threads(
        ranks: usize,
        plan: Result<DistributedPlan, String>,
    ) -> Result<Option<DistributedFrame>, AppError> {
        let handles: Vec<_> = ThreadExchange::group(ranks)
            .into_iter()
            .map(|mut ex| {
                let plan = (ex.rank() == 0).then(|| plan.clone());
                std::thread::spawn(move || (ex.rank(), render_frame(&mut ex, plan)))
            })
            .collect();
        let mut zero = None;
        for h in handles {
            let (rank, result) = h.join().unwrap();
            if rank == 0 {
                zero = Some(result);
            } else {
                assert!(matches!(result, Ok(None)), "rank {rank}: {result:?}");
            }
        }
        zero.unwrap()
    }

    /// Three ranks over threads draw the single-process image of the store, and rank 0 has
    /// every rank's figures.
    #[test]
    fn three_ranks_draw_the_single_process_image() {
        let dir = tempfile::tempdir().unwrap();
        let (dataset, volume) = store(dir.path());
        let v = Volume::Bricked(volume.clone(), Lod::Level(0));
        let camera = volux_core::CameraSpec::default()
            .resolve(&v.bounds())
            .unwrap();
        let mut scene = Scene::new(camera, 48, 40, v.preset_tf("auto").unwrap());
        scene.early_termination = None;
        let plan = DistributedPlan::new(dataset, &volume, &scene, Lod::Level(0), 64 << 20);
        let frame = over_threads(3, plan.map_err(|e| e.to_string()))
            .unwrap()
            .expect("rank 0's frame");
        assert_eq!(frame.ranks.len(), 3);
        assert!(frame.ranks.iter().enumerate().all(|(r, s)| s.rank == r));
        assert_eq!(
            frame.ranks.iter().map(|s| s.region_chunks).sum::<usize>(),
            27,
            "the regions share out the 3x3x3 chunks"
        );
        let single = BrickedRenderer::new(volume, Lod::Level(0))
            .render(&scene, &Control::default())
            .unwrap();
        let diff = frame.image.compare(&single.image, 0.0).unwrap();
        assert!(diff.max_error < 1e-5, "max {}", diff.max_error);
    }

    /// Rank 0 without a plan stops every rank, and says why.
    #[test]
    fn a_failed_plan_stops_every_rank() {
        let e = over_threads(2, Err("no such store".into())).unwrap_err();
        assert!(
            matches!(&e, AppError::Distributed { rank: 0, reason } if reason == "no such store"),
            "{e}"
        );
    }
}
