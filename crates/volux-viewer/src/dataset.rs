//! A dataset as the viewer holds it: the volume the renderers draw, its histogram, the grid
//! its slices are cut from, and where it came from (for the title and sessions). An OME-Zarr
//! store is opened out of core ([`crate::store`]).
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use volux_app::session::DatasetRef;
use volux_core::histogram::Histogram;
use volux_io::{Dataset, Format};
use volux_render::scene::{Volume, HISTOGRAM_BINS};

use crate::render_service::VolumeRef;
use crate::slices::SliceVolume;

/// A new identity for a volume (renderers are cached per identity).
pub fn next_volume_id() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// A loaded dataset.
#[derive(Clone)]
pub struct Loaded {
    /// The file and reader options.
    pub source: DatasetRef,
    /// Its format.
    pub format: Format,
    /// The volume as loaded.
    pub volume: VolumeRef,
    /// A grid split into tetrahedra, once a mesh method asked for it.
    pub tets: Option<VolumeRef>,
    /// Counts over the value range.
    pub histogram: Histogram,
    /// What the slice views cut.
    pub slices: Arc<SliceVolume>,
    /// What the reader noted (converted types, dropped metadata).
    pub notes: Vec<String>,
}

impl Loaded {
    /// Whether the data is a patient scan, whose world axes are LPS: DICOM, NIfTI, or a
    /// grid that carries direction cosines.
    pub fn is_medical(&self) -> bool {
        let oriented = matches!(&self.volume.volume, Volume::Grid(g) if !g.is_axis_aligned());
        oriented || matches!(self.format, Format::Dicom | Format::Nifti)
    }

    /// The volume a method draws: the tetrahedral split of a grid for the mesh methods.
    pub fn volume_for(&self, mesh_method: bool) -> Option<&VolumeRef> {
        match (&self.volume.volume, mesh_method) {
            (Volume::Grid(_), true) => self.tets.as_ref(),
            _ => Some(&self.volume),
        }
    }

    /// A short description: format, size, type, range.
    pub fn describe(&self) -> String {
        let r = self.volume.volume.range();
        let what = match &self.volume.volume {
            Volume::Grid(g) => {
                let d = g.dims();
                format!("{}x{}x{} {}", d[0], d[1], d[2], g.scalar_type().name())
            }
            Volume::Mesh(m) => format!("{} tets", m.tets().len()),
            Volume::Bricked(b, _) => {
                let l = b.multiscale().full().layout();
                let [x, y, z] = l.dims;
                format!(
                    "{x}x{y}x{z} {} in {} levels (bricked)",
                    l.scalar.name(),
                    b.levels()
                )
            }
            _ => "volume".into(),
        };
        format!(
            "{} · {what} · range [{}, {}]",
            self.format.name(),
            r[0] as f32,
            r[1] as f32
        )
    }
}

/// Loads `source` (any format the CLI reads); errors are one readable line.
pub fn load(source: &DatasetRef) -> Result<Loaded, String> {
    let opts = source.load_options();
    let shown = source.path.display().to_string();
    if volux_io::detect(&source.path).ok() == Some(Format::OmeZarr) {
        return load_store(source);
    }
    // The reader's error names the file (or the file inside a folder) already.
    let (data, format) = volux_io::load(&source.path, &opts).map_err(|e| e.to_string())?;
    let (volume, slices, notes) = match data {
        Dataset::Grid(g) => {
            let notes = g.notes().to_vec();
            let g = Arc::new(g);
            (Volume::Grid(g.clone()), SliceVolume::of_grid(g), notes)
        }
        Dataset::Mesh(m) => {
            let slices = SliceVolume::of_mesh(&m).map_err(|e| format!("{shown}: {e}"))?;
            let notes = m.notes().to_vec();
            (Volume::from(m), slices, notes)
        }
        _ => return Err(format!("{shown}: unsupported dataset kind")),
    };
    let mut loaded = Loaded {
        source: source.clone(),
        format,
        histogram: volume.histogram(HISTOGRAM_BINS),
        volume: VolumeRef {
            id: next_volume_id(),
            volume,
        },
        tets: None,
        slices: Arc::new(slices),
        notes,
    };
    if source.as_tets {
        loaded.split_into_tets()?;
    }
    Ok(loaded)
}

/// Opens an OME-Zarr store out of core, its bricks cached within the cache budget.
fn load_store(source: &DatasetRef) -> Result<Loaded, String> {
    let store = crate::store::open(source, crate::store::cache_budget())?;
    Ok(Loaded {
        source: source.clone(),
        format: Format::OmeZarr,
        histogram: store.volume.histogram(HISTOGRAM_BINS),
        volume: VolumeRef {
            id: next_volume_id(),
            volume: store.volume,
        },
        tets: None,
        slices: Arc::new(store.slices),
        notes: store.notes,
    })
}

impl Loaded {
    /// Splits a grid into tetrahedra (for PT and tet ray casting), within the memory budget.
    pub fn split_into_tets(&mut self) -> Result<(), String> {
        if self.tets.is_none() && matches!(self.volume.volume, Volume::Grid(_)) {
            let tets = self
                .volume
                .volume
                .to_tets()
                .map_err(|e| crate::phrase::phrase(&e))?;
            self.tets = Some(VolumeRef {
                id: next_volume_id(),
                volume: tets,
            });
        }
        self.source.as_tets = true;
        Ok(())
    }
}

/// The path as the title shows it: the file name, or the folder's for DICOM folders.
pub fn title_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}
