//! The out-of-core path of `volux render`: an OME-Zarr store rendered chunk by chunk
//! (`volux_render::bricked`, opened by the application layer's [`volux_app::store`]) when
//! `--lod` asks for it or its full level is over the memory budget.
use std::path::Path;

use volux_io::omezarr;
use volux_render::bricked::Lod;
use volux_render::scene::Volume;

use super::common::CmdError;
use crate::cli::RenderArgs;

/// The bricked volume of `file` when it is a store to render out of core; `None` to load it
/// in memory as any file. The store's note on its statistics is said on stderr.
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
    let dataset = args.load.dataset(file);
    let lod = args.lod.as_deref().map(parse_lod).transpose()?;
    let budget = volux_core::limits::memory_budget();
    let ms = omezarr::open_multiscale(file, &volux_app::store::zarr_options(&dataset))
        .map_err(|e| format!("{}: {e}", file.display()))?;
    let over = ms.full().layout().bytes() > u128::from(budget);
    let Some(lod) = lod.or(over.then_some(Lod::Auto)) else {
        return Ok(None);
    };
    let store = volux_app::store::open_store(&dataset, budget)?;
    volux_app::store::check_level(file, &store.volume, lod).map_err(|e| format!("--lod {e}"))?;
    if let Some(note) = store.volume.statistics().note() {
        eprintln!("note: {}: {note}", file.display());
    }
    Ok(Some(Volume::Bricked(store.volume, lod)))
}

/// `--lod`: `auto` or a level number ([`volux_app::words::level`]).
pub(crate) fn parse_lod(s: &str) -> Result<Lod, CmdError> {
    volux_app::words::level(s).map_err(|e| format!("--lod {e}").into())
}
