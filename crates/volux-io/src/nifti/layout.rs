//! The byte layouts of the two NIfTI headers: NIfTI-1's 348 bytes (`nifti1.h`) and NIfTI-2's
//! 540 bytes (`nifti2.h`, <https://nifti.nimh.nih.gov/nifti-2>). NIfTI-2 holds the same fields
//! widened (`dim` as int64, `pixdim`, scaling and geometry as float64, the form codes as
//! int32) in another order, with its magic at byte 4. Both are read into one [`RawFields`]
//! (NIfTI-1's values widened exactly), which `header.rs` validates the same way. An Analyze
//! 7.5 header (Mayo Clinic's `dbh.h`, the 348 bytes NIfTI-1 grew from) has the same offsets
//! for the fields both hold; its `glmax`/`glmin` and `originator` (SPM's origin) are read too.

/// Size of a NIfTI-1 header.
pub(super) const NIFTI1_BYTES: usize = 348;
/// Size of a NIfTI-2 header.
pub(super) const NIFTI2_BYTES: usize = 540;

/// The header fields Volux uses, as stored (before validation).
#[derive(Clone, Debug)]
pub(super) struct RawFields {
    pub dim: [i64; 8],
    pub datatype: i16,
    pub bitpix: i16,
    pub pixdim: [f64; 8],
    pub vox_offset: f64,
    pub scl_slope: f64,
    pub scl_inter: f64,
    pub qform_code: i32,
    pub sform_code: i32,
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f64; 3],
    pub qoffset: [f64; 3],
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f64; 4]; 3],
    /// The first four bytes of the magic (`n+1\0`, `ni1\0`, `n+2\0`, `ni2\0`).
    pub magic: [u8; 4],
    /// NIfTI-2's magic bytes 4 to 7 (`\r\n\x1a\n`, to catch a file mangled by a text-mode
    /// transfer); `None` for NIfTI-1.
    pub signature: Option<[u8; 4]>,
    /// `intent_code`: what the values (and `dim[5]`) mean.
    pub intent_code: i32,
    /// `xyzt_units`: the spatial (bits 0-2) and temporal (bits 3-5) units.
    pub xyzt_units: i32,
    /// `cal_max`, `cal_min`: the display range (Analyze: SPM2's scaling fallback).
    pub cal: [f64; 2],
    /// Analyze 7.5 only (`dsr.dime`, NIfTI-1's `glmax`/`glmin`): the raw data range.
    pub gl: [i32; 2],
    /// Analyze 7.5 only (`dsr.hist.originator`, as SPM uses it): five int16, the first three
    /// the 1-based voxel at the origin.
    pub originator: [i16; 5],
}

/// Little/big-endian field access on header bytes. Callers pass slices at least as long as the
/// header whose constant offsets they read.
pub(super) struct Fields<'a> {
    b: &'a [u8],
    le: bool,
}

impl<'a> Fields<'a> {
    /// Fields of `b` in the byte order `le`.
    pub(super) fn new(b: &'a [u8], le: bool) -> Self {
        Self { b, le }
    }

    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.b.get(at..at + N) {
            out.copy_from_slice(s);
        }
        if !self.le {
            out.reverse();
        }
        out
    }
    fn raw<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.b.get(at..at + N) {
            out.copy_from_slice(s);
        }
        out
    }
    fn u8(&self, at: usize) -> u8 {
        self.b.get(at).copied().unwrap_or(0)
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.bytes(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.bytes(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.bytes(at))
    }
    fn f32(&self, at: usize) -> f64 {
        f64::from(f32::from_le_bytes(self.bytes(at)))
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.bytes(at))
    }
    fn f32s<const N: usize>(&self, at: usize) -> [f64; N] {
        std::array::from_fn(|i| self.f32(at + 4 * i))
    }
    fn f64s<const N: usize>(&self, at: usize) -> [f64; N] {
        std::array::from_fn(|i| self.f64(at + 8 * i))
    }

    /// The fields of a NIfTI-1 header (`nifti_1_header`).
    pub(super) fn nifti1(&self) -> RawFields {
        RawFields {
            dim: std::array::from_fn(|i| i64::from(self.i16(40 + 2 * i))),
            datatype: self.i16(70),
            bitpix: self.i16(72),
            pixdim: self.f32s(76),
            vox_offset: self.f32(108),
            scl_slope: self.f32(112),
            scl_inter: self.f32(116),
            qform_code: i32::from(self.i16(252)),
            sform_code: i32::from(self.i16(254)),
            quatern: self.f32s(256),
            qoffset: self.f32s(268),
            srow: [self.f32s(280), self.f32s(296), self.f32s(312)],
            magic: self.raw(344),
            signature: None,
            intent_code: i32::from(self.i16(68)),
            xyzt_units: i32::from(self.u8(123)),
            cal: [self.f32(124), self.f32(128)],
            gl: [self.i32(140), self.i32(144)],
            originator: std::array::from_fn(|i| self.i16(253 + 2 * i)),
        }
    }

    /// The fields of a NIfTI-2 header (`nifti_2_header`).
    pub(super) fn nifti2(&self) -> RawFields {
        RawFields {
            dim: std::array::from_fn(|i| self.i64(16 + 8 * i)),
            datatype: self.i16(12),
            bitpix: self.i16(14),
            pixdim: self.f64s(104),
            // int64 in the file; as f64 it is exact up to 2^53, far past any real offset
            // (larger ones are refused by the reader's bound on `vox_offset`).
            vox_offset: self.i64(168) as f64,
            scl_slope: self.f64(176),
            scl_inter: self.f64(184),
            qform_code: self.i32(344),
            sform_code: self.i32(348),
            quatern: self.f64s(352),
            qoffset: self.f64s(376),
            srow: [self.f64s(400), self.f64s(432), self.f64s(464)],
            magic: self.raw(4),
            signature: Some(self.raw(8)),
            intent_code: self.i32(504),
            xyzt_units: self.i32(500),
            cal: [self.f64(192), self.f64(200)],
            gl: [0, 0],
            originator: [0; 5],
        }
    }
}
