//! Its own process (the memory budget is set once per process): a memory-mapped raw file
//! larger than the budget converts to an OME-Zarr store chunk by chunk, and a level larger
//! than the budget is refused when loaded whole.
#![cfg(feature = "zarr")]
use std::sync::Arc;

use volux_core::bricked::GridChunks;
use volux_core::grid::{Buffer, Grid, Samples};
use volux_io::omezarr::{open_store, write_ome_zarr, WriteOptions, ZarrOptions};
use volux_io::LoadOptions;

#[test]
fn a_mapped_raw_larger_than_the_budget_streams_into_a_store() {
    let tmp = tempfile::tempdir().unwrap();
    let n = 64;
    let values: Vec<f32> = (0..n * n * n).map(|i| (i % 1000) as f32).collect();
    let raw = tmp.path().join("big.raw");
    let grid = Grid::new(
        [n; 3],
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(values)),
    )
    .unwrap();
    volux_io::raw::write(&grid, &raw).unwrap();
    drop(grid);
    // The raw is 1 MiB; the budget a quarter of it.
    volux_core::limits::set_memory_budget(256 << 10).unwrap();
    let mapped = volux_io::raw::read(&raw).unwrap();
    assert!(mapped.samples().is_mapped());
    let out = tmp.path().join("big.ome.zarr");
    let src = GridChunks::new(Arc::new(mapped), [16; 3]).unwrap();
    let dims = write_ome_zarr(&src, &out, &WriteOptions::default()).unwrap();
    assert_eq!(dims, vec![[64; 3], [32; 3], [16; 3]]);
    let store = open_store(&out, &ZarrOptions::default()).unwrap();
    let c = store.multiscale.full().read_chunk([3, 3, 3]).unwrap();
    assert_eq!(c.len(), 16 * 16 * 16);
    assert_eq!(store.multiscale.full().value_range(), Some([0.0, 999.0]));
    // Level 0 (1 MiB) is over the budget; level 2 (16 KiB) loads.
    let e = volux_io::load(&out, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("level 1 fits") || e.contains("level 2 fits"),
        "{e}"
    );
    let opts = LoadOptions {
        level: Some(2),
        ..Default::default()
    };
    assert!(volux_io::load(&out, &opts).is_ok());
    // A mapped f32 file with a NaN would be copied: that copy is charged, and refused.
    let mut bytes = std::fs::read(&raw).unwrap();
    bytes[..4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(&raw, bytes).unwrap();
    let e = volux_io::raw::read(&raw).unwrap_err().to_string();
    assert!(e.contains("memory budget"), "{e}");
}
