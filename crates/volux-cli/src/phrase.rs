//! The engine's and the application layer's errors in the command line's words: a setting as
//! the flag that sets it, a remedy as the flag or command that applies it. The libraries'
//! errors are data ([`volux_render::Setting`], [`volux_render::Remedy`]) and name no flag;
//! this is the one place the command line's names are given to them.
use std::error::Error;

use volux_app::AppError;
use volux_render::{Refusal, Remedy, RenderError, Setting, SettingError, Vocabulary};

/// The command line's vocabulary.
pub struct Flags;

impl Vocabulary for Flags {
    fn setting(&self, setting: Setting) -> String {
        let flag = match setting {
            Setting::Step => "--step",
            Setting::Tolerance => "--tol",
            Setting::FirstStep => "--h0",
            Setting::MinStep => "--hmin",
            Setting::MaxStep => "--hmax",
            Setting::OpacityScale => "--opacity-scale",
            Setting::Ambient => "--ambient",
            Setting::Diffuse => "--diffuse",
            Setting::Specular => "--specular",
            Setting::Shininess => "--shininess",
            Setting::LightDirection => "--light",
            Setting::ClipPlane => "--clip-plane",
            // No flag of its own (a session file, the library): the engine's words.
            other => return other.name().to_string(),
        };
        flag.to_string()
    }

    fn remedy(&self, remedy: Remedy) -> String {
        match remedy {
            Remedy::GpuBackend => "use --backend gpu".into(),
            Remedy::CpuBackend => "use --backend cpu".into(),
            Remedy::SplitIntoTets => "split the grid into tetrahedra with --as-tets".into(),
            // The command line's ray casting draws meshes cell by cell.
            Remedy::Method("tet-raycast") => "use --method raycast".into(),
            Remedy::Method(m) => format!("use --method {m}"),
            Remedy::DropMip => "drop --mip".into(),
            Remedy::WritePyramid => "write a pyramid with volux convert --levels auto".into(),
            Remedy::LoadLevel => {
                "load a level that fits the memory budget (--level N, --memory-budget)".into()
            }
            Remedy::SmallerImage => "render a smaller image (--size)".into(),
            // A remedy added to the engine since: its own words.
            other => volux_render::EngineWords.remedy(other),
        }
    }
}

/// The application layer's error in the command line's words: a reader option as its flag,
/// the engine's errors phrased with [`Flags`].
fn app_error(e: &AppError) -> String {
    match e {
        AppError::Render(r) => r.phrase(&Flags),
        AppError::MisplacedOption { option, format } => format!(
            "--{} applies to {} files; this one is {}",
            option.word(),
            option.owners(),
            format.name()
        ),
        AppError::LodOnFile { lod, path, format } => {
            format!(
            "--lod {} applies to OME-Zarr stores, rendered out of core level by level; {} is {}, \
             read whole",
            volux_app::words::level_word(*lod),
            path.display(),
            format.map_or("not a store".to_string(), |f| format!("a {} file", f.name()))
        )
        }
        AppError::LayerWeight { layer, weight } => {
            format!("--tf '{layer}:{weight}': the weight {weight} must be >= 0")
        }
        AppError::MeshOnlyIntegrator { integrator } => {
            format!("--integrator {integrator} applies to tetrahedral meshes (--method raycast)")
        }
        AppError::NotRgb => "--tf-colour does not apply: it colours RGB volumes by the transfer \
                             function, and this volume has one value per voxel"
            .to_string(),
        other => other.to_string(),
    }
}

/// The error `e` as one line in the command line's words: the engine's errors phrased with
/// [`Flags`], and a memory budget exceeded anywhere in its chain pointed at `--memory-budget`.
pub fn phrase(e: &(dyn Error + 'static)) -> String {
    let mut text = if let Some(r) = e.downcast_ref::<RenderError>() {
        r.phrase(&Flags)
    } else if let Some(a) = e.downcast_ref::<AppError>() {
        app_error(a)
    } else if let Some(s) = e.downcast_ref::<SettingError>() {
        RenderError::from(s.clone()).phrase(&Flags)
    } else if let Some(r) = e.downcast_ref::<Refusal>() {
        RenderError::from(r.clone()).phrase(&Flags)
    } else {
        e.to_string()
    };
    let mut link = Some(e);
    while let Some(x) = link {
        if let Some(volux_core::Error::OverBudget { .. }) = x.downcast_ref::<volux_core::Error>() {
            text.push_str(" (--memory-budget)");
            break;
        }
        link = x.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_and_remedies_name_the_flags() {
        let e: Box<dyn Error + Send + Sync> = RenderError::from(SettingError::new(
            Setting::OpacityScale,
            -1,
            "finite and >= 0",
        ))
        .into();
        assert_eq!(
            phrase(e.as_ref()),
            "--opacity-scale -1 must be finite and >= 0"
        );
        // A setting's error on its own (a validation before any render) too.
        let e: Box<dyn Error + Send + Sync> =
            SettingError::new(Setting::Step, -1, ">= 1e-6").into();
        assert_eq!(phrase(e.as_ref()), "--step -1 must be >= 1e-6");
        let refusal = RenderError::from(Refusal::new(
            "the CPU engine",
            "does not draw texture slicing",
            Some(Remedy::GpuBackend),
        ));
        let e: Box<dyn Error + Send + Sync> = AppError::Render(refusal).into();
        assert_eq!(
            phrase(e.as_ref()),
            "the CPU engine does not draw texture slicing; use --backend gpu"
        );
    }

    #[test]
    fn an_exceeded_budget_points_at_the_flag_through_the_chain() {
        let over = volux_core::Error::OverBudget {
            what: "the gradient volume".into(),
            bytes: 8 << 30,
            budget: 1 << 30,
        };
        let e: Box<dyn Error + Send + Sync> = RenderError::from(over).into();
        let line = phrase(e.as_ref());
        assert!(line.starts_with("the gradient volume needs"), "{line}");
        assert!(line.ends_with("(--memory-budget)"), "{line}");
    }

    #[test]
    fn every_remedy_is_phrased_without_the_engines_api_names() {
        for r in [
            Remedy::GpuBackend,
            Remedy::CpuBackend,
            Remedy::SplitIntoTets,
            Remedy::Method("tet-raycast"),
            Remedy::Method("resample"),
            Remedy::DropMip,
            Remedy::WritePyramid,
            Remedy::LoadLevel,
            Remedy::SmallerImage,
        ] {
            let words = Flags.remedy(r);
            assert!(words.contains("--"), "{r:?}: {words}");
            assert!(!words.contains("Volume::"), "{r:?}: {words}");
        }
        assert_eq!(
            Flags.remedy(Remedy::Method("tet-raycast")),
            "use --method raycast"
        );
    }
}
