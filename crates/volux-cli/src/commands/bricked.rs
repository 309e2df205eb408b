//! The out-of-core path of `volux render`: an OME-Zarr store rendered chunk by chunk
//! (`volux_render::bricked`) when `--lod` asks for it or its full level is over the memory
//! budget.
use std::path::Path;
use std::sync::Arc;

use volux_io::omezarr::{self, ZarrOptions};
use volux_render::bricked::{BrickedVolume, Lod};
use volux_render::scene::Volume;

use super::common::CmdError;
use crate::cli::RenderArgs;

/// The bricked volume of `file` when it is a store to render out of core; `None` to load it
/// in memory as any file.
pub fn volume(file: &Path, args: &RenderArgs) -> Result<Option<Volume>, CmdError> {
    let format = volux_io::detect(file).ok();
    if let Some(lod) = &args.lod {
        if format != Some(volux_io::Format::OmeZarr) {
            let what = format.map_or("not a store".to_string(), |f| {
                format!("a {} file", f.name())
            });
            return Err(format!(
                "--lod {lod} applies to OME-Zarr stores, rendered out of core level by level; \
                 {} is {what}, read whole",
                file.display()
            )
            .into());
        }
    }
    if format != Some(volux_io::Format::OmeZarr) || args.load.level.is_some() {
        return Ok(None);
    }
    let opts = ZarrOptions {
        array: args.load.array.clone(),
        level: 0,
        channel: args.load.channel.unwrap_or(0),
        timepoint: args.load.timepoint.unwrap_or(0),
    };
    let lod = args.lod.as_deref().map(parse_lod).transpose()?;
    let budget = volux_core::limits::memory_budget();
    let ms =
        omezarr::open_multiscale(file, &opts).map_err(|e| format!("{}: {e}", file.display()))?;
    let over = ms.full().layout().bytes() > u128::from(budget);
    let Some(lod) = lod.or(over.then_some(Lod::Auto)) else {
        return Ok(None);
    };
    let volume = BrickedVolume::open(ms, budget).map_err(|e| format!("{}: {e}", file.display()))?;
    if let Lod::Level(n) = lod {
        let levels = volume.levels();
        if n >= levels {
            return Err(format!(
                "--lod {n}: {} has {levels} levels, 0 (full resolution) to {}",
                file.display(),
                levels - 1
            )
            .into());
        }
    }
    Ok(Some(Volume::Bricked(Arc::new(volume), lod)))
}

/// `auto` or a level number.
pub(crate) fn parse_lod(s: &str) -> Result<Lod, CmdError> {
    if s == "auto" {
        return Ok(Lod::Auto);
    }
    s.parse::<usize>()
        .map(Lod::Level)
        .map_err(|_| format!("--lod {s}: give auto or a level number (0 = full resolution)").into())
}
