//! OME-Zarr stores from the command line: `generate` and `convert` write stores chunk by
//! chunk, `info` describes them, `--level` loads a level, and bad inputs write nothing.
mod common;

use common::volux;

fn ok(args: &[&str], dir: &std::path::Path) -> String {
    let out = volux(args, dir);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn stores_are_generated_converted_described_and_loaded_by_level() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    ok(
        &[
            "generate",
            "marschner-lobb",
            "--size",
            "21x19x17",
            "--chunk",
            "8",
            "--dtype",
            "u16",
            "-o",
            "ml.ome.zarr",
        ],
        dir,
    );
    let info = ok(&["info", "--json", "ml.ome.zarr"], dir);
    let v: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(v["dims"], serde_json::json!([21, 19, 17]));
    assert_eq!(v["chunk"], serde_json::json!([8, 8, 8]));
    assert_eq!(v["dtype"], "uint16");
    assert_eq!(v["codec"], "zstd");
    assert_eq!(v["levels"].as_array().unwrap().len(), 3, "{info}");
    assert!(v["range"].is_array(), "{info}");
    // The same volume through convert (raw in, store out), level 1 loaded in-core.
    ok(&["generate", "sphere", "--size", "17", "-o", "s.raw"], dir);
    ok(
        &[
            "convert",
            "s.raw",
            "s.ome.zarr",
            "--chunk",
            "8",
            "--levels",
            "2",
        ],
        dir,
    );
    let text = ok(&["info", "s.ome.zarr"], dir);
    assert!(
        text.contains("OME-Zarr (Zarr v3, NGFF 0.5)") && text.contains("17x17x17"),
        "{text}"
    );
    let l1 = ok(&["info", "--json", "--level", "1", "s.ome.zarr"], dir);
    let v: serde_json::Value = serde_json::from_str(&l1).unwrap();
    assert_eq!(v["dims"], serde_json::json!([9, 9, 9]));
    assert_eq!(v["spacing"], serde_json::json!([2.0, 2.0, 2.0]));
    // Stores render like any grid.
    ok(
        &[
            "render",
            "s.ome.zarr",
            "--level",
            "1",
            "-o",
            "s.png",
            "--size",
            "32x32",
        ],
        dir,
    );
    assert!(dir.join("s.png").is_file());
}

#[test]
fn bad_store_inputs_are_one_line_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    ok(&["generate", "sphere", "--size", "9", "-o", "s.raw"], dir);
    ok(&["convert", "s.raw", "done.ome.zarr"], dir);
    let cases: &[(&[&str], &str)] = &[
        (
            &["convert", "s.raw", "a.ome.zarr", "--chunk", "0"],
            "--chunk 0",
        ),
        (
            &["convert", "s.raw", "a.ome.zarr", "--levels", "many"],
            "--levels many",
        ),
        (
            &["convert", "s.raw", "a.ome.zarr", "--levels", "9"],
            "more than halving",
        ),
        (
            &["convert", "s.raw", "a.nrrd", "--chunk", "8"],
            "apply to OME-Zarr outputs",
        ),
        (&["convert", "s.raw", "done.ome.zarr"], "already exists"),
        (
            &["generate", "sphere", "--size", "1", "-o", "a.ome.zarr"],
            "--size '1'",
        ),
        (
            &["generate", "sphere", "--size", "9x9", "-o", "a.ome.zarr"],
            "expected N or XxYxZ",
        ),
        (
            &["generate", "sphere", "--size", "9x9x9", "-o", "a.raw"],
            "only for .ome.zarr",
        ),
        (
            &["generate", "sphere", "--dtype", "u8", "-o", "a.ome.zarr"],
            "--dtype u8",
        ),
        (
            &["generate", "torus", "--size", "9", "-o", "a.ome.zarr"],
            "unknown chunked generator",
        ),
        (
            &["info", "--level", "7", "done.ome.zarr"],
            "level 7 does not exist",
        ),
        (
            // --channel now applies to every reader (TIFF, OME-Zarr, colour): a grey raw
            // volume has only channel 0.
            &["info", "--channel", "1", "s.raw"],
            "channel 1 does not exist: the file holds 1",
        ),
    ];
    for (args, expected) in cases {
        let out = volux(args, dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
    let mut left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["done.ome.zarr", "s.raw", "s.raw.json"]);
}

#[test]
fn a_store_renders_out_of_core_as_in_memory_and_a_bad_lod_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let gen = ["generate", "marschner-lobb", "--size", "33", "--chunk", "8"];
    ok(&[&gen[..], &["-o", "ml.ome.zarr"]].concat(), dir);
    let common = ["--size", "48x40", "--frame", "all", "--azimuth", "35"];
    // Out of core at full resolution (chunks of 8: rays cross many chunk faces), and in
    // memory: the same picture, bit for bit.
    ok(
        &[
            &["render", "ml.ome.zarr", "--lod", "0"],
            &common[..],
            &["-o", "bricked.png"],
        ]
        .concat(),
        dir,
    );
    ok(
        &[
            &["render", "ml.ome.zarr"],
            &common[..],
            &["-o", "incore.png"],
        ]
        .concat(),
        dir,
    );
    let a = std::fs::read(dir.join("bricked.png")).unwrap();
    let b = std::fs::read(dir.join("incore.png")).unwrap();
    assert!(a == b, "the out-of-core PNG differs from the in-memory one");
    // A coarse level renders too.
    ok(
        &[
            "render",
            "ml.ome.zarr",
            "--lod",
            "2",
            "--size",
            "16x16",
            "-o",
            "coarse.png",
        ],
        dir,
    );
    let out = volux(
        &["render", "ml.ome.zarr", "--lod", "fine", "-o", "bad.png"],
        dir,
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--lod 'fine'") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!dir.join("bad.png").exists());
    // A level past the last is refused with the levels there are (it rendered the last);
    // --lod on a file read whole is refused (it was ignored).
    ok(&["convert", "ml.ome.zarr", "ml.nrrd"], dir);
    let levels = ok(&["info", "--json", "ml.ome.zarr"], dir);
    let cases: [(&[&str], &str); 3] = [
        (
            &["render", "ml.ome.zarr", "--lod", "9", "-o", "bad.png"],
            "--lod 9: ml.ome.zarr has",
        ),
        (
            &["render", "ml.nrrd", "--lod", "1", "-o", "bad.png"],
            "--lod 1 applies to OME-Zarr stores",
        ),
        (
            &[
                "render",
                "ml.ome.zarr",
                "--lod",
                "1",
                "--level",
                "1",
                "-o",
                "bad.png",
            ],
            "cannot be used with '--level",
        ),
    ];
    for (args, want) in cases {
        let out = volux(args, dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(
            err.contains(want) && err.lines().count() == 1,
            "{args:?}: {err} ({levels})"
        );
        assert!(!dir.join("bad.png").exists());
    }
}

/// A store rendered out of core and the same data in memory get the same picture with the
/// default framing and automatic transfer function: the out-of-core path frames the voxels
/// its chunks' recorded ranges and its brick cache show (not the whole box), and fits the
/// preset on the full level's histogram the writer recorded (not a coarse level's).
#[test]
fn out_of_core_frames_and_fits_the_transfer_function_as_in_memory() {
    use volux_core::grid::{Buffer, Samples};
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // A ball off the centre of a 40 x 36 x 30 box, a ramp inside it.
    let dims = [40usize, 36, 30];
    let values: Vec<u16> = (0..dims.iter().product::<usize>())
        .map(|n| {
            let (i, j, k) = (n % 40, n / 40 % 36, n / (40 * 36));
            let d =
                ((i as f64 - 27.0).powi(2) + (j as f64 - 12.0).powi(2) + (k as f64 - 20.0).powi(2))
                    .sqrt();
            if d < 7.0 {
                (1000.0 - 100.0 * d) as u16
            } else {
                0
            }
        })
        .collect();
    let grid = volux_core::Grid::new(
        dims,
        [1.0, 1.0, 1.5],
        [3.0, -2.0, 0.0],
        Samples::U16(Buffer::owned(values)),
    )
    .unwrap();
    volux_io::nrrd::write(&grid, &dir.join("ball.nrrd")).unwrap();
    ok(
        &["convert", "ball.nrrd", "ball.ome.zarr", "--chunk", "8"],
        dir,
    );
    let common = ["--size", "48x40", "--azimuth", "35", "--elevation", "20"];
    ok(
        &[
            &["render", "ball.ome.zarr", "--lod", "0"],
            &common[..],
            &["-o", "bricked.png"],
        ]
        .concat(),
        dir,
    );
    ok(
        &[&["render", "ball.nrrd"], &common[..], &["-o", "incore.png"]].concat(),
        dir,
    );
    let a = std::fs::read(dir.join("bricked.png")).unwrap();
    let b = std::fs::read(dir.join("incore.png")).unwrap();
    assert!(a == b, "the out-of-core PNG differs from the in-memory one");

    // A foreign store (ome-zarr-py's: no range, chunk ranges or histogram recorded) is read
    // at opening for the same statistics, and says so.
    let stripped = strip_volux_attributes(&dir.join("ball.ome.zarr"));
    assert!(stripped > 0, "no level carried Volux's statistics");
    let out = volux(
        &[
            &["render", "ball.ome.zarr", "--lod", "0"],
            &common[..],
            &["-o", "foreign.png"],
        ]
        .concat(),
        dir,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("records no value statistics"), "{stderr}");
    let c = std::fs::read(dir.join("foreign.png")).unwrap();
    assert!(
        c == b,
        "the foreign store's PNG differs from the in-memory one"
    );
}

/// Removes the `volux` attributes (range, chunk ranges, histogram) from every level's
/// metadata under `store`, as a store written by another tool lacks them; the number of
/// files changed.
fn strip_volux_attributes(store: &std::path::Path) -> usize {
    let mut changed = 0;
    let mut dirs = vec![store.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let path = e.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name != "zarr.json" && name != ".zattrs" {
                continue;
            }
            let mut json: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
            let attrs = match json.get_mut("attributes") {
                Some(a) => a,
                None => &mut json,
            };
            if let Some(map) = attrs.as_object_mut() {
                if map.remove("volux").is_some() {
                    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
                    changed += 1;
                }
            }
        }
    }
    changed
}
