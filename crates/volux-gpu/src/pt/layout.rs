//! Sizes the PT passes share: a classified cell's bytes, the vertices drawn per cell, the
//! workgroup grid of a dispatch.

/// Bytes of one classified cell (`Cell` of the shaders).
pub(crate) const CELL_BYTES: u64 = 128;
/// Vertices drawn per cell (four triangles at most).
pub(crate) const VERTICES_PER_CELL: u64 = 12;

/// The workgroup grid for `n` groups: at most 65535 along x.
pub(crate) fn groups(n: u32) -> (u32, u32) {
    let x = n.clamp(1, 65535);
    (x, n.div_ceil(x).max(1))
}
