//! What every command shares: the error type, and loading a file with a spinner.
use std::path::Path;

use volux_io::{Dataset, Format};

use crate::cli::LoadArgs;
use crate::progress;

/// An error of a command: one readable line.
pub type CmdError = Box<dyn std::error::Error + Send + Sync>;

/// Loads a file with a spinner.
pub fn load(path: &Path, args: &LoadArgs, show: bool) -> Result<(Dataset, Format), CmdError> {
    let pb = progress::spinner(show, format!("loading {}", path.display()));
    let out = volux_io::load(path, &args.dataset(path).load_options());
    pb.finish_and_clear();
    let (data, format) = out?;
    check_reader_options(path, args, format)?;
    Ok((data, format))
}

/// The reader options apply to one format each: given for another, they are refused
/// ([`volux_app::open::check_reader_options`]).
fn check_reader_options(path: &Path, args: &LoadArgs, format: Format) -> Result<(), CmdError> {
    Ok(volux_app::open::check_reader_options(
        &args.dataset(path),
        format,
    )?)
}
