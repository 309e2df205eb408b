//! Small NIfTI-1 files written byte by byte, as nibabel writes them, for tests that need a
//! patient orientation.
use std::path::Path;

/// A NIfTI-1 `.nii` of int16 `dims` (x, y, z, t) with `pixdim` (x, y, z, t), `xyzt_units`
/// and an sform (`srow` rows), holding `data` (already little-endian).
pub fn nifti1(
    dims: [i16; 4],
    pixdim: [f32; 4],
    xyzt: u8,
    srow: [[f32; 4]; 3],
    data: &[u8],
) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let mut put = |at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(0, &348i32.to_le_bytes());
    let dim0: i16 = if dims[3] > 1 { 4 } else { 3 };
    for (i, d) in [dim0, dims[0], dims[1], dims[2], dims[3], 1, 1, 1]
        .iter()
        .enumerate()
    {
        put(40 + 2 * i, &d.to_le_bytes());
    }
    put(70, &4i16.to_le_bytes());
    put(72, &16i16.to_le_bytes());
    for (i, p) in [1.0f32, pixdim[0], pixdim[1], pixdim[2], pixdim[3]]
        .iter()
        .enumerate()
    {
        put(76 + 4 * i, &p.to_le_bytes());
    }
    put(108, &352f32.to_le_bytes());
    put(123, &[xyzt]);
    put(254, &1i16.to_le_bytes());
    for (r, row) in srow.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(280 + 16 * r + 4 * c, &v.to_le_bytes());
        }
    }
    put(344, b"n+1\0");
    h.extend_from_slice(data);
    h
}

/// Writes a 32^3 int16 head as nibabel stores it (RAS sform, i towards the patient's
/// right): a ball of 100 (radius 11) and a 4x5x5 block of 1000 outside it on the patient's
/// **left** (i in 1..5), at mid height and mid depth.
pub fn write_head_with_left_marker(path: &Path) {
    let n = 32i16;
    let c = (n as f32 - 1.0) / 2.0;
    let mut data = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let r2 = [i, j, k]
                    .map(|v| (v as f32 - c).powi(2))
                    .iter()
                    .sum::<f32>();
                // i small: x_RAS small, the patient's left (RAS +x is right).
                let marker = (1..5).contains(&i) && (j - 16).abs() < 3 && (k - 16).abs() < 3;
                let v: i16 = if marker {
                    1000
                } else if r2 < 11.0f32.powi(2) {
                    100
                } else {
                    0
                };
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let srow = [
        [1.0, 0.0, 0.0, -16.0],
        [0.0, 1.0, 0.0, -16.0],
        [0.0, 0.0, 1.0, -16.0],
    ];
    let bytes = nifti1([n, n, n, 1], [1.0, 1.0, 1.0, 0.0], 2, srow, &data);
    std::fs::write(path, bytes).expect("the test head is written");
}

/// A transfer function (Volux JSON) for [`write_head_with_left_marker`]: the head (0.1 of
/// the range) opaque grey, the marker (1.0) opaque red, the values between them (where the
/// marker meets the air) clear.
pub const MARKER_TF: &str = r#"{"space": "normalized",
    "color": [[0, 0.5, 0.5, 0.5], [0.5, 0.5, 0.5, 0.5], [0.6, 1, 0, 0], [1, 1, 0, 0]],
    "extinction": [[0, 0], [0.06, 0], [0.08, 5], [0.15, 5], [0.2, 0], [0.5, 0],
                   [0.6, 50], [1, 50]]}"#;
