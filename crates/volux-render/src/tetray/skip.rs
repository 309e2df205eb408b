//! Empty-space skipping for the per-segment colours (exact, ψ, average): the cells that may
//! contribute to the image under a frame's transfer function and isosurfaces, and a
//! hierarchy over them that lets a ray jump over runs of the others.
//!
//! A cell is **invisible** when its linear field cannot produce anything: the extinction is
//! zero over the range of its four vertex values (widened by a relative margin that covers the
//! rounding of the walk's `f64` field and of the `f32` lookups), both for the exact
//! integrator ([`SegmentIntegrator::is_transparent`], exact on the TF's linear pieces) and
//! for the lookup table of the ψ and average colours ([`CellClassifier::is_transparent`],
//! which includes the entries a lookup interpolates from), and no isovalue lies in that
//! range. Every such segment colours as exactly transparent black, and compositing it
//! (`under`) leaves the pixel unchanged bit for bit, so leaving it out changes nothing.
//!
//! The visible cells are boxed in a [`Bvh`]; the walk over them ([`Walker::trace_visible`])
//! steps across faces while the neighbour is visible, through short invisible runs, and
//! otherwise asks the hierarchy for the first visible cell past the exit, which covers long
//! invisible runs, boundary exits and re-entries (non-convex meshes) and rays leaving
//! through edges or vertices alike. The
//! structure depends on the TF and the isovalues only, so it is built once per TF
//! (classification) and kept by the caster while they do not change.
//!
//! [`Walker::trace_visible`]: super::walk::Walker::trace_visible
use rayon::prelude::*;
use volux_core::{TetMesh, TransferFunction};

use super::bvh::Bvh;
use super::geom::Geometry;
use super::tables::Tables;
use crate::isosurface::Isovalue;

/// Relative widening of a cell's value range before it is classified.
const MARGIN: f64 = 1e-6;

/// Largest share of visible cells for which skipping is used: above it the walk saves little
/// and the hierarchy costs build time and memory.
const WORTHWHILE: f64 = 0.9;

/// The visible cells of one TF and set of isovalues, and their hierarchy.
pub(crate) struct Visibility {
    /// The TF the cells were classified with (part of the key).
    pub source: TransferFunction,
    /// The isovalues (part of the key).
    pub isovalues: Vec<f32>,
    /// Per cell: whether it may contribute (usable cells only).
    visible: Vec<bool>,
    /// The hierarchy over the visible cells (empty when skipping does not pay).
    pub bvh: Bvh,
    /// Whether skipping pays (see [`Visibility::worthwhile`]).
    worthwhile: bool,
    /// Number of visible cells.
    cells: usize,
}

/// Whether a cell whose vertex values span `[lo, hi]` colours as transparent black with the
/// frame's `tables` and draws none of the `isovalues`.
fn invisible(tables: &Tables, isovalues: &[f32], lo: f64, hi: f64) -> bool {
    let m = MARGIN * ((hi - lo) + lo.abs().max(hi.abs())) + f64::MIN_POSITIVE;
    let (lo, hi) = (lo - m, hi + m);
    tables.exact.is_transparent(lo, hi)
        && tables.classifier.is_transparent(lo as f32, hi as f32)
        && !isovalues.iter().any(|&v| (lo..=hi).contains(&f64::from(v)))
}

impl Visibility {
    /// Classifies the usable cells of `mesh` with `tables` and `isosurfaces` and builds the
    /// hierarchy over the visible ones (boxes from `boxes`, padded by `pad`).
    pub fn new(
        mesh: &TetMesh,
        geo: &Geometry,
        tables: &Tables,
        isosurfaces: &[Isovalue],
        boxes: impl Fn(u32) -> (glam::DVec3, glam::DVec3),
        pad: f64,
    ) -> Self {
        let isovalues: Vec<f32> = isosurfaces.iter().map(|i| i.value).collect();
        let scalars = mesh.scalars();
        let visible: Vec<bool> = mesh
            .tets()
            .par_iter()
            .enumerate()
            .map(|(t, tet)| {
                let v = tet.map(|i| f64::from(scalars[i as usize]));
                let lo = v[0].min(v[1]).min(v[2].min(v[3]));
                let hi = v[0].max(v[1]).max(v[2].max(v[3]));
                geo.usable(t) && !invisible(tables, &isovalues, lo, hi)
            })
            .collect();
        let cells: Vec<u32> = (0..visible.len() as u32)
            .filter(|&t| visible[t as usize])
            .collect();
        let usable = (0..visible.len()).filter(|&t| geo.usable(t)).count();
        let fits = volux_core::limits::check_alloc(
            "the tet ray caster's hierarchy of visible cells",
            cells.len() as u64,
            Bvh::build_bytes_per_cell(),
        )
        .is_ok();
        let worthwhile = fits && (cells.len() as f64) <= WORTHWHILE * usable as f64;
        Self {
            source: tables.source.clone(),
            isovalues,
            cells: cells.len(),
            bvh: if worthwhile {
                Bvh::build(cells, boxes, pad)
            } else {
                Bvh::default()
            },
            visible,
            worthwhile,
        }
    }

    /// Whether cell `t` may contribute.
    #[inline]
    pub fn is_visible(&self, t: u32) -> bool {
        self.visible[t as usize]
    }

    /// Number of visible cells.
    pub fn len(&self) -> usize {
        self.cells
    }

    /// Whether the walk skips invisible cells with this structure: at most
    /// [`WORTHWHILE`] of the usable cells are visible and the hierarchy fits in the memory
    /// budget (otherwise it is not built and every cell is walked).
    pub fn worthwhile(&self) -> bool {
        self.worthwhile
    }
}
