//! The classification on the device ([`Tables`]): the transfer function tabulated as the CPU
//! lanes tabulate it, kept between frames while the TF and the step stay.
use volux_core::TransferFunction;
use volux_render::classify::ClassifyTable;
use wgpu::util::DeviceExt;

/// The slab table (premultiplied colour and opacity of one full step, `for_step(h)`) and the
/// extinction table (colour and extinction per world unit, for the shortened last slab) of a
/// TF over a value range, in storage buffers.
pub(crate) struct Tables {
    tf: TransferFunction,
    h: f64,
    pub(crate) slab: wgpu::Buffer,
    pub(crate) tau: wgpu::Buffer,
    /// `(lo, scale)`: value `s` sits at entry `(s - lo) scale`.
    pub(crate) domain: (f32, f32),
    /// Entries per table (with the copy of the last one).
    pub(crate) entries: usize,
}

impl Tables {
    /// The tables of `tf` over `range` for the step `h` (world units).
    pub(crate) fn new(
        device: &wgpu::Device,
        tf: &TransferFunction,
        range: [f64; 2],
        h: f64,
    ) -> Self {
        let table = ClassifyTable::new(tf, range, ClassifyTable::DEFAULT_SIZE);
        let (slab, tau) = (table.for_step(h as f32), table.for_lanes());
        let buffer = |label: &str, entries: &[[f32; 4]]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(entries),
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Self {
            tf: tf.clone(),
            h,
            slab: buffer("slab table", slab.entries()),
            tau: buffer("extinction table", tau.entries()),
            domain: slab.domain(),
            entries: slab.entries().len(),
        }
    }

    /// Whether these are the tables of `tf` at step `h` (the range is the grid's, fixed).
    pub(crate) fn is_for(&self, tf: &TransferFunction, h: f64) -> bool {
        self.h == h && &self.tf == tf
    }
}
