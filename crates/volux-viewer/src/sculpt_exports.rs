//! The sculpt's products (seed `004_*.txt` sec. 6.2 and ch. 4): the voxel count of each
//! region label, and the mask and label volumes written as NRRD `u8` with the data's geometry
//! (3D Slicer opens them). Labelling and writing run as background jobs.
use std::path::Path;

use volux_core::{Buffer, Grid, Samples};

use crate::app::ViewerApp;
use crate::jobs::{Job, Poll};

impl ViewerApp {
    /// Counts the voxels of each label (sec. 6.2) in the background.
    pub fn compute_labels(&mut self) {
        let Some(work) = self.labels_work() else {
            return;
        };
        self.tools.label_counts = None;
        self.tools.labels_job = Some(Job::spawn("labelling", move || {
            work().map(|labels| label_counts(&labels))
        }));
    }

    /// The label volume's computation on the current state, to run on a job thread.
    fn labels_work(&mut self) -> Option<impl FnOnce() -> Result<Vec<u8>, String> + Send> {
        let (grid, sculpt) = (self.sculpt_grid(), self.sculpt.clone());
        let (Some(grid), Some(sculpt)) = (grid, sculpt) else {
            self.show_error("labels apply to grids");
            return None;
        };
        if sculpt.label_seeds().is_empty() {
            self.show_error("pick labelling seeds first (the Label tool)");
            return None;
        }
        let scene = self.scene.clone();
        Some(move || {
            sculpt
                .labels(&grid, &scene)
                .map_err(|e| crate::phrase::phrase(&e))
        })
    }

    /// Takes the label counts once counted.
    pub(crate) fn poll_sculpt_jobs(&mut self) {
        if let Some(job) = &mut self.tools.labels_job {
            if let Poll::Done(r) = job.poll() {
                self.tools.labels_job = None;
                match r {
                    Ok(counts) => self.tools.label_counts = Some(counts),
                    Err(e) => self.show_error(e),
                }
            }
        }
    }

    /// Writes the mask (1 kept, 0 removed) to `path` as NRRD `u8` with the data's geometry,
    /// in the background.
    pub fn export_mask(&mut self, path: &Path) -> Result<(), String> {
        let (Some(grid), Some(sculpt)) = (self.sculpt_grid(), self.sculpt.as_ref()) else {
            return Err("a mask needs a grid dataset".into());
        };
        let mask = sculpt.mask().clone();
        let path = path.to_path_buf();
        self.export_job = Some(Job::spawn("exporting the mask", move || {
            write_u8(&grid, mask.to_values(), &path)
        }));
        Ok(())
    }

    /// Writes the label volume to `path` as NRRD `u8`, in the background.
    pub fn export_labels(&mut self, path: &Path) -> Result<(), String> {
        let grid = self.sculpt_grid().ok_or("labels apply to grids")?;
        let work = self.labels_work().ok_or("no labels to export")?;
        let path = path.to_path_buf();
        self.export_job = Some(Job::spawn("exporting the labels", move || {
            write_u8(&grid, work()?, &path)
        }));
        Ok(())
    }
}

/// The voxel count of every label present (label 0, unlabelled, left out).
pub fn label_counts(labels: &[u8]) -> Vec<(u8, u64)> {
    let mut counts = [0u64; 256];
    for &l in labels {
        counts[l as usize] += 1;
    }
    (1..=255u8)
        .filter(|&l| counts[l as usize] > 0)
        .map(|l| (l, counts[l as usize]))
        .collect()
}

/// Writes `values` as an NRRD `u8` volume with `grid`'s geometry (3D Slicer opens it).
fn write_u8(grid: &Grid, values: Vec<u8>, path: &Path) -> Result<String, String> {
    let out = Grid::new(
        grid.dims(),
        grid.spacing().to_array(),
        grid.origin().to_array(),
        Samples::U8(Buffer::owned(values)),
    )
    .and_then(|g| g.with_direction(grid.direction()))
    .map_err(|e| e.to_string())?;
    volux_io::nrrd::write(&out, path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(format!("saved {}", path.display()))
}
