//! Every `*.raw` / `*.raw.gz` dataset with a sidecar in `shared/data`, read with `raw::read`
//! and `volux_io::load`, checked against the sidecar. Skips (with a message) when absent.
use std::path::{Path, PathBuf};

use serde_json::Value;
use volux_core::Grid;
use volux_io::{load, raw, Dataset, Format, LoadOptions};
use volux_testkit::data::{shared, shared_root};

/// (data file, sidecar JSON) of every raw grid.
fn raw_datasets() -> Option<Vec<(PathBuf, Value)>> {
    let dir = shared("")?;
    let mut out = Vec::new();
    for folder in std::fs::read_dir(dir).unwrap().flatten() {
        if !folder.path().is_dir() {
            continue;
        }
        for f in std::fs::read_dir(folder.path()).unwrap().flatten() {
            let p = f.path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let car = p.with_file_name(format!("{name}.json"));
            if (name.ends_with(".raw") || name.ends_with(".raw.gz")) && car.exists() {
                let v = serde_json::from_str(&std::fs::read_to_string(&car).unwrap()).unwrap();
                out.push((p, v));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    Some(out)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-12)
}

fn check(p: &Path, g: &Grid, car: &Value) {
    let name = p.display();
    let num = |v: &Value| v.as_f64().unwrap();
    let dims: Vec<usize> = car["dims_xyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(g.dims().to_vec(), dims, "{name}");
    assert_eq!(
        g.scalar_type().name(),
        car["dtype"].as_str().unwrap(),
        "{name}"
    );
    for (k, s) in car["spacing"].as_array().unwrap().iter().enumerate() {
        assert!(
            close(g.spacing()[k], num(s)),
            "{name}: spacing {:?}",
            g.spacing()
        );
    }
    if let Some(o) = car.get("origin").and_then(Value::as_array) {
        for (k, v) in o.iter().enumerate() {
            assert!(
                close(g.origin()[k], num(v)),
                "{name}: origin {:?}",
                g.origin()
            );
        }
    }
    let r = car["value_range"].as_array().unwrap();
    assert_eq!(g.range(), [num(&r[0]), num(&r[1])], "{name}: value range");
    assert!(g.notes().is_empty(), "{name}: {:?}", g.notes());
}

#[test]
fn shared_raw_datasets_match_their_sidecars() {
    let Some(sets) = raw_datasets() else {
        return;
    };
    assert!(
        !sets.is_empty(),
        "no raw datasets found in {}",
        shared_root().display()
    );
    for (p, car) in &sets {
        let gz = p.to_string_lossy().ends_with(".gz");
        let g = raw::read(p).unwrap_or_else(|e| panic!("{e}"));
        check(p, &g, car);
        assert_eq!(
            g.samples().is_mapped(),
            !gz,
            "{}: mapped iff uncompressed",
            p.display()
        );
        let (ds, format) = load(p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(format, Format::RawJson, "{}", p.display());
        match ds {
            Dataset::Grid(g2) => {
                check(p, &g2, car);
                if !gz {
                    assert_eq!(g2.to_f32_vec().unwrap(), g.to_f32_vec().unwrap());
                }
            }
            other => panic!("{}: not a grid: {other:?}", p.display()),
        }
        eprintln!("ok: {} {:?}", p.display(), g.dims());
    }
}

#[test]
fn shared_raw_through_the_sidecar_path() {
    let Some(p) = shared("vtk_carotid/carotid_76x49x45_float32.raw.json") else {
        return;
    };
    let g = raw::read(&p).unwrap();
    assert_eq!(g.dims(), [76, 49, 45]);
    assert_eq!(g.range(), [0.0, 580.0]);
}
