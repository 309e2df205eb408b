//! `volux tf show PRESET`: a transfer-function preset as JSON, to start a hand-made one from.
use std::path::Path;

use volux_core::histogram::Histogram;
use volux_core::transfer::Space;
use volux_core::TransferFunction;

use super::common::CmdError;
use crate::cli::LoadArgs;

/// Prints `preset` as JSON: fitted to the file `data` as `volux render` fits it (value
/// space, the data's unit length), or as defined (CT presets in Hounsfield units, the others
/// normalized over the data's range).
pub fn show(
    preset: &str,
    data: Option<&Path>,
    load: &LoadArgs,
    show: bool,
) -> Result<(), CmdError> {
    let tf = match data {
        _ if crate::settings::is_tf_file(preset) => crate::settings::tf_file(preset)?,
        Some(path) => {
            let (dataset, _) = super::common::load(path, load, show)?;
            crate::settings::plain_volume(dataset)?.preset_tf(preset)?
        }
        None => unfitted(preset)?,
    };
    outln!("{}", tf.to_json())?;
    Ok(())
}

/// A preset without data: value-space presets as they are, the others normalized (fitted
/// to the range [0, 1], where normalized and value positions coincide).
fn unfitted(preset: &str) -> Result<TransferFunction, CmdError> {
    if preset == "auto" {
        return Err("the auto preset is fitted to a data set's histogram: add --data FILE".into());
    }
    let unit = Histogram::from_values(&[0.0f32, 1.0], [0.0, 1.0], 2);
    let mut tf = TransferFunction::preset(preset, &unit)?;
    if !preset.starts_with("ct-") {
        tf.space = Space::Normalized;
    }
    Ok(tf)
}
