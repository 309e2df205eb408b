//! Colour volumes end to end: an RGB NRRD (as 3D Slicer and ITK write a cryosection) is
//! rendered in its own colour, `--component` reads one channel as a scalar, `--tf-colour`
//! colours it by the transfer function instead, and `volux info` lists the channels.
use std::path::Path;

mod common;
use common::{png_pixels, volux};

/// A 16^3 RGB NRRD: red voxels left of the middle, blue ones right of it, black slabs at the
/// two x ends.
fn rgb_nrrd(dir: &Path) {
    let n = 16usize;
    let mut bytes = format!(
        "NRRD0004\ntype: uint8\ndimension: 4\nspace: left-posterior-superior\n\
         sizes: 3 {n} {n} {n}\nkinds: RGB-color domain domain domain\n\
         space directions: none (1,0,0) (0,1,0) (0,0,1)\nspace origin: (0,0,0)\n\
         endian: little\nencoding: raw\n\n"
    )
    .into_bytes();
    // Black (transparent: the opacity follows the luminance over its range) at the two
    // x ends, so that red (luminance 72) and blue (70) both lie high in that range.
    for i in 0..n * n * n {
        let x = i % n;
        bytes.extend(match x {
            _ if x < 2 || x >= n - 2 => [0, 0, 0],
            _ if x < n / 2 => [230, 30, 30],
            _ => [40, 60, 250],
        });
    }
    std::fs::write(dir.join("rgb.nrrd"), bytes).unwrap();
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn an_rgb_volume_is_drawn_in_its_own_colour() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rgb_nrrd(d);
    let info = volux(&["info", "rgb.nrrd"], d);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("colour: 3 channels (all kept)"), "{text}");
    let args = [
        "render",
        "rgb.nrrd",
        "--view",
        "front",
        "--size",
        "64x64",
        "--tf",
        "grayscale",
    ];
    let out = volux(&[&args[..], &["-o", "data.png"]].concat(), d);
    assert!(out.status.success(), "{}", stderr(&out));
    let (w, h, px) = png_pixels(&d.join("data.png"));
    // The front view looks along +y (anterior to posterior): +x, the left half of the
    // index range, is on the image's right (the patient's left on the viewer's right).
    let row = (h / 2) as usize * w as usize;
    let (a, b) = (&px[row + w as usize / 4], &px[row + 3 * w as usize / 4]);
    let reddish = |p: &[u8]| p[0] > p[2] + 40;
    let bluish = |p: &[u8]| p[2] > p[0] + 40;
    assert!(
        (reddish(a) && bluish(b)) || (bluish(a) && reddish(b)),
        "one side red, the other blue: {a:?} {b:?}"
    );
    // The TF's colours (grayscale) instead: no hue.
    let out = volux(&[&args[..], &["--tf-colour", "-o", "tf.png"]].concat(), d);
    assert!(out.status.success(), "{}", stderr(&out));
    let (_, _, px) = png_pixels(&d.join("tf.png"));
    let grey = |p: &[u8]| p[0].abs_diff(p[2]) <= 2 && p[0].abs_diff(p[1]) <= 2;
    assert!(px.iter().all(|p| grey(p)), "grayscale TF on the luminance");
    // One channel as the scalar: a scalar grid, where --tf-colour changes nothing.
    let blue = volux(&["info", "rgb.nrrd", "--component", "2"], d);
    let text = String::from_utf8_lossy(&blue.stdout);
    assert!(text.contains("component 2 read"), "{text}");
    let out = volux(
        &[
            &args[..],
            &["--component", "2", "--tf-colour", "-o", "x.png"],
        ]
        .concat(),
        d,
    );
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("--tf-colour"),
        "{err}"
    );
    assert!(!d.join("x.png").exists());
}
