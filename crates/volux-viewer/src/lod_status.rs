//! The window's side of progressive LOD ([`crate::progressive`]): the level a bricked
//! volume refines to (the `--lod` choice, or level 0 with "Full resolution"), the level on
//! screen and the status line's words (level, refinement, cache figures), and why the tools
//! that need the volume in memory are off.
use volux_render::bricked::Lod;
use volux_render::scene::Volume;

use crate::app::{ViewerApp, LEVEL_LOG};
use crate::dataset::next_volume_id;
use crate::progressive::{CacheFigures, LevelShown};
use crate::render_service::VolumeRef;

/// Why sculpting tools, labels and cubic filters are off for a bricked volume.
pub const NEEDS_MEMORY: &str = "needs the volume in memory: this store is rendered out of core (open a level that fits with volux convert, or a smaller store)";

impl ViewerApp {
    /// The level choice bricked volumes are rendered with now.
    pub fn lod(&self) -> Lod {
        if self.full_resolution {
            Lod::Level(0)
        } else {
            self.options.lod
        }
    }

    /// "Full resolution": refine a bricked volume to level 0 whatever the view (`false`:
    /// back to the `--lod` choice, by default the level whose voxels are about a pixel).
    pub fn set_full_resolution(&mut self, on: bool) {
        if self.full_resolution == on {
            return;
        }
        self.full_resolution = on;
        let lod = self.lod();
        if let Some(data) = &mut self.data {
            if let Volume::Bricked(b, _) = &data.volume.volume {
                // A new identity: the render thread is asked again (the bricks stay cached
                // in the volume).
                data.volume = VolumeRef {
                    id: next_volume_id(),
                    volume: Volume::Bricked(b.clone(), lod),
                };
            }
        }
    }

    /// Whether the dataset on screen is a bricked volume (an OME-Zarr store out of core).
    pub fn is_bricked(&self) -> bool {
        matches!(self.volume(), Some(Volume::Bricked(..)))
    }

    /// The level of the bricked volume's frame on screen.
    pub fn shown_level(&self) -> Option<LevelShown> {
        self.shown.as_ref().and_then(|s| s.frame.level)
    }

    /// The levels shown so far with their request numbers, oldest first (the last
    /// [`LEVEL_LOG`]; cleared when a dataset is opened).
    pub fn level_log(&self) -> Vec<(u64, LevelShown)> {
        self.level_log.iter().copied().collect()
    }

    pub(crate) fn log_level(&mut self, generation: u64, level: LevelShown) {
        self.level_log.push_back((generation, level));
        while self.level_log.len() > LEVEL_LOG {
            self.level_log.pop_front();
        }
    }

    /// The status line of a bricked volume: the level on screen, whether it is refining,
    /// and the brick cache's figures.
    pub fn lod_status(&self) -> Option<String> {
        let Some(Volume::Bricked(b, _)) = self.volume() else {
            return None;
        };
        let cache = CacheFigures::of(b).describe();
        let level = match self.shown_level() {
            Some(l) if self.shown_full() || !l.is_final() => l.describe(),
            Some(l) => format!("{} (preview)", l.describe()),
            None => "rendering the coarsest level…".into(),
        };
        Some(format!("{level} · {cache}"))
    }
}
