//! Synthetic volumes of any size computed chunk by chunk ([`SyntheticChunks`]): `volux
//! generate` streams them into a store without ever holding the volume.
use glam::DVec3;
use volux_core::bricked::{ChunkLayout, ChunkSource};
use volux_core::grid::{Buffer, Samples, ScalarType};
use volux_core::{synth, Error, Result};

/// A synthetic field sampled over [-1, 1]^3 on a lattice of `dims` samples (spacing 1, origin
/// 0, as [`synth::generate_grid`]), computed per chunk. As u16, values are
/// `round(clamp(v, 0, 1) * 65535)`.
pub struct SyntheticChunks {
    layout: ChunkLayout,
    f: fn(DVec3) -> f64,
}

fn sphere_value(p: DVec3) -> f64 {
    0.6 - p.length()
}

impl SyntheticChunks {
    /// The synthetic grid `kind` (`marschner-lobb`, `shepp-logan`, `sphere`) at `dims`
    /// samples in chunks of `chunk`, stored as `scalar` (f32 or u16).
    pub fn new(
        kind: &str,
        dims: [usize; 3],
        chunk: [usize; 3],
        scalar: ScalarType,
    ) -> Result<Self> {
        let f: fn(DVec3) -> f64 = match kind {
            "marschner-lobb" => synth::marschner_lobb_value,
            "shepp-logan" => synth::shepp_logan_value,
            "sphere" => sphere_value,
            _ => {
                return Err(Error::UnknownName {
                    kind: "chunked generator",
                    name: kind.into(),
                    known: "marschner-lobb, shepp-logan, sphere".into(),
                })
            }
        };
        if !matches!(scalar, ScalarType::F32 | ScalarType::U16) {
            return Err(Error::Chunked(format!(
                "synthetic volumes are f32 or u16, not {}",
                scalar.name()
            )));
        }
        if dims.iter().any(|&d| d < 2) {
            return Err(Error::Chunked(format!(
                "a synthetic volume needs at least 2 samples per axis, not {dims:?}"
            )));
        }
        Ok(Self {
            layout: ChunkLayout::new(dims, chunk, [1.0; 3], [0.0; 3], scalar)?,
            f,
        })
    }
}

impl ChunkSource for SyntheticChunks {
    fn layout(&self) -> &ChunkLayout {
        &self.layout
    }

    fn read_chunk(&self, c: [usize; 3]) -> Result<Samples> {
        let (lo, size) = self.layout.checked_extent(c)?;
        let d = self.layout.dims;
        let step: [f64; 3] = std::array::from_fn(|a| 2.0 / (d[a] - 1) as f64);
        let mut v = Vec::with_capacity(size.iter().product());
        for k in lo[2]..lo[2] + size[2] {
            for j in lo[1]..lo[1] + size[1] {
                for i in lo[0]..lo[0] + size[0] {
                    let p = DVec3::new(
                        i as f64 * step[0] - 1.0,
                        j as f64 * step[1] - 1.0,
                        k as f64 * step[2] - 1.0,
                    );
                    v.push((self.f)(p));
                }
            }
        }
        Ok(match self.layout.scalar {
            ScalarType::U16 => Samples::U16(Buffer::owned(
                v.into_iter()
                    .map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16)
                    .collect(),
            )),
            _ => Samples::F32(Buffer::owned(v.into_iter().map(|x| x as f32).collect())),
        })
    }
}
