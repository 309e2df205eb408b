//! Axes beyond the three spatial ones: a file that holds several volumes (fMRI and perfusion
//! time series, DWI b-values, vector components, colour channels) is read one 3-D volume at a
//! time, and the grid records the axes it was chosen along ([`ExtraAxis`]) so that `volux
//! info` and the viewer can list them and offer the others.
use serde::Serialize;

use crate::error::{Error, Result};

/// What an axis beyond x, y, z means, as the file's header says.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum AxisKind {
    /// Acquisitions at successive times (fMRI, perfusion, 4-D CT): chosen with `timepoint`.
    Time,
    /// Volumes at the same positions told apart by something else than time (DWI b-values
    /// and directions, echoes, a DICOM series' stacks), or a list the header does not name:
    /// chosen with `timepoint`.
    Volume,
    /// Components of a vector or tensor at each voxel (NIfTI intent vector, NRRD `vector`):
    /// chosen with `component`.
    Component,
    /// Colour channels (RGB): the grid keeps the colour, or holds one channel chosen with
    /// `component`.
    Color,
    /// Channels of a microscope image (fluorescence channels of an ImageJ hyperstack, an
    /// OME-TIFF or an OME-Zarr image), each a volume of its own: chosen with `channel`.
    Channel,
}

impl AxisKind {
    /// The reader option that chooses along this axis (`"timepoint"`, `"component"` or
    /// `"channel"`).
    pub fn option(&self) -> &'static str {
        match self {
            AxisKind::Time | AxisKind::Volume => "timepoint",
            AxisKind::Component | AxisKind::Color => "component",
            AxisKind::Channel => "channel",
        }
    }
}

/// One axis beyond x, y, z along which the file holds several volumes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExtraAxis {
    /// What the axis means.
    pub kind: AxisKind,
    /// How many volumes lie along it.
    pub len: usize,
    /// The one the grid holds (`None`: all of them, as the colour of an RGB grid).
    pub chosen: Option<usize>,
    /// What tells the volumes apart, per volume, where the header says (acquisition times,
    /// b-values); empty when it does not.
    pub values: Vec<f64>,
    /// What `values` measure and their unit ("time (s)", "b-value (s/mm²)"), or the step
    /// between volumes when only a step is known ("step 2.5 s"); empty when unknown.
    pub meaning: String,
}

impl ExtraAxis {
    /// An axis of `len` volumes of which `chosen` is read, with no further meaning.
    pub fn new(kind: AxisKind, len: usize, chosen: Option<usize>) -> Self {
        Self {
            kind,
            len,
            chosen,
            values: Vec::new(),
            meaning: String::new(),
        }
    }

    /// This axis with per-volume `values` and what they measure.
    pub fn with_values(mut self, values: Vec<f64>, meaning: impl Into<String>) -> Self {
        self.values = values;
        self.meaning = meaning.into();
        self
    }

    /// This axis with a meaning and no per-volume values ("step 2.5 s").
    pub fn with_meaning(mut self, meaning: impl Into<String>) -> Self {
        self.meaning = meaning.into();
        self
    }

    /// One line for people: "time: 4 volumes (timepoint 0 read), step 2.5 s".
    pub fn describe(&self) -> String {
        let kind = match self.kind {
            AxisKind::Time => "time",
            AxisKind::Volume => "volumes",
            AxisKind::Component => "components",
            AxisKind::Color => "colour",
            AxisKind::Channel => "channels",
        };
        let what = match self.kind {
            AxisKind::Color | AxisKind::Channel => format!("{} channels", self.len),
            AxisKind::Component => format!("{} components", self.len),
            _ => format!("{} volumes", self.len),
        };
        let chosen = match self.chosen {
            Some(i) => format!(" ({} {i} read)", self.kind.option()),
            None => " (all kept)".to_string(),
        };
        let mut s = format!("{kind}: {what}{chosen}");
        if !self.meaning.is_empty() {
            s.push_str(", ");
            s.push_str(&self.meaning);
        }
        if !self.values.is_empty() {
            let shown: Vec<String> = self
                .values
                .iter()
                .take(12)
                .map(|v| format!("{v}"))
                .collect();
            let more = if self.values.len() > 12 { ", ..." } else { "" };
            s.push_str(&format!(": {}{more}", shown.join(", ")));
        }
        s
    }
}

/// The index chosen along an axis of `len` volumes, or the error that names the option, the
/// index and how many there are.
pub fn choose(option: &'static str, index: usize, len: usize) -> Result<usize> {
    if index < len {
        Ok(index)
    } else {
        Err(Error::NoSuchVolume { option, index, len })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_axis_describes_itself_with_its_values() {
        let a = ExtraAxis::new(AxisKind::Volume, 3, Some(1))
            .with_values(vec![0.0, 1000.0, 1000.0], "b-value (s/mm²)");
        assert_eq!(
            a.describe(),
            "volumes: 3 volumes (timepoint 1 read), b-value (s/mm²): 0, 1000, 1000"
        );
        let t = ExtraAxis::new(AxisKind::Time, 4, Some(0)).with_meaning("step 2.5 s");
        assert_eq!(
            t.describe(),
            "time: 4 volumes (timepoint 0 read), step 2.5 s"
        );
    }

    #[test]
    fn channels_are_chosen_with_channel() {
        let c = ExtraAxis::new(AxisKind::Channel, 3, Some(2));
        assert_eq!(c.kind.option(), "channel");
        assert_eq!(c.describe(), "channels: 3 channels (channel 2 read)");
    }

    #[test]
    fn an_index_past_the_axis_is_an_error_that_names_it() {
        assert_eq!(choose("timepoint", 2, 3).unwrap(), 2);
        let e = choose("timepoint", 3, 3).unwrap_err();
        assert!(matches!(
            e,
            Error::NoSuchVolume {
                option: "timepoint",
                index: 3,
                len: 3
            }
        ));
        assert_eq!(
            e.to_string(),
            "timepoint 3 does not exist: the file holds 3 (0 to 2)"
        );
    }
}
