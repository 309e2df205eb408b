//! Transfer syntaxes: names, which ones are read, and why the others are not.
/// Implicit VR little endian.
pub(super) const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
/// Explicit VR little endian.
pub(super) const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
/// Explicit VR big endian (retired).
pub(super) const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
/// Deflated explicit VR little endian: the data set (pixel data included, uncompressed) is a
/// deflate stream.
pub(super) const DEFLATED: &str = "1.2.840.10008.1.2.1.99";

/// A readable name for the transfer syntax `uid`.
pub(super) fn ts_name(uid: &str) -> &'static str {
    match uid {
        IMPLICIT_LE => "Implicit VR Little Endian",
        EXPLICIT_LE => "Explicit VR Little Endian",
        EXPLICIT_BE => "Explicit VR Big Endian",
        DEFLATED => "Deflated Explicit VR Little Endian",
        "1.2.840.10008.1.2.1.98" => "Encapsulated Uncompressed Explicit VR Little Endian",
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended",
        "1.2.840.10008.1.2.4.57" => "JPEG Lossless, non-hierarchical",
        "1.2.840.10008.1.2.4.70" => "JPEG Lossless, first-order prediction",
        "1.2.840.10008.1.2.4.80" => "JPEG-LS Lossless",
        "1.2.840.10008.1.2.4.81" => "JPEG-LS Lossy (near-lossless)",
        "1.2.840.10008.1.2.4.90" => "JPEG 2000 Lossless",
        "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.92" => "JPEG 2000 Part 2 Multi-component Lossless",
        "1.2.840.10008.1.2.4.93" => "JPEG 2000 Part 2 Multi-component",
        "1.2.840.10008.1.2.4.94" => "JPIP Referenced",
        "1.2.840.10008.1.2.4.95" => "JPIP Referenced Deflate",
        "1.2.840.10008.1.2.4.100"
        | "1.2.840.10008.1.2.4.101"
        | "1.2.840.10008.1.2.4.102"
        | "1.2.840.10008.1.2.4.103"
        | "1.2.840.10008.1.2.4.104"
        | "1.2.840.10008.1.2.4.105"
        | "1.2.840.10008.1.2.4.106"
        | "1.2.840.10008.1.2.4.107"
        | "1.2.840.10008.1.2.4.108" => "MPEG / H.264 / HEVC video",
        "1.2.840.10008.1.2.4.110" => "JPEG XL Lossless",
        "1.2.840.10008.1.2.4.111" => "JPEG XL JPEG Recompression",
        "1.2.840.10008.1.2.4.112" => "JPEG XL",
        HTJ2K_LOSSLESS => "High-Throughput JPEG 2000 Lossless",
        HTJ2K_RPCL => "High-Throughput JPEG 2000 with RPCL Options Lossless",
        HTJ2K => "High-Throughput JPEG 2000",
        "1.2.840.10008.1.2.4.204" => "JPIP HTJ2K Referenced",
        "1.2.840.10008.1.2.4.205" => "JPIP HTJ2K Referenced Deflate",
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        "1.2.840.10008.1.2.6.1" => "RFC 2557 MIME encapsulation",
        "1.2.840.10008.1.2.6.2" => "XML Encoding",
        "1.2.840.10008.1.2.7.1" | "1.2.840.10008.1.2.7.2" | "1.2.840.10008.1.2.7.3" => {
            "SMPTE ST 2110 video"
        }
        u if u.starts_with("1.2.840.10008.1.2.4.") => "JPEG (a retired process)",
        _ => "unknown",
    }
}

/// Whether the pixel data of the transfer syntax is uncompressed (native): the three
/// uncompressed syntaxes, and the deflated one (whose data set `dicom-object` inflates).
pub(super) fn is_native(ts: &str) -> bool {
    [IMPLICIT_LE, EXPLICIT_LE, EXPLICIT_BE, DEFLATED].contains(&ts)
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
/// High-Throughput JPEG 2000 Image Compression (Lossless Only).
pub(super) const HTJ2K_LOSSLESS: &str = "1.2.840.10008.1.2.4.201";
/// High-Throughput JPEG 2000 with RPCL Options Image Compression (Lossless Only).
pub(super) const HTJ2K_RPCL: &str = "1.2.840.10008.1.2.4.202";
/// High-Throughput JPEG 2000 Image Compression (lossy or lossless).
pub(super) const HTJ2K: &str = "1.2.840.10008.1.2.4.203";

/// The codestream family of a decoded transfer syntax.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Family {
    /// RLE Lossless (decoded here, module `codec`).
    Rle,
    /// JPEG (baseline, extended, lossless), through `jpeg-decoder`; 12-bit lossy frames
    /// through module `jpeg12`.
    Jpeg,
    /// JPEG-LS, through `pure_jpegls`.
    JpegLs,
    /// JPEG 2000 and High-Throughput JPEG 2000 (Part 15), through `openjp2`.
    Jpeg2000,
}

/// The codestream family of `ts`, if Volux decodes it.
pub(super) fn family(ts: &str) -> Option<Family> {
    match ts {
        RLE => Some(Family::Rle),
        JPEG_BASELINE | JPEG_EXTENDED | JPEG_LOSSLESS | JPEG_LOSSLESS_SV1 => Some(Family::Jpeg),
        JPEG_LS | JPEG_LS_NEAR => Some(Family::JpegLs),
        J2K_LOSSLESS | J2K | HTJ2K_LOSSLESS | HTJ2K_RPCL | HTJ2K => Some(Family::Jpeg2000),
        _ => None,
    }
}

/// Whether the transfer syntax is one this module decodes.
pub(super) fn decodes(ts: &str) -> bool {
    family(ts).is_some()
}

/// The BitsAllocated values read in transfer syntax `ts`: 1, 8, 16, 32 and 64 for uncompressed
/// pixel data (single bits; 64 for DoubleFloatPixelData), 8, 16 and 32 for RLE (one byte
/// plane per byte of a sample), 8 and 16 for the others.
pub(super) fn bits_read(ts: &str) -> &'static [u32] {
    if is_native(ts) {
        &[1, 8, 16, 32, 64]
    } else if ts == RLE {
        &[8, 16, 32]
    } else {
        &[8, 16]
    }
}

/// What Volux decodes, for the refusals.
const DECODED: &str = "Volux decodes uncompressed and deflated, RLE, JPEG (8- and 12-bit \
                       lossy, lossless), JPEG-LS, JPEG 2000 and High-Throughput JPEG 2000 pixel \
                       data";

/// Why a transfer syntax is not read; `None` for those that are. One line naming the
/// syntax's UID and name.
pub(super) fn unsupported(ts: &str) -> Option<String> {
    if decodes(ts) || is_native(ts) {
        return None;
    }
    let name = ts_name(ts);
    let why = match ts {
        "1.2.840.10008.1.2.4.92" | "1.2.840.10008.1.2.4.93" => {
            "the multi-component transforms of JPEG 2000 Part 2 are not decoded"
        }
        "1.2.840.10008.1.2.4.94"
        | "1.2.840.10008.1.2.4.95"
        | "1.2.840.10008.1.2.4.204"
        | "1.2.840.10008.1.2.4.205" => "the pixel data is not in the file but on a JPIP server",
        "1.2.840.10008.1.2.4.110" | "1.2.840.10008.1.2.4.111" | "1.2.840.10008.1.2.4.112" => {
            "no JPEG XL decoder is linked"
        }
        "1.2.840.10008.1.2.1.98" => "encapsulated uncompressed frames are not read",
        _ if name.contains("video") => "video is not a volume Volux reads",
        _ if name.starts_with("JPEG (a retired") => "the retired JPEG processes are not decoded",
        _ if name == "unknown" => "an unknown (private or newer) transfer syntax",
        _ => "not decoded",
    };
    Some(format!("transfer syntax {ts} ({name}): {why}; {DECODED}"))
}

/// The note a grid gets for a compressed transfer syntax.
pub(super) fn note(ts: &str) -> String {
    format!(
        "DICOM transfer syntax {ts} ({}), decoded with {}",
        ts_name(ts),
        match family(ts) {
            _ if ts == JPEG_EXTENDED => {
                "dicom-pixeldata (8-bit frames) or Volux's 12-bit JPEG decoder (12-bit frames)"
            }
            Some(Family::Rle) => "Volux's RLE decoder (PS3.5 Annex G)",
            Some(Family::JpegLs) => "pure_jpegls",
            _ => "dicom-pixeldata",
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_refusal_names_the_syntax_on_one_line() {
        for ts in [
            "1.2.840.10008.1.2.4.92",
            "1.2.840.10008.1.2.4.94",
            "1.2.840.10008.1.2.4.102",
            "1.2.840.10008.1.2.4.110",
            "1.2.840.10008.1.2.4.53",
            "1.2.840.10008.1.2.1.98",
            "1.2.3.4.5",
        ] {
            let m = unsupported(ts).unwrap();
            assert!(m.starts_with(&format!("transfer syntax {ts} (")), "{m}");
            assert!(!m.contains('\n'), "{m}");
        }
        for ts in [
            DEFLATED,
            RLE,
            JPEG_LS,
            JPEG_LS_NEAR,
            HTJ2K,
            J2K,
            EXPLICIT_BE,
        ] {
            assert_eq!(unsupported(ts), None, "{ts}");
        }
    }
}
