//! `volux-view`, the interactive viewer of Volux: open a file, turn it with the mouse, shape
//! the transfer function over the histogram, look at slices, save pictures and sessions.
//!
//! The window ([`app::ViewerApp`], eframe/egui with the glow back end: the picture is the
//! CPU engine's, shown as a texture) builds a [`volux_render::scene::Scene`] and hands it to
//! the render thread ([`render_service`]), which renders through the engine API like every
//! other front end: reduced-resolution previews while the user drags, the full frame when
//! input stops. Sessions ([`volux_app::session`]) are shared with `volux render
//! --session`, so a view found by hand renders in batch to the same pixels.
//!
//! Where each part lives:
//!
//! - [`app`]: the state (dataset, scene, slices, jobs) and what acts on it; [`window`]: one
//!   frame of the window (poll, draw the panels, submit);
//! - [`render_service`]: the render thread (mailbox, previews, full frames, cancellation);
//!   [`jobs`]: loading and other background work;
//! - [`backend`]: where frames are rendered (`--backend auto|cpu|gpu`): the CPU engine or the
//!   GPU backend (`volux-gpu`, the default `gpu` feature), and which drew each frame;
//! - [`volume_picker`]: the timepoint/component slider of files holding several volumes;
//!   [`headless`]: `--screenshot` without a display;
//! - [`store`]: OME-Zarr stores opened out of core as bricked volumes;
//!   [`progressive`]: progressive level of detail (coarsest level at once, then each finer
//!   level in the background); [`lod_status`]: the level choice, the level on screen and the
//!   status line's level and cache figures;
//! - [`view3d`]: the 3D view, its gestures and overlay; [`overlay_text`]: text on a dark
//!   backing over pictures; [`navigation`]: the camera gestures
//!   as pure functions (orbit, pan, zoom, standard views);
//! - [`slices`]: the axial, coronal and sagittal planes cut from the data;
//!   [`slice_views`]: their views, crosshair and window/level;
//! - [`sculpt_state`]: the sculpting tools' settings; [`sculpt_actions`]: what the tools do
//!   (steps of the engine's sculpt, undo); [`sculpt_exports`]: label counts and NRRD exports;
//!   [`sculpt_panel`]: their panel; [`sculpt_labels`]: region labels colouring the
//!   rendering, with the setting and label volume of [`label_colours`];
//!   [`sculpt_tools`]: their gestures and overlay in the 3D view (seed `004` ch. 4-6);
//!   [`plane_handle`]: the clipping planes' tilt handles;
//! - [`tf_editor`]: the transfer-function editor over the histogram;
//! - [`panels`]: the menu and the settings panel; [`status_bar`]: the error, message and
//!   cache line at the bottom; [`phrase`]: the engine's errors in the viewer's words (widgets,
//!   not flags); [`file_dialog`]: the file dialog;
//!   [`files`]: TF files, sessions and screenshots read and written; [`dataset`]: a loaded dataset; [`bench`](mod@bench): the scripted benchmark (`--bench`).
#![deny(missing_docs)]
#![forbid(unsafe_code)]
pub mod app;
pub mod backend;
pub mod bench;
pub mod dataset;
pub mod file_dialog;
pub mod files;
pub mod headless;
pub mod jobs;
pub mod label_colours;
pub mod lod_status;
pub mod navigation;
pub mod overlay_text;
pub mod panels;
pub mod phrase;
pub mod plane_handle;
pub mod progressive;
pub mod render_service;
pub mod sculpt_actions;
pub mod sculpt_exports;
pub mod sculpt_labels;
pub mod sculpt_panel;
pub mod sculpt_state;
pub mod sculpt_tools;
pub mod slice_views;
pub mod slices;
pub mod status_bar;
pub mod store;
pub mod tf_editor;
pub mod view3d;
pub mod volume_picker;
pub mod window;

use std::path::Path;

/// Screenshots are PNG: any other extension is an error (nothing is written).
pub fn png_path(path: &Path) -> Result<(), String> {
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        Ok(())
    } else {
        Err(format!(
            "{}: screenshots are PNG files (name it .png)",
            path.display()
        ))
    }
}
