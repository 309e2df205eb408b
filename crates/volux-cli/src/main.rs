//! `volux`: load, inspect, convert, generate and render volumes and tetrahedral meshes.
#![forbid(unsafe_code)]

mod cli;
mod commands;
mod progress;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match commands::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("volux: error: {e}");
            ExitCode::FAILURE
        }
    }
}
