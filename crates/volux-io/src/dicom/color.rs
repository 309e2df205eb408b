//! Colour images (PS3.3 C.7.6.3.1.2): three samples per pixel, RGB or YBR_FULL /
//! YBR_FULL_422 (converted to RGB as pydicom's `convert_color_space` does), either
//! interleaved or plane after plane (PlanarConfiguration, C.7.6.3.1.3); and PALETTE COLOR
//! images (C.7.6.3.1.5, C.7.6.3.1.6), whose stored values index the red, green and blue
//! Palette Color LUTs. The result is the colour ([`Rgb`]) or, when one component is asked
//! for, that channel as a scalar.
use volux_core::color::Rgb;
use volux_core::{Buffer, Samples};

use super::lut::Lut;
use super::pixels::Fmt;
use super::values::sign_extend;

/// The colour of a grid, or one of its channels.
pub(super) enum Colour {
    /// Red, green and blue.
    Rgb(Rgb),
    /// The channel asked for.
    Channel(Samples),
}

/// Each frame's planes (RRR...GGG...BBB, PlanarConfiguration 1) interleaved (RGBRGB...);
/// `frame`: bytes of a frame, `size`: bytes of a sample.
pub(super) fn interleave(bytes: &[u8], frame: usize, size: usize) -> Vec<u8> {
    let plane = frame / 3;
    let mut out = Vec::with_capacity(bytes.len());
    for f in bytes.chunks(frame.max(1)) {
        let pixels = plane / size.max(1);
        for p in 0..pixels {
            for c in 0..3 {
                let at = c * plane + p * size;
                out.extend_from_slice(f.get(at..at + size).unwrap_or(&[]));
            }
        }
    }
    out
}

/// 8-bit YBR_FULL_422 samples (Y1 Y2 Cb Cr for two pixels) expanded to YBR_FULL (Y Cb Cr
/// for each), as pydicom's `expand_ybr422`.
pub(super) fn expand_422(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len() / 2 * 3);
    for q in bytes.chunks_exact(4) {
        out.extend_from_slice(&[q[0], q[2], q[3], q[1], q[2], q[3]]);
    }
    out
}

/// 8-bit YBR_FULL samples converted to RGB in place (PS3.3 C.7.6.3.1.2; ITU-T T.871) with
/// pydicom's float32 arithmetic: the matrix product in fused multiply-adds (as its BLAS
/// computes it), rounded half up and clipped to 0..255.
pub(super) fn ybr_to_rgb(bytes: &mut [u8]) {
    // Columns of pydicom's YBR-to-RGB matrix, each coefficient rounded to float32.
    let m: [[f32; 3]; 3] = [
        [1.0, 0.0, 1.402],
        [
            1.0,
            (-0.114 * 1.772 / 0.587) as f32,
            (-0.299 * 1.402 / 0.587) as f32,
        ],
        [1.0, 1.772, 0.0],
    ];
    for px in bytes.chunks_exact_mut(3) {
        let y = f32::from(px[0]);
        let cb = f32::from(px[1]) - 128.0;
        let cr = f32::from(px[2]) - 128.0;
        for (c, k) in m.iter().enumerate() {
            let v = cr.mul_add(k[2], cb.mul_add(k[1], y * k[0]));
            px[c] = (v + 0.5).floor().clamp(0.0, 255.0) as u8;
        }
    }
}

/// Splits interleaved three-sample pixels into the colour, or the channel `component`:
/// 8-bit as uint8, 16-bit as uint16 (int16 when signed), 32-bit integers converted to
/// float32 (noted).
pub(super) fn channels(
    bytes: &[u8],
    fmt: Fmt,
    bits_stored: u32,
    component: Option<usize>,
    notes: &mut Vec<String>,
) -> Result<Colour, volux_core::Error> {
    let bytes = &*sign_extend(bytes, fmt, bits_stored);
    let n = bytes.len() / fmt.size() / 3;
    let channel = |c: usize| -> Samples {
        let at = |i: usize| 3 * i + c;
        match fmt {
            Fmt::U8 => Samples::U8(Buffer::owned((0..n).map(|i| bytes[at(i)]).collect())),
            Fmt::U16 => Samples::U16(Buffer::owned(
                (0..n).map(|i| fmt.get(bytes, at(i)) as u16).collect(),
            )),
            Fmt::I8 | Fmt::I16 => Samples::I16(Buffer::owned(
                (0..n).map(|i| fmt.get(bytes, at(i)) as i16).collect(),
            )),
            _ => Samples::F32(Buffer::owned(
                (0..n).map(|i| fmt.get(bytes, at(i)) as f32).collect(),
            )),
        }
    };
    match fmt {
        Fmt::U32 | Fmt::I32 => notes.push(format!(
            "32-bit {} colour samples converted to float32",
            if fmt == Fmt::I32 {
                "signed"
            } else {
                "unsigned"
            }
        )),
        Fmt::I8 => notes.push("signed 8-bit colour samples widened to int16".into()),
        _ => {}
    }
    pick(channel, component)
}

/// The colour of PALETTE COLOR pixels: each stored value (sign-extended from BitsStored)
/// looked up in the three LUTs, whose entries are kept (uint8 or uint16, as pydicom's
/// `apply_color_lut` returns them).
pub(super) fn palette(
    bytes: &[u8],
    fmt: Fmt,
    bits_stored: u32,
    luts: &[Lut; 3],
    component: Option<usize>,
    notes: &mut Vec<String>,
) -> Result<Colour, volux_core::Error> {
    let bytes = &*sign_extend(bytes, fmt, bits_stored);
    let n = bytes.len() / fmt.size();
    let bits8 = luts.iter().all(|l| l.bits8);
    notes.push(format!(
        "PALETTE COLOR: the stored values looked up in the red, green and blue palette \
         (Palette Color LUTs of {} entries from stored value {}, {}-bit entries)",
        luts[0].entries.len(),
        luts[0].first,
        if bits8 { 8 } else { 16 }
    ));
    let channel = |c: usize| -> Samples {
        let l = &luts[c];
        let v = (0..n).map(|i| l.map(fmt.get(bytes, i) as i64));
        if bits8 {
            Samples::U8(Buffer::owned(v.map(|x| x as u8).collect()))
        } else {
            Samples::U16(Buffer::owned(v.collect()))
        }
    };
    pick(channel, component)
}

/// The three channels, or the one asked for.
fn pick(
    channel: impl Fn(usize) -> Samples,
    component: Option<usize>,
) -> Result<Colour, volux_core::Error> {
    match component {
        Some(c) => {
            volux_core::volume_axes::choose("component", c, 3)?;
            Ok(Colour::Channel(channel(c)))
        }
        None => Ok(Colour::Rgb(Rgb::new([channel(0), channel(1), channel(2)])?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planes_are_interleaved_per_frame() {
        // Two frames of two pixels.
        let planar = [1, 2, 10, 20, 100, 200, 3, 4, 30, 40, 150, 250];
        assert_eq!(
            interleave(&planar, 6, 1),
            [1, 10, 100, 2, 20, 200, 3, 30, 150, 4, 40, 250]
        );
        let w: Vec<u8> = [1u16, 2, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(interleave(&w, 6, 2), w);
    }

    #[test]
    fn ybr_full_422_expands_and_converts_as_pydicom() {
        assert_eq!(
            expand_422(&[10, 20, 128, 128]),
            [10, 128, 128, 20, 128, 128]
        );
        // Values pydicom 3.0 gives (convert_color_space YBR_FULL -> RGB).
        let mut px = [
            76, 85, 255, // red
            150, 44, 21, // green
            29, 255, 107, // blue
            128, 128, 128, // grey
            0, 0, 0, 255, 255, 255,
        ];
        ybr_to_rgb(&mut px);
        assert_eq!(
            px,
            [254, 0, 0, 0, 255, 1, 0, 0, 254, 128, 128, 128, 0, 135, 0, 255, 121, 255]
        );
    }
}
