//! The engine's errors in the viewer's words: a setting as the widget that sets it, a remedy
//! as the widget (or the start-up option) that applies it. The libraries' errors are data
//! ([`volux_render::Setting`], [`volux_render::Remedy`]) and name no front end's option; the
//! command line gives them its flags, the viewer its widgets, here.
use volux_render::{EngineWords, Remedy, RenderError, Setting, Vocabulary};

/// The viewer's vocabulary.
pub struct Widgets;

impl Vocabulary for Widgets {
    fn setting(&self, setting: Setting) -> String {
        let widget = match setting {
            // The labels of the sliders that set them.
            Setting::Step => "step (voxels)",
            Setting::Tolerance => "tolerance",
            Setting::OpacityScale => "opacity scale",
            other => return other.name().to_string(),
        };
        widget.to_string()
    }

    fn remedy(&self, remedy: Remedy) -> String {
        match remedy {
            Remedy::GpuBackend => "start volux-view with --backend gpu".into(),
            Remedy::CpuBackend => "start volux-view with --backend cpu".into(),
            Remedy::SplitIntoTets => "choose a method marked (split) in the method menu".into(),
            Remedy::Method(m) => format!("choose {} in the method menu", method_label(m)),
            Remedy::DropMip => "untick MIP".into(),
            Remedy::WritePyramid => {
                "write a pyramid of the store (volux convert --levels auto)".into()
            }
            Remedy::LoadLevel => "open a level that fits the memory budget (--level N)".into(),
            Remedy::SmallerImage => "make the window smaller".into(),
            // A remedy added to the engine since: its own words.
            other => EngineWords.remedy(other),
        }
    }
}

/// The method menu's label of the method named `name` ([`volux_render::scene::Method::name`]).
fn method_label(name: &str) -> String {
    match name {
        "raycast" => "Ray casting".into(),
        "tet-raycast" => "Tet ray casting".into(),
        "pt" => "Projected Tetrahedra".into(),
        "resample" => "Resample + ray casting".into(),
        "slicing" => "Texture slicing (GPU)".into(),
        other => format!("'{other}'"),
    }
}

/// `e` as the viewer shows it.
pub fn phrase(e: &RenderError) -> String {
    e.phrase(&Widgets)
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_render::scene::{Appearance, Method, PtSettings};
    use volux_render::{Refusal, SettingError};

    #[test]
    fn the_engines_refusals_name_the_viewers_widgets() {
        let tf = volux_core::TransferFunction::from_json(
            r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1], [1, 1]]}"#,
        )
        .unwrap();
        let mip = Appearance {
            mip: true,
            ..Appearance::new(tf)
        };
        let e = Method::ProjectedTetrahedra(PtSettings::default())
            .check_appearance(&mip)
            .unwrap_err();
        let line = phrase(&e);
        assert!(
            line.ends_with("choose Ray casting in the method menu"),
            "{line}"
        );
        assert!(!line.contains("--method"), "{line}");
        let e = RenderError::from(Refusal::new("x", "y", Some(Remedy::DropMip)));
        assert_eq!(phrase(&e), "x y; untick MIP");
        let e = RenderError::from(SettingError::new(Setting::Step, 0, ">= 1e-6"));
        assert_eq!(phrase(&e), "step (voxels) 0 must be >= 1e-6");
    }
}
