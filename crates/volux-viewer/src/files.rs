//! What the viewer reads and writes besides datasets: the file dialog's choices, transfer
//! function files, sessions, screenshots (at any size, on a job thread), and `--screenshot`'s
//! write-and-exit.
use std::path::{Path, PathBuf};

use eframe::egui;
use volux_core::image::PngOptions;

use crate::app::ViewerApp;
use crate::file_dialog::Purpose;
use crate::jobs::Job;
use crate::tf_editor::in_value_space;

impl ViewerApp {
    /// Opens the file dialog for `purpose`: files to read are looked for beside the dataset,
    /// files to write go where the last one went ([`FileDialog::save_folder`]).
    ///
    /// [`FileDialog::save_folder`]: crate::file_dialog::FileDialog::save_folder
    pub fn open_dialog(&mut self, purpose: Purpose) {
        let folder = if purpose.saves() {
            self.dialog.save_folder()
        } else {
            self.data
                .as_ref()
                .and_then(|d| d.source.path.parent().map(Path::to_path_buf))
                .filter(|p| p.is_dir())
                .or_else(|| std::env::current_dir().ok())
                .unwrap_or_else(|| PathBuf::from("."))
        };
        let name = match purpose {
            Purpose::SaveTf => "tf.json",
            Purpose::SaveSession => "session.json",
            Purpose::SaveScreenshot => "screenshot.png",
            Purpose::ExportMask => "mask.nrrd",
            Purpose::ExportLabels => "labels.nrrd",
            _ => "",
        };
        self.dialog.open(purpose, &folder, name);
    }

    /// The file dialog (open or not).
    pub fn file_dialog(&self) -> &crate::file_dialog::FileDialog {
        &self.dialog
    }

    /// Acts on a path chosen in the file dialog.
    pub(crate) fn chosen(&mut self, purpose: Purpose, path: &Path) {
        let result = match purpose {
            Purpose::Open => {
                self.open(path);
                Ok(None)
            }
            Purpose::LoadTf => self.load_tf(path),
            Purpose::SaveTf => {
                let text = self.scene.appearance.tf.to_json();
                volux_core::image::write_atomically(path, text.as_bytes())
                    .map(|_| Some(format!("saved {}", path.display())))
                    .map_err(|e| format!("{}: {e}", path.display()))
            }
            Purpose::SaveSession => self.save_session(path).map(Some),
            Purpose::SaveScreenshot => {
                self.export_screenshot(path, self.export_size);
                Ok(None)
            }
            Purpose::ExportMask => self.export_mask(path).map(|_| None),
            Purpose::ExportLabels => self.export_labels(path).map(|_| None),
        };
        match result {
            Ok(m) => self.status = m,
            Err(e) => self.error = Some(e),
        }
    }

    /// Replaces the TF with one read from `path` (any format `volux render --tf` reads);
    /// returns what the file sets that Volux does not apply (to show), if anything.
    pub fn load_tf(&mut self, path: &Path) -> Result<Option<String>, String> {
        let imported = volux_core::transfer_import::import_file(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        self.scene.appearance.tf = in_value_space(&imported.tf, self.range());
        if let Some(e) = &mut self.editor {
            e.fit_height(&self.scene.appearance.tf);
        }
        let notes = imported.notes.join("; ");
        Ok((!notes.is_empty()).then(|| format!("{}: {notes}", path.display())))
    }

    /// Saves the session to `path`.
    pub fn save_session(&self, path: &Path) -> Result<String, String> {
        let s = self.session().ok_or("no dataset to save a session of")?;
        s.save(path).map_err(|e| e.to_string())?;
        Ok(format!("saved {}", path.display()))
    }

    /// Renders the current scene at `size` on a thread of its own and writes it to `path`.
    pub fn export_screenshot(&mut self, path: &Path, size: (usize, usize)) {
        let Some(data) = &self.data else {
            self.error = Some("no dataset to take a screenshot of".into());
            return;
        };
        if let Err(e) = crate::png_path(path) {
            self.error = Some(e);
            return;
        }
        // The sculpt's planes and mask too.
        let mut scene = self.render_scene();
        scene.view.width = size.0.max(1);
        scene.view.height = size.1.max(1);
        let mesh_method = scene.method.draws_tets();
        let Some(volume) = data.volume_for(mesh_method).cloned() else {
            return;
        };
        let png = PngOptions {
            background: Some(self.background),
            sixteen_bit: false,
        };
        let path = path.to_path_buf();
        self.export_job = Some(Job::spawn("screenshot", move || {
            let control = volux_render::tiles::Control::default();
            let frame = volux_render::engine::render_once(&volume.volume, &scene, &control)
                .map_err(|e| e.to_string())?;
            frame
                .image
                .write_png(&path, &png)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            Ok(format!("saved {} ({}x{})", path.display(), size.0, size.1))
        }));
    }

    /// `--screenshot`: once the full frame of the current scene is on screen and nothing is
    /// loading, write it (and the session) and close the window.
    pub(crate) fn finish_screenshot(&mut self, ctx: &egui::Context) {
        let Some(path) = self.options.screenshot.clone() else {
            return;
        };
        if self.finished {
            return;
        }
        // A file that cannot be read, or a scene that cannot be rendered: say so and stop.
        if !self.busy() && self.error.is_some() {
            eprintln!("volux-view: {}", self.error.as_deref().unwrap_or_default());
            self.finished = true;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        let Some(shown) = &self.shown else { return };
        let current = self.submitted.as_ref().map(|s| &s.scene);
        if !shown.frame.full
            || shown.frame.generation != self.service.generation()
            || current != Some(&shown.frame.scene)
            || self.busy()
        {
            return;
        }
        let png = PngOptions {
            background: Some(shown.frame.background),
            sixteen_bit: false,
        };
        let result = shown
            .frame
            .image
            .write_png(&path, &png)
            .map_err(|e| e.to_string());
        let result = result.and_then(|_| match &self.options.save_session {
            Some(s) => self.save_session(s).map(|_| ()),
            None => Ok(()),
        });
        match result {
            Ok(()) => eprintln!("wrote {}", path.display()),
            Err(e) => {
                eprintln!("volux-view: {}: {e}", path.display());
                self.error = Some(e);
            }
        }
        self.finished = true;
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}
