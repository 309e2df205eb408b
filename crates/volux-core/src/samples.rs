//! Samples in their native type: [`ScalarType`], the [`Scalar`] trait, [`Buffer`] (owned or
//! memory-mapped, cheap to clone) and [`Samples`], the typed values of a grid or of one
//! colour channel ([`crate::color`]), with [`with_samples!`](crate::with_samples) to reach the
//! typed slice.
use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result};

/// The native scalar type of a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum ScalarType {
    /// Unsigned 8-bit.
    U8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit (CT Hounsfield units).
    I16,
    /// 32-bit float.
    F32,
}

impl ScalarType {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::F32 => 4,
        }
    }
    /// The sidecar name (`uint8`, `uint16`, `int16`, `float32`).
    pub fn name(self) -> &'static str {
        match self {
            ScalarType::U8 => "uint8",
            ScalarType::U16 => "uint16",
            ScalarType::I16 => "int16",
            ScalarType::F32 => "float32",
        }
    }
    /// Parses a sidecar / NRRD / numpy-style type name.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "uint8" | "u8" | "uchar" | "unsigned char" | "uint8_t" | "met_uchar" => ScalarType::U8,
            "uint16" | "u16" | "ushort" | "unsigned short" | "uint16_t" | "met_ushort" => {
                ScalarType::U16
            }
            "int16" | "i16" | "short" | "signed short" | "int16_t" | "met_short" => ScalarType::I16,
            "float32" | "f32" | "float" | "met_float" => ScalarType::F32,
            _ => return None,
        })
    }
}

/// A plain-old-data scalar that a [`Buffer`] can hold.
pub trait Scalar: bytemuck::Pod + Send + Sync + 'static {
    /// The value as `f32`.
    fn to_f32(self) -> f32;
}
impl Scalar for u8 {
    fn to_f32(self) -> f32 {
        self as f32
    }
}
impl Scalar for u16 {
    fn to_f32(self) -> f32 {
        self as f32
    }
}
impl Scalar for i16 {
    fn to_f32(self) -> f32 {
        self as f32
    }
}
impl Scalar for f32 {
    fn to_f32(self) -> f32 {
        self
    }
}

/// Bytes owned by someone else that a [`Buffer`] may read in place: a numpy array shared by
/// the Python bindings, say. The owner keeps the bytes alive and unmoved for as long as it
/// lives; they may change in place between renders (a user's `array[...] = v`), never while
/// one reads them.
pub trait SharedBytes: Send + Sync + std::fmt::Debug {
    /// The bytes, aligned for the buffer's scalar type.
    fn bytes(&self) -> &[u8];
}

#[derive(Clone, Debug)]
enum Storage<T> {
    Owned(Arc<Vec<T>>),
    Mapped {
        map: Arc<memmap2::Mmap>,
        offset: usize,
        len: usize,
    },
    Shared(Arc<dyn SharedBytes>),
}

/// A read-only slice of scalars, owned or memory-mapped; cheap to clone.
#[derive(Clone, Debug)]
pub struct Buffer<T> {
    storage: Storage<T>,
}

impl<T: Scalar> Buffer<T> {
    /// Wraps owned values.
    pub fn owned(values: Vec<T>) -> Self {
        Self {
            storage: Storage::Owned(Arc::new(values)),
        }
    }

    /// Reads `owner`'s bytes in place, without a copy. Errors when their length is not a whole
    /// number of values or they are not aligned for `T`.
    pub fn shared(owner: Arc<dyn SharedBytes>) -> Result<Self> {
        let bytes = owner.bytes();
        let size = std::mem::size_of::<T>();
        if !bytes.len().is_multiple_of(size) {
            return Err(Error::SizeMismatch {
                expected: (bytes.len() / size + 1) as u64,
                actual: (bytes.len() / size) as u64,
            });
        }
        if bytemuck::try_cast_slice::<u8, T>(bytes).is_err() {
            return Err(Error::Unaligned {
                address: bytes.as_ptr() as usize,
                alignment: std::mem::align_of::<T>(),
            });
        }
        Ok(Self {
            storage: Storage::Shared(owner),
        })
    }

    /// Memory-maps `count` little-endian values of `T` starting at byte `offset` of `path`.
    ///
    /// Returns `Ok(None)` when mapping is not possible (big-endian host, misaligned offset), in
    /// which case the caller reads the file instead. Errors when the file is too short.
    pub fn map_file(path: &Path, offset: u64, count: usize) -> Result<Option<Self>> {
        let size = std::mem::size_of::<T>();
        if cfg!(target_endian = "big")
            || !(offset as usize).is_multiple_of(std::mem::align_of::<T>())
        {
            return Ok(None);
        }
        let file = std::fs::File::open(path)?;
        let file_len = file.metadata()?.len();
        let need = (count as u64)
            .checked_mul(size as u64)
            .and_then(|b| b.checked_add(offset))
            .ok_or(Error::SizeMismatch {
                expected: u64::MAX,
                actual: file_len,
            })?;
        if file_len < need {
            return Err(Error::SizeMismatch {
                expected: count as u64,
                actual: file_len.saturating_sub(offset) / size as u64,
            });
        }
        if count == 0 {
            return Ok(Some(Self::owned(Vec::new())));
        }
        let map = map_read_only(&file)?;
        Ok(Some(Self {
            storage: Storage::Mapped {
                map: Arc::new(map),
                offset: offset as usize,
                len: count,
            },
        }))
    }

    /// The values.
    pub fn as_slice(&self) -> &[T] {
        match &self.storage {
            Storage::Owned(v) => v,
            Storage::Mapped { map, offset, len } => {
                let bytes = &map[*offset..*offset + *len * std::mem::size_of::<T>()];
                bytemuck::cast_slice(bytes)
            }
            // Checked by `shared`: a whole number of aligned values.
            Storage::Shared(owner) => bytemuck::cast_slice(owner.bytes()),
        }
    }

    /// Whether the values are read in place from someone else's memory ([`Buffer::shared`]).
    pub fn is_shared(&self) -> bool {
        matches!(self.storage, Storage::Shared(_))
    }

    /// Whether the values are memory-mapped from a file.
    pub fn is_mapped(&self) -> bool {
        matches!(self.storage, Storage::Mapped { .. })
    }
}

/// Maps a file read-only.
///
/// `unsafe` is needed because the OS may change a mapped file under us. This is sound for our
/// use: the map is read-only, and volume files are inputs that Volux never writes while mapped;
/// a file truncated by another process could raise SIGBUS, the same trade-off every mmap-based
/// viewer accepts to avoid copying multi-gigabyte volumes (DEVELOPERS.md: "large files are
/// memory-mapped, not copied").
#[allow(unsafe_code)]
fn map_read_only(file: &std::fs::File) -> Result<memmap2::Mmap> {
    // SAFETY: see the function's documentation.
    Ok(unsafe { memmap2::Mmap::map(file)? })
}

impl<T: Scalar> std::ops::Deref for Buffer<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

/// Grid samples in their native type (exhaustive: [`with_samples!`](crate::with_samples)
/// matches every variant).
#[derive(Clone, Debug)]
pub enum Samples {
    /// Unsigned 8-bit values.
    U8(Buffer<u8>),
    /// Unsigned 16-bit values.
    U16(Buffer<u16>),
    /// Signed 16-bit values.
    I16(Buffer<i16>),
    /// 32-bit float values.
    F32(Buffer<f32>),
}

/// Applies `$body` to the typed slice inside a [`Samples`].
#[macro_export]
macro_rules! with_samples {
    ($samples:expr, |$s:ident| $body:expr) => {
        match $samples {
            $crate::samples::Samples::U8(b) => {
                let $s: &[u8] = b.as_slice();
                $body
            }
            $crate::samples::Samples::U16(b) => {
                let $s: &[u16] = b.as_slice();
                $body
            }
            $crate::samples::Samples::I16(b) => {
                let $s: &[i16] = b.as_slice();
                $body
            }
            $crate::samples::Samples::F32(b) => {
                let $s: &[f32] = b.as_slice();
                $body
            }
        }
    };
}

impl Samples {
    /// The scalar type.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            Samples::U8(_) => ScalarType::U8,
            Samples::U16(_) => ScalarType::U16,
            Samples::I16(_) => ScalarType::I16,
            Samples::F32(_) => ScalarType::F32,
        }
    }
    /// Number of values.
    pub fn len(&self) -> usize {
        with_samples!(self, |s| s.len())
    }
    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Value `i` as `f32`.
    #[inline]
    pub fn get_f32(&self, i: usize) -> f32 {
        with_samples!(self, |s| s[i].to_f32())
    }
    /// Whether the values are memory-mapped.
    pub fn is_mapped(&self) -> bool {
        match self {
            Samples::U8(b) => b.is_mapped(),
            Samples::U16(b) => b.is_mapped(),
            Samples::I16(b) => b.is_mapped(),
            Samples::F32(b) => b.is_mapped(),
        }
    }
    /// Decodes `bytes` of type `ty` with the given endianness into owned samples.
    pub fn from_bytes(ty: ScalarType, bytes: &[u8], little_endian: bool) -> Result<Self> {
        if !bytes.len().is_multiple_of(ty.size()) {
            return Err(Error::SizeMismatch {
                expected: (bytes.len() / ty.size() + 1) as u64,
                actual: (bytes.len() / ty.size()) as u64,
            });
        }
        fn conv<T: Scalar, const N: usize>(
            bytes: &[u8],
            f: impl Fn([u8; N]) -> T + Sync,
        ) -> Vec<T> {
            bytes
                .chunks_exact(N)
                .map(|c| f(c.try_into().expect("chunk of N bytes")))
                .collect()
        }
        let le = little_endian;
        Ok(match ty {
            ScalarType::U8 => Samples::U8(Buffer::owned(bytes.to_vec())),
            ScalarType::U16 => Samples::U16(Buffer::owned(conv(bytes, |b| {
                if le {
                    u16::from_le_bytes(b)
                } else {
                    u16::from_be_bytes(b)
                }
            }))),
            ScalarType::I16 => Samples::I16(Buffer::owned(conv(bytes, |b| {
                if le {
                    i16::from_le_bytes(b)
                } else {
                    i16::from_be_bytes(b)
                }
            }))),
            ScalarType::F32 => Samples::F32(Buffer::owned(conv(bytes, |b| {
                if le {
                    f32::from_le_bytes(b)
                } else {
                    f32::from_be_bytes(b)
                }
            }))),
        })
    }
}
