//! What names a store and what is known of it once opened: the options choosing an image,
//! level, channel and timepoint, the opened store ([`OmeZarr`]) and Volux's attribute key.
use volux_core::bricked::Multiscale;

/// The attribute key of Volux's per-level metadata (value ranges).
pub const VOLUX_KEY: &str = "volux";

/// Which image, level, channel and timepoint of a store to read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ZarrOptions {
    /// A path inside the store to the image group (or plain array) to read, e.g.
    /// `labels/cells`; default: the store's root.
    pub array: Option<String>,
    /// The level [`load_level`](super::load_level) reads (0 = full resolution).
    pub level: usize,
    /// The index on a channel axis (`c`).
    pub channel: usize,
    /// The index on a time axis (`t`).
    pub timepoint: usize,
}

/// An opened store: its pyramid and what `volux info` reports about it.
#[derive(Clone, Debug)]
pub struct OmeZarr {
    /// The levels, full resolution first.
    pub multiscale: Multiscale,
    /// Zarr format, 2 or 3.
    pub zarr_format: u8,
    /// NGFF version (`0.4`, `0.5`) when the metadata says.
    pub ngff_version: Option<String>,
    /// Axis names of the arrays, slowest first.
    pub axes: Vec<String>,
    /// Units of our x, y, z (`micrometer`), when the axes give them.
    pub units: [Option<String>; 3],
    /// The compression of level 0, in words.
    pub codec: String,
    /// The stored data type of level 0 (Zarr name).
    pub data_type: String,
    /// Level array paths, full resolution first.
    pub paths: Vec<String>,
    /// Conversions made while reading.
    pub notes: Vec<String>,
}

impl OmeZarr {
    /// The unit of the spatial axes in words: `micrometer`, `x: micrometer, z: ...` when they
    /// differ, or `unitless` when none is given.
    pub fn unit_words(&self) -> String {
        let [x, y, z] = &self.units;
        match (x, y, z) {
            (None, None, None) => "unitless".into(),
            _ if x == y && (y == z || z.is_none()) => x.clone().unwrap_or_default(),
            _ => ["x", "y", "z"]
                .iter()
                .zip(&self.units)
                .map(|(n, u)| format!("{n}: {}", u.as_deref().unwrap_or("-")))
                .collect::<Vec<_>>()
                .join(", "),
        }
    }
}
