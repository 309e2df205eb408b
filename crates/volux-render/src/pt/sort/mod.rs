//! Visibility ordering of tetrahedra for the Projected Tetrahedra renderer.
//!
//! Cell projection composites cells in *visibility order*; the seeds name that order the main
//! drawback of PT (seed `000_afff90a9230f72b1.txt`, §2.6 and §4.2; seed `002_...txt`, §1).
//! Every order produced here is **front to back** (nearest cell first), the order in which the
//! renderer composites with the *under* operator.
//!
//! # Two orders
//!
//! - **Centroid order** ([`centroid_keys`], [`centroid_order`]): the seeds' approach
//!   (`000` §4.2): sort the cells by the depth of their centroid (*baricentro*), with a bucket
//!   sort of 20 slabs while the view moves and a merge sort for still frames. Here an O(n) LSD
//!   radix sort on the `f32` depth replaces both: it is exact on the keys (unlike the 20
//!   buckets), stable, deterministic and faster than a merge sort. The seed itself warns that
//!   the centroid order "does not guarantee 100% correct results in all cases" (`000` §4.2).
//! - **MPVO** ([`mpvo`], [`mpvo_order`]): Williams' *Meshed Polyhedra Visibility Ordering*
//!   (Williams 1992, cited as \[42\] in `000` §4.2 as the exact alternative): across every
//!   interior face the cell on the eye's side of the face plane must be composited first;
//!   these face constraints ([`FaceOrder`]) form a directed graph, and a topological sort of
//!   it is a visibility order, exact for **convex** acyclic meshes. For non-convex meshes
//!   ([`is_convex`] false) face constraints alone miss occlusions through empty space, so the
//!   renderer adds a per-pixel fragment sort; MPVO's topological order, with centroid depth
//!   breaking the ties, is still the best starting order there.
//!
//! [`count_violations`] counts the face pairs an order gets wrong: `volux render --stats`
//! uses it to report the ordering errors of the centroid sort against MPVO.
//!
//! # Depth of a centroid
//!
//! For a perspective view the key is the **Euclidean distance from the eye** to the centroid,
//! not the view depth `z` the seeds read from the first pass (`000` §4.2): distance is what
//! every pixel ray measures, so it orders two cells lying on one ray the same way at the
//! centre of the image and at its corners, and it does not change when the camera only turns
//! about the eye. It is also measurably better: on the 1.25M-tet lattice of
//! `synth::smooth_tets`, seen in perspective from close by, the distance key broke no face
//! constraint at all where the view-depth key broke about 440 000 of 2.5M (and 281 against
//! 5519 over four perspective views of a 5000-tet lattice, one from inside, in the tests).
//! For an orthographic view rays are parallel and the key is the depth
//! along the view direction.
use glam::DVec3;
use volux_core::{Camera, Projection};

mod convex;
mod mpvo;
mod radix;

pub use convex::{is_convex, Convexity};
pub use mpvo::{
    count_violations, face_precedence, mpvo, mpvo_order, mpvo_with, FaceOrder, MpvoResult,
    Precedence,
};
pub use radix::{centroid_keys, centroid_order, depth_key};

/// The viewing geometry the visibility order depends on: where the eye is and, for parallel
/// projection, the direction of the rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Eye position (perspective centre of projection; for orthographic views only used to
    /// measure depth along [`View::forward`]).
    pub eye: DVec3,
    /// Unit view direction (from the eye into the scene).
    pub forward: DVec3,
    /// `true` for a perspective view (rays from [`View::eye`]), `false` for parallel rays
    /// along [`View::forward`].
    pub perspective: bool,
}

impl View {
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

#[cfg(test)]
mod tests;
