//! What a render returns: a [`Frame`] (the image, the error map where the method estimates
//! one) and its [`FrameStats`]: the figures every method has (`ms`, `pixels`, which caches
//! were rebuilt) and, typed, each method's own ([`MethodStats`]: [`RenderStats`] of grid ray
//! casting, [`PtStats`] of Projected Tetrahedra, [`TetRayStats`] of tetrahedral ray casting).
use volux_core::image::Image;

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Premultiplied linear RGBA.
    pub image: Image,
    /// Estimated absolute integration error per pixel (largest channel), row-major, where the
    /// method estimates it (adaptive Simpson; 0 elsewhere); `None` for methods that do not.
    pub error_map: Option<Vec<f32>>,
    /// What the frame did.
    pub stats: FrameStats,
}

/// Figures of a frame: the common ones, and the method's own.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameStats {
    /// Wall time of the frame in milliseconds, without the diagnostics a method times apart
    /// ([`PtStats::diagnostics_s`]).
    pub ms: f64,
    /// Pixels rendered.
    pub pixels: usize,
    /// Which caches the frame rebuilt.
    pub rebuilt: Rebuilt,
    /// The method's own figures.
    pub method: MethodStats,
}

/// Which derived data a frame had to build (the rest came from the renderer's caches).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Rebuilt {
    /// Data structures of the volume (macrocells, gradients, adjacency, ray-caster planes
    /// and hierarchy, a resampled grid): built once per volume, or per setting they need.
    pub data: bool,
    /// Classification: what depends on the transfer function and the isovalues.
    pub classification: bool,
    /// View: what depends on the camera and the image size.
    pub view: bool,
}

impl Rebuilt {
    /// Everything rebuilt (a renderer without caches for that stage).
    pub const ALL: Self = Self {
        data: true,
        classification: true,
        view: true,
    };
}

/// The figures only one method has.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum MethodStats {
    /// Grid ray casting (also of a resampled mesh).
    GridRaycast(RenderStats),
    /// Projected Tetrahedra.
    ProjectedTetrahedra(PtStats),
    /// Tetrahedral ray casting.
    TetRaycast(TetRayStats),
    /// The brute-force mesh reference (no figures of its own).
    MeshReference,
}

/// Figures of one grid ray casting render ([`crate::raycast`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    /// Rays that hit the volume.
    pub rays: u64,
    /// Field samples taken.
    pub samples: u64,
    /// Wall time in seconds.
    pub seconds: f64,
    /// Rays whose adaptive integration accepted a step at `hmin` above its tolerance.
    pub rays_over_tolerance: u64,
    /// What the render had to build (the rest came from the renderer's caches).
    pub rebuilt: Rebuilt,
}

/// What a Projected Tetrahedra render did and how long each stage took ([`crate::pt`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PtStats {
    /// Tetrahedra in the mesh.
    pub tets: usize,
    /// Kept by the discard step.
    pub tets_kept: usize,
    /// Drawn (kept, projected, not degenerate).
    pub tets_drawn: usize,
    /// Kept but with a degenerate projection (zero-area; the mesh's zero-volume cells are
    /// discarded before, see [`volux_core::MeshReport::degenerate`]).
    pub degenerate: usize,
    /// Kept but with a vertex behind the near plane or outside the guard band.
    pub clipped: usize,
    /// Kept but culled: all four vertices outside one clipping plane.
    pub culled: usize,
    /// Fragments shaded.
    pub fragments: u64,
    /// Face pairs ordered against the exact face order by the centroid sort (when counted).
    pub sort_violations: Option<u64>,
    /// How the exact order was obtained: "mpvo", "per-pixel", or "" for centroid.
    pub exact_strategy: &'static str,
    /// Cycles MPVO had to break.
    pub cycles_broken: usize,
    /// Seconds in the discard step (0 when cached).
    pub discard_s: f64,
    /// Seconds in the per-tetrahedron pass (0 when cached).
    pub project_s: f64,
    /// Seconds sorting (0 when cached).
    pub sort_s: f64,
    /// Seconds of the centroid sort when violations were counted.
    pub centroid_sort_s: f64,
    /// Seconds of the MPVO sort when violations were counted or the exact order was asked.
    pub exact_sort_s: f64,
    /// Seconds binning (0 when cached).
    pub bin_s: f64,
    /// Seconds rasterizing and compositing.
    pub raster_s: f64,
    /// Seconds of the diagnostics that only [`PtSettings::count_violations`] asks for (the
    /// other order, its adjacency, the count), not in [`PtStats::seconds`] nor the stages.
    ///
    /// [`PtSettings::count_violations`]: crate::scene::PtSettings::count_violations
    pub diagnostics_s: f64,
    /// Seconds of the frame, diagnostics excluded.
    pub seconds: f64,
    /// Per-frame bytes per tetrahedron (projection, order, bins; not the mesh).
    pub bytes_per_tet: f64,
    /// What the frame had to build: adjacency, gradients or the ψ table (data), the kept set
    /// (classification), projection, order and bins (view).
    pub rebuilt: Rebuilt,
}

/// What a tetrahedral ray casting frame did ([`crate::tetray`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetRayStats {
    /// Rays cast (one per pixel).
    pub rays: u64,
    /// Segments integrated (cells crossed, summed over rays). With empty-space skipping
    /// (the tet ray caster's `skip_empty` option) only the
    /// visible cells' segments are walked and counted.
    pub segments: u64,
    /// Scalar values evaluated: the medium samples of the adaptive rule, two per segment
    /// otherwise.
    pub samples: u64,
    /// Rays whose adaptive integration accepted a step at `hmin` above its tolerance.
    pub rays_over_tolerance: u64,
    /// Re-entries into the mesh after leaving it through a boundary face (non-convex meshes,
    /// gaps).
    pub reentries: u64,
    /// Walks that lost the cell-to-cell path (non-manifold faces) and were resumed from the
    /// boundary hierarchy.
    pub recovered: u64,
    /// Local searches around edges and vertices ([`WalkOutcome::local_searches`](crate::tetray::WalkOutcome::local_searches)).
    pub local_searches: u64,
    /// Rays stopped by the step bound.
    pub abandoned: u64,
    /// Jumps over runs of invisible cells through the hierarchy of visible cells (empty-space
    /// skipping), summed over rays.
    pub skips: u64,
    /// Visible cells of the frame's TF and isovalues when it skips empty space, 0 otherwise.
    pub visible_cells: usize,
    /// Cells in the per-frame start set (camera inside the mesh), 0 otherwise.
    pub start_cells: usize,
    /// Tetrahedra in the mesh.
    pub tets: usize,
    /// Bytes of the acceleration structures per tetrahedron
    /// ([`TetRayCaster::bytes_per_tet`](crate::tetray::TetRayCaster::bytes_per_tet)).
    pub bytes_per_tet: f64,
    /// What the frame had to build: the caster's structures on the first frame, gradients or
    /// the ψ table (data), the TF's tables (classification), the start cells (view).
    pub rebuilt: Rebuilt,
    /// Seconds for the frame.
    pub seconds: f64,
}
