//! The "Colour by labels" setting of the Sculpt panel and the label volume it draws with
//! (kept apart from the viewer's update code in `sculpt_labels.rs`, which fills it).
use std::sync::Arc;

use volux_core::TransferFunction;
use volux_render::scene::Scene;
use volux_render::sculpt::{LabelVolume, SculptStep};

use crate::jobs::Job;

/// What a label volume is computed from.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelsKey {
    /// The grid (its address: a new dataset is a new grid).
    pub(crate) grid: usize,
    /// The sculpt steps but measurements.
    pub(crate) steps: Vec<SculptStep>,
    /// The transfer function as drawn, which says which voxels are visible.
    pub(crate) tf: TransferFunction,
}

/// The "Colour by labels" setting and its label volume.
#[derive(Default)]
pub struct LabelColours {
    /// Colour the rendering by the labels (turned on when the first seed is placed).
    pub on: bool,
    /// Whether seeds existed at the last update (to turn `on` when the first comes).
    pub(crate) had_seeds: bool,
    /// The newest label volume and what it was computed from.
    pub(crate) volume: Option<(LabelsKey, Arc<LabelVolume>)>,
    /// The computation under way.
    pub(crate) job: Option<(LabelsKey, Job<LabelVolume>)>,
}

impl LabelColours {
    /// Whether a label volume is being computed.
    pub fn computing(&self) -> bool {
        self.job.is_some()
    }

    /// Why `scene` cannot draw labels, when it cannot: MIP shows the transfer function's
    /// colours, and the mesh renderers draw no labels.
    pub fn not_drawn(scene: &Scene) -> Option<&'static str> {
        scene.labels_not_drawn()
    }
}
