//! `volux`: load, inspect, convert, generate and render volumes and tetrahedral meshes.
#![forbid(unsafe_code)]

mod cli;
mod commands;
mod progress;
mod settings;

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::Parser;

fn main() -> ExitCode {
    let args = match cli::Cli::try_parse() {
        Ok(args) => args,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            e.exit()
        }
        Err(e) => {
            eprintln!("volux: error: {}", one_line(&e.to_string()));
            return ExitCode::from(2);
        }
    };
    match commands::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("volux: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A clap error on one line: its first line without clap's own `error: ` prefix, followed by
/// the accepted values when clap lists them.
fn one_line(text: &str) -> String {
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("invalid arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    match lines.find(|l| l.starts_with("[possible values:")) {
        Some(values) => format!("{first} {values}"),
        None => format!("{first} (see --help)"),
    }
}
