//! 12-bit lossy JPEG (ITU-T T.81 extended sequential DCT, Huffman coded, SOF0 / SOF1 of
//! precision 12), single-component: the frames of DICOM's JPEG Extended transfer syntax
//! (1.2.840.10008.1.2.4.51) at 12 bits, which `jpeg-decoder` and `zune-jpeg` do not decode.
//!
//! A small decoder written for hostile input: every table and marker segment is checked
//! against its length, Huffman tables against the code space (Kraft), coefficient indices
//! against the block, and the image size against Rows / Columns before anything is
//! allocated. Entropy-coded data that ends before the last block, or a scan not followed by
//! EOI, is an error (libjpeg would pad with zero bits and warn). The inverse DCT is the
//! separable floating-point one of T.81 A.3.3; results are rounded and clamped to 0..4095, so
//! they may differ from libjpeg's integer IDCT by 1.

/// Zig-zag order: the natural (row-major) index of the k-th coefficient.
const ZIGZAG: [usize; 64] = [
    0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34, 27, 20,
    13, 6, 7, 14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51, 58, 59,
    52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63,
];

/// A Huffman table in the form of T.81 F.2.2.3 (MAXCODE, VALPTR, MINCODE per length).
#[derive(Clone, Default)]
struct Huffman {
    maxcode: [i32; 17],
    valptr: [usize; 17],
    mincode: [i32; 17],
    values: Vec<u8>,
}

impl Huffman {
    /// Builds the table from the 16 code counts and the symbols; `None` when the counts
    /// overflow the code space.
    fn new(counts: &[u8], values: &[u8]) -> Option<Self> {
        let mut h = Self {
            values: values.to_vec(),
            ..Self::default()
        };
        let (mut code, mut k) = (0i32, 0usize);
        for len in 1..=16 {
            let n = usize::from(counts[len - 1]);
            h.valptr[len] = k;
            h.mincode[len] = code;
            code += n as i32;
            k += n;
            if code > (1 << len) {
                return None;
            }
            h.maxcode[len] = if n == 0 { -1 } else { code - 1 };
            code <<= 1;
        }
        (k == values.len()).then_some(h)
    }
}

/// Bits of the entropy-coded data, with byte stuffing (FF 00) removed; a marker ends them.
struct Bits<'a> {
    data: &'a [u8],
    at: usize,
    acc: u32,
    n: u32,
    /// Zero bits supplied past the end of the data (or a marker).
    padded: u32,
}

impl Bits<'_> {
    fn bit(&mut self) -> u32 {
        if self.n == 0 {
            let b = match (self.data.get(self.at), self.data.get(self.at + 1)) {
                (Some(0xFF), Some(0x00)) => {
                    self.at += 2;
                    0xFF
                }
                (Some(0xFF), _) | (None, _) => {
                    self.padded += 8;
                    0
                }
                (Some(&b), _) => {
                    self.at += 1;
                    b
                }
            };
            self.acc = u32::from(b);
            self.n = 8;
        }
        self.n -= 1;
        (self.acc >> self.n) & 1
    }

    fn bits(&mut self, s: u32) -> i32 {
        (0..s).fold(0i32, |v, _| (v << 1) | self.bit() as i32)
    }

    fn decode(&mut self, h: &Huffman) -> Result<u8, String> {
        let mut code = 0i32;
        for len in 1..=16 {
            code = (code << 1) | self.bit() as i32;
            if code <= h.maxcode[len] {
                return usize::try_from(code - h.mincode[len])
                    .ok()
                    .and_then(|d| d.checked_add(h.valptr[len]))
                    .and_then(|i| h.values.get(i).copied())
                    .ok_or_else(|| "a bad Huffman code".into());
            }
        }
        Err("a Huffman code longer than 16 bits".into())
    }

    /// T.81 F.2.2.1 EXTEND of an `s`-bit magnitude.
    fn receive_extend(&mut self, s: u8) -> i32 {
        if s == 0 {
            return 0;
        }
        let v = self.bits(u32::from(s));
        if v < 1 << (s - 1) {
            v - (1 << s) + 1
        } else {
            v
        }
    }

    /// Skips to the byte after the next RSTn marker (a restart interval's end).
    fn restart(&mut self) -> Result<(), String> {
        self.n = 0;
        while let Some(&b) = self.data.get(self.at) {
            if b == 0xFF {
                if let Some(0xD0..=0xD7) = self.data.get(self.at + 1) {
                    self.at += 2;
                    return Ok(());
                }
                if self.data.get(self.at + 1) != Some(&0) {
                    break;
                }
            }
            self.at += 1;
        }
        Err("a restart marker (RSTn) is missing".into())
    }
}

/// The 8 x 8 inverse DCT (T.81 A.3.3), separable, in floating point.
fn idct(coef: &[f32; 64], out: &mut [f32; 64]) {
    let c = |u: usize, x: usize| {
        let cu = if u == 0 {
            std::f32::consts::FRAC_1_SQRT_2
        } else {
            1.0
        };
        cu * (((2 * x + 1) as f32 * u as f32 * std::f32::consts::PI) / 16.0).cos()
    };
    let mut table = [[0f32; 8]; 8];
    for (u, row) in table.iter_mut().enumerate() {
        for (x, v) in row.iter_mut().enumerate() {
            *v = c(u, x);
        }
    }
    let mut tmp = [0f32; 64];
    for y in 0..8 {
        for u in 0..8 {
            tmp[y * 8 + u] = (0..8).map(|v| table[v][y] * coef[v * 8 + u]).sum::<f32>() / 2.0;
        }
    }
    for y in 0..8 {
        for x in 0..8 {
            out[y * 8 + x] = (0..8).map(|u| table[u][x] * tmp[y * 8 + u]).sum::<f32>() / 2.0;
        }
    }
}

/// A big-endian 16-bit field.
fn be16(d: &[u8], i: usize) -> Option<usize> {
    d.get(i..i + 2)
        .map(|b| usize::from(u16::from_be_bytes([b[0], b[1]])))
}

/// Decodes a 12-bit, single-component, Huffman-coded sequential DCT JPEG of `cols` x
/// `rows` samples to 12-bit values (0..4095), row by row.
pub(super) fn decode(data: &[u8], rows: u32, cols: u32) -> Result<Vec<u16>, String> {
    if data.get(..2) != Some(&[0xFF, 0xD8][..]) {
        return Err("no SOI marker".into());
    }
    let short = || "a marker segment is cut short".to_string();
    let mut qt = [[0u16; 64]; 4];
    let (mut dc, mut ac) = (vec![None; 4], vec![None; 4]);
    let (mut frame, mut restart) = (None, 0usize);
    let mut at = 2usize;
    loop {
        while data.get(at) == Some(&0xFF) && data.get(at + 1) == Some(&0xFF) {
            at += 1;
        }
        let (Some(&0xFF), Some(&m)) = (data.get(at), data.get(at + 1)) else {
            return Err(format!("no marker at byte {at}"));
        };
        let len = be16(data, at + 2).ok_or_else(short)?;
        let seg = data
            .get(at + 4..(at + 2 + len).max(at + 4))
            .filter(|_| len >= 2)
            .ok_or_else(short)?;
        match m {
            0xDB => {
                let mut i = 0;
                while i < seg.len() {
                    let (pq, tq) = (seg[i] >> 4, usize::from(seg[i] & 15));
                    let t = qt.get_mut(tq).ok_or("a quantisation table id over 3")?;
                    let w = if pq == 0 { 1 } else { 2 };
                    let v = seg.get(i + 1..i + 1 + 64 * w).ok_or_else(short)?;
                    for (k, q) in t.iter_mut().enumerate() {
                        *q = if w == 1 {
                            u16::from(v[k])
                        } else {
                            u16::from_be_bytes([v[2 * k], v[2 * k + 1]])
                        };
                    }
                    i += 1 + 64 * w;
                }
            }
            0xC4 => {
                let mut i = 0;
                while i < seg.len() {
                    let (tc, th) = (seg[i] >> 4, usize::from(seg[i] & 15));
                    let counts = seg.get(i + 1..i + 17).ok_or_else(short)?;
                    let n: usize = counts.iter().map(|&c| usize::from(c)).sum();
                    let values = seg.get(i + 17..i + 17 + n).ok_or_else(short)?;
                    let h = Huffman::new(counts, values).ok_or("a Huffman table overflows")?;
                    let slot = match tc {
                        0 => dc.get_mut(th),
                        1 => ac.get_mut(th),
                        _ => None,
                    }
                    .ok_or("a Huffman table class or id out of range")?;
                    *slot = Some(h);
                    i += 17 + n;
                }
            }
            0xC0 | 0xC1 => {
                let p = seg.first().copied().ok_or_else(short)?;
                let y = be16(seg, 1).ok_or_else(short)?;
                let x = be16(seg, 3).ok_or_else(short)?;
                let nf = seg.get(5).copied().ok_or_else(short)?;
                let tq = seg.get(8).copied().ok_or_else(short)?;
                if p != 12 || nf != 1 {
                    return Err(format!(
                        "a {p}-bit frame of {nf} components (this decoder reads 12-bit grey)"
                    ));
                }
                if (y, x) != (rows as usize, cols as usize) {
                    return Err(format!("the frame is {x} x {y}, not {cols} x {rows}"));
                }
                frame = Some(usize::from(tq & 3));
            }
            0xC2 | 0xC3 | 0xC5..=0xC7 | 0xC9..=0xCB | 0xCD..=0xCF => {
                return Err(format!(
                    "a frame of marker {m:02X} (progressive, lossless, hierarchical or \
                     arithmetic-coded) is not a 12-bit sequential one"
                ));
            }
            0xDD => restart = be16(seg, 0).ok_or_else(short)?,
            0xDA => {
                let tq = frame.ok_or("the scan comes before the frame header")?;
                let ns = seg.first().copied().ok_or_else(short)?;
                let t = seg.get(2).copied().ok_or_else(short)?;
                if ns != 1 {
                    return Err(format!("a scan of {ns} components"));
                }
                let field = |i: usize| seg.get(i).copied().ok_or_else(short);
                let (ss, se, a) = (field(3)?, field(4)?, field(5)?);
                if (ss, se, a) != (0, 63, 0) {
                    return Err(format!(
                        "a scan of spectral selection {ss}..{se} and approximation {a:02X}: a \
                         sequential scan has 0..63 and 00"
                    ));
                }
                let dc = dc[usize::from(t >> 4) & 3]
                    .clone()
                    .ok_or("no DC Huffman table")?;
                let ac = ac[usize::from(t & 15) & 3]
                    .clone()
                    .ok_or("no AC Huffman table")?;
                let q = qt[tq];
                return scan(&data[at + 2 + len..], (rows, cols), &q, (&dc, &ac), restart);
            }
            0xD9 => return Err("the data ends (EOI) before its scan".into()),
            _ => {}
        }
        at += 2 + len;
    }
}

/// Decodes the entropy-coded data of the one scan.
fn scan(
    data: &[u8],
    (rows, cols): (u32, u32),
    q: &[u16; 64],
    (dc, ac): (&Huffman, &Huffman),
    restart: usize,
) -> Result<Vec<u16>, String> {
    let (w, h) = (cols as usize, rows as usize);
    let (bw, bh) = (w.div_ceil(8), h.div_ceil(8));
    let mut out = vec![0u16; w * h];
    let mut bits = Bits {
        data,
        at: 0,
        acc: 0,
        n: 0,
        padded: 0,
    };
    let mut pred = 0i32;
    let (mut coef, mut px) = ([0f32; 64], [0f32; 64]);
    for b in 0..bw * bh {
        if restart > 0 && b > 0 && b % restart == 0 {
            bits.restart()?;
            pred = 0;
        }
        coef.fill(0.0);
        let t = bits.decode(dc)?;
        if t > 16 {
            return Err(format!("a DC difference of category {t}"));
        }
        pred = pred.saturating_add(bits.receive_extend(t));
        coef[0] = pred as f32 * f32::from(q[0]);
        let mut k = 1;
        while k < 64 {
            let rs = bits.decode(ac)?;
            let (r, s) = (usize::from(rs >> 4), rs & 15);
            if s == 0 {
                if r != 15 {
                    break;
                }
                k += 16;
                continue;
            }
            k += r;
            if k > 63 {
                return Err("an AC coefficient past the block".into());
            }
            coef[ZIGZAG[k]] = bits.receive_extend(s) as f32 * f32::from(q[k]);
            k += 1;
        }
        if bits.padded > 0 {
            return Err("the entropy-coded data ends early".into());
        }
        idct(&coef, &mut px);
        let (bx, by) = (b % bw * 8, b / bw * 8);
        for y in 0..8 {
            for x in 0..8 {
                if by + y < h && bx + x < w {
                    let v = (px[y * 8 + x] + 2048.0).round().clamp(0.0, 4095.0);
                    out[(by + y) * w + bx + x] = v as u16;
                }
            }
        }
    }
    // The scan ends with the image (EOI), possibly after fill bytes.
    let rest = data.get(bits.at..).unwrap_or(&[]);
    let fill = rest.iter().take_while(|&&b| b == 0xFF).count();
    if fill == 0 || rest.get(fill) != Some(&0xD9) {
        return Err("the entropy-coded data does not end with an EOI marker".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dicom_core::value::Value;
    use dicom_dictionary_std::tags;

    /// The first frame of the committed 12-bit fixture (libjpeg-turbo 3, quality 90).
    fn frame() -> Vec<u8> {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/dicom_compressed/emri_jpeg51_12bit.dcm");
        let obj = dicom_object::open_file(p).unwrap();
        match obj.element(tags::PIXEL_DATA).unwrap().value() {
            Value::PixelSequence(s) => s.fragments()[0].to_vec(),
            _ => panic!("not encapsulated"),
        }
    }

    #[test]
    fn decodes_and_refuses_cut_or_mislabelled_frames() {
        let f = frame();
        let v = decode(&f, 32, 32).unwrap();
        assert_eq!(v.len(), 32 * 32);
        assert!(v.iter().any(|&x| x > 255) && v.iter().all(|&x| x < 4096));
        assert!(decode(&f, 32, 31)
            .unwrap_err()
            .contains("32 x 32, not 31 x 32"));
        for n in [0, 2, 20, f.len() / 2, f.len() - 2] {
            assert!(decode(&f[..n], 32, 32).is_err(), "{n}");
        }
    }

    /// Thousands of damaged frames (bytes replaced, a fixed seed; overflow checks on in
    /// tests): each decodes or is refused, never a panic.
    #[test]
    fn damaged_frames_never_panic() {
        let f = frame();
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize
        };
        let mut ok = 0;
        for i in 0..4000 {
            let mut m = f.clone();
            for _ in 0..1 + next() % 3 {
                let at = if i % 2 == 0 {
                    next() % 700.min(m.len())
                } else {
                    next() % m.len()
                };
                m[at] = next() as u8;
            }
            if i % 7 == 0 {
                m.truncate(next() % m.len());
            }
            ok += usize::from(decode(&m, 32, 32).is_ok());
        }
        eprintln!("4000 damaged frames: {ok} decoded");
    }
}
