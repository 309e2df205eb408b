//! # volux-testkit
//!
//! Helpers every Volux test suite shares, so that each exists once (a dev-dependency only):
//!
//! - [`rng`]: [`TestRng`], a seeded generator for reproducible random cases;
//! - [`tf`]: random piecewise-linear transfer functions;
//! - [`data`]: paths into `../shared/data`, skipping with a message when a file is absent;
//! - [`images`]: image comparison with stated tolerances, writing the expected, actual and
//!   difference images on failure (the metrics are [`volux_core::image::compare`]'s);
//! - [`reference`](mod@reference): brute-force integrals used as independent references (composite
//!   Simpson of a linear ray segment).
//! - [`mutate`]: seeded mutations of input files for the hostile-input tests (bit flips,
//!   header and sidecar edits, bombs, file-system cases), and the gzip/zlib encoders the
//!   readers' tests share;
//! - [`nifti`]: small NIfTI-1 files written byte by byte (a head with a marker on the
//!   patient's left, for the named views).
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod data;
pub mod images;
pub mod mutate;
pub mod nifti;
pub mod reference;
pub mod rng;
pub mod tf;

pub use rng::TestRng;
