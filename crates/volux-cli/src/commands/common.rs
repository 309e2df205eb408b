//! What every command shares: the error type, and loading a file with a spinner.
use std::path::Path;

use volux_io::{Dataset, Format, LoadOptions};

use crate::cli::LoadArgs;
use crate::progress;

/// An error of a command: one readable line.
pub type CmdError = Box<dyn std::error::Error + Send + Sync>;

/// Loads a file with a spinner.
pub fn load(path: &Path, args: &LoadArgs, show: bool) -> Result<(Dataset, Format), CmdError> {
    let pb = progress::spinner(show, format!("loading {}", path.display()));
    let opts = LoadOptions {
        q_variable: args.q_variable.clone(),
        q_file: args.q_file.clone(),
        series_uid: args.series.clone(),
        array: args.array.clone(),
    };
    let out = volux_io::load(path, &opts);
    pb.finish_and_clear();
    Ok(out?)
}
