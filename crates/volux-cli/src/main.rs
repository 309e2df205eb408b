//! `volux`: load, inspect, convert, generate and render volumes and tetrahedral meshes.
#![forbid(unsafe_code)]

mod applicable;
mod cli;
mod commands;
mod numbers;
mod progress;
mod settings;

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches};

fn main() -> ExitCode {
    let args = match parse() {
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

/// Parses the command line, noting which `render` options were given (not defaulted).
fn parse() -> Result<cli::Cli, clap::Error> {
    let matches = cli::Cli::command().try_get_matches()?;
    let mut args = cli::Cli::from_arg_matches(&matches)?;
    if let (cli::Command::Render(r), Some(("render", sub))) =
        (&mut args.command, matches.subcommand())
    {
        r.given = given_options(sub);
    }
    Ok(args)
}

/// The long names of the options the user typed.
fn given_options(sub: &ArgMatches) -> Vec<String> {
    let render = cli::Cli::command();
    let Some(render) = render.find_subcommand("render") else {
        return Vec::new();
    };
    render
        .get_arguments()
        .filter(|a| sub.value_source(a.get_id().as_str()) == Some(ValueSource::CommandLine))
        .filter_map(|a| a.get_long().map(str::to_string))
        .collect()
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
