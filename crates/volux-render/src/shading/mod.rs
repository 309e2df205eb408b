//! Gradient shading: normals from the scalar field and the Blinn-Phong model.
//!
//! The seeds light isosurfaces with the Phong model along the *gradient* of the scalar field,
//! the gradient standing in for the surface normal (seed `002` §4.6; seed `001` treats no
//! lighting, §2.4); Volux lights volume samples the same way on request (Blinn-Phong, as
//! classic direct volume renderers do). This module holds the pieces a traversal needs:
//!
//! - [`gradient()`](fn@gradient): central differences on any [`Field`](crate::sampling::Field) (on the fly, no extra memory);
//! - [`GradientVolume`]: the same gradients precomputed once per volume (3 x `i16` per voxel,
//!   padded to 8 bytes)
//!   with trilinear lookup, for renderers that shade every sample and can spare the memory;
//! - [`BlinnPhong`] and [`Light`]: the two-sided lighting model with a gradient-magnitude
//!   threshold, so homogeneous (noisy, flat) regions stay unlit and keep their emission only;
//! - [`CutFaces`]: the faces clip planes and the sculpt mask expose, lit with the cut's own
//!   normal instead of the gradient (seed `004` sec. 4).
//!
//! Coordinates: positions are in voxel space (sample `(i, j, k)` at `(i, j, k)`, as in
//! [`crate::sampling`]); gradients are returned in *world* units (data units per world unit),
//! i.e. the voxel-space differences divided by the grid spacing.
pub mod blinn_phong;
pub mod cut_faces;
pub mod gradient;
mod lanes;

pub use blinn_phong::{BlinnPhong, Light};
pub use cut_faces::CutFaces;
pub use gradient::{gradient, GradientKey, GradientVolume};
pub use lanes::{ln_lanes, pow_lanes, Lanes3, RayLight};
