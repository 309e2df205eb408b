//! The classification on the device ([`Tables`]): the transfer function tabulated as the CPU
//! lanes tabulate it, the macrocells it leaves empty, and the pre-integration table, kept
//! between frames while the TF, the step, the isovalues and the integrator stay.
use volux_core::TransferFunction;
use volux_render::backend_kit::ClassifyTable;
use volux_render::backend_kit::MacrocellGrid;
use volux_render::backend_kit::PreintegrationTable;
use wgpu::util::DeviceExt;

use crate::error::GpuError;

/// What the tables were built from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TableKey {
    pub(crate) tf: TransferFunction,
    /// The step (world units).
    pub(crate) h: f64,
    pub(crate) isovalues: Vec<f32>,
    pub(crate) preintegrated: bool,
}

/// The slab table (premultiplied colour and opacity of one full step, `for_step(h)`) followed
/// by the extinction table (colour and extinction per world unit, for the shortened last slab
/// and MIP's colour) in one storage buffer; the macrocells' flags (1 sampled, 0 skipped); the
/// pre-integration table (one unused entry without it).
pub(crate) struct Tables {
    key: TableKey,
    pub(crate) lut: wgpu::Buffer,
    pub(crate) cells: wgpu::Buffer,
    pub(crate) preint: wgpu::Buffer,
    /// `(lo, scale)`: value `s` sits at entry `(s - lo) scale`.
    pub(crate) domain: (f32, f32),
    /// Entries per table (with the copy of the last one).
    pub(crate) entries: usize,
    /// The pre-integration table's `(lo, scale)` and entries per axis.
    pub(crate) preint_domain: (f32, f32, usize),
}

impl Tables {
    /// The tables of `key` over `range` (the grid's values), with the macrocells of `cells`.
    pub(crate) fn new(
        device: &wgpu::Device,
        key: TableKey,
        range: [f64; 2],
        cells: &MacrocellGrid,
    ) -> Result<Self, GpuError> {
        let table = ClassifyTable::new(&key.tf, range, ClassifyTable::DEFAULT_SIZE);
        let (slab, tau) = (table.for_step(key.h as f32), table.for_lanes());
        let lut: Vec<[f32; 4]> = slab
            .entries()
            .iter()
            .chain(tau.entries())
            .copied()
            .collect();
        let flags: Vec<u32> = cells
            .empty_flags(&table, &key.isovalues)
            .into_iter()
            .map(|empty| u32::from(!empty))
            .collect();
        let (preint, preint_domain) = if key.preintegrated {
            let t = PreintegrationTable::new(&key.tf, range, key.h)
                .map_err(|e| GpuError::Failed(e.to_string()))?;
            let (lo, scale) = t.lane_domain();
            (t.table_entries().to_vec(), (lo, scale, t.size()))
        } else {
            (vec![[0.0; 4]], (0.0, 0.0, 2))
        };
        let storage = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Ok(Self {
            lut: storage("slab and extinction tables", bytemuck::cast_slice(&lut)),
            cells: storage("macrocell flags", bytemuck::cast_slice(&flags)),
            preint: storage("pre-integration table", bytemuck::cast_slice(&preint)),
            domain: slab.domain(),
            entries: slab.entries().len(),
            preint_domain,
            key,
        })
    }

    /// Whether these are the tables of `key` (the range is the grid's, fixed).
    pub(crate) fn is_for(&self, key: &TableKey) -> bool {
        &self.key == key
    }
}
