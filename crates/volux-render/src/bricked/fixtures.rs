//! The small volume the bricked and distributed tests render: odd sizes not divisible by the
//! chunk, anisotropic spacing, an offset origin, structure in every brick, and its TF.
use volux_core::grid::{Buffer, Samples};
use volux_core::{Grid, TransferFunction};

/// Samples per axis of [`grid`].
pub(crate) const DIMS: [usize; 3] = [23, 17, 13];
/// Its chunk shape (no axis divides evenly).
pub(crate) const CHUNK: [usize; 3] = [8, 5, 4];

/// A smooth field with structure in every brick, anisotropic spacing, an offset origin.
pub(crate) fn grid() -> Grid {
    let [nx, ny, nz] = DIMS;
    let mut v = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let (x, y, z) = (i as f32 / 22.0, j as f32 / 16.0, k as f32 / 12.0);
                let r = ((x - 0.5).powi(2) + (y - 0.45).powi(2) + (z - 0.55).powi(2)).sqrt();
                v.push(100.0 * (1.0 - r) + 20.0 * (7.0 * x).sin() * (5.0 * y).cos());
            }
        }
    }
    Grid::new(
        DIMS,
        [0.8, 1.1, 1.7],
        [-3.0, 2.0, 5.0],
        Samples::F32(Buffer::owned(v)),
    )
    .unwrap()
}

/// A TF with transparent and opaque ranges over [`grid`]'s values.
pub(crate) fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"color": [[40,0.2,0.4,1],[70,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[40,0],[60,0.08],[75,0.3],[90,0.05],[110,0.4]]}"#,
    )
    .unwrap()
}
