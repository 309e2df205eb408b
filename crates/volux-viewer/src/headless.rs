//! `volux-view --screenshot` on a machine without a display (a server, CI, a batch job): the
//! same window frame ([`crate::window::frame`]) runs in an egui context with no window, as
//! the tests' harness runs it, until the screenshot is written. The picture is the one the
//! window takes: the render thread draws it, egui only lays out the panels around it.
use std::time::{Duration, Instant};

use eframe::egui;

use crate::app::{Options, ViewerApp};

/// The size of the virtual window (the window's default), which sets the 3D view's size
/// when `--size` does not.
pub const WINDOW: [f32; 2] = [1280.0, 900.0];

/// How long a headless screenshot may take before it is given up with an error.
pub const TIME_LIMIT: Duration = Duration::from_secs(900);

/// Whether this process has a display to open a window on (X11 or Wayland).
pub fn have_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|k| std::env::var_os(k).is_some_and(|v| !v.is_empty()))
}

/// Runs the viewer without a window until `options.screenshot` is written (or the load or
/// render failed, which the viewer has printed). Errors when no screenshot is asked for, or
/// after [`TIME_LIMIT`].
pub fn screenshot(options: Options) -> Result<(), String> {
    if options.screenshot.is_none() {
        return Err("a headless viewer only takes screenshots (--screenshot OUT.png)".into());
    }
    let ctx = egui::Context::default();
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::Vec2::from(WINDOW),
        )),
        ..Default::default()
    };
    let mut app: Option<ViewerApp> = None;
    let start = Instant::now();
    loop {
        let mut closed = false;
        let output = ctx.run(input.clone(), |ctx| {
            let app = app.get_or_insert_with(|| ViewerApp::new(ctx, options.clone()));
            crate::window::frame(app, ctx);
        });
        for viewport in output.viewport_output.values() {
            closed |= viewport
                .commands
                .iter()
                .any(|c| matches!(c, egui::ViewportCommand::Close));
        }
        if closed || app.as_ref().is_some_and(|a| a.finished) {
            return Ok(());
        }
        if start.elapsed() > TIME_LIMIT {
            return Err(format!(
                "no screenshot after {} s without a display",
                TIME_LIMIT.as_secs()
            ));
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}
