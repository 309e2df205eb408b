//! One level of a store as a [`ChunkSource`]: [`ZarrLevel`], which reads the in-grid part of
//! a chunk through `zarrs` (decoding, clipping the padded edge chunks) and converts the
//! stored type to our sample types.
use volux_core::bricked::{ChunkLayout, ChunkSource};
use volux_core::grid::{Buffer, Samples, ScalarType};
use volux_core::histogram::Histogram;
use zarrs::array::{Array, DataType, ElementOwned};
use zarrs::array_subset::ArraySubset;
use zarrs::filesystem::FilesystemStore;

/// How stored elements become our samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stored {
    U8,
    U16,
    I16,
    F32,
    /// int8, widened exactly to i16.
    I8,
    /// uint32, int32, uint64, int64, float64: converted to the nearest f32.
    U32,
    I32,
    U64,
    I64,
    F64,
}

impl Stored {
    pub(super) fn of(dt: &DataType) -> Option<Self> {
        Some(match dt {
            DataType::UInt8 => Self::U8,
            DataType::UInt16 => Self::U16,
            DataType::Int16 => Self::I16,
            DataType::Float32 => Self::F32,
            DataType::Int8 => Self::I8,
            DataType::UInt32 => Self::U32,
            DataType::Int32 => Self::I32,
            DataType::UInt64 => Self::U64,
            DataType::Int64 => Self::I64,
            DataType::Float64 => Self::F64,
            _ => return None,
        })
    }

    pub(super) fn scalar(self) -> ScalarType {
        match self {
            Self::U8 => ScalarType::U8,
            Self::U16 => ScalarType::U16,
            Self::I16 | Self::I8 => ScalarType::I16,
            _ => ScalarType::F32,
        }
    }
}

/// One level of an OME-Zarr store read chunk by chunk. Our x is the array's last spatial
/// axis (NGFF orders axes `t, c, z, y, x`); time and channel are fixed at the chosen index.
pub struct ZarrLevel {
    pub(super) array: Array<FilesystemStore>,
    pub(super) layout: ChunkLayout,
    pub(super) stored: Stored,
    /// Array axis of our x, y, z (`None` for z of a 2-D image).
    pub(super) spatial: [Option<usize>; 3],
    /// The fixed index of every array axis that is not spatial.
    pub(super) fixed: Vec<u64>,
    /// Per-chunk ranges recorded by the volux writer (x fastest), when present and consistent.
    pub(super) ranges: Option<Vec<[f64; 2]>>,
    /// The level's histogram counts over `range` recorded by the volux writer
    /// ([`volux_core::histogram::STORED_BINS`] bins), when present and consistent.
    pub(super) histogram: Option<Vec<u64>>,
    pub(super) range: Option<[f64; 2]>,
    pub(super) name: String,
}

impl std::fmt::Debug for ZarrLevel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ZarrLevel")
            .field("name", &self.name)
            .field("layout", &self.layout)
            .finish()
    }
}

fn elements<T: ElementOwned>(
    a: &Array<FilesystemStore>,
    s: &ArraySubset,
) -> std::result::Result<Vec<T>, zarrs::array::ArrayError> {
    a.retrieve_array_subset_elements::<T>(s)
}

impl ChunkSource for ZarrLevel {
    fn layout(&self) -> &ChunkLayout {
        &self.layout
    }

    fn read_chunk(&self, c: [usize; 3]) -> volux_core::Result<Samples> {
        let n = self.layout.chunks_per_axis();
        if (0..3).any(|a| c[a] >= n[a]) {
            return Err(volux_core::Error::Chunked(format!(
                "{}: chunk {c:?} is outside the {n:?} chunks of the level",
                self.name
            )));
        }
        let (lo, size) = self.layout.chunk_extent(c);
        let mut ranges: Vec<std::ops::Range<u64>> = self.fixed.iter().map(|&i| i..i + 1).collect();
        for a in 0..3 {
            if let Some(ax) = self.spatial[a] {
                ranges[ax] = lo[a] as u64..(lo[a] + size[a]) as u64;
            }
        }
        let subset = ArraySubset::new_with_ranges(&ranges);
        let a = &self.array;
        let err = |e: zarrs::array::ArrayError| {
            volux_core::Error::Chunked(format!(
                "{}: chunk {c:?} (x, y, z) cannot be read: {e}",
                self.name
            ))
        };
        let f32s = |v: Vec<f32>| Samples::F32(Buffer::owned(v));
        let samples = match self.stored {
            Stored::U8 => Samples::U8(Buffer::owned(elements::<u8>(a, &subset).map_err(err)?)),
            Stored::U16 => Samples::U16(Buffer::owned(elements::<u16>(a, &subset).map_err(err)?)),
            Stored::I16 => Samples::I16(Buffer::owned(elements::<i16>(a, &subset).map_err(err)?)),
            Stored::F32 => f32s(elements::<f32>(a, &subset).map_err(err)?),
            Stored::I8 => Samples::I16(Buffer::owned(
                elements::<i8>(a, &subset)
                    .map_err(err)?
                    .into_iter()
                    .map(i16::from)
                    .collect(),
            )),
            Stored::U32 => f32s(conv(elements::<u32>(a, &subset).map_err(err)?, |v| {
                v as f32
            })),
            Stored::I32 => f32s(conv(elements::<i32>(a, &subset).map_err(err)?, |v| {
                v as f32
            })),
            Stored::U64 => f32s(conv(elements::<u64>(a, &subset).map_err(err)?, |v| {
                v as f32
            })),
            Stored::I64 => f32s(conv(elements::<i64>(a, &subset).map_err(err)?, |v| {
                v as f32
            })),
            Stored::F64 => f32s(conv(elements::<f64>(a, &subset).map_err(err)?, |v| {
                v as f32
            })),
        };
        let expected: usize = size.iter().product();
        if samples.len() != expected {
            return Err(volux_core::Error::Chunked(format!(
                "{}: chunk {c:?} decoded to {} samples, expected {expected}",
                self.name,
                samples.len()
            )));
        }
        Ok(samples)
    }

    fn chunk_range(&self, c: [usize; 3]) -> Option<[f64; 2]> {
        let n = self.layout.chunks_per_axis();
        if (0..3).any(|a| c[a] >= n[a]) {
            return None;
        }
        self.ranges.as_ref().map(|r| r[self.layout.chunk_index(c)])
    }

    fn value_range(&self) -> Option<[f64; 2]> {
        self.range
    }

    fn value_histogram(&self) -> Option<Histogram> {
        let [min, max] = self.range?;
        Some(Histogram {
            min,
            max,
            counts: self.histogram.clone()?,
        })
    }
}

fn conv<T: Copy>(v: Vec<T>, f: impl Fn(T) -> f32) -> Vec<f32> {
    v.into_iter().map(f).collect()
}
