//! Progress bars on stderr, shown only when stderr is a terminal and `--quiet` is not given.
use std::io::IsTerminal;
use std::sync::Arc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// Whether progress should be shown.
pub fn enabled(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal()
}

/// A spinner with a message, or a hidden bar.
pub fn spinner(show: bool, msg: String) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner().with_message(msg);
    pb.enable_steady_tick(Duration::from_millis(100));
    pb
}

/// A bar counting image rows, and the callback that advances it.
pub fn rows(show: bool, total: usize) -> (ProgressBar, Option<volux_render::tiles::ProgressFn>) {
    if !show {
        return (ProgressBar::hidden(), None);
    }
    let pb = ProgressBar::new(total as u64).with_style(
        ProgressStyle::with_template("rendering {bar:40} {pos}/{len} rows {elapsed}")
            .expect("static template is valid"),
    );
    let p = pb.clone();
    (
        pb,
        Some(Arc::new(move |done, _| p.set_position(done as u64))),
    )
}

/// A bar counting bytes written, named after the file.
pub fn bytes(show: bool, name: String) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    ProgressBar::new(0).with_message(name).with_style(
        ProgressStyle::with_template("writing {msg} {bar:40} {bytes}/{total_bytes} {eta}")
            .expect("static template is valid"),
    )
}
