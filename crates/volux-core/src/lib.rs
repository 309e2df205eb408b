//! # volux-core
//!
//! The data model of Volux, the first stage of the pipeline
//! (**data** -> sampling -> classification -> integration -> traversal -> compositing -> image):
//!
//! - [`grid::Grid`]: a regular grid of scalars kept in their native type, possibly memory-mapped;
//! - [`mesh::TetMesh`]: a tetrahedral mesh with one scalar per vertex, validation, boundary faces,
//!   face adjacency and per-vertex gradients;
//! - [`tetrahedralize`]: regular and curvilinear grids split into conforming tetrahedra;
//! - [`transfer::TransferFunction`]: piecewise-linear colour and extinction, presets, JSON;
//! - [`camera::Camera`]: perspective and orthographic cameras, JSON;
//! - [`image::Image`]: the RGBA f32 linear framebuffer and PNG output;
//! - [`synth`]: synthetic datasets for tests, benchmarks and the demo.
#![deny(missing_docs)]
#![deny(unsafe_code)]

pub mod camera;
pub mod error;
pub mod grid;
pub mod histogram;
pub mod image;
pub mod limits;
pub mod mesh;
pub mod synth;
pub mod tetrahedralize;
pub mod transfer;

pub use camera::{Camera, CameraSpec, Projection, RayGenerator};
pub use error::{Error, Result};
pub use grid::{Buffer, Grid, Samples, ScalarType};
pub use image::Image;
pub use mesh::{MeshReport, TetMesh};
pub use transfer::TransferFunction;

/// A world-space axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: glam::DVec3,
    /// Maximum corner.
    pub max: glam::DVec3,
}

impl Aabb {
    /// The smallest box holding all `points`; `None` when empty.
    pub fn from_points(points: impl IntoIterator<Item = glam::DVec3>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = it.next()?;
        let (min, max) = it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        Some(Self { min, max })
    }
    /// Centre of the box.
    pub fn center(&self) -> glam::DVec3 {
        (self.min + self.max) * 0.5
    }
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }
}
