//! The out-of-core path of `volux render`: an OME-Zarr store rendered chunk by chunk
//! (`volux_render::bricked`, opened by the application layer's [`volux_app::store`]) when
//! `--lod` asks for it or its full level is over the memory budget.
use std::path::Path;

use volux_app::open::OpenRequest;
use volux_render::bricked::Lod;
use volux_render::scene::Volume;

use super::common::CmdError;
use crate::cli::RenderArgs;

/// The bricked volume of `file` when it is a store to render out of core; `None` to load it
/// in memory as any file. The store's note on its statistics is said on stderr.
pub fn volume(file: &Path, args: &RenderArgs) -> Result<Option<Volume>, CmdError> {
    let dataset = args.load.dataset(file);
    let request = OpenRequest {
        lod: args.lod.as_deref().map(parse_lod).transpose()?,
        budget: volux_core::limits::memory_budget(),
    };
    let Some(lod) = volux_app::open::out_of_core_lod(&dataset, &request)? else {
        return Ok(None);
    };
    let store = volux_app::store::open_store(&dataset, request.budget)?;
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
