//! Geometry of tetrahedral meshes shared by every mesh renderer: the exact orientation
//! predicate of projected cells ([`orient`]) and the canonical face planes of cells with
//! their ray crossings ([`planes`]); the face table is [`volux_core::mesh::FACES`].
pub mod orient;
pub mod planes;

pub use orient::{orient2d, Sign};
pub(crate) use planes::TetPlanes;
pub use planes::{cell_volume6, lex_cmp, lex_negative, ray_tet_intersection, TetCrossing};
