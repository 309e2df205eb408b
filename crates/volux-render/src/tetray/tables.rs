//! What a tet ray casting frame's colour depends on through the transfer function only
//! (its classification): the caster keeps it while the TF does not change, and both the
//! pixels ([`super::pixel`]) and the visible-cell set ([`super::skip`]) read it.
use volux_core::TransferFunction;

use crate::integrate::psi::CellClassifier;
use crate::integrate::segment::SegmentIntegrator;

/// The classification of a frame, what depends on the transfer function only: the caster
/// keeps it while the TF does not change.
pub(crate) struct Tables {
    /// The TF as given (the key).
    pub source: TransferFunction,
    /// The TF resolved against the mesh's range.
    pub tf: TransferFunction,
    pub exact: SegmentIntegrator,
    pub classifier: CellClassifier,
    pub breakpoints: Vec<f64>,
    /// The breakpoints in `f32`, for the ψ model's cuts.
    pub knots: Vec<f32>,
}

impl Tables {
    /// The tables of `tf` on the data range `range`.
    pub fn new(tf: &TransferFunction, range: [f64; 2]) -> Self {
        let resolved = tf.resolved(range);
        let breakpoints = resolved.breakpoints();
        Self {
            source: tf.clone(),
            exact: SegmentIntegrator::new(&resolved),
            classifier: CellClassifier::new(&resolved, range),
            knots: breakpoints.iter().map(|&k| k as f32).collect(),
            breakpoints,
            tf: resolved,
        }
    }
}
