//! The errors of the renderers, and the image size they accept.
//!
//! Errors are data: which setting holds which value and what it must be ([`SettingError`]),
//! which renderer refuses what and what the user can do instead ([`Refusal`], [`Remedy`]),
//! which limit a request is over. Their `Display` uses the engine's own words; a front end
//! that wants its own (a command line's flags, a viewer's widgets) phrases them through a
//! [`Vocabulary`] with [`RenderError::phrase`]. No message here names a front end's option.
use std::fmt;

/// Errors of the renderers.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The render was cancelled through its cancellation flag.
    #[error("render cancelled")]
    Cancelled,
    /// A setting holds a value it does not accept.
    #[error("{0}")]
    Setting(SettingError),
    /// The renderer, the method or the backend does not draw what the scene asks for.
    #[error("{0}")]
    Refused(Refusal),
    /// An image size outside `1..=max` on a side.
    #[error("image size {width}x{height} must be between 1 and {max} on a side")]
    ImageSize {
        /// The width asked for.
        width: usize,
        /// The height asked for.
        height: usize,
        /// The largest side accepted.
        max: usize,
    },
    /// A voxel layer (a sculpt mask, region labels) made for a grid of other dimensions.
    #[error(
        "the {layer} is {layer_dims:?} voxels but the grid is {grid_dims:?}: it applies to the grid it was made for"
    )]
    LayerMismatch {
        /// The layer ("sculpt mask", "region labels").
        layer: &'static str,
        /// The layer's dimensions.
        layer_dims: [usize; 3],
        /// The grid's.
        grid_dims: [usize; 3],
    },
    /// A pyramid level past a bricked volume's last.
    #[error("level {level} does not exist: the volume has {levels} levels")]
    NoSuchLevel {
        /// The level asked for.
        level: usize,
        /// How many levels the volume has.
        levels: usize,
    },
    /// A count over a limit of the engine (PT's tile bins, the samples a statistic reads).
    #[error("{what} would hold {count}, more than {limit}{}", remedy_words(remedy, &EngineWords))]
    OverLimit {
        /// What is too large.
        what: String,
        /// Its size.
        count: u64,
        /// The limit.
        limit: u64,
        /// What avoids it.
        remedy: Option<Remedy>,
    },
    /// A sculpt step of a saved sequence that cannot apply (seed `004`).
    #[error("sculpt step {step} of {steps}: {source}")]
    SculptStep {
        /// The step, from 1.
        step: usize,
        /// How many steps the sequence has.
        steps: usize,
        /// Why it cannot apply.
        source: Box<RenderError>,
    },
    /// A sculpt step that names a clip plane the state does not have.
    #[error("there is no plane {index} to {action} (the sculpt has {planes})")]
    NoSuchPlane {
        /// The plane's index.
        index: usize,
        /// "move", "remove".
        action: &'static str,
        /// How many planes there are.
        planes: usize,
    },
    /// An error of the data model.
    #[error("{0}")]
    Data(#[from] volux_core::Error),
    /// A rendering backend (the GPU) failed or cannot draw the scene: no adapter, a device
    /// limit, out of device memory, a lost device.
    #[error("{reason}{}", remedy_words(remedy, &EngineWords))]
    Backend {
        /// What went wrong.
        reason: String,
        /// What avoids it, when something does (the CPU engine).
        remedy: Option<Remedy>,
    },
    /// A broken invariant of the engine (a bug): what broke.
    #[error("internal error: {0}")]
    Internal(String),
}

/// A setting of a scene or a tool, named in the engine's words ([`Setting::name`]); a front
/// end maps it to its own option or widget.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Setting {
    /// The integrators' fixed step (voxels).
    Step,
    /// Adaptive Simpson's error tolerance.
    Tolerance,
    /// Adaptive Simpson's first step.
    FirstStep,
    /// Adaptive Simpson's smallest step.
    MinStep,
    /// Adaptive Simpson's largest step.
    MaxStep,
    /// The opacity scale.
    OpacityScale,
    /// The early ray termination opacity.
    EarlyTermination,
    /// Blinn-Phong's ambient coefficient.
    Ambient,
    /// Blinn-Phong's diffuse coefficient.
    Diffuse,
    /// Blinn-Phong's specular coefficient.
    Specular,
    /// Blinn-Phong's specular exponent.
    Shininess,
    /// The gradient magnitude under which a sample is unlit.
    MinGradient,
    /// The light's direction.
    LightDirection,
    /// A clipping plane.
    ClipPlane,
    /// A pixel picked on the image.
    PickPixel,
    /// The opacity at which a pick stops.
    PickThreshold,
    /// A point picked in the volume.
    PickedPoint,
    /// A region label.
    Label,
    /// A label's colour.
    LabelColour,
    /// The number of values of a label volume.
    LabelCount,
    /// A grid's dimensions.
    Dimensions,
    /// A grid's spacing.
    Spacing,
    /// The data range a table is built on.
    ValueRange,
    /// The length of a segment a table integrates.
    SegmentLength,
    /// The entries per axis of a table.
    TableSize,
}

impl Setting {
    /// The setting in the engine's words ("opacity scale").
    pub fn name(self) -> &'static str {
        match self {
            Self::Step => "step",
            Self::Tolerance => "adaptive tolerance",
            Self::FirstStep => "adaptive first step",
            Self::MinStep => "adaptive smallest step",
            Self::MaxStep => "adaptive largest step",
            Self::OpacityScale => "opacity scale",
            Self::EarlyTermination => "early termination",
            Self::Ambient => "shading ambient",
            Self::Diffuse => "shading diffuse",
            Self::Specular => "shading specular",
            Self::Shininess => "shading shininess",
            Self::MinGradient => "shading min_gradient",
            Self::LightDirection => "light direction",
            Self::ClipPlane => "clip plane",
            Self::PickPixel => "picked pixel",
            Self::PickThreshold => "picking opacity threshold",
            Self::PickedPoint => "picked point",
            Self::Label => "label",
            Self::LabelColour => "label colour",
            Self::LabelCount => "label volume",
            Self::Dimensions => "grid dimensions",
            Self::Spacing => "grid spacing",
            Self::ValueRange => "value range",
            Self::SegmentLength => "segment length",
            Self::TableSize => "table size",
        }
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A setting with a value it does not accept: which, the value, and what it must be.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{setting} {value} must be {expected}")]
pub struct SettingError {
    /// The setting.
    pub setting: Setting,
    /// Its value, as written.
    pub value: String,
    /// What it must be ("finite and >= 0").
    pub expected: String,
}

impl SettingError {
    /// `setting` holds `value`, which is not `expected`.
    pub fn new(setting: Setting, value: impl fmt::Display, expected: impl Into<String>) -> Self {
        Self {
            setting,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}

impl From<SettingError> for RenderError {
    fn from(e: SettingError) -> Self {
        Self::Setting(e)
    }
}

/// Something the user can change to get what a renderer refused, named without any front
/// end's words: each front end says it in its own ([`Vocabulary::remedy`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Remedy {
    /// Render on a GPU backend (the method is drawn there only).
    GpuBackend,
    /// Render on the CPU engine (the GPU backend does not draw this).
    CpuBackend,
    /// Split the grid into tetrahedra first ([`crate::scene::Volume::to_tets`]).
    SplitIntoTets,
    /// Use another method, by its name ([`crate::scene::Method::name`]).
    Method(&'static str),
    /// Leave maximum intensity projection.
    DropMip,
    /// Write a multiscale pyramid of the store, whose coarse levels are small.
    WritePyramid,
    /// Load a level that fits in the memory budget into memory.
    LoadLevel,
    /// Render a smaller image.
    SmallerImage,
}

/// A renderer (a method, a backend) that does not draw what a scene asks for: who, what it
/// does not do, and what to do instead.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{by} {refuses}{}", remedy_words(remedy, &EngineWords))]
pub struct Refusal {
    /// Who refuses ("Projected Tetrahedra", "the GPU backend").
    pub by: String,
    /// What it does not do, and why ("does not draw tricubic reconstruction yet").
    pub refuses: String,
    /// What the user can do instead.
    pub remedy: Option<Remedy>,
}

impl Refusal {
    /// `by` refuses: `refuses`, with `remedy` as the way out.
    pub fn new(by: impl Into<String>, refuses: impl Into<String>, remedy: Option<Remedy>) -> Self {
        Self {
            by: by.into(),
            refuses: refuses.into(),
            remedy,
        }
    }
}

impl From<Refusal> for RenderError {
    fn from(e: Refusal) -> Self {
        Self::Refused(e)
    }
}

/// A front end's words for what the engine's errors name: settings and remedies.
pub trait Vocabulary {
    /// The setting as the front end's users know it (`--opacity-scale`, "Opacity").
    fn setting(&self, setting: Setting) -> String;
    /// The remedy as an instruction to the front end's users ("use --backend gpu").
    fn remedy(&self, remedy: Remedy) -> String;
}

/// The engine's own words (the `Display` of every error).
#[derive(Clone, Copy, Debug, Default)]
pub struct EngineWords;

impl Vocabulary for EngineWords {
    fn setting(&self, setting: Setting) -> String {
        setting.name().to_string()
    }

    fn remedy(&self, remedy: Remedy) -> String {
        match remedy {
            Remedy::GpuBackend => "render it on a GPU backend".into(),
            Remedy::CpuBackend => "render it on the CPU engine".into(),
            Remedy::SplitIntoTets => {
                "split the grid into tetrahedra first (Volume::to_tets)".into()
            }
            Remedy::Method(m) => format!("use the {m} method"),
            Remedy::DropMip => "leave maximum intensity projection".into(),
            Remedy::WritePyramid => "write a multiscale pyramid of the store".into(),
            Remedy::LoadLevel => "load a level that fits the memory budget".into(),
            Remedy::SmallerImage => "render a smaller image".into(),
        }
    }
}

/// `"; " + ` the remedy in `words`, or nothing.
fn remedy_words(remedy: &Option<Remedy>, words: &dyn Vocabulary) -> String {
    remedy.map_or_else(String::new, |r| format!("; {}", words.remedy(r)))
}

impl RenderError {
    /// The error in a front end's words: settings and remedies as `words` names them, the
    /// rest as `Display` writes it.
    pub fn phrase(&self, words: &dyn Vocabulary) -> String {
        match self {
            Self::Setting(e) => format!(
                "{} {} must be {}",
                words.setting(e.setting),
                e.value,
                e.expected
            ),
            Self::Refused(r) => format!("{} {}{}", r.by, r.refuses, remedy_words(&r.remedy, words)),
            Self::OverLimit {
                what,
                count,
                limit,
                remedy,
            } => format!(
                "{what} would hold {count}, more than {limit}{}",
                remedy_words(remedy, words)
            ),
            Self::Backend { reason, remedy } => format!("{reason}{}", remedy_words(remedy, words)),
            Self::SculptStep {
                step,
                steps,
                source,
            } => {
                format!("sculpt step {step} of {steps}: {}", source.phrase(words))
            }
            other => other.to_string(),
        }
    }

    /// The remedy the error offers, if any.
    pub fn remedy(&self) -> Option<Remedy> {
        match self {
            Self::Refused(r) => r.remedy,
            Self::OverLimit { remedy, .. } | Self::Backend { remedy, .. } => *remedy,
            Self::SculptStep { source, .. } => source.remedy(),
            _ => None,
        }
    }

    /// A backend failure with no way around it.
    pub fn backend(reason: impl Into<String>) -> Self {
        Self::Backend {
            reason: reason.into(),
            remedy: None,
        }
    }
}

/// Largest image side accepted by the renderers.
pub const MAX_IMAGE_SIDE: usize = 1 << 15;

/// Checks an image size: both sides between 1 and [`MAX_IMAGE_SIDE`].
pub fn check_image_size(width: usize, height: usize) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(RenderError::ImageSize {
            width,
            height,
            max: MAX_IMAGE_SIDE,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A front end's words, to show that phrasing reaches every setting and remedy.
    struct Flags;

    impl Vocabulary for Flags {
        fn setting(&self, setting: Setting) -> String {
            format!("--{}", setting.name().replace(' ', "-"))
        }
        fn remedy(&self, remedy: Remedy) -> String {
            format!("flag for {remedy:?}")
        }
    }

    #[test]
    fn settings_are_phrased_in_the_front_ends_words() {
        let e = RenderError::from(SettingError::new(
            Setting::OpacityScale,
            -1.0,
            "finite and >= 0",
        ));
        assert_eq!(e.to_string(), "opacity scale -1 must be finite and >= 0");
        assert_eq!(
            e.phrase(&Flags),
            "--opacity-scale -1 must be finite and >= 0"
        );
    }

    #[test]
    fn remedies_are_phrased_in_the_front_ends_words() {
        let e = RenderError::from(Refusal::new(
            "the CPU engine",
            "does not draw texture slicing",
            Some(Remedy::GpuBackend),
        ));
        assert_eq!(
            e.to_string(),
            "the CPU engine does not draw texture slicing; render it on a GPU backend"
        );
        assert_eq!(
            e.phrase(&Flags),
            "the CPU engine does not draw texture slicing; flag for GpuBackend"
        );
        let nested = RenderError::SculptStep {
            step: 2,
            steps: 3,
            source: Box::new(e),
        };
        assert_eq!(nested.remedy(), Some(Remedy::GpuBackend));
        assert!(
            nested.phrase(&Flags).ends_with("flag for GpuBackend"),
            "{}",
            nested.phrase(&Flags)
        );
        let b = RenderError::Backend {
            reason: "too big".into(),
            remedy: Some(Remedy::CpuBackend),
        };
        assert_eq!(b.phrase(&Flags), "too big; flag for CpuBackend");
    }

    #[test]
    fn image_sizes_outside_the_range_are_refused_with_the_limit() {
        assert!(check_image_size(1, MAX_IMAGE_SIDE).is_ok());
        match check_image_size(0, 4) {
            Err(RenderError::ImageSize {
                width: 0,
                height: 4,
                max,
            }) => assert_eq!(max, MAX_IMAGE_SIDE),
            other => panic!("{other:?}"),
        }
    }
}
