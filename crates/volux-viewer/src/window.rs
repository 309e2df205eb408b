//! One frame of the window: jobs polled, finished frames taken, the panels drawn
//! ([`crate::panels`], the file dialog, [`crate::slice_views`], [`crate::view3d`]), then the
//! scene submitted when it changed.
use std::time::Duration;

use eframe::egui;

use crate::app::ViewerApp;

/// Runs one frame of `app` in `ctx` (eframe's update, and the tests' harness).
pub fn frame(app: &mut ViewerApp, ctx: &egui::Context) {
    app.poll_jobs();
    app.take_dropped_files(ctx);
    app.take_frames(ctx);
    crate::panels::show(app, ctx);
    if let Some((purpose, path)) = app.dialog.show(ctx) {
        app.chosen(purpose, &path);
    }
    crate::sculpt_tools::shortcuts(app, ctx);
    crate::slice_views::show(app, ctx);
    crate::view3d::show(app, ctx);
    app.submit_if_changed();
    app.finish_screenshot(ctx);
    if app.busy()
        || app.export_job.is_some()
        || app.tools.labels_job.is_some()
        || app.tools.label_colours.computing()
    {
        ctx.request_repaint_after(Duration::from_millis(100));
    }
}

impl eframe::App for ViewerApp {
    fn update(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        frame(self, ctx);
    }
}
