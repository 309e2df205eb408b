//! Label colouring (seed `004` sec. 6.2): the label volume of region labelling, with a colour
//! per label, drawn by the grid ray caster in place of the transfer function's colour (the
//! opacity stays the TF's, and shading lights the label colour as it lights the TF's).
use glam::Vec3;

use crate::error::{RenderError, Setting, SettingError};

/// Colours given to labels in turn (linear RGB): label `n` takes entry `(n - 1) % 6`, as
/// `volux regions` saves them in its sculpt steps.
pub const LABEL_PALETTE: [[f32; 3]; 6] = [
    [0.9, 0.2, 0.2],
    [0.2, 0.7, 0.9],
    [0.3, 0.85, 0.3],
    [0.95, 0.8, 0.2],
    [0.75, 0.35, 0.9],
    [0.95, 0.55, 0.2],
];

/// The [`LABEL_PALETTE`] colour of label `label` (1 to 255; 0 has none).
pub fn palette_colour(label: u8) -> Option<[f32; 3]> {
    (label > 0).then(|| LABEL_PALETTE[usize::from(label - 1) % LABEL_PALETTE.len()])
}

/// One label per voxel (0: none) and the colour of each label (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub struct LabelVolume {
    dims: [usize; 3],
    values: Vec<u8>,
    colours: Vec<Option<[f32; 3]>>,
}

impl LabelVolume {
    /// The labels `values` (one per voxel of a `dims` grid, x fastest) with the `colours` of
    /// labels 1 to 255; a label without a colour keeps the TF's colour. Errors when the count
    /// is not the product of `dims` or a colour is not finite.
    pub fn new(
        dims: [usize; 3],
        values: Vec<u8>,
        colours: &[(u8, [f32; 3])],
    ) -> Result<Self, RenderError> {
        let expected = volux_core::limits::count_of(&dims);
        if values.len() as u64 != expected {
            return Err(volux_core::Error::SizeMismatch {
                expected,
                actual: values.len() as u64,
            }
            .into());
        }
        let mut table = vec![None; 256];
        for &(label, rgb) in colours {
            if !rgb.iter().all(|c| c.is_finite()) {
                return Err(SettingError::new(
                    Setting::LabelColour,
                    format!("{rgb:?} of label {label}"),
                    "finite",
                )
                .into());
            }
            if label != 0 {
                table[label as usize] = Some(rgb);
            }
        }
        Ok(Self {
            dims,
            values,
            colours: table,
        })
    }

    /// Samples per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The labels, one per voxel.
    pub fn values(&self) -> &[u8] {
        &self.values
    }

    /// The colour of the label of the voxel nearest to voxel position `p`, if it has one.
    #[inline]
    pub fn colour_at(&self, p: Vec3) -> Option<[f32; 3]> {
        let [nx, ny, nz] = self.dims;
        let idx = |x: f32, n: usize| (x.round().max(0.0) as usize).min(n - 1);
        let (i, j, k) = (idx(p.x, nx), idx(p.y, ny), idx(p.z, nz));
        self.colours[self.values[i + nx * (j + ny * k)] as usize]
    }
}
