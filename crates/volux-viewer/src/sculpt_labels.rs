//! Region labels colouring the rendering (seed `004_*.txt` sec. 6.2): once labelling seeds
//! exist and "Colour by labels" is on, the label volume of the engine's
//! [`volux_render::sculpt::Sculpt::label_volume`] goes into the rendered scene
//! ([`Scene::labels`]), and the labelled voxels take their seed's colour. The volume is
//! computed in the background, again only when what it depends on changes: the sculpt steps
//! other than measurements (seeds, planes, mask) and the transfer function (which voxels
//! are visible). Grid ray casting draws labels; under MIP and with the mesh renderers the scene
//! goes without them and the panel says why ([`LabelColours::not_drawn`]).
use std::sync::Arc;

use volux_render::scene::Scene;
use volux_render::sculpt::{LabelVolume, SculptStep};

use crate::app::ViewerApp;
use crate::jobs::{Job, Poll};
use crate::label_colours::{LabelColours, LabelsKey};

impl ViewerApp {
    /// Keeps the label volume in step with the sculpt (call once a frame): turns the
    /// colouring on when the first seed is placed, starts a computation when the seeds, mask,
    /// planes or transfer function changed (dropping one for an older state), and takes a
    /// finished one.
    pub(crate) fn update_label_colours(&mut self) {
        let key = self.labels_key();
        let colours = &mut self.tools.label_colours;
        let seeds = key.is_some();
        if seeds && !colours.had_seeds {
            colours.on = true;
        }
        colours.had_seeds = seeds;
        let Some(key) = key.filter(|_| colours.on) else {
            colours.job = None;
            return;
        };
        if let Some((done_key, job)) = &mut colours.job {
            if let Poll::Done(r) = job.poll() {
                let done_key = done_key.clone();
                colours.job = None;
                match r {
                    Ok(v) => colours.volume = Some((done_key, Arc::new(v))),
                    Err(e) => return self.show_error(e),
                }
            }
        }
        let colours = &mut self.tools.label_colours;
        let current = colours.volume.as_ref().is_some_and(|(k, _)| *k == key);
        let running = colours.job.as_ref().is_some_and(|(k, _)| *k == key);
        if current {
            colours.job = None;
        } else if !running {
            self.start_label_volume(key);
        }
    }

    /// What the label volume of the current state is computed from; `None` without a grid or
    /// seeds.
    fn labels_key(&self) -> Option<LabelsKey> {
        let (grid, sculpt) = (self.sculpt_grid()?, self.sculpt.as_ref()?);
        if sculpt.label_seeds().is_empty() {
            return None;
        }
        let steps = sculpt
            .steps()
            .into_iter()
            .filter(|s| !matches!(s, SculptStep::Measure { .. }))
            .collect();
        Some(LabelsKey {
            grid: Arc::as_ptr(&grid) as usize,
            steps,
            tf: self.scene.appearance.effective_tf(),
        })
    }

    /// Computes the label volume for `key` in the background (a computation for an older
    /// state is dropped: its result is discarded).
    fn start_label_volume(&mut self, key: LabelsKey) {
        let (Some(grid), Some(sculpt)) = (self.sculpt_grid(), self.sculpt.clone()) else {
            return;
        };
        let scene = self.scene.clone();
        let job = Job::spawn("colouring by labels", move || {
            sculpt
                .label_volume(&grid, &scene)
                .map_err(|e| crate::phrase::phrase(&e))
        });
        self.tools.label_colours.job = Some((key, job));
    }

    /// The labels the rendered scene `scene` draws: the newest label volume while the
    /// colouring is on, seeds exist and the scene can draw labels.
    pub(crate) fn scene_labels(&self, scene: &Scene) -> Option<Arc<LabelVolume>> {
        let colours = &self.tools.label_colours;
        let seeds = self
            .sculpt
            .as_ref()
            .is_some_and(|s| !s.label_seeds().is_empty());
        if !(colours.on && seeds) || LabelColours::not_drawn(scene).is_some() {
            return None;
        }
        colours.volume.as_ref().map(|(_, v)| v.clone())
    }
}
