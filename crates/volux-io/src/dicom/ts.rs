//! Transfer syntaxes: names, which ones are read, and why the others are not.
/// Implicit VR little endian.
pub(super) const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
/// Explicit VR little endian.
pub(super) const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
/// Explicit VR big endian (retired).
pub(super) const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";

/// A readable name for the transfer syntax `uid`.
pub(super) fn ts_name(uid: &str) -> &'static str {
    match uid {
        IMPLICIT_LE => "Implicit VR Little Endian",
        EXPLICIT_LE => "Explicit VR Little Endian",
        EXPLICIT_BE => "Explicit VR Big Endian",
        "1.2.840.10008.1.2.1.99" => "Deflated Explicit VR Little Endian",
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended",
        "1.2.840.10008.1.2.4.57" => "JPEG Lossless, non-hierarchical",
        "1.2.840.10008.1.2.4.70" => "JPEG Lossless, first-order prediction",
        "1.2.840.10008.1.2.4.80" => "JPEG-LS Lossless",
        "1.2.840.10008.1.2.4.81" => "JPEG-LS Lossy (near-lossless)",
        "1.2.840.10008.1.2.4.90" => "JPEG 2000 Lossless",
        "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.201" | "1.2.840.10008.1.2.4.202" | "1.2.840.10008.1.2.4.203" => {
            "High-Throughput JPEG 2000"
        }
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        _ => "compressed or unknown",
    }
}

/// Whether the transfer syntax is an uncompressed (native) one.
pub(super) fn is_native(ts: &str) -> bool {
    [IMPLICIT_LE, EXPLICIT_LE, EXPLICIT_BE].contains(&ts)
}

/// RLE Lossless.
pub(super) const RLE: &str = "1.2.840.10008.1.2.5";
/// JPEG Baseline (process 1), 8-bit lossy.
pub(super) const JPEG_BASELINE: &str = "1.2.840.10008.1.2.4.50";
/// JPEG Extended (processes 2 and 4), 8- or 12-bit lossy.
pub(super) const JPEG_EXTENDED: &str = "1.2.840.10008.1.2.4.51";
/// JPEG Lossless, non-hierarchical (process 14).
pub(super) const JPEG_LOSSLESS: &str = "1.2.840.10008.1.2.4.57";
/// JPEG Lossless, first-order prediction (process 14, selection value 1).
pub(super) const JPEG_LOSSLESS_SV1: &str = "1.2.840.10008.1.2.4.70";
/// JPEG-LS Lossless.
pub(super) const JPEG_LS: &str = "1.2.840.10008.1.2.4.80";
/// JPEG-LS Lossy (near-lossless).
pub(super) const JPEG_LS_NEAR: &str = "1.2.840.10008.1.2.4.81";
/// JPEG 2000 Image Compression (Lossless Only).
pub(super) const J2K_LOSSLESS: &str = "1.2.840.10008.1.2.4.90";
/// JPEG 2000 Image Compression (lossy or lossless).
pub(super) const J2K: &str = "1.2.840.10008.1.2.4.91";

/// The codestream family of a decoded transfer syntax.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Family {
    /// RLE Lossless.
    Rle,
    /// JPEG (baseline, extended, lossless).
    Jpeg,
    /// JPEG 2000.
    Jpeg2000,
}

/// The codestream family of `ts`, if Volux decodes it.
pub(super) fn family(ts: &str) -> Option<Family> {
    match ts {
        RLE => Some(Family::Rle),
        JPEG_BASELINE | JPEG_EXTENDED | JPEG_LOSSLESS | JPEG_LOSSLESS_SV1 => Some(Family::Jpeg),
        J2K_LOSSLESS | J2K => Some(Family::Jpeg2000),
        _ => None,
    }
}

/// Whether the transfer syntax is one this module decodes.
pub(super) fn decodes(ts: &str) -> bool {
    family(ts).is_some()
}

/// Why a compressed transfer syntax is not decoded; `None` for those that are.
pub(super) fn unsupported(ts: &str) -> Option<String> {
    if decodes(ts) {
        return None;
    }
    let name = ts_name(ts);
    Some(if ts == JPEG_LS || ts == JPEG_LS_NEAR {
        format!(
            "transfer syntax {ts} ({name}): no pure-Rust JPEG-LS decoder is linked \
             (dicom-pixeldata decodes JPEG-LS only through CharLS, a C++ library); Volux decodes \
             uncompressed, RLE, 8-bit lossy and lossless JPEG, and JPEG 2000 pixel data"
        )
    } else {
        format!(
            "transfer syntax {ts} ({name}): Volux decodes uncompressed, RLE, 8-bit lossy and \
             lossless JPEG, and JPEG 2000 pixel data"
        )
    })
}

/// The note a grid gets for a compressed transfer syntax.
pub(super) fn note(ts: &str) -> String {
    format!(
        "DICOM transfer syntax {ts} ({}), decoded with dicom-pixeldata",
        ts_name(ts)
    )
}
