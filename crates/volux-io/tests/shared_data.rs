//! Every dataset in `../shared/data` that a reader supports, loaded through `volux_io::load`
//! and checked against its JSON sidecar. Skips (with a message) when the folder is absent.
use std::path::{Path, PathBuf};

use serde_json::Value;
use volux_io::{load, Dataset, LoadOptions};
use volux_testkit::data::shared;

fn sidecars(dir: &Path) -> Vec<(PathBuf, Value)> {
    let mut out = Vec::new();
    for folder in std::fs::read_dir(dir).unwrap().flatten() {
        if !folder.path().is_dir() {
            continue;
        }
        for f in std::fs::read_dir(folder.path()).unwrap().flatten() {
            let p = f.path();
            if p.extension().is_some_and(|e| e == "json") {
                let v: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
                out.push((p, v));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-6)
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn check_grid(path: &Path, side: &Value) {
    let (data, _) = load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let Dataset::Grid(g) = data else {
        panic!("{}: expected a grid", path.display())
    };
    let dims: Vec<usize> = f64s(&side["dims_xyz"])
        .iter()
        .map(|&d| d as usize)
        .collect();
    assert_eq!(g.dims().to_vec(), dims, "{}", path.display());
    for (a, b) in g.spacing().to_array().iter().zip(f64s(&side["spacing"])) {
        assert!(close(*a, b, 1e-5), "{}: spacing {a} vs {b}", path.display());
    }
    let r = f64s(&side["value_range"]);
    assert!(
        close(g.range()[0], r[0], 1e-6) && close(g.range()[1], r[1], 1e-6),
        "{}: range {:?} vs {r:?}",
        path.display(),
        g.range()
    );
    assert_eq!(g.scalar_type().name(), side["dtype"].as_str().unwrap());
}

fn check_mesh(path: &Path, side: &Value, opts: &LoadOptions) {
    let (data, _) = load(path, opts).unwrap_or_else(|e| panic!("{e}"));
    let Dataset::Mesh(m) = data else {
        panic!("{}: expected a mesh", path.display())
    };
    assert_eq!(
        m.tets().len() as u64,
        side["tets"].as_u64().unwrap(),
        "{}",
        path.display()
    );
    let used = m.positions().len() - m.report().unused_vertices;
    assert!(
        used as u64 <= side["vertices"].as_u64().unwrap(),
        "{}",
        path.display()
    );
    if let Some(r) = side.get("scalar_range") {
        let r = f64s(r);
        assert!(
            close(m.range()[0], r[0], 1e-5) && close(m.range()[1], r[1], 1e-5),
            "{}: range {:?} vs {r:?}",
            path.display(),
            m.range()
        );
        assert_eq!(
            m.positions().len() as u64,
            side["vertices"].as_u64().unwrap()
        );
    }
    if let (Some(lo), Some(hi)) = (side.get("bounds_min"), side.get("bounds_max")) {
        let b = m.bounds();
        for (a, e) in b
            .min
            .to_array()
            .iter()
            .chain(b.max.to_array().iter())
            .zip(f64s(lo).into_iter().chain(f64s(hi)))
        {
            assert!((a - e).abs() < 1e-4, "{}: bounds", path.display());
        }
    }
}

/// An SLC file (whose sidecar gives no dims) against the raw copy decoded by `vtkSLCReader`
/// next to it, whose sidecar names the SLC file as its source: the same voxels.
fn check_slc(path: &Path) {
    let (data, _) = load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let Dataset::Grid(g) = data else {
        panic!("{}: expected a grid", path.display())
    };
    let folder = path.parent().unwrap();
    let raw = sidecars(folder.parent().unwrap())
        .into_iter()
        .find(|(json, side)| json.parent() == Some(folder) && side.get("dims_xyz").is_some())
        .unwrap_or_else(|| panic!("{}: no raw copy to compare with", path.display()));
    let (raw, _) = load(
        &folder.join(raw.1["file"].as_str().unwrap()),
        &LoadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Dataset::Grid(raw) = raw else {
        panic!("expected a grid")
    };
    assert_eq!(g.dims(), raw.dims(), "{}", path.display());
    assert_eq!(g.spacing(), raw.spacing(), "{}", path.display());
    let differ = (0..g.len())
        .filter(|&i| g.samples().get_f32(i) != raw.samples().get_f32(i))
        .count();
    assert_eq!(differ, 0, "{}: {differ} voxels differ", path.display());
}

#[test]
fn every_shared_dataset_matches_its_sidecar() {
    let Some(dir) = shared("") else { return };
    let mut checked = 0;
    for (json, side) in sidecars(&dir) {
        let folder = json.parent().unwrap();
        let file = side["file"].as_str().map(|f| folder.join(f));
        match (side["kind"].as_str().unwrap_or(""), file) {
            ("grid", Some(f)) if side.get("dims_xyz").is_some() => check_grid(&f, &side),
            ("grid", Some(f))
                if side["format"]
                    .as_str()
                    .is_some_and(|s| s.starts_with("SLC")) =>
            {
                check_slc(&f)
            }
            ("tets", Some(f)) | ("tets (quadratic)", Some(f)) => {
                check_mesh(&f, &side, &LoadOptions::default())
            }
            ("curvilinear (PLOT3D)", Some(f)) if side["role"] == "grid (XYZ)" => {
                let n = f64s(&side["dims_ijk"]);
                let tets = 5.0 * (n[0] - 1.0) * (n[1] - 1.0) * (n[2] - 1.0);
                let (data, _) = load(&f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
                let Dataset::Mesh(m) = data else {
                    panic!("PLOT3D gives a mesh")
                };
                assert_eq!(m.tets().len() as f64, tets);
                assert_eq!(m.positions().len() as u64, side["points"].as_u64().unwrap());
            }
            ("grid (DICOM series)", _) => {
                let (data, _) =
                    load(folder, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
                let Dataset::Grid(g) = data else {
                    panic!("DICOM gives a grid")
                };
                assert_eq!(
                    g.dims(),
                    [512, 512, side["files"].as_array().unwrap().len()]
                );
                assert!(
                    (g.spacing().z - 12.0).abs() < 1e-3,
                    "slices are 12 mm apart"
                );
            }
            ("grid (DICOM multi-frame)", Some(f)) => {
                let (data, _) = load(&f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
                let Dataset::Grid(g) = data else {
                    panic!("DICOM gives a grid")
                };
                let n = |k: &str| side[k].as_u64().unwrap() as usize;
                assert_eq!(g.dims(), [n("columns"), n("rows"), n("frames")]);
                let r = f64s(&side["pixel_range"]);
                assert_eq!(g.range(), [r[0], r[1]]);
            }
            _ => {
                eprintln!("not checked: {}", json.display());
                continue;
            }
        }
        eprintln!("ok: {}", json.display());
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} datasets checked");
}
