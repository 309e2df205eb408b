//! The view a visibility order is computed for, and the errors of the sorts.
use glam::DVec3;
use volux_core::camera::{Camera, Projection};

/// The viewing geometry the visibility order depends on: where the eye is and, for parallel
/// projection, the direction of the rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SortView {
    /// Eye position (perspective centre of projection; for orthographic views only used to
    /// measure depth along [`SortView::forward`]).
    pub eye: DVec3,
    /// Unit view direction (from the eye into the scene).
    pub forward: DVec3,
    /// `true` for a perspective view (rays from [`SortView::eye`]), `false` for parallel rays
    /// along [`SortView::forward`].
    pub perspective: bool,
}

impl SortView {
    /// The view of a camera: its eye, its forward axis and its projection kind.
    pub fn from_camera(camera: &Camera) -> Self {
        let (_, _, forward) = camera.basis();
        Self {
            eye: camera.eye,
            forward,
            perspective: matches!(camera.projection, Projection::Perspective { .. }),
        }
    }

    /// A perspective view from `eye` looking along `forward` (normalized here).
    pub fn perspective(eye: DVec3, forward: DVec3) -> Self {
        Self {
            eye,
            forward: forward.normalize(),
            perspective: true,
        }
    }

    /// A parallel (orthographic) view along `forward` (normalized here), depth measured from
    /// `eye`.
    pub fn orthographic(eye: DVec3, forward: DVec3) -> Self {
        Self {
            eye,
            forward: forward.normalize(),
            perspective: false,
        }
    }

    /// The sort key of a point: distance from the eye for perspective views, depth along the
    /// view direction for orthographic ones (see the module documentation).
    pub fn depth(&self, p: DVec3) -> f64 {
        if self.perspective {
            (p - self.eye).length()
        } else {
            (p - self.eye).dot(self.forward)
        }
    }
}

/// Errors of the visibility sorts: inputs that do not describe a mesh, an adjacency or a
/// subset of its cells.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SortError {
    /// The adjacency (or depth) array does not have one entry per tet.
    #[error("{what} has {actual} entries but the mesh has {tets} tets")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        actual: usize,
        /// Number of tets.
        tets: usize,
    },
    /// An adjacency entry names a tet that does not exist.
    #[error("tet {tet} face {face}: neighbour {neighbour} out of range")]
    NeighbourOutOfRange {
        /// Tet.
        tet: u32,
        /// Face (opposite vertex `face`).
        face: u8,
        /// The bad neighbour index.
        neighbour: u32,
    },
    /// Tet `tet` names `neighbour` across `face` but the neighbour does not name it back.
    #[error("tet {tet} face {face}: neighbour {neighbour} does not list it back")]
    AsymmetricAdjacency {
        /// Tet.
        tet: u32,
        /// Face (opposite vertex `face`).
        face: u8,
        /// The neighbour.
        neighbour: u32,
    },
    /// A kept id is not a tet of the mesh.
    #[error("kept tet {id} out of range (mesh has {tets} tets)")]
    KeptOutOfRange {
        /// The bad id.
        id: u32,
        /// Number of tets.
        tets: usize,
    },
    /// A kept id is listed twice.
    #[error("kept tet {0} listed twice")]
    DuplicateKept(u32),
}
