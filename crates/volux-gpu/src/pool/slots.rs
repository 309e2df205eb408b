//! The atlas of the brick pool ([`Slots`]): its slots, which brick each holds, the page
//! table handed to the shader, and the loading of asked bricks (longest-resident evicted).
use super::source::PoolSource;
use crate::context::GpuContext;
use crate::error::GpuError;

/// How the pool is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolOptions {
    /// Cells per brick side (a multiple of 8, the macrocells' side).
    pub brick: usize,
    /// The most bytes the atlas may take on the device.
    pub bytes: u64,
}

impl Default for PoolOptions {
    /// Bricks of 32 cells, an atlas of at most 1 GiB.
    fn default() -> Self {
        Self {
            brick: 32,
            bytes: 1 << 30,
        }
    }
}

/// The page entry of a brick the TF leaves transparent (`pool.wgsl`'s `EMPTY`).
const EMPTY: u32 = u32::MAX;

/// Bricks per axis of a grid of `dims` samples cut into bricks of `side` cells.
pub(crate) fn bricks_per_axis(dims: [usize; 3], side: usize) -> [usize; 3] {
    dims.map(|n| n.saturating_sub(1).max(1).div_ceil(side))
}

/// The atlas texture and its bookkeeping.
pub(crate) struct Slots {
    dims: [usize; 3],
    side: usize,
    bricks: [usize; 3],
    per_axis: [usize; 3],
    capacity: usize,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// Per brick: its slot + 1, or 0 when not resident.
    slot_of: Vec<u32>,
    /// Per slot: the brick it holds and when it was loaded.
    held: Vec<Option<(usize, u64)>>,
    clock: u64,
}

impl Slots {
    /// The atlas for a grid of `dims` samples laid out by `options`, as many slots as the
    /// bytes allow (and no more than there are bricks), within the 3D texture limit.
    pub(crate) fn new(
        ctx: &GpuContext,
        dims: [usize; 3],
        options: PoolOptions,
    ) -> Result<Self, GpuError> {
        let side = options.brick;
        let bricks = bricks_per_axis(dims, side);
        let total: usize = bricks.iter().product();
        let slot_side = side + 1;
        let limit = ctx.limits().max_texture_dimension_3d as usize;
        let most_per_axis = limit / slot_side;
        let by_bytes = options.bytes / (4 * slot_side.pow(3)) as u64;
        let capacity = total.min(by_bytes as usize).min(most_per_axis.pow(3));
        if capacity == 0 {
            return Err(GpuError::OverLimit {
                what: format!("a brick of {slot_side}^3 samples"),
                limit: format!(
                    "{} bytes for the pool and 3D textures up to {limit} per side",
                    options.bytes
                ),
            });
        }
        let sx = capacity.min(most_per_axis);
        let sy = capacity.div_ceil(sx).min(most_per_axis);
        let sz = capacity.div_ceil(sx * sy).min(most_per_axis);
        let per_axis = [sx, sy, sz];
        let size = wgpu::Extent3d {
            width: (sx * slot_side) as u32,
            height: (sy * slot_side) as u32,
            depth_or_array_layers: (sz * slot_side) as u32,
        };
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("brick atlas"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Ok(Self {
            dims,
            side,
            bricks,
            per_axis,
            capacity,
            texture,
            view,
            slot_of: vec![0; total],
            held: vec![None; capacity],
            clock: 0,
        })
    }

    pub(crate) fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    pub(crate) fn capacity(&self) -> usize {
        self.capacity
    }

    pub(crate) fn bricks(&self) -> usize {
        self.slot_of.len()
    }

    /// The shader's `Pool` uniform: bricks per axis and side, slots per axis and side.
    pub(crate) fn layout(&self) -> [[u32; 4]; 2] {
        let [bx, by, bz] = self.bricks.map(|n| n as u32);
        let [sx, sy, sz] = self.per_axis.map(|n| n as u32);
        let side = self.side as u32;
        [[bx, by, bz, side], [sx, sy, sz, side + 1]]
    }

    /// The page table: per brick its slot + 1, 0 when absent, [`EMPTY`] when `empty` says
    /// the TF leaves it transparent.
    pub(crate) fn page(&self, empty: Option<&[bool]>) -> Vec<u32> {
        let mut page = self.slot_of.clone();
        if let Some(empty) = empty {
            for (p, &e) in page.iter_mut().zip(empty) {
                if e {
                    *p = EMPTY;
                }
            }
        }
        page
    }

    /// Loads the bricks `wanted` (as many as there are slots), each into a free slot or the
    /// one holding the longest-resident brick not loaded in this call; the bricks written.
    pub(crate) fn load(
        &mut self,
        ctx: &GpuContext,
        source: &PoolSource,
        wanted: &[usize],
    ) -> Result<usize, GpuError> {
        self.clock += 1;
        let slot_side = self.side + 1;
        let mut values = vec![0.0f32; slot_side.pow(3)];
        let mut loaded = 0;
        for &brick in wanted.iter().take(self.capacity) {
            let Some(slot) = self.victim() else { break };
            if let Some((old, _)) = self.held[slot] {
                self.slot_of[old] = 0;
            }
            let b = self.brick_coords(brick);
            let lo = b.map(|c| c * self.side);
            source.read_box(lo, slot_side, self.dims, &mut values)?;
            self.write(ctx, slot, &values);
            self.held[slot] = Some((brick, self.clock));
            self.slot_of[brick] = slot as u32 + 1;
            loaded += 1;
        }
        Ok(loaded)
    }

    /// A free slot, else the one loaded longest ago (before this round).
    fn victim(&self) -> Option<usize> {
        if let Some(free) = self.held.iter().position(Option::is_none) {
            return Some(free);
        }
        self.held
            .iter()
            .enumerate()
            .filter_map(|(s, h)| h.filter(|(_, at)| *at < self.clock).map(|(_, at)| (s, at)))
            .min_by_key(|&(_, at)| at)
            .map(|(s, _)| s)
    }

    fn brick_coords(&self, brick: usize) -> [usize; 3] {
        let [bx, by, _] = self.bricks;
        [brick % bx, brick / bx % by, brick / (bx * by)]
    }

    /// Writes a brick's samples into `slot`.
    fn write(&self, ctx: &GpuContext, slot: usize, values: &[f32]) {
        let [sx, sy, _] = self.per_axis;
        let s = [slot % sx, slot / sx % sy, slot / (sx * sy)];
        let n = (self.side + 1) as u32;
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: s[0] as u32 * n,
                    y: s[1] as u32 * n,
                    z: s[2] as u32 * n,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(values),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * n),
                rows_per_image: Some(n),
            },
            wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: n,
            },
        );
    }
}
