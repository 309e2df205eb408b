//! One 3-D volume out of the 4-D data of a NRRD or MetaImage file: the samples at one index
//! along the axis that is not spatial (time, a list, vector components, colour channels),
//! wherever that axis lies in the file's order, and colour channels gathered into
//! [`volux_core::color::Rgb`].
use std::path::Path;

use glam::DMat3;
use volux_core::color::Rgb;
use volux_core::volume_axes::{choose, AxisKind, ExtraAxis};
use volux_core::{Buffer, Grid, Samples};

use crate::dataset::VolumeChoice;
use crate::error::{ReadError, Result};
use crate::raw::{self, Decoded};

/// What the axis that is not spatial holds.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Role {
    /// Acquisitions at successive times (`timepoint` chooses); the meaning says the step.
    Time(String),
    /// Other volumes at the same place (`timepoint` chooses).
    Volume(String),
    /// Several values per voxel, a vector or tensor (`component` chooses, default 0).
    Component(String),
    /// Colour channels: red, green, blue (and alpha, dropped), kept as colour unless
    /// `component` picks one.
    Colour,
}

/// Where a grid lies: spacing, origin and direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Place {
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
    pub direction: DMat3,
}

/// The grid of the volume `choice` asks for in the 4-D `data` (`four`: its layout and what
/// its extra axis holds; `None`: `data` is one 3-D volume), with the conversion note of
/// `data`, `notes`, and a record of the axis chosen along.
pub(crate) fn grid(
    path: &Path,
    dims: [usize; 3],
    place: Place,
    data: Decoded,
    notes: Vec<String>,
    four: Option<(Layout4, &Role)>,
    choice: VolumeChoice,
) -> Result<Grid> {
    let err = |e| ReadError::new(path, e);
    let Some((layout, role)) = four else {
        return raw::make_grid(path, dims, place.spacing, place.origin, data, notes)?
            .with_direction(place.direction)
            .map_err(err);
    };
    let n = layout.sizes[layout.extra];
    let scalar = |index: usize, axis: ExtraAxis| -> Result<Grid> {
        let picked = Decoded {
            samples: layout.pick(&data.samples, index),
            note: data.note.clone(),
        };
        Ok(raw::make_grid(
            path,
            dims,
            place.spacing,
            place.origin,
            picked,
            notes.clone(),
        )?
        .with_direction(place.direction)
        .map_err(err)?
        .with_extra_axis(axis))
    };
    let axis = |kind: AxisKind, index: usize, meaning: &str| {
        ExtraAxis::new(kind, n, Some(index)).with_meaning(meaning)
    };
    match role {
        Role::Time(m) | Role::Volume(m) => {
            let t = choose("timepoint", choice.timepoint, n).map_err(err)?;
            let kind = match role {
                Role::Time(_) => AxisKind::Time,
                _ => AxisKind::Volume,
            };
            scalar(t, axis(kind, t, m))
        }
        Role::Component(m) => {
            let c = choose("component", choice.component.unwrap_or(0), n).map_err(err)?;
            scalar(c, axis(AxisKind::Component, c, m))
        }
        Role::Colour => match choice.component {
            Some(c) => {
                let c = choose("component", c, n).map_err(err)?;
                scalar(c, axis(AxisKind::Color, c, ""))
            }
            None => {
                let rgb = layout.rgb(&data.samples).map_err(err)?;
                let mut g = Grid::from_rgb(dims, place.spacing, place.origin, rgb)
                    .and_then(|g| g.with_direction(place.direction))
                    .map_err(err)?;
                if n == 4 {
                    g = g.with_note("the alpha channel was dropped (component 3 reads it)");
                }
                let all = data.note.into_iter().chain(notes);
                Ok(all.fold(g, Grid::with_note))
            }
        },
    }
}

/// A 4-D array's sizes, fastest axis first, and which of its axes is not spatial.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout4 {
    /// Sizes of the four axes as stored (the first varies fastest).
    pub sizes: [usize; 4],
    /// The axis that is not spatial (0 to 3).
    pub extra: usize,
}

impl Layout4 {
    /// How many values one 3-D volume holds.
    pub(crate) fn volume_len(&self) -> usize {
        self.sizes
            .iter()
            .enumerate()
            .filter(|&(a, _)| a != self.extra)
            .map(|(_, n)| n)
            .product()
    }

    /// The samples at `index` along the extra axis, x fastest (the spatial axes keep their
    /// order). The caller checks `index` against the axis' size and `samples` against the
    /// sizes.
    pub(crate) fn pick(&self, samples: &Samples, index: usize) -> Samples {
        let mut stride = [1usize; 4];
        for a in 1..4 {
            stride[a] = stride[a - 1] * self.sizes[a - 1];
        }
        let spatial: Vec<usize> = (0..4).filter(|&a| a != self.extra).collect();
        let (a, b, c) = (spatial[0], spatial[1], spatial[2]);
        let base = index * stride[self.extra];
        let (na, nb, nc) = (self.sizes[a], self.sizes[b], self.sizes[c]);
        let n = self.volume_len();
        macro_rules! gather {
            ($buf:expr, $variant:ident) => {{
                let s = $buf.as_slice();
                // The extra axis last: each volume is one contiguous run.
                if self.extra == 3 {
                    return Samples::$variant(Buffer::owned(s[base..base + n].to_vec()));
                }
                let mut out = Vec::with_capacity(n);
                for k in 0..nc {
                    for j in 0..nb {
                        let row = base + j * stride[b] + k * stride[c];
                        out.extend((0..na).map(|i| s[row + i * stride[a]]));
                    }
                }
                Samples::$variant(Buffer::owned(out))
            }};
        }
        match samples {
            Samples::U8(buf) => gather!(buf, U8),
            Samples::U16(buf) => gather!(buf, U16),
            Samples::I16(buf) => gather!(buf, I16),
            Samples::F32(buf) => gather!(buf, F32),
        }
    }

    /// The first three entries along the extra axis as red, green and blue.
    pub(crate) fn rgb(&self, samples: &Samples) -> volux_core::Result<Rgb> {
        Rgb::new([0, 1, 2].map(|c| self.pick(samples, c)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u16s(v: Vec<u16>) -> Samples {
        Samples::U16(Buffer::owned(v))
    }

    fn values(s: &Samples) -> Vec<f32> {
        (0..s.len()).map(|i| s.get_f32(i)).collect()
    }

    #[test]
    fn picks_along_every_axis() {
        // sizes 2, 3, 1, 2: value = the flat index.
        let data = u16s((0..12).collect());
        let at = |extra, i| {
            let l = Layout4 {
                sizes: [2, 3, 1, 2],
                extra,
            };
            values(&l.pick(&data, i))
        };
        assert_eq!(at(0, 1), vec![1.0, 3.0, 5.0, 7.0, 9.0, 11.0]);
        assert_eq!(at(1, 2), vec![4.0, 5.0, 10.0, 11.0]);
        assert_eq!(at(3, 1), vec![6.0, 7.0, 8.0, 9.0, 10.0, 11.0]);
        let l = Layout4 {
            sizes: [3, 2, 1, 1],
            extra: 0,
        };
        let rgb = l.rgb(&u16s(vec![1, 2, 3, 4, 5, 6])).unwrap();
        assert_eq!(values(&rgb.channels()[2]), vec![3.0, 6.0]);
    }
}
