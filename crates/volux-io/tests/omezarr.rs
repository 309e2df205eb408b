//! OME-Zarr stores: the committed ome-zarr-py fixtures, write -> read round trips, the
//! pyramid's averages, and damaged stores (each one clear error, no panic).
#![cfg(feature = "zarr")]
use std::path::{Path, PathBuf};
use std::sync::Arc;

use volux_core::bricked::{ChunkSource, GridChunks};
use volux_core::grid::{Buffer, Grid, Samples};
use volux_io::omezarr::{
    open_store, write_ome_zarr, Compression, Levels, WriteOptions, ZarrOptions,
};
use volux_io::{Dataset, LoadOptions};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Every sample of a level, x fastest, as f64.
fn read_level(level: &dyn ChunkSource) -> Vec<f64> {
    let l = level.layout().clone();
    let mut out = vec![f64::NAN; l.dims.iter().product()];
    for i in 0..l.chunk_count() {
        let c = l.chunk_coords(i);
        let (lo, size) = l.chunk_extent(c);
        let s = level.read_chunk(c).unwrap();
        assert_eq!(s.len(), size.iter().product::<usize>());
        for n in 0..s.len() {
            let (x, y, z) = (
                n % size[0],
                (n / size[0]) % size[1],
                n / (size[0] * size[1]),
            );
            out[lo[0] + x + l.dims[0] * (lo[1] + y + l.dims[1] * (lo[2] + z))] =
                s.get_f32(n) as f64;
        }
    }
    out
}

#[test]
fn ome_zarr_py_fixtures_read_with_the_formula_spacing_and_origin() {
    for (name, format) in [("tiny_v04.ome.zarr", 2), ("tiny_v05.ome.zarr", 3)] {
        let store = open_store(&data(name), &ZarrOptions::default()).unwrap();
        assert_eq!(store.zarr_format, format, "{name}");
        assert_eq!(store.unit_words(), "micrometer");
        let levels = store.multiscale.levels();
        assert_eq!(levels.len(), 2);
        let l0 = levels[0].layout();
        assert_eq!(l0.dims, [9, 7, 5]);
        assert_eq!(l0.chunk, [4, 3, 2]);
        assert_eq!(l0.spacing, [0.25, 0.5, 2.5]);
        assert_eq!(l0.origin, [30.0, 20.0, 10.0]);
        assert_eq!(l0.scalar, volux_core::grid::ScalarType::U16);
        let v = read_level(levels[0].as_ref());
        for z in 0..5 {
            for y in 0..7 {
                for x in 0..9 {
                    assert_eq!(v[x + 9 * (y + 7 * z)], (x + 10 * y + 100 * z) as f64);
                }
            }
        }
        assert_eq!(levels[1].layout().dims, [5, 4, 3]);
        assert_eq!(levels[1].layout().spacing, [0.5, 1.0, 5.0]);
        let v1 = read_level(levels[1].as_ref());
        // (x, y, z) = (1, 2, 1) of level 1 is (2, 4, 2) of level 0.
        assert_eq!(v1[1 + 5 * (2 + 4)], (2 + 40 + 200) as f64);
        // Foreign stores carry no ranges, nor a histogram.
        assert_eq!(levels[0].chunk_range([0, 0, 0]), None);
        assert_eq!(levels[0].value_histogram(), None);
        // Through the loader, as an in-core grid, at either level.
        let (d, f) = volux_io::load(&data(name), &LoadOptions::default()).unwrap();
        assert_eq!(f, volux_io::Format::OmeZarr);
        let Dataset::Grid(g) = d else { panic!("grid") };
        assert_eq!(g.dims(), [9, 7, 5]);
        assert_eq!(g.value(8, 6, 4), 468.0);
        assert_eq!(g.origin().to_array(), [30.0, 20.0, 10.0]);
        let opts = LoadOptions {
            level: Some(1),
            ..Default::default()
        };
        let (Dataset::Grid(g1), _) = volux_io::load(&data(name), &opts).unwrap() else {
            panic!("grid")
        };
        assert_eq!(g1.dims(), [5, 4, 3]);
        let opts = LoadOptions {
            level: Some(2),
            ..Default::default()
        };
        let e = volux_io::load(&data(name), &opts).unwrap_err().to_string();
        assert!(e.contains("level 2 does not exist"), "{e}");
    }
}

fn lcg(seed: u64, n: usize) -> Vec<f32> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) % 1000) as f32
        })
        .collect()
}

fn grid(dims: [usize; 3], samples: Samples) -> Grid {
    Grid::new(dims, [0.3, 1.25, 2.0], [1.0, -2.0, 3.5], samples).unwrap()
}

fn write(
    g: Grid,
    chunk: [usize; 3],
    dir: &Path,
    levels: Levels,
    compression: Compression,
) -> PathBuf {
    let out = dir.join("v.ome.zarr");
    let src = GridChunks::new(Arc::new(g), chunk).unwrap();
    let opts = WriteOptions {
        levels,
        compression,
        name: "test".into(),
        unit: Some("millimeter".into()),
    };
    write_ome_zarr(&src, &out, &opts).unwrap();
    out
}

#[test]
fn round_trip_of_odd_anisotropic_volumes_equals_the_source() {
    let dims = [11, 6, 5];
    let n = 11 * 6 * 5;
    let values = lcg(7, n);
    for (samples, compression) in [
        (
            Samples::F32(Buffer::owned(values.clone())),
            Compression::Zstd(3),
        ),
        (
            Samples::U16(Buffer::owned(
                values.iter().map(|&v| v as u16 * 60).collect(),
            )),
            Compression::BloscZstd(5),
        ),
        (
            Samples::I16(Buffer::owned(
                values.iter().map(|&v| v as i16 - 500).collect(),
            )),
            Compression::None,
        ),
        (
            Samples::U8(Buffer::owned(
                values.iter().map(|&v| (v as u32 % 256) as u8).collect(),
            )),
            Compression::Gzip(6),
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let g = grid(dims, samples);
        let out = write(g.clone(), [4, 4, 2], tmp.path(), Levels::Auto, compression);
        let store = open_store(&out, &ZarrOptions::default()).unwrap();
        assert_eq!(store.unit_words(), "millimeter");
        let l0 = store.multiscale.full();
        assert_eq!(l0.layout().dims, dims);
        assert_eq!(l0.layout().chunk, [4, 4, 2]);
        assert_eq!(l0.layout().spacing, [0.3, 1.25, 2.0]);
        assert_eq!(l0.layout().origin, [1.0, -2.0, 3.5]);
        assert_eq!(l0.layout().scalar, g.scalar_type());
        let v = read_level(l0.as_ref());
        for (i, x) in v.iter().enumerate() {
            assert_eq!(*x, g.samples().get_f32(i) as f64);
        }
        assert_eq!(l0.value_range(), Some(g.range()));
        // The full level's histogram is recorded: the in-core grid's, bin for bin; coarser
        // levels record none.
        assert_eq!(
            l0.value_histogram(),
            Some(volux_core::histogram::Histogram::of_grid(
                &g,
                volux_core::histogram::STORED_BINS
            ))
        );
        assert_eq!(store.multiscale.levels()[1].value_histogram(), None);
        // Per-chunk ranges are those of the chunk's samples.
        let c = [2, 1, 2];
        let s = l0.read_chunk(c).unwrap();
        let lo = (0..s.len())
            .map(|i| s.get_f32(i) as f64)
            .fold(f64::INFINITY, f64::min);
        let hi = (0..s.len())
            .map(|i| s.get_f32(i) as f64)
            .fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(l0.chunk_range(c), Some([lo, hi]));
        // Auto levels: 11x6x5 -> 6x3x3 -> 3x2x2 (fits one 4x4x2 chunk? no: z 2 fits, x 3 fits).
        let dims: Vec<_> = store
            .multiscale
            .levels()
            .iter()
            .map(|l| l.layout().dims)
            .collect();
        assert_eq!(dims, vec![[11, 6, 5], [6, 3, 3], [3, 2, 2]]);
        let l1 = store.multiscale.levels()[1].layout();
        assert_eq!(l1.spacing, [0.6, 2.5, 4.0]);
        assert_eq!(l1.origin, [1.15, -1.375, 4.5]);
        // Loaded whole through the loader: the same grid.
        let (Dataset::Grid(back), _) = volux_io::load(&out, &LoadOptions::default()).unwrap()
        else {
            panic!("grid")
        };
        assert_eq!(back.to_f32_vec().unwrap(), g.to_f32_vec().unwrap());
    }
}

/// The 2x average of `v` (`dims`, x fastest): odd axes average what exists.
fn brute_halve(v: &[f64], d: [usize; 3]) -> (Vec<f64>, [usize; 3]) {
    let o = d.map(|x| x.div_ceil(2));
    let mut out = vec![0.0; o.iter().product()];
    for k in 0..o[2] {
        for j in 0..o[1] {
            for i in 0..o[0] {
                let mut vals = vec![];
                for z in [2 * k, 2 * k + 1] {
                    for y in [2 * j, 2 * j + 1] {
                        for x in [2 * i, 2 * i + 1] {
                            if x < d[0] && y < d[1] && z < d[2] {
                                vals.push(v[x + d[0] * (y + d[1] * z)]);
                            }
                        }
                    }
                }
                out[i + o[0] * (j + o[1] * k)] = vals.iter().sum::<f64>() / vals.len() as f64;
            }
        }
    }
    (out, o)
}

#[test]
fn pyramid_levels_equal_a_brute_force_2x_average() {
    let dims = [13, 9, 7];
    let values = lcg(3, 13 * 9 * 7);
    let g = grid(dims, Samples::F32(Buffer::owned(values)));
    let tmp = tempfile::tempdir().unwrap();
    let out = write(
        g.clone(),
        [4, 4, 4],
        tmp.path(),
        Levels::Count(4),
        Compression::Zstd(3),
    );
    let store = open_store(&out, &ZarrOptions::default()).unwrap();
    let levels = store.multiscale.levels();
    assert_eq!(levels.len(), 4);
    let (mut expect, mut d) = (
        g.to_f32_vec()
            .unwrap()
            .iter()
            .map(|&v| v as f64)
            .collect::<Vec<_>>(),
        dims,
    );
    for (k, level) in levels.iter().enumerate() {
        assert_eq!(level.layout().dims, d, "level {k}");
        let got = read_level(level.as_ref());
        for (a, b) in got.iter().zip(&expect) {
            assert!((a - b).abs() < 1e-3, "level {k}: {a} vs {b}");
        }
        (expect, d) = brute_halve(&got, d);
    }
    assert_eq!(levels[3].layout().dims, [2, 2, 1]);
    // Too many levels for the size is refused, and nothing is written.
    let src = GridChunks::new(Arc::new(g), [4, 4, 4]).unwrap();
    let bad = tmp.path().join("bad.ome.zarr");
    let opts = WriteOptions {
        levels: Levels::Count(9),
        ..Default::default()
    };
    let e = write_ome_zarr(&src, &bad, &opts).unwrap_err().to_string();
    assert!(e.contains("more than halving"), "{e}");
    assert!(!bad.exists());
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        1,
        "no partial store left"
    );
}

/// A source whose chunk 3 fails.
struct Failing(GridChunks);
impl ChunkSource for Failing {
    fn layout(&self) -> &volux_core::bricked::ChunkLayout {
        self.0.layout()
    }
    fn read_chunk(&self, c: [usize; 3]) -> volux_core::Result<Samples> {
        if self.0.layout().chunk_index(c) == 3 {
            return Err(volux_core::Error::Chunked("disk on fire".into()));
        }
        self.0.read_chunk(c)
    }
}

#[test]
fn a_failing_source_leaves_no_partial_store() {
    let g = grid([9, 9, 9], Samples::F32(Buffer::owned(lcg(1, 729))));
    let src = Failing(GridChunks::new(Arc::new(g), [4, 4, 4]).unwrap());
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x.ome.zarr");
    let e = write_ome_zarr(&src, &out, &WriteOptions::default()).unwrap_err();
    assert!(e.to_string().contains("disk on fire"), "{e}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// A small written store (u16, no pyramid) to damage.
fn damaged(compression: Compression) -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let g = grid(
        [10, 6, 4],
        Samples::U16(Buffer::owned(
            lcg(5, 240).iter().map(|&v| v as u16).collect(),
        )),
    );
    let out = write(g, [4, 4, 4], tmp.path(), Levels::Count(1), compression);
    (tmp, out)
}

/// Reading every chunk and loading the store both fail with one error containing `needle`.
fn fails_cleanly(out: &Path, needle: &str) {
    let e = volux_io::load(out, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains(needle), "{e}");
    assert!(!e.contains('\n'), "one line: {e}");
}

#[test]
fn corrupt_or_truncated_chunks_are_one_clear_error() {
    for compression in [
        Compression::Zstd(3),
        Compression::BloscZstd(5),
        Compression::None,
    ] {
        let (_tmp, out) = damaged(compression);
        let chunk = out.join("0/c/0/0/1");
        assert!(chunk.is_file(), "{chunk:?}");
        // Garbage bytes.
        let len = std::fs::metadata(&chunk).unwrap().len() as usize;
        std::fs::write(&chunk, vec![0xA5u8; len]).unwrap();
        if compression != Compression::None {
            fails_cleanly(&out, "chunk [1, 0, 0]");
        }
        let level = open_store(&out, &ZarrOptions::default()).unwrap();
        let full = level.multiscale.full();
        if compression != Compression::None {
            assert!(full.read_chunk([1, 0, 0]).is_err());
        }
        assert!(full.read_chunk([0, 0, 0]).is_ok());
        // Truncated.
        std::fs::write(&chunk, vec![0x28u8, 0xB5, 0x2F]).unwrap();
        fails_cleanly(&out, "chunk [1, 0, 0]");
        let e = full.read_chunk([1, 0, 0]).unwrap_err().to_string();
        assert!(e.contains("cannot be read"), "{e}");
    }
}

fn edit_json(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_vec(&v).unwrap()).unwrap();
}

#[test]
fn missing_metadata_is_one_clear_error() {
    let (_tmp, out) = damaged(Compression::Zstd(3));
    std::fs::remove_file(out.join("0/zarr.json")).unwrap();
    let e = open_store(&out, &ZarrOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot open the Zarr array"), "{e}");
    std::fs::remove_file(out.join("zarr.json")).unwrap();
    fails_cleanly(&out, "missing metadata");
    // A folder that is no store at all.
    let empty = tempfile::tempdir().unwrap();
    let e = open_store(empty.path(), &ZarrOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a Zarr group or array"), "{e}");
}

#[test]
fn metadata_that_lies_about_the_shape_is_one_clear_error() {
    // Chunks larger than the chunk files hold.
    let (_tmp, out) = damaged(Compression::Zstd(3));
    edit_json(&out.join("0/zarr.json"), |v| {
        v["shape"] = serde_json::json!([8, 12, 20]);
        v["chunk_grid"]["configuration"]["chunk_shape"] = serde_json::json!([8, 8, 8]);
    });
    fails_cleanly(&out, "cannot be read");
    // Absurd sizes: refused when opened, before any allocation.
    for shape in [[1_000_000_000_000u64; 3], [1_000_000_000_000, 6, 10]] {
        let (_tmp, out) = damaged(Compression::Zstd(3));
        edit_json(&out.join("0/zarr.json"), |v| {
            v["shape"] = serde_json::json!(shape)
        });
        let e = volux_io::load(&out, &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("absurd") || e.contains("larger than the memory budget"),
            "{e}"
        );
        assert!(!e.contains('\n'));
    }
    // Absurd chunk shapes.
    let (_tmp, out) = damaged(Compression::Zstd(3));
    edit_json(&out.join("0/zarr.json"), |v| {
        v["chunk_grid"]["configuration"]["chunk_shape"] =
            serde_json::json!([100000, 100000, 100000])
    });
    fails_cleanly(&out, "larger than the 1 GiB");
}

#[test]
fn a_level_over_the_budget_names_level_and_the_bricked_renderer() {
    let (_tmp, out) = damaged(Compression::Zstd(3));
    edit_json(&out.join("0/zarr.json"), |v| {
        v["shape"] = serde_json::json!([4000, 4000, 4000u64 * 1000])
    });
    let e = volux_io::load(&out, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("coarser level") && e.contains("bricked"), "{e}");
}

#[test]
fn time_and_channel_axes_are_fixed_and_int32_reads_as_f32() {
    let path = data("tczyx_v05.ome.zarr");
    let opts = ZarrOptions {
        channel: 1,
        timepoint: 1,
        ..Default::default()
    };
    let store = open_store(&path, &opts).unwrap();
    assert_eq!(store.axes, ["t", "c", "z", "y", "x"]);
    assert!(store.notes[0].contains("int32"), "{:?}", store.notes);
    let l = store.multiscale.full();
    assert_eq!(l.layout().dims, [5, 4, 3]);
    assert_eq!(l.layout().chunk, [4, 3, 2]);
    assert_eq!(l.layout().spacing, [1.0, 2.0, 3.0]);
    assert_eq!(l.layout().scalar, volux_core::grid::ScalarType::F32);
    let v = read_level(l.as_ref());
    for z in 0..3 {
        for y in 0..4 {
            for x in 0..5 {
                assert_eq!(v[x + 5 * (y + 4 * z)], (x + 5 * y + 20 * z + 180) as f64);
            }
        }
    }
    let bad = ZarrOptions {
        channel: 2,
        ..Default::default()
    };
    let e = open_store(&path, &bad).unwrap_err().to_string();
    assert!(e.contains("channel 2 is out of range"), "{e}");
}
