//! # volux-core
//!
//! The data model of Volux, the first stage of the pipeline
//! (**data** -> sampling -> classification -> integration -> traversal -> compositing -> image):
//!
//! - [`aabb::Aabb`]: world-space bounding boxes;
//! - [`grid::Grid`]: a regular grid of scalars kept in their native type, possibly memory-mapped,
//!   placed in LPS world millimetres by an origin, spacing and direction matrix; [`samples`]:
//!   the typed sample buffers; [`geometry_match`]: whether a mask or labels lie on a grid's
//!   own lattice;
//! - [`bricked`]: volumes stored in chunks and read a chunk at a time ([`bricked::ChunkSource`],
//!   one level; [`bricked::Multiscale`], the pyramid), the seam between chunked storage and the
//!   bricked renderer (seed `003`);
//! - [`orientation`]: direction matrices and their patient-orientation letters (LPS, RAS);
//! - [`color::Rgb`]: the colour channels of an RGB grid, kept beside its luminance;
//! - [`volume_axes`]: the axes beyond x, y, z (time, b-values, components) of files holding
//!   several volumes, one of which a grid is;
//! - [`mesh::TetMesh`]: a tetrahedral mesh with one scalar per vertex, validation, boundary faces,
//!   face adjacency and per-vertex gradients;
//! - [`tetrahedralize`]: regular and curvilinear grids split into conforming tetrahedra;
//! - [`transfer::TransferFunction`]: piecewise-linear colour and extinction, presets, JSON;
//! - [`transfer_import`]: ParaView presets and 3D Slicer `.vp` volume properties read into a
//!   transfer function;
//! - [`camera::Camera`]: perspective and orthographic cameras, JSON; [`named_view`]: the
//!   anatomical and axis views every front end names (`left` shows the patient's left);
//! - [`image::Image`]: the RGBA f32 linear framebuffer and PNG output;
//! - [`voi::ConvexVoi`]: the convex volume of interest cut by planes (seed `004`, ch. 4);
//! - [`sculpt`]: the full-resolution sculpt mask, the eraser's and digger's regions and
//!   region labelling (seed `004`, ch. 4-6);
//! - [`segment`]: distances in the plane (the eraser's swept disc, drawn segments);
//! - [`heatmap`]: heat-map images of per-pixel values with a colour-scale legend;
//! - [`histogram`]: value histograms (the automatic transfer function is fitted on them);
//! - [`synth`]: synthetic datasets for tests, benchmarks and the demo;
//! - [`error`]: the typed errors of the data model; [`limits`]: allocation limits checked
//!   before any large buffer is reserved, against the process's memory budget; [`units`]: byte
//!   counts in human units.
#![deny(missing_docs)]
#![deny(unsafe_code)]

pub mod aabb;
pub mod bricked;
pub mod camera;
pub mod color;
pub mod error;
pub mod geometry_match;
pub mod grid;
pub mod heatmap;
pub mod histogram;
pub mod image;
mod json_shape;
pub mod limits;
pub mod mesh;
pub mod named_view;
pub mod orientation;
pub mod samples;
pub mod sculpt;
pub mod segment;
pub mod synth;
pub mod tetrahedralize;
pub mod transfer;
pub mod transfer_import;
pub mod units;
pub mod voi;
pub mod volume_axes;

pub use aabb::Aabb;
pub use camera::{Camera, CameraSpec, Projection, RayGenerator};
pub use error::{Error, Result};
pub use grid::{Buffer, Grid, Samples, ScalarType};
pub use image::Image;
pub use mesh::{MeshReport, TetMesh};
pub use named_view::NamedView;
pub use transfer::TransferFunction;
