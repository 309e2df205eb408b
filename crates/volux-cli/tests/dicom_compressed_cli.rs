//! `volux info` on compressed DICOM (volux-io's committed fixtures): the grid's note names
//! the transfer syntax and decoder; a 16-bit DCT JPEG frame is one clear error line naming
//! it.
use std::path::PathBuf;

mod common;
use common::volux;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../volux-io/tests/fixtures/dicom_compressed")
        .join(name)
}

#[test]
fn info_names_the_transfer_syntax() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "mr_jpll70",
            "DICOM transfer syntax 1.2.840.10008.1.2.4.70 (JPEG Lossless, first-order \
             prediction), decoded with dicom-pixeldata",
        ),
        (
            "emri_rle.dcm",
            "DICOM transfer syntax 1.2.840.10008.1.2.5 (RLE Lossless), decoded with Volux's \
             RLE decoder (PS3.5 Annex G)",
        ),
        (
            "mr_jls80",
            "DICOM transfer syntax 1.2.840.10008.1.2.4.80 (JPEG-LS Lossless), decoded with \
             pure_jpegls",
        ),
        (
            "emri_jpeg51_12bit.dcm",
            "DICOM transfer syntax 1.2.840.10008.1.2.4.51 (JPEG Extended), decoded with \
             dicom-pixeldata (8-bit frames) or Volux's 12-bit JPEG decoder (12-bit frames)",
        ),
        (
            "emri_htj2k201.dcm",
            "DICOM transfer syntax 1.2.840.10008.1.2.4.201 (High-Throughput JPEG 2000 \
             Lossless), decoded with dicom-pixeldata",
        ),
        (
            "emri_j2k90.dcm",
            "DICOM transfer syntax 1.2.840.10008.1.2.4.90 (JPEG 2000 Lossless), decoded with \
             dicom-pixeldata",
        ),
    ];
    for (name, note) in cases {
        let p = fixture(name);
        let out = volux(&["info", p.to_str().unwrap()], dir.path());
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            stdout.contains(&format!("note: {note}")),
            "{name}: {stdout}"
        );
    }
}

#[test]
fn info_refuses_16_bit_lossy_jpeg_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let p = fixture("emri_jpeg51.dcm");
    let out = volux(&["info", p.to_str().unwrap()], dir.path());
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("volux: error: ")
            && stderr.contains("1.2.840.10008.1.2.4.51 (JPEG Extended)")
            && stderr.contains("16-bit"),
        "{stderr}"
    );
}
