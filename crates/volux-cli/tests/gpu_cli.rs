//! `volux render --backend gpu` end to end, in a build with the `gpu` feature
//! (`cargo test -p volux-cli --features gpu --test gpu_cli`, run by `.ci/run` on lavapipe):
//! the GPU's pictures equal the CPU engine's, `auto` never prefers a software adapter to the
//! CPU engine and says why, and what the GPU does not draw is refused by name. Skipped, with
//! a message, when this machine has no adapter, unless `VOLUX_GPU_REQUIRED=1` (set by CI).
#![cfg(feature = "gpu")]
mod common;

use std::path::Path;

use common::{png_close, volux};

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn ok(args: &[&str], dir: &Path) -> String {
    let out = volux(args, dir);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stderr(&out)
}

/// The adapters `volux info --gpu --json` lists, or `None` (the test skips) when there are
/// none and CI does not require one.
fn adapters(dir: &Path) -> Option<Vec<String>> {
    let out = volux(&["info", "--gpu", "--json"], dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let list: Vec<String> = serde_json::from_slice(&out.stdout).unwrap();
    if list.is_empty() {
        if std::env::var_os("VOLUX_GPU_REQUIRED").is_some() {
            panic!("VOLUX_GPU_REQUIRED is set and volux lists no GPU adapter");
        }
        eprintln!("SKIPPED: no GPU adapter; set VOLUX_GPU_REQUIRED=1 to fail instead");
        return None;
    }
    Some(list)
}

#[test]
fn the_gpu_backend_draws_what_the_cpu_engine_draws() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    if adapters(d).is_none() {
        return;
    }
    ok(
        &["generate", "shepp-logan", "--size", "40", "-o", "grid.raw"],
        d,
    );
    ok(
        &[
            "generate",
            "tets-smooth",
            "--size",
            "3000",
            "-o",
            "mesh.vtet",
        ],
        d,
    );
    let cases: [(&str, &[&str]); 4] = [
        ("grid", &["grid.raw"]),
        (
            "shaded",
            &["grid.raw", "--shade", "--clip-plane", "0,-1,0,20"],
        ),
        ("mip", &["grid.raw", "--mip"]),
        ("pt", &["mesh.vtet", "--method", "pt"]),
    ];
    for (name, args) in cases {
        let common = [args, &["--size", "64x64", "--azimuth", "30"][..]].concat();
        let cpu = format!("{name}-cpu.png");
        let gpu = format!("{name}-gpu.png");
        ok(
            &[&["render"][..], &common, &["--backend", "cpu", "-o", &cpu]].concat(),
            d,
        );
        let said = ok(
            &[&["render"][..], &common, &["--backend", "gpu", "-o", &gpu]].concat(),
            d,
        );
        assert!(said.contains("rendering on the GPU"), "{name}: {said}");
        let figures =
            png_close(&d.join(&gpu), &d.join(&cpu)).unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!("{name}: {figures}");
    }
}

/// `auto` renders on a hardware adapter, never on a software one (lavapipe) unless the method
/// is GPU-only, and says on stderr which it chose and why; a GPU-only method is drawn on the
/// GPU whatever the adapter, and what the GPU does not draw is refused by name.
#[test]
fn auto_says_what_it_chose_and_why() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let Some(list) = adapters(d) else { return };
    ok(
        &["generate", "shepp-logan", "--size", "24", "-o", "grid.raw"],
        d,
    );
    let render = |extra: &[&str]| {
        let args = [
            &["render", "grid.raw", "--size", "32x32", "-o", "x.png"][..],
            extra,
        ]
        .concat();
        volux(&args, d)
    };
    let software = list[0].contains("Cpu") || list[0].contains("llvmpipe");
    let said = stderr(&render(&["--backend", "auto"]));
    if software {
        assert!(said.contains("rendering on the CPU"), "{said}");
        assert!(said.contains("software rasterizer"), "{said}");
        assert!(
            !said.contains("     "),
            "one line, no run of spaces: {said}"
        );
    } else {
        assert!(said.contains("rendering on the GPU"), "{said}");
    }
    let said = ok(
        &[
            "render", "grid.raw", "--size", "32x32", "-o", "s.png", "--method", "slicing",
        ],
        d,
    );
    assert!(said.contains("rendering on the GPU"), "{said}");
    let out = render(&["--backend", "gpu", "--method", "slicing", "--mip"]);
    assert!(!out.status.success());
    let said = stderr(&out);
    assert!(said.contains("maximum intensity"), "{said}");
    assert!(!said.contains("rendering on the CPU"), "{said}");
}
