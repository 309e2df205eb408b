//! What the PT shaders look up: the ternary truth table (seed `000` table 4.1 and eq. 4.1,
//! seed `002` figure 4; the CPU's [`TERNARY_TABLE`], packed), the TF's pieces and its
//! classification table ([`CellClassifier`]), and the ψ table ([`PsiTable`]) as a texture.
use volux_core::TransferFunction;
use volux_render::backend_kit::{CellClassifier, PsiTable};
use volux_render::backend_kit::{ThickTopology, TERNARY_TABLE};
use wgpu::util::DeviceExt;

use super::view::TfShape;

/// One table entry as the shaders read it: `kind | fan length << 8` (kind 0 degenerate,
/// 1 interior, 2 crossing, 3 on edge, 4 coincident), the thick vertex's vertices as bytes,
/// and the fan's indices as bytes (0-3, 4-5).
pub(crate) fn packed_table() -> Vec<[u32; 4]> {
    let bytes = |b: &[u8]| {
        b.iter()
            .enumerate()
            .fold(0u32, |acc, (i, &x)| acc | u32::from(x) << (8 * i))
    };
    TERNARY_TABLE
        .iter()
        .map(|e| {
            let (kind, verts) = match e.thick {
                ThickTopology::None => (0, [0; 4]),
                ThickTopology::Interior { vertex, face } => {
                    (1, [vertex, face[0], face[1], face[2]])
                }
                ThickTopology::Crossing { edges } => {
                    (2, [edges[0][0], edges[0][1], edges[1][0], edges[1][1]])
                }
                ThickTopology::OnEdge { vertex, edge, apex } => {
                    (3, [vertex, edge[0], edge[1], apex])
                }
                ThickTopology::Coincident { pair } => (4, [pair[0], pair[1], 0, 0]),
            };
            let fan = e.fan.indices();
            let len = if e.is_valid() { fan.len() as u32 } else { 0 };
            let kind = if len >= 3 { kind } else { 0 };
            let (head, tail) = fan.split_at(fan.len().min(4));
            [kind | len << 8, bytes(&verts), bytes(head), bytes(tail)]
        })
        .collect()
}

/// The TF's pieces on the device: for the first pass the breakpoints with, per piece,
/// whether its extinction is non-zero (the CPU's discard, `volux_render::pt::render`'s
/// `Support`, seed `002` §4.5); for the second the pieces' linear coefficients and the
/// classification table.
pub(crate) struct TfBuffers {
    /// `(breakpoint k, piece k non-zero, 0, 0)`, one more than the breakpoints.
    pub(crate) knots: wgpu::Buffer,
    /// Their rows: the zero set, the key of the kept set.
    pub(crate) knot_rows: Vec<[f32; 4]>,
    /// Per piece: `(origin, 0, 0, 0)`, the value at the origin, the slope.
    pub(crate) pieces: wgpu::Buffer,
    /// The classification table (`[r, g, b, tau]` per entry).
    pub(crate) entries: wgpu::Buffer,
    pub(crate) shape: TfShape,
}

impl TfBuffers {
    /// The buffers of `tf` (resolved against `range`), for the ψ rule or the average.
    pub(crate) fn new(
        device: &wgpu::Device,
        tf: &TransferFunction,
        range: [f64; 2],
        psi: bool,
    ) -> Self {
        let classifier = CellClassifier::new(tf, range);
        let (knots, pieces) = classifier
            .pieces_on(f32::NEG_INFINITY, f32::INFINITY)
            .unwrap_or_default();
        let nonzero = nonzero_pieces(&tf.resolved(range), knots);
        let knot_rows: Vec<[f32; 4]> = (0..pieces.len().max(1))
            .map(|k| {
                let at = knots.get(k).copied().unwrap_or(0.0);
                [at, f32::from(u8::from(nonzero[k])), 0.0, 0.0]
            })
            .collect();
        let piece_rows: Vec<[[f32; 4]; 3]> = pieces
            .iter()
            .map(|p| {
                let (origin, at, slope) = p.coefficients();
                [[origin, 0.0, 0.0, 0.0], at, slope]
            })
            .chain(std::iter::once([[0.0; 4]; 3]))
            .collect();
        let (entries, lo, scale) = classifier.table();
        let storage = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Self {
            knots: storage("tf breakpoints", bytemuck::cast_slice(&knot_rows)),
            knot_rows,
            pieces: storage("tf pieces", bytemuck::cast_slice(&piece_rows)),
            entries: storage("classification table", bytemuck::cast_slice(entries)),
            shape: TfShape {
                knots: knots.len() as u32,
                entries: entries.len() as u32,
                lo,
                scale,
                psi_nodes: 2,
                psi,
            },
        }
    }
}

/// Whether the extinction is non-zero on each piece between the breakpoints `knots` (and
/// the two unbounded ends), sampled as the CPU's discard samples it.
fn nonzero_pieces(tf: &TransferFunction, knots: &[f32]) -> Vec<bool> {
    let tau = |s: f64| {
        let v = tf.tau_per_world(s);
        v.is_finite() && v > 0.0
    };
    let k: Vec<f64> = knots.iter().map(|&x| f64::from(x)).collect();
    let Some((&first, &last)) = k.first().zip(k.last()) else {
        return vec![tau(0.0)];
    };
    let inner = k.windows(2).map(|w| {
        [0.0, 0.25, 0.5, 0.75, 1.0]
            .iter()
            .any(|f| tau(w[0] + f * (w[1] - w[0])))
    });
    std::iter::once(tau(first - 1.0) || tau(first))
        .chain(inner)
        .chain(std::iter::once(tau(last) || tau(last + 1.0)))
        .collect()
}

/// The ψ table (`1 - psi`, [`PsiTable::values`]) as an `r32float` texture, row `i` the
/// front thickness node; read with `textureLoad` and interpolated in the shader as on the
/// CPU.
pub(crate) fn psi_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    table: &PsiTable,
) -> wgpu::TextureView {
    let n = table.size() as u32;
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("psi table"),
            size: wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(table.values()),
    );
    texture.create_view(&Default::default())
}
