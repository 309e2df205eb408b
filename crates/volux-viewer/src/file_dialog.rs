//! A file dialog drawn with egui (no system dialog dependency): the folder's entries,
//! folders first, a path field (Enter confirms it), and the action's button. Opening a DICOM folder is opening
//! the folder itself, and so is opening an OME-Zarr store (a `.zarr` folder).
use std::path::{Path, PathBuf};

use eframe::egui;

/// What the chosen path is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Open a dataset (file or DICOM folder) or a session.
    Open,
    /// Load a transfer function (Volux JSON, ParaView JSON, Slicer `.vp`).
    LoadTf,
    /// Save the transfer function as Volux JSON.
    SaveTf,
    /// Save the session.
    SaveSession,
    /// Save a screenshot PNG.
    SaveScreenshot,
    /// Export the sculpt mask as NRRD `u8` (seed `004` ch. 4).
    ExportMask,
    /// Export the region labels as NRRD `u8` (seed `004` sec. 6.2).
    ExportLabels,
}

impl Purpose {
    fn title(self) -> &'static str {
        match self {
            Purpose::Open => "Open a dataset or session",
            Purpose::LoadTf => "Load a transfer function",
            Purpose::SaveTf => "Save the transfer function",
            Purpose::SaveSession => "Save the session",
            Purpose::SaveScreenshot => "Save a screenshot",
            Purpose::ExportMask => "Export the sculpt mask (NRRD)",
            Purpose::ExportLabels => "Export the labels (NRRD)",
        }
    }

    /// Whether the chosen path is written (a save or an export), not read.
    pub fn saves(self) -> bool {
        matches!(
            self,
            Purpose::SaveTf
                | Purpose::SaveSession
                | Purpose::SaveScreenshot
                | Purpose::ExportMask
                | Purpose::ExportLabels
        )
    }
}

/// The dialog's state; `None` purpose: closed.
#[derive(Clone, Debug, Default)]
pub struct FileDialog {
    purpose: Option<Purpose>,
    folder: PathBuf,
    path_text: String,
    entries: Vec<(String, bool)>,
    listing_error: Option<String>,
    /// The folder of the last file saved through the dialog in this session.
    last_save_folder: Option<PathBuf>,
}

impl FileDialog {
    /// Opens the dialog in `folder` for `purpose`, with `name` proposed when saving.
    pub fn open(&mut self, purpose: Purpose, folder: &Path, name: &str) {
        self.purpose = Some(purpose);
        self.enter(folder.to_path_buf());
        self.path_text = if purpose.saves() {
            self.folder.join(name).display().to_string()
        } else {
            self.folder.display().to_string()
        };
    }

    /// Whether it is open.
    pub fn is_open(&self) -> bool {
        self.purpose.is_some()
    }

    /// The path in the dialog's path field (what Enter or the action's button would choose).
    pub fn path_text(&self) -> &str {
        &self.path_text
    }

    /// Where a file is saved unless the user goes elsewhere: the folder of the last file
    /// saved in this session, else the working directory (not the dataset's folder, which
    /// may be read-only, as shared data often is).
    pub fn save_folder(&self) -> PathBuf {
        self.last_save_folder
            .clone()
            .filter(|p| p.is_dir())
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_else(|| PathBuf::from("."))
    }

    fn enter(&mut self, folder: PathBuf) {
        self.folder = folder;
        self.entries.clear();
        self.listing_error = None;
        match std::fs::read_dir(&self.folder) {
            Ok(rd) => {
                for e in rd.flatten().take(10_000) {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if name.starts_with('.') {
                        continue;
                    }
                    let dir = e.file_type().map(|t| t.is_dir()).unwrap_or(false);
                    self.entries.push((name, dir));
                }
                self.entries
                    .sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
            }
            Err(e) => self.listing_error = Some(format!("{}: {e}", self.folder.display())),
        }
    }

    /// Draws the dialog; returns the purpose and path when the user confirms.
    pub fn show(&mut self, ctx: &egui::Context) -> Option<(Purpose, PathBuf)> {
        let purpose = self.purpose?;
        let mut chosen = None;
        let mut open = true;
        egui::Window::new(purpose.title())
            .open(&mut open)
            .default_size([520.0, 420.0])
            .collapsible(false)
            .show(ctx, |ui| {
                chosen = self.contents(ui, purpose);
            });
        if !open || chosen.is_some() {
            self.purpose = None;
        }
        if let Some(folder) = chosen
            .as_deref()
            .filter(|_| purpose.saves())
            .and_then(Path::parent)
            .filter(|p| !p.as_os_str().is_empty())
        {
            self.last_save_folder = Some(folder.to_path_buf());
        }
        chosen.map(|p| (purpose, p))
    }

    fn contents(&mut self, ui: &mut egui::Ui, purpose: Purpose) -> Option<PathBuf> {
        let mut chosen = None;
        ui.horizontal(|ui| {
            if ui.button("⬆ up").clicked() {
                if let Some(p) = self.folder.parent().map(Path::to_path_buf) {
                    self.enter(p);
                }
            }
            ui.label(self.folder.display().to_string());
        });
        if let Some(e) = &self.listing_error {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        let mut go = None;
        egui::ScrollArea::vertical()
            .max_height(280.0)
            .show(ui, |ui| {
                for (name, dir) in &self.entries {
                    let store = *dir && is_store_name(name);
                    let label = if store {
                        format!("🗄 {name} (OME-Zarr store)")
                    } else if *dir {
                        format!("📁 {name}")
                    } else {
                        name.clone()
                    };
                    let r = ui.selectable_label(false, label);
                    if r.clicked() {
                        self.path_text = self.folder.join(name).display().to_string();
                    }
                    if r.double_clicked() {
                        go = Some((self.folder.join(name), *dir));
                    }
                }
            });
        if let Some((path, dir)) = go {
            let opens = is_dicom_folder(&path) || volux_io::omezarr::is_store(&path);
            if dir && !(purpose == Purpose::Open && opens) {
                self.enter(path.clone());
                self.path_text = path.display().to_string();
            } else {
                chosen = Some(path);
            }
        }
        ui.horizontal(|ui| {
            let field =
                ui.add(egui::TextEdit::singleline(&mut self.path_text).desired_width(380.0));
            // A single-line field gives up the focus on Enter.
            let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            let action = if purpose.saves() { "Save" } else { "Open" };
            let clicked = ui.button(action).clicked();
            if (entered || clicked) && !self.path_text.trim().is_empty() {
                chosen = Some(PathBuf::from(self.path_text.trim()));
            }
        });
        chosen
    }
}

/// A folder named as a Zarr store (`.zarr`, `.ome.zarr`), shown as one in the list (its
/// contents are checked when it is opened).
fn is_store_name(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".zarr")
}

/// A folder holding `.dcm` files (or files without extension, as DICOM exports often are).
fn is_dicom_folder(path: &Path) -> bool {
    std::fs::read_dir(path)
        .map(|rd| {
            rd.flatten().take(64).any(|e| {
                e.path()
                    .extension()
                    .is_some_and(|x| x.eq_ignore_ascii_case("dcm"))
            })
        })
        .unwrap_or(false)
}
