//! The engine's parts a rendering backend reuses, in one place: the interface between
//! `volux-render` and a backend such as the GPU's (`volux-gpu`).
//!
//! A front end does not need this module: its API is [`Scene`](crate::scene::Scene),
//! [`create_renderer`](crate::engine::create_renderer) and the [`Renderer`](crate::engine::Renderer)
//! trait. A backend implements that trait with its own traversal, and reuses the engine's
//! stages so that its pictures equal the CPU engine's: the ray set-up of a scene
//! ([`RenderOptions::from_scene`], [`Placement`], the clip planes in voxel space and the cut
//! faces), the classification and integration tables ([`ClassifyTable`],
//! [`PreintegrationTable`], [`PsiTable`], [`CellClassifier`]), the lattices of empty-space
//! skipping ([`MacrocellGrid`]) and of the gradient volume ([`GradientVolume`]), the
//! sampler's arithmetic ([`Trilinear`]), the brick cache of volumes larger than memory
//! ([`BrickCache`], [`Brick`], [`level_placement`]) and, for Projected Tetrahedra, the
//! classification table of projected tetrahedra ([`TERNARY_TABLE`], [`ThickTopology`]), the
//! near-plane rule ([`NEAR_FRACTION`]) and the visibility order ([`mpvo_order`],
//! [`SortView`]).
//!
//! Each item is documented where it is defined; a backend imports it from here, so that
//! what the backends depend on is this list, and a change to it is a change of this file.
pub use crate::bricked::{level_placement, Brick, BrickCache};
pub use crate::classify::ClassifyTable;
pub use crate::integrate::preintegrated::PreintegrationTable;
pub use crate::integrate::psi::{CellClassifier, PsiTable};
pub use crate::macrocell::MacrocellGrid;
pub use crate::pt::classify::{ThickTopology, TERNARY_TABLE};
pub use crate::pt::project::NEAR_FRACTION;
pub use crate::pt::sort::{mpvo_order, SortView};
pub use crate::raycast::{cut_layer, local_clip_planes, Placement, RenderOptions};
pub use crate::sampling::Trilinear;
pub use crate::shading::{CutFaces, GradientVolume};
