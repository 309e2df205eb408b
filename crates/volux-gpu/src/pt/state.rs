//! What GPU Projected Tetrahedra keeps between frames ([`Caches`]): the mesh-sized buffers
//! of the first pass, the TF's buffers, the kept set and the key of the classified cells
//! (`frame.rs` fills and reads them).
use volux_core::voi::ClipPlane;
use volux_core::{Camera, TransferFunction};

use super::tables::TfBuffers;

/// The mesh-sized buffers of the first pass, allocated with the first frame and kept.
pub(super) struct FrameBuffers {
    pub(super) uniform: wgpu::Buffer,
    pub(super) screen: wgpu::Buffer,
    pub(super) cells: wgpu::Buffer,
    pub(super) items: wgpu::Buffer,
    pub(super) scratch: wgpu::Buffer,
    pub(super) kept: wgpu::Buffer,
    pub(super) counters: wgpu::Buffer,
}

/// What the classified cells were built from.
#[derive(Clone, PartialEq)]
pub(super) struct ViewKey {
    pub(super) camera: Camera,
    pub(super) size: (usize, usize),
    pub(super) planes: Vec<ClipPlane>,
    pub(super) kept_version: u64,
    pub(super) lit: bool,
    pub(super) exact: bool,
}

/// The caches of `GpuPtRenderer` (see the module docs).
#[derive(Default)]
pub(super) struct Caches {
    pub(super) buffers: Option<FrameBuffers>,
    /// The effective TF and its buffers.
    pub(super) tf: Option<(TransferFunction, TfBuffers)>,
    /// The zero set's rows and the isovalues the kept set was built from, and its size.
    pub(super) kept: Option<(Vec<[f32; 4]>, Vec<f32>, usize)>,
    pub(super) kept_version: u64,
    pub(super) view: Option<ViewKey>,
    /// The mesh's face adjacency, built with the first exact-order frame.
    pub(super) adjacency: Option<Vec<[u32; 4]>>,
}
