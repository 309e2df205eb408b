//! TIFF stacks from the command line: `volux info` reports a stack's dims, spacing and
//! compression; `--channel` / `--timepoint` choose in an ImageJ hyperstack (whose channel and
//! time axes `info` lists), and an index out of range fails in one line; a colour TIFF
//! converts to a colour NRRD, or one channel with `--component`; an unsupported compression
//! is refused in one line. The files are volux-io's tifffile fixtures.
mod common;

use std::path::Path;

use common::volux;

/// Copies volux-io's fixture `name` into `dir`.
fn fixture(name: &str, dir: &Path) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../volux-io/tests/fixtures/tiff")
        .join(name);
    std::fs::copy(src, dir.join(name)).unwrap();
}

fn ok(args: &[&str], dir: &Path) -> String {
    let out = volux(args, dir);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn info_reports_dims_spacing_and_compression() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixture("lzw_u16.tif", dir);
    let text = ok(&["info", "lzw_u16.tif"], dir);
    assert!(text.contains("TIFF"), "{text}");
    assert!(
        text.contains("5 pages, LZW compression, 16-bit unsigned"),
        "{text}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["info", "--json", "lzw_u16.tif"], dir)).unwrap();
    assert_eq!(v["dims"], serde_json::json!([16, 12, 5]));
    assert_eq!(v["spacing"], serde_json::json!([1.0, 1.0, 1.0]));
}

#[test]
fn channel_and_timepoint_choose_in_a_hyperstack() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixture("imagej_hyperstack.tif", dir);
    let json =
        |args: &[&str]| -> serde_json::Value { serde_json::from_str(&ok(args, dir)).unwrap() };
    let v = json(&["info", "--json", "imagej_hyperstack.tif"]);
    assert_eq!(v["dims"], serde_json::json!([16, 12, 5]));
    assert_eq!(v["spacing"], serde_json::json!([0.25, 0.5, 1.5]));
    // v = x + 10 y + 100 z + 1000 c + 3000 t: channel 1, timepoint 2 spans 7000..=7525.
    let v = json(&[
        "info",
        "--json",
        "--channel",
        "1",
        "--timepoint",
        "2",
        "imagej_hyperstack.tif",
    ]);
    assert_eq!(v["range"], serde_json::json!([7000.0, 7525.0]));
    let texts: Vec<&str> = v["volumes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["text"].as_str().unwrap())
        .collect();
    assert_eq!(
        texts,
        [
            "channels: 2 channels (channel 1 read)",
            "time: 3 volumes (timepoint 2 read)"
        ]
    );
    for (args, expected) in [
        (
            &["info", "--channel", "9", "imagej_hyperstack.tif"][..],
            "channel 9 does not exist: the file holds 2 (0 to 1)",
        ),
        (
            &["info", "--timepoint", "3", "imagej_hyperstack.tif"][..],
            "timepoint 3 does not exist: the file holds 3 (0 to 2)",
        ),
        (
            &["info", "--component", "1", "imagej_hyperstack.tif"][..],
            "component 1 does not exist: the file holds 1 (0 to 0)",
        ),
    ] {
        let out = volux(args, dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn colour_converts_to_colour_or_one_channel() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixture("palette_u8.tif", dir);
    let out = volux(&["convert", "palette_u8.tif", "rgb.nrrd"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("note: palette (photometric 3)"), "{err}");
    let header = std::fs::read(dir.join("rgb.nrrd")).unwrap();
    let header = String::from_utf8_lossy(&header[..200.min(header.len())]);
    assert!(header.contains("RGB-color"), "{header}");
    let v: serde_json::Value = serde_json::from_str(&ok(
        &["info", "--json", "--component", "2", "palette_u8.tif"],
        dir,
    ))
    .unwrap();
    assert_eq!(
        v["volumes"][0]["text"],
        "colour: 3 channels (component 2 read)"
    );
    assert_eq!(v["dtype"], "uint16");
}

#[test]
fn an_unsupported_compression_is_refused_in_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixture("lzma.tif", dir);
    let out = volux(&["convert", "lzma.tif", "out.nrrd"], dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("compression 34925 (LZMA)"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.join("out.nrrd").exists());
}
