//! The sculpting tools' settings in the window (seed `004_*.txt` ch. 4-6): which tool the
//! left button uses in the 3D view, the eraser's and digger's radius, the label picked next
//! and how it claims voxels, the stroke being drawn. The sculpt itself (planes, mask, picks, undo) is the engine's
//! [`volux_render::sculpt::Sculpt`], held by the app.
use eframe::egui;
use volux_core::sculpt::RegionRule;

use crate::jobs::Job;
use crate::label_colours::LabelColours;

/// What a left click or drag does in the 3D view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tool {
    /// Turn, pan and zoom the camera (the viewer's own gestures).
    #[default]
    Navigate,
    /// Drag a disc over the screen: everything under it is removed through the whole depth
    /// (sec. 4.4).
    Erase,
    /// Click: remove a ball at the visible surface (sec. 4.5).
    Dig,
    /// Click: add a point on the visible surface to the measured polyline (sec. 6.2).
    Measure,
    /// Click: a labelling seed on the visible surface (sec. 6.2).
    Label,
}

impl Tool {
    /// Every tool, in the panel's order.
    pub const ALL: [Tool; 5] = [
        Tool::Navigate,
        Tool::Erase,
        Tool::Dig,
        Tool::Measure,
        Tool::Label,
    ];

    /// Its name in the panel.
    pub fn label(self) -> &'static str {
        match self {
            Tool::Navigate => "Navigate",
            Tool::Erase => "Erase",
            Tool::Dig => "Dig",
            Tool::Measure => "Measure",
            Tool::Label => "Label",
        }
    }

    /// Its keyboard shortcut.
    pub fn key(self) -> egui::Key {
        match self {
            Tool::Navigate => egui::Key::N,
            Tool::Erase => egui::Key::E,
            Tool::Dig => egui::Key::D,
            Tool::Measure => egui::Key::M,
            Tool::Label => egui::Key::L,
        }
    }

    /// Whether it changes the mask or picks points (grids only).
    pub fn needs_grid(self) -> bool {
        self != Tool::Navigate
    }
}

/// The tools' settings and the gesture in progress.
pub struct SculptTools {
    /// The left button's tool.
    pub tool: Tool,
    /// The eraser's and digger's radius, pixels of the rendered image.
    pub radius_px: f64,
    /// The label the next labelling seed takes (1 to 255).
    pub label: u8,
    /// Its colour (linear RGB).
    pub colour: [f32; 3],
    /// How the next labelling seed claims voxels: connected by default (a seed on a
    /// structure labels that structure), nearest as the seed `004` sec. 6.2 does; seeds
    /// already placed keep theirs (sessions saved before issue 41 are nearest).
    pub rule: RegionRule,
    /// The next measurement point starts a new polyline.
    pub new_line: bool,
    /// The eraser stroke being drawn, pixels of the rendered image.
    pub stroke: Vec<[f64; 2]>,
    /// The voxel count of each label, once computed.
    pub label_counts: Option<Vec<(u8, u64)>>,
    /// Counting the labels (in the background).
    pub labels_job: Option<Job<Vec<(u8, u64)>>>,
    /// The plane whose slider is being dragged (its moves make one undo step).
    pub plane_gesture: Option<usize>,
    /// The plane whose tilt handle is being dragged, and whether it moved yet.
    pub handle_drag: Option<(usize, bool)>,
    /// "Colour by labels" and its label volume.
    pub label_colours: LabelColours,
}

impl Default for SculptTools {
    fn default() -> Self {
        Self {
            tool: Tool::Navigate,
            radius_px: 12.0,
            label: 1,
            colour: [0.9, 0.2, 0.2],
            rule: RegionRule::Connected,
            new_line: false,
            stroke: Vec::new(),
            label_counts: None,
            labels_job: None,
            plane_gesture: None,
            handle_drag: None,
            label_colours: LabelColours::default(),
        }
    }
}
