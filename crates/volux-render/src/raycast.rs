//! Image-order traversal of regular grids: one ray per pixel, exact ray/box entry and exit,
//! front-to-back compositing with early ray termination, parallel over image rows.
//!
//! Integration here is the Riemann sum of [`crate::integrate`] with trilinear reconstruction
//! ([`crate::sampling`]); the step is given in voxel units (the smallest spacing), as in the
//! seed `001_...txt`. Output does not depend on the number of threads: every pixel is computed
//! independently.
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::{Camera, Grid, Image, TransferFunction};

use crate::classify::ClassifyTable;
use crate::integrate::{riemann_step, RayAccumulator};
use crate::sampling::{Field, Trilinear};
use crate::RenderError;

/// Called with (rows done, total rows) as the render progresses.
pub type ProgressFn = Arc<dyn Fn(usize, usize) + Send + Sync>;

/// What to render and how.
#[derive(Clone)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The camera.
    pub camera: Camera,
    /// The transfer function (resolved against the data range by the renderer).
    pub tf: TransferFunction,
    /// Sampling step in voxel units (of the smallest spacing).
    pub step: f64,
    /// Stop a ray once its opacity reaches this value; `None` integrates to the end
    /// (reference mode).
    pub early_termination: Option<f32>,
    /// Set to true from another thread to stop the render with [`RenderError::Cancelled`].
    pub cancel: Option<Arc<AtomicBool>>,
    /// Progress callback.
    pub progress: Option<ProgressFn>,
}

impl RenderOptions {
    /// Defaults: 512 x 512, step 0.5 voxel, early termination at 0.99.
    pub fn new(camera: Camera, tf: TransferFunction) -> Self {
        Self {
            width: 512,
            height: 512,
            camera,
            tf,
            step: 0.5,
            early_termination: Some(0.99),
            cancel: None,
            progress: None,
        }
    }

    fn validate(&self) -> Result<(), RenderError> {
        if self.width == 0 || self.height == 0 || self.width > 1 << 15 || self.height > 1 << 15 {
            return Err(RenderError::InvalidOptions(format!(
                "image size {}x{} must be between 1 and 32768",
                self.width, self.height
            )));
        }
        if !(self.step.is_finite() && self.step > 1e-4) {
            return Err(RenderError::InvalidOptions(format!(
                "step {} must be > 1e-4",
                self.step
            )));
        }
        self.tf.validate()?;
        self.camera.validate()?;
        Ok(())
    }
}

/// Figures of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    /// Rays that hit the volume.
    pub rays: u64,
    /// Field samples taken.
    pub samples: u64,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// Placement of a field in the world: sample (i, j, k) at `origin + spacing * (i, j, k)`.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// World position of sample (0, 0, 0).
    pub origin: DVec3,
    /// Distance between samples per axis.
    pub spacing: DVec3,
    /// Samples per axis.
    pub dims: [usize; 3],
}

impl Placement {
    /// The placement of a grid.
    pub fn of(grid: &Grid) -> Self {
        Self {
            origin: grid.origin(),
            spacing: grid.spacing(),
            dims: grid.dims(),
        }
    }
    fn extent(&self) -> DVec3 {
        DVec3::new(
            (self.dims[0].max(2) - 1) as f64,
            (self.dims[1].max(2) - 1) as f64,
            (self.dims[2].max(2) - 1) as f64,
        ) * self.spacing
    }
}

/// Renders a grid with the Riemann ray caster.
pub fn render_grid(grid: &Grid, opts: &RenderOptions) -> Result<(Image, RenderStats), RenderError> {
    let place = Placement::of(grid);
    volux_core::with_samples!(grid.samples(), |s| render_field(
        &Trilinear::new(s, grid.dims()),
        place,
        grid.range(),
        opts
    ))
}

/// Renders any [`Field`] placed in the world, classifying with `opts.tf` over `range`.
pub fn render_field<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
) -> Result<(Image, RenderStats), RenderError> {
    opts.validate()?;
    let start = Instant::now();
    let table = ClassifyTable::new(&opts.tf, range, ClassifyTable::DEFAULT_SIZE);
    let (w, h) = (opts.width, opts.height);
    let mut pixels = vec![[0.0f32; 4]; w * h];
    let (rays, samples) = (AtomicU64::new(0), AtomicU64::new(0));
    let rows_done = AtomicU64::new(0);
    let cancelled = || {
        opts.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    };
    pixels
        .par_chunks_mut(w)
        .enumerate()
        .try_for_each(|(y, row)| {
            if cancelled() {
                return Err(RenderError::Cancelled);
            }
            let (mut r, mut s) = (0, 0);
            for (x, px) in row.iter_mut().enumerate() {
                let ray = opts.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
                if let Some(out) = cast_ray(field, &place, &table, ray.origin, ray.dir, opts) {
                    *px = out.0.rgba;
                    r += 1;
                    s += out.1;
                }
            }
            rays.fetch_add(r, Ordering::Relaxed);
            samples.fetch_add(s, Ordering::Relaxed);
            let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            if let Some(p) = &opts.progress {
                p(done as usize, h);
            }
            Ok(())
        })?;
    let image = Image::from_pixels(w, h, pixels)?;
    let stats = RenderStats {
        rays: rays.into_inner(),
        samples: samples.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((image, stats))
}

/// Entry and exit distances of a ray through the box [lo, hi] (slab test), if it hits.
pub fn ray_box(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let inv = dir.recip();
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    // NaN (0 * inf, ray in a slab plane) is ignored by max/min below.
    let tn = near.x.max(near.y).max(near.z).max(0.0);
    let tf = far.x.min(far.y).min(far.z);
    (tf > tn).then_some((tn, tf))
}

/// Integrates one ray; returns the accumulated colour and the number of samples.
fn cast_ray<F: Field>(
    field: &F,
    place: &Placement,
    table: &ClassifyTable,
    origin: DVec3,
    dir: DVec3,
    opts: &RenderOptions,
) -> Option<(RayAccumulator, u64)> {
    let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
    let h_world = opts.step * place.spacing.min_element();
    // Voxel-space ray: p_vox(t) = o_v + t * d_v.
    let o_v = ((origin - place.origin) / place.spacing).as_vec3();
    let d_v = (dir / place.spacing).as_vec3();
    let stop = opts.early_termination.unwrap_or(2.0);
    let mut acc = RayAccumulator::default();
    let mut n = 0u64;
    let mut t = t0;
    while t < t1 {
        let len = h_world.min(t1 - t);
        let tm = (t + 0.5 * len) as f32;
        if let Some(v) = field.sample(o_v + d_v * tm) {
            riemann_step(&mut acc, table.lookup(v), len as f32);
        }
        n += 1;
        if acc.alpha() >= stop {
            break;
        }
        t += h_world;
    }
    Some((acc, n))
}

/// The voxel-space position of a world point (for tests and tools).
pub fn to_voxel(place: &Placement, p: DVec3) -> Vec3 {
    ((p - place.origin) / place.spacing).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::grid::{Buffer, Samples};
    use volux_core::CameraSpec;

    fn constant_grid(v: f32) -> Grid {
        Grid::new(
            [8, 8, 8],
            [1.0; 3],
            [0.0; 3],
            Samples::F32(Buffer::owned(vec![v; 512])),
        )
        .unwrap()
    }

    /// A constant field seen orthographically along an axis: every ray crosses 7 units of a
    /// medium of constant extinction, whose exact opacity is 1 - exp(-7 tau).
    #[test]
    fn constant_slab_matches_closed_form() {
        let g = constant_grid(1.0);
        let tf =
            TransferFunction::from_json(r#"{"color": [[0,1,0.5,0.25]], "extinction": [[0,0.2]]}"#)
                .unwrap();
        let spec = CameraSpec {
            projection: Some("orthographic".into()),
            zoom: Some(4.0),
            ..Default::default()
        };
        let cam = spec.resolve(&g.bounds()).unwrap();
        for step in [0.1, 0.5, 1.3] {
            let mut o = RenderOptions::new(cam, tf.clone());
            (o.width, o.height, o.step, o.early_termination) = (16, 16, step, None);
            let (img, stats) = render_grid(&g, &o).unwrap();
            let exact = 1.0 - (-0.2f32 * 7.0).exp();
            let p = img.get(8, 8);
            assert!(
                (p[3] - exact).abs() < 1e-4,
                "step {step}: {} vs {exact}",
                p[3]
            );
            assert!((p[1] - 0.5 * exact).abs() < 1e-4);
            assert_eq!(stats.rays, 256);
        }
    }

    #[test]
    fn thread_count_does_not_change_the_image() {
        let g = volux_core::synth::marschner_lobb(24).unwrap();
        let tf = TransferFunction::preset(
            "viridis",
            &volux_core::histogram::Histogram::of_grid(&g, 64),
        )
        .unwrap();
        let mut o = RenderOptions::new(Camera::fit(&g.bounds()), tf);
        (o.width, o.height) = (40, 30);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let a = one.install(|| render_grid(&g, &o)).unwrap().0;
        let b = render_grid(&g, &o).unwrap().0;
        assert_eq!(a, b);
        assert!(a.coverage(0.01) > 0.2);
    }

    #[test]
    fn cancellation_stops_the_render() {
        let g = constant_grid(1.0);
        let tf = TransferFunction::from_json(r#"{"color": [[0,1,1,1]], "extinction": [[0,0.2]]}"#)
            .unwrap();
        let mut o = RenderOptions::new(Camera::fit(&g.bounds()), tf);
        o.cancel = Some(Arc::new(AtomicBool::new(true)));
        assert!(matches!(render_grid(&g, &o), Err(RenderError::Cancelled)));
    }

    #[test]
    fn ray_box_hits_and_misses() {
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let (a, b) = ray_box(DVec3::new(0.5, 0.5, -1.0), DVec3::Z, lo, hi).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
        assert!(ray_box(DVec3::new(2.0, 0.5, -1.0), DVec3::Z, lo, hi).is_none());
    }
}
