//! The viewer in a real window under Xvfb: `--screenshot` against `volux render --session`,
//! and a mouse drag (xdotool) that must change the picture. `.ci/run` installs Xvfb,
//! xdotool, x11-apps (xwd) and Mesa when they are missing; without them these tests say so
//! and skip, unless `VOLUX_WINDOW_REQUIRED=1` (set by `.ci/run`): then they fail.
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use volux_core::synth;

const VIEWER: &str = env!("CARGO_BIN_EXE_volux-view");

/// An Xvfb server on its own display, stopped on drop.
struct Display {
    name: String,
    server: Child,
}

impl Drop for Display {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Says that a test skips for `why`, or fails with it when `VOLUX_WINDOW_REQUIRED` is set.
fn skip_or_fail(why: &str) {
    if std::env::var_os("VOLUX_WINDOW_REQUIRED").is_some_and(|v| v != "0") {
        panic!("VOLUX_WINDOW_REQUIRED is set and {why}");
    }
    eprintln!("skipped: {why}");
}

/// Starts Xvfb, or says why not (the test then skips).
fn display() -> Option<Display> {
    for tool in ["Xvfb", "xdotool", "xwd"] {
        if !have(tool) {
            skip_or_fail(&format!("{tool} is not installed (.ci/run installs it)"));
            return None;
        }
    }
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let number = 100 + (std::process::id() % 200) * 4 + k;
    let name = format!(":{number}");
    let server = Command::new("Xvfb")
        .args([&name, "-screen", "0", "1400x960x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let d = Display { name, server };
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        let ok = Command::new("xdotool")
            .arg("getdisplaygeometry")
            .env("DISPLAY", &d.name)
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Some(d);
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    panic!("Xvfb did not start on {}", d.name);
}

/// The shared CT head when present, else a synthetic grid written to `dir`.
fn dataset(dir: &Path) -> PathBuf {
    if let Some(shared) =
        volux_testkit::data::shared("invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz")
    {
        return shared;
    }
    eprintln!("note: the shared CT head is absent; using a synthetic grid");
    let path = dir.join("ml.raw");
    volux_io::raw::write(&synth::marschner_lobb(48).unwrap(), &path).unwrap();
    path
}

/// Runs `cmd`, which must succeed (its stderr shown otherwise).
fn succeed(cmd: &mut Command) {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{cmd:?}: {err}");
}

/// `--screenshot` writes the fully refined frame, and the session it saves renders in
/// batch (`volux render --session`) to the same picture within 1/255.
#[test]
fn screenshot_equals_the_batch_render_of_its_session() {
    let Some(d) = display() else { return };
    let dir = tempfile::tempdir().unwrap();
    let data = dataset(dir.path());
    let (shot, session, batch) = (
        dir.path().join("shot.png"),
        dir.path().join("s.json"),
        dir.path().join("batch.png"),
    );
    succeed(
        Command::new(VIEWER)
            .arg(&data)
            .args(["--screenshot", shot.to_str().unwrap(), "--size", "200x150"])
            .args(["--save-session", session.to_str().unwrap()])
            .env("DISPLAY", &d.name),
    );
    let volux = Path::new(VIEWER).with_file_name("volux");
    if !volux.is_file() {
        skip_or_fail(&format!(
            "the batch half needs {}, not built",
            volux.display()
        ));
        return;
    }
    let (session, batch_name) = (session.to_str().unwrap(), batch.to_str().unwrap());
    succeed(Command::new(&volux).args(["render", "--session", session, "-o", batch_name]));
    let (a, b) = (png_rgb(&shot), png_rgb(&batch));
    assert_eq!((a.0, a.1), (200, 150));
    assert_eq!((a.0, a.1), (b.0, b.1));
    let worst =
        a.2.iter()
            .zip(&b.2)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
    eprintln!("screenshot vs batch render: largest channel difference {worst}/255");
    assert!(worst <= 1, "{worst}/255");
    let lit = a.2.chunks(3).filter(|p| p.iter().any(|c| *c > 40)).count();
    assert!(
        lit > 200 * 150 / 20,
        "the screenshot is nearly blank ({lit} lit pixels)"
    );
}

/// A real window: the first screenshot shows a render, a drag with xdotool turns it.
#[test]
fn a_mouse_drag_in_a_real_window_changes_the_render() {
    let Some(d) = display() else { return };
    let dir = tempfile::tempdir().unwrap();
    let data = dataset(dir.path());
    let mut viewer = Command::new(VIEWER)
        .arg(&data)
        .env("DISPLAY", &d.name)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let result = std::panic::catch_unwind(|| drag_check(&d.name, dir.path()));
    let _ = viewer.kill();
    let _ = viewer.wait();
    if let Err(e) = result {
        std::panic::resume_unwind(e);
    }
}

fn drag_check(display: &str, dir: &Path) {
    let xdotool = |args: &[&str]| {
        let o = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", display)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "xdotool {args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let window = xdotool(&["search", "--sync", "--name", "volux-view"]);
    let window = window.lines().next().unwrap().to_string();
    let geometry = xdotool(&["getwindowgeometry", "--shell", &window]);
    let field = |k: &str| -> i64 {
        geometry
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{k}=")))
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let (x, y, w, h) = (field("X"), field("Y"), field("WIDTH"), field("HEIGHT"));
    // The 3D view: right of the settings panel, above the slice strip.
    let region = (x + w * 2 / 5, y + h / 6, x + w * 9 / 10, y + h * 11 / 20);
    let before = settled(display, dir, region, "first");
    assert!(spread(&before) > 20, "the render region is blank");
    let (cx, cy) = ((region.0 + region.2) / 2, (region.1 + region.3) / 2);
    // The pointer enters first, in a frame of its own, so that the press lands on a
    // hovered view (as a hand would), then the press in another frame.
    xdotool(&["mousemove", &cx.to_string(), &cy.to_string()]);
    std::thread::sleep(Duration::from_millis(300));
    xdotool(&["mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(100));
    for k in 1..=10 {
        xdotool(&[
            "mousemove",
            &(cx + 12 * k).to_string(),
            &(cy + 3 * k).to_string(),
        ]);
        std::thread::sleep(Duration::from_millis(30));
    }
    xdotool(&["mouseup", "1"]);
    let changed = |a: &[u8]| {
        before
            .iter()
            .zip(a)
            .filter(|(x, y)| x.abs_diff(**y) > 8)
            .count()
    };
    // The full frame of the new view comes after the previews: wait for a settled picture
    // that differs (or time out and fail).
    let start = Instant::now();
    let after = loop {
        let after = settled(display, dir, region, "after the drag");
        if changed(&after) > before.len() / 50 || start.elapsed() > Duration::from_secs(30) {
            break after;
        }
    };
    let n = changed(&after);
    eprintln!("{n} of {} channel values changed by the drag", before.len());
    assert!(n > before.len() / 50, "the drag did not change the render");
}

/// Screenshots the region until two in a row agree (the full frame is on screen).
fn settled(display: &str, dir: &Path, region: (i64, i64, i64, i64), what: &str) -> Vec<u8> {
    let start = Instant::now();
    let mut last: Option<Vec<u8>> = None;
    loop {
        std::thread::sleep(Duration::from_millis(500));
        let grab = crop(&xwd(display, dir), region);
        if last.as_ref() == Some(&grab) && spread(&grab) > 20 {
            return grab;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no settled {what} picture"
        );
        last = Some(grab);
    }
}

fn spread(rgb: &[u8]) -> u8 {
    rgb.iter().max().unwrap() - rgb.iter().min().unwrap()
}

/// The root window as (width, height, RGB), through `xwd` (ZPixmap, 24/32 bits).
fn xwd(display: &str, dir: &Path) -> (usize, usize, Vec<u8>) {
    let path = dir.join("root.xwd");
    let ok = Command::new("sh")
        .args(["-c", &format!("xwd -root -silent > '{}'", path.display())])
        .env("DISPLAY", display)
        .status()
        .unwrap()
        .success();
    assert!(ok, "xwd failed");
    let data = std::fs::read(&path).unwrap();
    let field = |i: usize| u32::from_be_bytes(data[i * 4..i * 4 + 4].try_into().unwrap()) as usize;
    let (header, w, h, order, bpp, bpl) =
        (field(0), field(4), field(5), field(7), field(11), field(12));
    let masks = [field(14), field(15), field(16)];
    let ncolors = field(19);
    assert!(bpp == 32 || bpp == 24, "xwd: {bpp} bits per pixel");
    let start = header + 12 * ncolors;
    let mut rgb = Vec::with_capacity(w * h * 3);
    for row in 0..h {
        for col in 0..w {
            let o = start + row * bpl + col * bpp / 8;
            let bytes = &data[o..o + bpp / 8];
            let v = bytes.iter().enumerate().fold(0usize, |acc, (k, b)| {
                if order == 0 {
                    acc | (*b as usize) << (8 * k)
                } else {
                    acc << 8 | *b as usize
                }
            });
            rgb.extend(masks.map(|m| ((v & m) >> m.trailing_zeros()) as u8));
        }
    }
    (w, h, rgb)
}

fn crop((w, _, rgb): &(usize, usize, Vec<u8>), (x0, y0, x1, y1): (i64, i64, i64, i64)) -> Vec<u8> {
    let mut out = Vec::new();
    for y in y0.max(0) as usize..y1 as usize {
        let row = &rgb[(y * w + x0.max(0) as usize) * 3..(y * w + x1 as usize) * 3];
        out.extend_from_slice(row);
    }
    out
}

fn png_rgb(path: &Path) -> (usize, usize, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// Without a display, `--screenshot` renders without a window (it was "cannot open a
/// window"): the picture at its size, the data in it, and no warning from a Wayland probe
/// on stderr.
#[test]
fn a_screenshot_without_a_display_is_taken_headless() {
    let dir = tempfile::tempdir().unwrap();
    let data = dataset(dir.path());
    let shot = dir.path().join("shot.png");
    let out = Command::new(VIEWER)
        .arg(&data)
        .args(["--screenshot", shot.to_str().unwrap(), "--size", "200x150"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    let (w, h, rgb) = png_rgb(&shot);
    assert_eq!((w, h), (200, 150));
    let lit = rgb.chunks(3).filter(|p| p.iter().any(|c| *c > 40)).count();
    assert!(lit > 200 * 150 / 20, "nearly blank ({lit} lit pixels)");
}
