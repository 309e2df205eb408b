//! `volux`: load, inspect, convert, generate and render volumes and tetrahedral meshes.
#![forbid(unsafe_code)]

/// `println!` that returns the write's `io::Result` instead of panicking: a closed pipe
/// (`volux info F | head -1`) comes back as [`std::io::ErrorKind::BrokenPipe`] through `?`,
/// and [`main`] ends quietly on it, as Unix tools do.
macro_rules! outln {
    () => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock())
    }};
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// `print!` as [`outln!`] is `println!`.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
    }};
}

mod applicable;
mod cli;
mod commands;
mod label_file;
mod mask_file;
mod memory;
mod messages;
mod numbers;
mod phrase;
mod progress;
mod settings;

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches};
use messages::sanitize;

fn main() -> ExitCode {
    #[cfg(feature = "gpu")]
    volux_gpu::quiet_headless_vulkan();
    let args = match parse() {
        Ok(args) => args,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            e.exit()
        }
        Err(e) => {
            eprintln!("volux: error: {}", sanitize(&one_line(&e.to_string())));
            return ExitCode::from(2);
        }
    };
    if let Err(e) = memory::apply(args.memory_budget) {
        eprintln!("volux: error: {}", sanitize(&e.to_string()));
        return ExitCode::from(2);
    }
    match commands::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`| head`): nothing more to say, as Unix tools end.
        Err(e) if is_closed_pipe(e.as_ref()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("volux: error: {}", sanitize(&phrase::phrase(e.as_ref())));
            ExitCode::FAILURE
        }
    }
}

/// Whether `e` is a write to a closed pipe.
fn is_closed_pipe(e: &(dyn std::error::Error + 'static)) -> bool {
    e.downcast_ref::<std::io::Error>()
        .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
}

/// Parses the command line, noting which `render` options were given (not defaulted).
fn parse() -> Result<cli::Cli, clap::Error> {
    parse_from(std::env::args_os())
}

/// Parses `argv` (the program name first) as [`parse`] does the command line.
fn parse_from<I, T>(argv: I) -> Result<cli::Cli, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let matches = cli::Cli::command().try_get_matches_from(argv)?;
    let mut args = cli::Cli::from_arg_matches(&matches)?;
    if let Some((name, sub)) = matches.subcommand() {
        args.given = given_options(name, sub);
    }
    match &mut args.command {
        cli::Command::Render(r) => r.given = args.given.clone(),
        cli::Command::Sculpt(s) => {
            if let Some((_, sub)) = matches.subcommand() {
                s.fill_order(sub);
            }
        }
        _ => {}
    }
    Ok(args)
}

/// The long names of the options of subcommand `name` the user typed.
fn given_options(name: &str, sub: &ArgMatches) -> Vec<String> {
    let cli = cli::Cli::command();
    let Some(command) = cli.find_subcommand(name) else {
        return Vec::new();
    };
    command
        .get_arguments()
        .filter(|a| sub.value_source(a.get_id().as_str()) == Some(ValueSource::CommandLine))
        .filter_map(|a| a.get_long().map(str::to_string))
        .collect()
}

/// A clap error on one line: its first line without clap's own `error: ` prefix, the items
/// it lists when it ends with a colon, clap's tip, and the accepted values when clap lists
/// them.
fn one_line(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .take_while(|l| !l.starts_with("Usage:"))
        .collect();
    let first = lines.first().copied().unwrap_or("invalid arguments");
    let mut out = first.strip_prefix("error: ").unwrap_or(first).to_string();
    if out.ends_with(':') {
        let items: Vec<&str> = lines[1..]
            .iter()
            .take_while(|l| !l.starts_with("tip:") && !l.starts_with('['))
            .copied()
            .collect();
        out = format!("{} {}", out, items.join(", "));
    }
    for extra in lines[1..]
        .iter()
        .filter(|l| l.starts_with("tip:") || l.starts_with("[possible values:"))
    {
        out = format!("{out}; {extra}");
    }
    format!("{out} (see --help)")
}

#[cfg(test)]
mod tests {
    use super::{one_line, parse_from};
    use crate::cli::{Command, ToolKind};

    /// `volux sculpt` keeps the tools in command-line order, whichever option names them.
    #[test]
    fn sculpt_tools_keep_their_order() {
        let argv = [
            "volux",
            "sculpt",
            "a.nrrd",
            "--dig",
            "1,1,1",
            "--erase",
            "2,2,2",
            "--stroke",
            "1,1,2,2,3",
            "--dig",
            "3,3,3",
            "-o",
            "m.nrrd",
        ];
        let Command::Sculpt(s) = parse_from(argv).unwrap().command else {
            panic!("a sculpt command")
        };
        let want = [
            (ToolKind::Dig, 0),
            (ToolKind::Erase, 0),
            (ToolKind::Stroke, 0),
            (ToolKind::Dig, 1),
        ];
        assert_eq!(s.order, want);
    }

    #[test]
    fn clap_errors_fit_one_line_with_what_they_list() {
        let missing = "error: the following required arguments were not provided:\n  <FILE>\n\nUsage: volux render <FILE>\n\nFor more information, try '--help'.\n";
        assert_eq!(
            one_line(missing),
            "the following required arguments were not provided: <FILE> (see --help)"
        );
        let typo = "error: unexpected argument '--sizee' found\n\n  tip: a similar argument exists: '--size'\n\nUsage: volux render --size <SIZE> <FILE>\n";
        assert_eq!(
            one_line(typo),
            "unexpected argument '--sizee' found; tip: a similar argument exists: '--size' (see --help)"
        );
        let value = "error: invalid value 'foo' for '--method <METHOD>'\n  [possible values: auto, pt]\n\nFor more information, try '--help'.\n";
        assert_eq!(
            one_line(value),
            "invalid value 'foo' for '--method <METHOD>'; [possible values: auto, pt] (see --help)"
        );
    }
}
