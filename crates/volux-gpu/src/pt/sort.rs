//! The visibility order on the device (seed `000` §4.2, seed `002` §4.2): a stable LSD radix
//! sort of `(key, cell)` pairs (`sort.wgsl`), eight passes of 4 bits over the 32-bit
//! centroid depth keys. Stable, and the pairs start in cell order, so equal depths keep the
//! order of their ids: the CPU's `centroid_order` exactly, for the same keys.
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::layout::groups;

/// Items per block of `sort.wgsl`.
const BLOCK: u32 = 256;
/// Bits per pass.
const BITS: u32 = 4;
/// Digits per pass.
const RADIX: u64 = 1 << BITS;

/// `sort.wgsl`'s `Pass`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PassParams {
    n: u32,
    shift: u32,
    blocks: u32,
    unused: u32,
}

/// The three pipelines of a pass.
pub(crate) struct RadixSort {
    count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
}

impl RadixSort {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sort.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("sort.wgsl").into()),
        });
        let layout = sort_layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("radix sort"),
            bind_group_layouts: &[&layout],
            push_constant_ranges: &[],
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            count: pipeline("count"),
            scan: pipeline("scan"),
            scatter: pipeline("scatter"),
        }
    }

    /// Bytes of the scratch buffers for `n` items (the second item buffer and the counts).
    pub(crate) fn scratch_bytes(n: u64) -> (u64, u64) {
        let blocks = n.div_ceil(u64::from(BLOCK)).max(1);
        (8 * n.max(1), 4 * RADIX * blocks)
    }

    /// Records the sort of the `n` pairs of `items` (sorted in place, `scratch` as the
    /// other half of each pass).
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        items: &wgpu::Buffer,
        scratch: &wgpu::Buffer,
        n: u32,
    ) {
        let blocks = n.div_ceil(BLOCK).max(1);
        let counts = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("radix counts"),
            size: Self::scratch_bytes(u64::from(n)).1,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let layout = self.count.get_bind_group_layout(0);
        let (gx, gy) = groups(blocks);
        for pass in 0..32 / BITS {
            let (src, dst) = if pass % 2 == 0 {
                (items, scratch)
            } else {
                (scratch, items)
            };
            let params = PassParams {
                n,
                shift: pass * BITS,
                blocks,
                unused: 0,
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("radix pass"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let entries = [
                uniform.as_entire_binding(),
                src.as_entire_binding(),
                dst.as_entire_binding(),
                counts.as_entire_binding(),
            ];
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("radix pass"),
                layout: &layout,
                entries: &bind_entries(&entries),
            });
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            cpass.set_bind_group(0, &bind, &[]);
            cpass.set_pipeline(&self.count);
            cpass.dispatch_workgroups(gx, gy, 1);
            cpass.set_pipeline(&self.scan);
            cpass.dispatch_workgroups(1, 1, 1);
            cpass.set_pipeline(&self.scatter);
            cpass.dispatch_workgroups(gx, gy, 1);
        }
    }
}

fn bind_entries<'a>(resources: &[wgpu::BindingResource<'a>]) -> Vec<wgpu::BindGroupEntry<'a>> {
    resources
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect()
}

/// The layout shared by the three entry points (a uniform, the source, the destination and
/// the counts).
fn sort_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let uniform = wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("radix sort"),
        entries: &[
            uniform,
            storage(1, true),
            storage(2, false),
            storage(3, false),
        ],
    })
}
