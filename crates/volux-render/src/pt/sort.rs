//! Visibility ordering of tetrahedra (work in progress).
