//! One frame on the device, with the caches between frames: the TF's buffers (keyed by the
//! TF), the kept set (keyed by the TF's zero set and the isovalues, rebuilt by the `keep`
//! pass of `classify.wgsl`), and the classified and sorted cells (keyed by the camera, the
//! image size, the clipping planes, the kept set and whether gradients are needed). A frame
//! runs only the stages whose key changed, then the fans and the readback.
use volux_core::{TetMesh, TransferFunction};
use volux_render::backend_kit::{mpvo_order, SortView};
use volux_render::frame::Rebuilt;
use volux_render::scene::Scene;
use wgpu::util::DeviceExt;

use super::layout::{groups, CELL_BYTES, VERTICES_PER_CELL};
use super::sort::RadixSort;
use super::state::{FrameBuffers, ViewKey};
use super::tables::TfBuffers;
use super::view::{Extras, ViewParams};
use super::{draw, GpuPtRenderer};
use crate::error::GpuError;
use crate::grid::{map, readback};

/// What a frame did, for its statistics.
pub(super) struct FrameReport {
    pub(super) rgba: Vec<[f32; 4]>,
    pub(super) rebuilt: Rebuilt,
    pub(super) kept: usize,
}

fn buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    })
}

fn bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    resources: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
        .iter()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: resource.clone(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("pt"),
        layout,
        entries: &entries,
    })
}

impl FrameBuffers {
    fn new(device: &wgpu::Device, (tets, vertices): (usize, usize)) -> Self {
        use wgpu::BufferUsages as U;
        let n = tets as u64;
        let (scratch, _) = RadixSort::scratch_bytes(n);
        Self {
            uniform: buffer(
                device,
                "pt view",
                std::mem::size_of::<ViewParams>() as u64,
                U::UNIFORM | U::COPY_DST,
            ),
            screen: buffer(device, "screen", 16 * vertices as u64, U::STORAGE),
            cells: buffer(device, "cells", CELL_BYTES * n, U::STORAGE),
            items: buffer(device, "items", 8 * n, U::STORAGE | U::COPY_DST),
            scratch: buffer(device, "sort scratch", scratch, U::STORAGE),
            kept: buffer(device, "kept", 4 * n, U::STORAGE),
            counters: buffer(
                device,
                "counters",
                16,
                U::STORAGE | U::COPY_DST | U::COPY_SRC,
            ),
        }
    }
}

/// The CPU's exact visibility order (`volux_render::pt::sort::mpvo_order`, MPVO with
/// the centroid tie-break, cycles broken) of every cell, as `(0, id)` pairs; the face
/// adjacency built once.
fn exact_order(
    adjacency: &mut Option<Vec<[u32; 4]>>,
    mesh: &TetMesh,
    scene: &Scene,
) -> Result<Vec<[u32; 2]>, GpuError> {
    let adjacency = adjacency.get_or_insert_with(|| mesh.face_adjacency());
    let view = SortView::from_camera(&scene.view.camera);
    let order = mpvo_order(mesh, adjacency, &view, None)
        .map_err(|e| GpuError::Failed(format!("exact visibility sort: {e}")))?;
    if order.len() != mesh.tets().len() {
        return Err(GpuError::Failed(format!(
            "exact visibility sort: {} of {} cells",
            order.len(),
            mesh.tets().len()
        )));
    }
    let mut items: Vec<[u32; 2]> = order.into_iter().map(|id| [0, id]).collect();
    items.resize(items.len().max(1), [0, 0]);
    Ok(items)
}

impl GpuPtRenderer {
    /// The vertex gradients, or one zero element before the first isosurface.
    fn gradients(&self) -> &wgpu::Buffer {
        self.data
            .gradients
            .as_ref()
            .unwrap_or(&self.data.no_gradients)
    }

    /// Renders `scene` with `tf` (the ψ rule or the average), running only the stages whose
    /// inputs changed since the last frame.
    pub(super) fn frame(
        &mut self,
        scene: &Scene,
        tf: &TransferFunction,
        psi: bool,
        exact: bool,
    ) -> Result<FrameReport, GpuError> {
        let device = &self.ctx.device;
        let (tets, vertices) = (self.mesh.tets().len(), self.mesh.positions().len());
        let mut rebuilt = Rebuilt::default();
        if self.caches.buffers.is_none() {
            self.caches.buffers = Some(FrameBuffers::new(device, (tets, vertices)));
        }
        if self.caches.tf.as_ref().is_none_or(|(t, _)| t != tf) {
            let tfb = TfBuffers::new(device, tf, self.mesh.range(), psi);
            self.caches.tf = Some((tf.clone(), tfb));
            rebuilt.classification = true;
        }
        let (w, h) = (scene.view.width, scene.view.height);
        let extras = Extras {
            isosurfaces: scene.appearance.isosurfaces.as_slice(),
            lighting: scene.appearance.lighting,
            planes: &scene.clip_planes,
        };
        let c = &self.caches;
        let (Some(fb), Some((_, tfb))) = (&c.buffers, &c.tf) else {
            return Err(GpuError::Failed("the PT caches were not built".into()));
        };
        let psi_view = match (&self.psi, psi) {
            (Some(v), true) => v,
            _ => &self.tiny_psi,
        };
        let mut shape = tfb.shape;
        shape.psi = psi;
        shape.psi_nodes = psi_view.texture().width();
        let params = ViewParams::new(
            &scene.view.camera,
            (w, h),
            (tets, vertices),
            &shape,
            &extras,
        );
        self.ctx
            .queue
            .write_buffer(&fb.uniform, 0, bytemuck::bytes_of(&params));
        let isovalues: Vec<f32> = extras.isosurfaces.iter().map(|i| i.value).collect();
        let kept_fresh = c
            .kept
            .as_ref()
            .is_some_and(|(rows, isos, _)| *rows == tfb.knot_rows && *isos == isovalues);
        let mut kept = c.kept.as_ref().map_or(0, |k| k.2);
        let mut kept_version = c.kept_version;
        if !kept_fresh {
            kept = self.keep(fb, tfb, tets)?;
            kept_version += 1;
            rebuilt.classification = true;
        }
        let key = ViewKey {
            camera: scene.view.camera,
            size: (w, h),
            planes: scene.clip_planes.clone(),
            kept_version,
            lit: !isovalues.is_empty(),
            exact,
        };
        let view_stale = c.view.as_ref() != Some(&key);
        let exact_order = match (view_stale, exact) {
            (true, true) => Some(exact_order(&mut self.caches.adjacency, &self.mesh, scene)?),
            _ => None,
        };
        let c = &self.caches;
        let (Some(fb), Some((_, tfb))) = (&c.buffers, &c.tf) else {
            return Err(GpuError::Failed("the PT caches were not built".into()));
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        if view_stale {
            self.first_pass(&mut encoder, fb, (tets, vertices));
            match &exact_order {
                // The CPU's exact order replaces the classified keys: (0, id) in order.
                Some(order) => {
                    let staging = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("exact order"),
                        contents: bytemuck::cast_slice(order),
                        usage: wgpu::BufferUsages::COPY_SRC,
                    });
                    let bytes = 8 * order.len() as u64;
                    encoder.copy_buffer_to_buffer(&staging, 0, &fb.items, 0, bytes);
                }
                None => self
                    .sort
                    .record(device, &mut encoder, &fb.items, &fb.scratch, tets as u32),
            }
            rebuilt.view = true;
        }
        let target = draw::target(device, self.format, (w as u32, h as u32));
        self.second_pass(&mut encoder, fb, tfb, psi_view, &target, tets);
        let (out, padded) = draw::copy_out(device, &mut encoder, &target);
        self.ctx.queue.submit([encoder.finish()]);
        let rgba = draw::pixels(device, &out, self.format, (w as u32, h as u32, padded))?;
        let new_kept = (!kept_fresh).then(|| (tfb.knot_rows.clone(), isovalues, kept));
        if let Some(k) = new_kept {
            self.caches.kept = Some(k);
            self.caches.kept_version = kept_version;
        }
        self.caches.view = Some(key);
        Ok(FrameReport {
            rgba,
            rebuilt,
            kept,
        })
    }

    /// Runs the `keep` pass (the kept set) and reads back how many cells it kept.
    fn keep(&self, fb: &FrameBuffers, tfb: &TfBuffers, tets: usize) -> Result<usize, GpuError> {
        let device = &self.ctx.device;
        let pipeline = &self.classify[2];
        let group = bind(
            device,
            &pipeline.get_bind_group_layout(0),
            &[
                (0, fb.uniform.as_entire_binding()),
                (1, self.data.positions.as_entire_binding()),
                (3, self.data.tets.as_entire_binding()),
                (6, tfb.knots.as_entire_binding()),
                (9, fb.kept.as_entire_binding()),
                (10, fb.counters.as_entire_binding()),
            ],
        );
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&fb.counters, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            let (gx, gy) = groups((tets as u32).div_ceil(64));
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        let out = readback(device, &mut encoder, &fb.counters, 16);
        self.ctx.queue.submit([encoder.finish()]);
        let bytes = map(device, &out)?;
        let count: [u32; 4] = bytemuck::pod_read_unaligned(
            bytes
                .get(..16)
                .ok_or_else(|| GpuError::Failed("short counter readback".into()))?,
        );
        Ok(count[0] as usize)
    }

    /// Records the projection and the classification of the kept cells.
    fn first_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        fb: &FrameBuffers,
        (tets, vertices): (usize, usize),
    ) {
        let device = &self.ctx.device;
        let d = &self.data;
        let [project, classify, _] = &self.classify;
        let project_bind = bind(
            device,
            &project.get_bind_group_layout(0),
            &[
                (0, fb.uniform.as_entire_binding()),
                (1, d.positions.as_entire_binding()),
                (2, fb.screen.as_entire_binding()),
            ],
        );
        let classify_bind = bind(
            device,
            &classify.get_bind_group_layout(0),
            &[
                (0, fb.uniform.as_entire_binding()),
                (1, d.positions.as_entire_binding()),
                (2, fb.screen.as_entire_binding()),
                (3, d.tets.as_entire_binding()),
                (4, self.gradients().as_entire_binding()),
                (5, self.table.as_entire_binding()),
                (7, fb.cells.as_entire_binding()),
                (8, fb.items.as_entire_binding()),
                (9, fb.kept.as_entire_binding()),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&Default::default());
        for (pipeline, bind, n) in [
            (project, &project_bind, vertices),
            (classify, &classify_bind, tets),
        ] {
            let (gx, gy) = groups((n as u32).div_ceil(64));
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
    }

    /// Records the fans, front to back, into `target`.
    fn second_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        fb: &FrameBuffers,
        tfb: &TfBuffers,
        psi: &wgpu::TextureView,
        target: &wgpu::Texture,
        tets: usize,
    ) {
        let device = &self.ctx.device;
        let group = bind(
            device,
            &self.draw.get_bind_group_layout(0),
            &[
                (0, fb.uniform.as_entire_binding()),
                (1, fb.cells.as_entire_binding()),
                (2, fb.items.as_entire_binding()),
                (3, self.table.as_entire_binding()),
                (4, tfb.knots.as_entire_binding()),
                (5, tfb.pieces.as_entire_binding()),
                (6, tfb.entries.as_entire_binding()),
                (7, wgpu::BindingResource::TextureView(psi)),
                (8, self.data.tets.as_entire_binding()),
                (9, self.gradients().as_entire_binding()),
            ],
        );
        let view = target.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("pt fans"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
        });
        pass.set_pipeline(&self.draw);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..(VERTICES_PER_CELL * tets as u64) as u32, 0..1);
    }
}
