//! `volux view [PATH]`: starts the viewer, `volux-view`, which lives in its own crate so
//! that the CLI builds small. It is looked for next to this executable (the same cargo
//! target folder or install folder), then on the `PATH`.
use std::path::{Path, PathBuf};
use std::process::Command;

use super::common::CmdError;

/// The viewer's executable name.
const VIEWER: &str = "volux-view";

/// Runs `volux-view PATH REST...` and returns its exit status as the command's.
pub fn run(path: Option<&Path>, rest: &[String]) -> Result<(), CmdError> {
    let exe = find_viewer().ok_or(
        "volux-view is not built: build it with `cargo build --release -p volux-viewer` \
         (or install it: `cargo install --path crates/volux-viewer`)",
    )?;
    let mut cmd = Command::new(&exe);
    cmd.args(path).args(rest);
    let status = cmd
        .status()
        .map_err(|e| format!("{}: cannot start: {e}", exe.display()))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("volux-view exited with {status}").into())
    }
}

/// `volux-view` beside the running executable, else on the `PATH`.
fn find_viewer() -> Option<PathBuf> {
    let name = format!("{VIEWER}{}", std::env::consts::EXE_SUFFIX);
    let beside = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(|d| d.join(&name)))
        .filter(|p| p.is_file());
    beside.or_else(|| {
        std::env::var_os("PATH").and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|d| d.join(&name))
                .find(|p| p.is_file())
        })
    })
}
