//! The commands, one module each; arguments become library objects in
//! [`crate::settings`], and every render goes through the engine API
//! ([`volux_render::engine`]).
mod accuracy;
mod backend;
mod bench;
pub(crate) mod bricked;
pub mod common;
mod compare;
mod convert;
mod distributed;
mod help;
mod info;
mod measure;
mod orbit;
mod raw;
mod regions;
mod render;
mod report;
mod sculpt;
mod session;
mod store;
mod tf;
mod view;
mod workbench;

use crate::cli::{Cli, Command, TfCommand};
use crate::progress;
use common::CmdError;

/// Runs the command.
pub fn run(cli: Cli) -> Result<(), CmdError> {
    let show = progress::enabled(cli.quiet);
    match cli.command {
        Command::Info {
            file,
            gpu,
            json,
            load,
        } => {
            if gpu {
                return backend::list_adapters(json);
            }
            let file = file.ok_or("give the file to describe")?;
            // A store is described from its metadata (unless a level is to be loaded).
            let store = volux_io::detect(&file).ok() == Some(volux_io::Format::OmeZarr);
            if store && load.level.is_none() {
                store::info(&file, json, &load)
            } else {
                info::run(&file, json, &load, show)
            }
        }
        Command::Convert {
            input,
            output,
            load,
            chunk,
            levels,
        } => {
            if store::is_zarr_output(&output) {
                let args = store::StoreArgs::parse(chunk, levels.as_deref())?;
                store::convert(&input, &output, &load, &args, show)
            } else if chunk.is_some() || levels.is_some() {
                Err("--chunk and --levels apply to OME-Zarr outputs (OUT.ome.zarr)".into())
            } else {
                convert::run(&input, &output, &load, show)
            }
        }
        Command::Generate {
            kind,
            size,
            output,
            chunk,
            levels,
            dtype,
        } => {
            if store::is_zarr_output(&output) {
                let args = store::StoreArgs::parse(chunk, levels.as_deref())?;
                store::generate(
                    &crate::cli::value_name(&kind),
                    store::parse_dims(&size)?,
                    dtype.as_deref(),
                    &output,
                    &args,
                )
            } else if chunk.is_some() || levels.is_some() || dtype.is_some() {
                Err("--chunk, --levels and --dtype apply to OME-Zarr outputs (OUT.ome.zarr)".into())
            } else {
                let n = size.parse::<usize>().map_err(|_| {
                    format!("--size '{size}': expected a count (XxYxZ only for .ome.zarr stores)")
                })?;
                convert::generate(kind, n, &output)
            }
        }
        // A session file replays a saved view (its own module, which renders through
        // `render::render_on`); anything else is a render of a file.
        Command::Render(args) => match &args.session {
            Some(session) => session::run(&args, session, show),
            None => render::run(&args, show),
        },
        Command::Sculpt(args) => sculpt::run(&args, &cli.given, show),
        Command::Measure(args) => measure::run(&args, &cli.given, show),
        Command::Regions(args) => regions::run(&args, &cli.given, show),
        Command::Demo { output } => render::demo(&output, show),
        Command::View { path, rest } => view::run(path.as_deref(), &rest),
        Command::Help { topic } => help::run(topic.as_deref()),
        Command::Tf {
            action: TfCommand::Show { preset, data, load },
        } => tf::show(&preset, data.as_deref(), &load, show),
        Command::Compare {
            a,
            b,
            threshold,
            diff,
            diff_max,
            json,
        } => compare::run(&compare::Args {
            a: &a,
            b: &b,
            threshold,
            diff: diff.as_deref(),
            diff_max,
            json,
        }),
        Command::Accuracy {
            file,
            tf,
            size,
            eps,
            json,
            load,
            hmax,
            hmin,
        } => accuracy::run(
            &accuracy::Args {
                file,
                tf,
                size,
                eps,
                hmax,
                hmin,
                json,
                load,
            },
            show,
        ),
        Command::Bench {
            quick,
            frames,
            grid_size,
            json,
            suite,
            only,
            file,
            render,
        } => match file {
            Some(file) => bench::file::run(&file, &render, frames, json, &cli.given),
            None => {
                bench::check_options(quick, frames, suite, &cli.given)?;
                bench::run(quick, frames, grid_size, json, suite, only.as_deref())
            }
        },
    }
}
