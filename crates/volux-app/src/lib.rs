//! The application layer of Volux: what every front end (the `volux` CLI, the `volux-view`
//! viewer, the MPI driver, the Python bindings) needs once, between the libraries (core, io,
//! render, gpu) and the front ends, as f3d's libf3d sits under its application and its
//! Python bindings. A front end translates its arguments or widgets into these calls and
//! phrases their errors for its users; it never decides what another front end also needs.
//!
//! - [`backend`]: where frames are rendered ([`Backend`] `auto | cpu | gpu`), and the one
//!   [`RendererFactory`] that opens renderers on it (OSPRay's device role); `auto` never
//!   prefers a software adapter to the CPU engine;
//! - [`compose`]: a scene composed from a front end's choices (transfer-function layers
//!   from presets and files, the method for the volume at hand, a camera framed on what is
//!   there);
//! - [`distributed`]: a frame of a store rendered by several ranks (sort-last, seed `003`)
//!   over any message passing (MPI in the CLI, threads in tests), equal to one process's;
//! - [`open`]: a dataset opened as the volume to render (files read whole, stores out of
//!   core over the memory budget), its reader options checked against its format;
//! - [`preview`]: what an interactive front end shows while the user drags (previews sized
//!   to a time budget, fixed-step integrators) and how a store refines level by level;
//! - [`session`]: a scene and its dataset saved as versioned JSON (the viewer's sessions,
//!   rendered in batch by `volux render --session`);
//! - [`store`]: OME-Zarr stores opened out of core as bricked volumes, with the notes a user
//!   should read;
//! - [`tools`]: the seed's tools on a grid in a view without a window (eraser, digger,
//!   measurement, region labelling);
//! - [`words`]: the words of options (memory sizes and budgets, pyramid levels, image sizes,
//!   backends), parsed the same way in every front end;
//! - [`AppError`]: errors as data (which session, which word, which backend).
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod backend;
pub mod compose;
pub mod distributed;
mod error;
pub mod open;
pub mod preview;
mod reader_option;
pub mod session;
pub mod store;
pub mod tools;
pub mod words;

pub use backend::{Backend, Device, RendererFactory};
pub use error::AppError;
