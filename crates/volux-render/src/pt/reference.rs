//! Brute-force per-pixel reference renderer for tetrahedral meshes (work in progress).
