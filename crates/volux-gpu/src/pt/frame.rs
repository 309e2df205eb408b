//! One frame on the device: the first pass, the sort, the fans, the readback.
use volux_core::TransferFunction;
use volux_render::scene::Scene;

use super::tables::TfBuffers;
use super::view::{Extras, ViewParams};
use super::{draw, groups, GpuPtRenderer, RadixSort, CELL_BYTES, VERTICES_PER_CELL};
use crate::error::GpuError;

/// The per-frame buffers of the first pass.
struct FrameBuffers {
    uniform: wgpu::Buffer,
    screen: wgpu::Buffer,
    cells: wgpu::Buffer,
    items: wgpu::Buffer,
    scratch: wgpu::Buffer,
}

fn buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE,
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

impl GpuPtRenderer {
    /// The vertex gradients, or one zero element before the first isosurface.
    fn gradients(&self) -> &wgpu::Buffer {
        self.data
            .gradients
            .as_ref()
            .unwrap_or(&self.data.no_gradients)
    }

    /// Renders `scene` with `tf` (the ψ rule or the average): the image's pixels.
    pub(super) fn frame(
        &self,
        scene: &Scene,
        tf: &TransferFunction,
        psi: bool,
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let device = &self.ctx.device;
        let mesh = &self.mesh;
        let mut tfb = TfBuffers::new(device, tf, mesh.range(), psi);
        let psi_view = match (&self.psi, psi) {
            (Some(v), true) => v,
            _ => &self.tiny_psi,
        };
        tfb.shape.psi_nodes = psi_view.texture().width();
        let (w, h) = (scene.view.width, scene.view.height);
        let (tets, vertices) = (mesh.tets().len(), mesh.positions().len());
        let extras = Extras {
            isosurfaces: scene.appearance.isosurfaces.as_slice(),
            lighting: scene.appearance.lighting,
            planes: &scene.clip_planes,
        };
        let params = ViewParams::new(
            &scene.view.camera,
            (w, h),
            (tets, vertices),
            &tfb.shape,
            &extras,
        );
        let n = tets as u64;
        let (scratch, _) = RadixSort::scratch_bytes(n);
        let fb = FrameBuffers {
            uniform: wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("pt view"),
                    contents: bytemuck::bytes_of(&params),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            ),
            screen: buffer(device, "screen", 16 * vertices as u64),
            cells: buffer(device, "cells", CELL_BYTES * n),
            items: buffer(device, "items", 8 * n),
            scratch: buffer(device, "sort scratch", scratch),
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        self.first_pass(&mut encoder, &fb, &tfb, (tets, vertices));
        self.sort
            .record(device, &mut encoder, &fb.items, &fb.scratch, tets as u32);
        let target = draw::target(device, self.format, (w as u32, h as u32));
        self.second_pass(&mut encoder, &fb, &tfb, psi_view, &target, tets);
        let (out, padded) = draw::copy_out(device, &mut encoder, &target);
        self.ctx.queue.submit([encoder.finish()]);
        draw::pixels(device, &out, self.format, (w as u32, h as u32, padded))
    }

    /// Records the projection and the classification.
    fn first_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        fb: &FrameBuffers,
        tfb: &TfBuffers,
        (tets, vertices): (usize, usize),
    ) {
        let device = &self.ctx.device;
        let d = &self.data;
        let [project, classify] = &self.classify;
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
                (6, tfb.knots.as_entire_binding()),
                (7, fb.cells.as_entire_binding()),
                (8, fb.items.as_entire_binding()),
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

    /// Records the fans, back to front, into `target`.
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
