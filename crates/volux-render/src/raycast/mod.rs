//! Image-order traversal of regular grids: one ray per pixel, exact ray/box entry and exit,
//! front-to-back compositing with early ray termination, parallel over square image tiles.
//!
//! Each ray is handed to one of the [`Integrator`]s of [`crate::integrate`] as a
//! [`RayMedium`] (trilinear reconstruction of [`crate::sampling`], classification of
//! [`crate::classify`]); steps are given in voxel units (the smallest spacing), as in the seed
//! `001_...txt`. A tile takes one of these paths:
//!
//! - Riemann sums and pre-integration, emission only or shaded with the cached gradient
//!   volume: the lane stream (`raycast/stream.rs`), 16 rays advanced together;
//! - adaptive Simpson with coupled control, emission only or shaded with the cached gradient
//!   volume: `raycast/adaptive_stream.rs`, four rays' steps sampled and judged together in
//!   f32 lanes;
//! - maximum intensity projection: `raycast/mip_stream.rs`, 16 rays sampled together;
//! - everything else (isosurfaces, decoupled adaptive Simpson, trapezoid, Simpson, the
//!   reference): ray by ray.
//!
//! The paths compute the same sums (tested). Output does not depend on the number of threads:
//! every pixel is computed independently.
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use glam::{DVec3, Vec3};
use volux_core::{Camera, Grid, Image, RayGenerator, TransferFunction};

use crate::classify::{BreakpointRanks, Classified, ClassifyTable, LaneTable};
use crate::composite::{under_partial, RayAccumulator};
use crate::integrate::preintegrated::PreintegrationTable;
use crate::integrate::{
    adaptive_simpson_intervals, adaptive_simpson_pieces, fixed_intervals, hides_breakpoints,
    hides_breakpoints_along, riemann_step, AdaptiveParams, FixedRule, Integrator, Medium,
    RayIntegral, RayMedium,
};
use crate::isosurface::{Crossing, Isosurfaces};
use crate::macrocell::{MacrocellGrid, Occupancy};
use crate::mip;
use crate::sampling::{Field, Reconstruction, Tricubic, Trilinear};
use crate::shading::{self, BlinnPhong, GradientVolume};
use crate::tiles::{render_tiles, Control, TileGrid, TILE};
use crate::RenderError;
use stream::TrapezoidRule;

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
    /// How rays are integrated (steps in voxel units of the smallest spacing).
    pub integrator: Integrator,
    /// Stop a ray once its opacity reaches this value; `None` integrates to the end
    /// (reference mode).
    pub early_termination: Option<f32>,
    /// Skip macrocells whose extinction is zero, when enough of them are empty for it to pay
    /// (never changes the image).
    pub empty_space_skipping: bool,
    /// Offset each ray's first Riemann sample by a per-pixel pseudo-random fraction of the
    /// step, trading wood-grain artifacts for fine noise (deterministic per pixel).
    pub jitter: bool,
    /// Reconstruction filter of grids (trilinear, or tricubic Catmull-Rom / B-spline).
    pub reconstruction: Reconstruction,
    /// Blinn-Phong gradient shading of the volume samples and isosurfaces (`None`: emission
    /// only).
    pub shading: Option<BlinnPhong>,
    /// Isosurfaces composited with the volume (Riemann integrator).
    pub isosurfaces: Isosurfaces,
    /// Maximum intensity projection instead of compositing: each pixel shows the TF colour of
    /// the largest value along its ray.
    pub mip: bool,
    /// Cancellation and progress.
    pub control: Control,
}

impl RenderOptions {
    /// Defaults: 512 x 512, Riemann with step 0.5 voxel, early termination at 0.99.
    pub fn new(camera: Camera, tf: TransferFunction) -> Self {
        Self {
            width: 512,
            height: 512,
            camera,
            tf,
            integrator: Integrator::Riemann { step: 0.5 },
            early_termination: Some(0.99),
            empty_space_skipping: true,
            jitter: false,
            reconstruction: Reconstruction::Trilinear,
            shading: None,
            isosurfaces: Isosurfaces::default(),
            mip: false,
            control: Control::default(),
        }
    }

    fn validate(&self) -> Result<(), RenderError> {
        crate::check_image_size(self.width, self.height)?;
        self.integrator
            .validate()
            .map_err(RenderError::InvalidOptions)?;
        if let Some(s) = &self.shading {
            s.validate().map_err(RenderError::InvalidOptions)?;
        }
        if !self.isosurfaces.is_empty()
            && !self.mip
            && !matches!(self.integrator, Integrator::Riemann { .. })
        {
            return Err(RenderError::InvalidOptions(format!(
                "isosurfaces are drawn by the riemann integrator only, not {}",
                self.integrator.name()
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
    /// Rays whose adaptive integration accepted a step at `hmin` above its tolerance.
    pub rays_over_tolerance: u64,
}

/// A rendered image with its figures and per-pixel estimated integration error.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image.
    pub image: Image,
    /// Figures of the render.
    pub stats: RenderStats,
    /// Estimated absolute error per pixel (largest channel; 0 where the integrator does not
    /// estimate it), row-major.
    pub error_map: Vec<f32>,
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

/// Renders a grid with the integrator of `opts` (no caching: see [`GridRenderer`]).
pub fn render_grid(grid: &Grid, opts: &RenderOptions) -> Result<Rendered, RenderError> {
    GridRenderer::new(grid).render(opts)
}

/// A grid ray caster that keeps data-derived structures (the macrocell min/max grid) between
/// renders, so an interactive session pays for them once per volume; TF-derived data (the
/// classification table, empty flags) is rebuilt per render, which costs milliseconds.
pub struct GridRenderer<'g> {
    grid: &'g Grid,
    macrocells: OnceLock<MacrocellGrid>,
    preintegration: Mutex<Option<Arc<PreintegrationTable>>>,
    gradients: OnceLock<Option<GradientVolume>>,
    /// Whether tiles may take the lane paths; tests turn it off to compare them with the
    /// ray-by-ray paths, which compute the same sums.
    lanes: bool,
}

impl<'g> GridRenderer<'g> {
    /// A renderer for `grid`.
    pub fn new(grid: &'g Grid) -> Self {
        Self {
            grid,
            macrocells: OnceLock::new(),
            preintegration: Mutex::new(None),
            gradients: OnceLock::new(),
            lanes: true,
        }
    }

    /// The macrocell min/max grid, built on first use.
    pub fn macrocells(&self) -> &MacrocellGrid {
        self.macrocells.get_or_init(|| {
            volux_core::with_samples!(self.grid.samples(), |s| MacrocellGrid::build(
                s,
                self.grid.dims()
            ))
        })
    }

    /// The pre-integration table for `opts`, rebuilt only when the TF or the step changed.
    pub fn preintegration(
        &self,
        opts: &RenderOptions,
    ) -> Result<Option<Arc<PreintegrationTable>>, RenderError> {
        let Integrator::Preintegrated { step } = opts.integrator else {
            return Ok(None);
        };
        let d = step * self.grid.spacing().min_element();
        let range = self.grid.range();
        let mut cache = self
            .preintegration
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if let Some(t) = cache
            .as_ref()
            .filter(|t| t.is_valid_for(&opts.tf, range, d))
        {
            return Ok(Some(t.clone()));
        }
        let table = Arc::new(
            PreintegrationTable::new(&opts.tf, range, d).map_err(RenderError::InvalidOptions)?,
        );
        *cache = Some(table.clone());
        Ok(Some(table))
    }

    /// The precomputed gradient volume, built on the first shaded render (`None` if it does
    /// not fit in memory: gradients are then computed on the fly).
    pub fn gradients(&self) -> Option<&GradientVolume> {
        self.gradients
            .get_or_init(|| {
                let g = self.grid;
                volux_core::with_samples!(g.samples(), |s| GradientVolume::build(
                    &Trilinear::new(s, g.dims()),
                    g.spacing().as_vec3(),
                    0
                )
                .ok())
            })
            .as_ref()
    }

    /// Renders with `opts`, at `1 / divisor` of the resolution (progressive refinement: a
    /// viewer shows a coarse image first); `divisor` 1 is the full image.
    pub fn render_reduced(
        &self,
        opts: &RenderOptions,
        divisor: usize,
    ) -> Result<Rendered, RenderError> {
        let k = divisor.max(1);
        let mut small = opts.clone();
        (small.width, small.height) = (opts.width.div_ceil(k), opts.height.div_ceil(k));
        self.render(&small)
    }

    /// Renders with `opts`.
    pub fn render(&self, opts: &RenderOptions) -> Result<Rendered, RenderError> {
        let g = self.grid;
        let cells = opts.empty_space_skipping.then(|| self.macrocells());
        let pre = self.preintegration(opts)?;
        let gradients = opts.shading.as_ref().and_then(|_| self.gradients());
        let derived = Derived {
            macrocells: cells,
            preintegration: pre.as_deref(),
            gradients,
            lanes: self.lanes,
        };
        let (place, range) = (Placement::of(g), g.range());
        match opts.reconstruction {
            Reconstruction::CatmullRom | Reconstruction::BSpline => {
                // Cubic filters reach one voxel further than a macrocell's samples (and
                // Catmull-Rom overshoots), so empty-space skipping is off for them.
                let derived = Derived {
                    macrocells: None,
                    ..derived
                };
                let bspline = opts.reconstruction == Reconstruction::BSpline;
                volux_core::with_samples!(g.samples(), |s| render_with(
                    &Tricubic::new(s, g.dims(), bspline),
                    place,
                    range,
                    opts,
                    derived
                ))
            }
            _ => volux_core::with_samples!(g.samples(), |s| render_with(
                &Trilinear::new(s, g.dims()),
                place,
                range,
                opts,
                derived
            )),
        }
    }
}

/// Whether empty-space skipping pays for itself: a ray walks every macrocell it crosses (a
/// few nanoseconds each) to save the samples of the empty ones, so skipping is used when the
/// expected samples saved per macrocell crossed, `empty fraction x BLOCK / sample spacing`,
/// reach one. Measured at 512x512: Marschner-Lobb with the bench's TF (3.3 % of macrocells
/// empty) renders 8 % faster without skipping at step 0.5 and 10 % slower at step 0.2; the
/// CT head with its automatic TF (2 % empty), faster without at both. Skipping never changes
/// the image (tested), so this only decides speed.
fn worth_skipping(empty_fraction: f64, integrator: &Integrator) -> bool {
    let spacing = match *integrator {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Preintegrated { step } => step,
        Integrator::Simpson { step } => step / 2.0,
        // Four samples per step, steps up to hmax.
        Integrator::AdaptiveSimpson(p) => p.hmax / 4.0,
        _ => 0.01,
    };
    empty_fraction * MacrocellGrid::BLOCK as f64 / spacing.max(1e-6) >= 1.0
}

/// One pixel's result.
#[derive(Clone, Copy, Debug, Default)]
struct PixelOut {
    rgba: [f32; 4],
    samples: u64,
    error: f32,
    missed: bool,
    hit: bool,
}

impl PixelOut {
    /// A hit ray composited into `acc` with `samples` samples (no error estimate).
    fn composited(acc: &RayAccumulator, samples: u64) -> Self {
        Self {
            rgba: acc.rgba,
            samples,
            error: 0.0,
            missed: false,
            hit: true,
        }
    }
}

/// Renders any [`Field`] placed in the world, classifying with `opts.tf` over `range`
/// (without empty-space skipping).
pub fn render_field<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
) -> Result<Rendered, RenderError> {
    let pre = match opts.integrator {
        Integrator::Preintegrated { step } => Some(
            PreintegrationTable::new(&opts.tf, range, step * place.spacing.min_element())
                .map_err(RenderError::InvalidOptions)?,
        ),
        _ => None,
    };
    render_with(
        field,
        place,
        range,
        opts,
        Derived {
            macrocells: None,
            preintegration: pre.as_ref(),
            gradients: None,
            lanes: true,
        },
    )
}

/// Data derived from the volume and the TF that a render uses, built (and cached) by the caller.
#[derive(Clone, Copy, Default)]
struct Derived<'a> {
    macrocells: Option<&'a MacrocellGrid>,
    preintegration: Option<&'a PreintegrationTable>,
    gradients: Option<&'a GradientVolume>,
    /// Whether tiles may take the lane paths.
    lanes: bool,
}

fn render_with<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
) -> Result<Rendered, RenderError> {
    opts.validate()?;
    let start = Instant::now();
    let table = ClassifyTable::new(&opts.tf, range, ClassifyTable::DEFAULT_SIZE);
    let isovalues: Vec<f32> = opts
        .isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect();
    let occupancy = derived
        .macrocells
        .filter(|_| !opts.mip)
        .map(|m| Occupancy::new(m, &table, &isovalues))
        .filter(|o| worth_skipping(o.empty_fraction(), &opts.integrator));
    let breakpoints = opts.tf.resolved(range).breakpoints();
    let (lane_table, breakpoint_ranks) = match opts.integrator {
        Integrator::Riemann { step } => (
            Some(table.for_step((step * place.spacing.min_element()) as f32)),
            None,
        ),
        Integrator::Trapezoid { .. } => (Some(table.for_lanes()), None),
        Integrator::AdaptiveSimpson(_) => {
            let lanes = table.for_lanes();
            let ranks = lanes.breakpoint_ranks(&breakpoints);
            (Some(lanes), Some(ranks))
        }
        _ => (None, None),
    };
    let ctx = RayContext {
        field,
        place,
        table: &table,
        occupancy: occupancy.as_ref(),
        preintegration: derived.preintegration,
        gradients: derived.gradients,
        lane_table,
        breakpoint_ranks,
        tf: opts.tf.resolved(range),
        breakpoints,
        rays: opts.camera.rays(opts.width, opts.height),
        opts,
    };
    let grid = TileGrid::new(opts.width, opts.height, TILE);
    let out = render_tiles(&grid, &opts.control, |_, r| {
        let (x0, y0) = (r.x0, r.y0);
        let px = if !derived.lanes {
            ctx.tile_ray_by_ray(x0, y0)
        } else if opts.mip {
            ctx.mip_stream(x0, y0)
        } else if let Some(st) = ctx.packet_table() {
            ctx.lane_stream(st, x0, y0)
        } else if let Some(pt) = ctx.preintegrated_stream_table() {
            ctx.lane_stream(pt, x0, y0)
        } else if let Some(tr) = ctx.trapezoid_stream_rule() {
            ctx.lane_stream(&tr, x0, y0)
        } else if let Some(p) = ctx.adaptive_stream_params() {
            ctx.adaptive_stream(p, x0, y0)
        } else {
            ctx.tile_ray_by_ray(x0, y0)
        };
        (px, ())
    })?
    .pixels;
    let (w, h) = (opts.width, opts.height);
    let stats = RenderStats {
        rays: out.iter().filter(|p| p.hit).count() as u64,
        samples: out.iter().map(|p| p.samples).sum(),
        seconds: start.elapsed().as_secs_f64(),
        rays_over_tolerance: out.iter().filter(|p| p.missed).count() as u64,
    };
    let error_map = out.iter().map(|p| p.error).collect();
    let image = Image::from_pixels(w, h, out.iter().map(|p| p.rgba).collect())?;
    Ok(Rendered {
        image,
        stats,
        error_map,
    })
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

/// Everything a ray needs, shared by all rays of a render.
struct RayContext<'a, F> {
    field: &'a F,
    place: Placement,
    table: &'a ClassifyTable,
    occupancy: Option<&'a Occupancy<'a>>,
    preintegration: Option<&'a PreintegrationTable>,
    gradients: Option<&'a GradientVolume>,
    /// The classification for the lane-wise paths: per-slab colour and opacity for the
    /// Riemann step (no `exp` per sample), colour and extinction for adaptive Simpson.
    lane_table: Option<LaneTable>,
    /// Breakpoint counts per lane-table entry, for adaptive Simpson's hidden-peak test.
    breakpoint_ranks: Option<BreakpointRanks>,
    tf: TransferFunction,
    breakpoints: Vec<f64>,
    /// The camera's rays for this image size.
    rays: RayGenerator,
    opts: &'a RenderOptions,
}

/// The classified medium along one ray through a grid, in voxel space.
struct GridRay<'a, F> {
    field: &'a F,
    o_v: DVec3,
    d_v: DVec3,
    table: &'a ClassifyTable,
    /// Classify exactly with this TF instead of the table (the reference path).
    exact: Option<&'a TransferFunction>,
    breakpoints: &'a [f64],
    /// Shading of the emitted colour: the lighting model and the ray's context.
    shade: Option<RayShading<'a>>,
}

impl<F: Field> RayMedium for GridRay<'_, F> {
    fn at(&mut self, t: f64) -> Medium {
        let p = self.o_v + self.d_v * t;
        // The f64 reconstruction for the reference; the table-classified integrators work to
        // tolerances far above f32 rounding (1e-7 of the data range).
        let v = match self.exact {
            Some(_) => self.field.sample64(p),
            None => self.field.sample(p.as_vec3()).map(f64::from),
        };
        let Some(v) = v else {
            return Medium::default();
        };
        let mut m = self.classify(v);
        if let (Some(sh), true) = (&self.shade, m.tau > 0.0) {
            let p = p.as_vec3();
            let g = match sh.gradients {
                Some(g) => g.gradient(p),
                None => shading::gradient(self.field, p, sh.spacing),
            };
            m.rgb = sh
                .model
                .shade(m.rgb.map(|c| c as f32), g, sh.view)
                .map(f64::from);
        }
        m
    }

    fn at4(&mut self, t: [f64; 4]) -> [Medium; 4] {
        if self.exact.is_some() || self.shade.is_some() {
            return t.map(|t| self.at(t));
        }
        let mut p = [[0.0f32; 4]; 3];
        for (k, &t) in t.iter().enumerate() {
            let q = self.o_v + self.d_v * t;
            (p[0][k], p[1][k], p[2][k]) = (q.x as f32, q.y as f32, q.z as f32);
        }
        let v = self.field.sample4(&p);
        let mut out = [Medium::default(); 4];
        for (o, &v) in out.iter_mut().zip(&v) {
            if !v.is_nan() {
                *o = self.classify(f64::from(v));
            }
        }
        out
    }

    fn hides_features(&self, a: f64, b: f64) -> bool {
        hides_breakpoints(self.breakpoints, a, b)
    }

    fn hides_features_along(&self, values: &[f64; 5]) -> bool {
        hides_breakpoints_along(self.breakpoints, values)
    }
}

/// What a [`GridRay`] needs to light its samples.
struct RayShading<'a> {
    model: &'a BlinnPhong,
    gradients: Option<&'a GradientVolume>,
    spacing: Vec3,
    view: Vec3,
}

impl<F: Field> GridRay<'_, F> {
    #[inline(always)]
    fn classify(&self, v: f64) -> Medium {
        match self.exact {
            Some(tf) => classify_exact(tf, v),
            None => {
                let c = self.table.lookup(v as f32);
                Medium {
                    rgb: c.rgb.map(f64::from),
                    tau: c.tau as f64,
                    value: v,
                }
            }
        }
    }
}

impl<F: Field> RayContext<'_, F> {
    /// Integrates one ray; `spans` is scratch space reused across the rays of a tile.
    fn cast(
        &self,
        origin: DVec3,
        dir: DVec3,
        jitter: f64,
        spans: &mut Vec<(f64, f64)>,
    ) -> PixelOut {
        let Some((o_v, d_v, t0, t1, unit)) = self.setup(origin, dir, spans) else {
            return PixelOut::default();
        };
        let spans = &spans[..];
        let integral = match self.opts.integrator {
            Integrator::Riemann { step } => {
                return self.riemann(o_v, d_v, (t0, t1), spans, step * unit, jitter)
            }
            Integrator::Trapezoid { step } => {
                self.fixed(o_v, d_v, (t0, t1), spans, step * unit, FixedRule::Trapezoid)
            }
            Integrator::Simpson { step } => {
                self.fixed(o_v, d_v, (t0, t1), spans, step * unit, FixedRule::Simpson)
            }
            Integrator::AdaptiveSimpson(p) => adaptive_simpson_intervals(
                &mut self.medium(o_v, d_v),
                spans,
                &self.adaptive_in_world(&p),
            ),
            Integrator::Preintegrated { step } => {
                return self.preintegrated(o_v, d_v, (t0, t1), spans, step * unit, jitter)
            }
            Integrator::Reference => self.reference(o_v, d_v, t0, t1, unit),
        };
        pixel(&integral)
    }

    /// A ray's voxel-space origin and direction, its entry and exit distances, the voxel unit
    /// of steps, and in `spans` the parts of it to sample; `None` if it misses the volume.
    fn setup(
        &self,
        origin: DVec3,
        dir: DVec3,
        spans: &mut Vec<(f64, f64)>,
    ) -> Option<(DVec3, DVec3, f64, f64, f64)> {
        let place = &self.place;
        let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
        let unit = place.spacing.min_element();
        let o_v = (origin - place.origin) / place.spacing;
        let d_v = dir / place.spacing;
        spans.clear();
        match self.occupancy {
            Some(occ) => occ.occupied(o_v, d_v, t0, t1, spans),
            None => spans.push((t0, t1)),
        }
        Some((o_v, d_v, t0, t1, unit))
    }

    /// The table-classified medium along a ray (voxel-space origin and direction).
    fn medium(&self, o_v: DVec3, d_v: DVec3) -> GridRay<'_, F> {
        GridRay {
            field: self.field,
            o_v,
            d_v,
            table: self.table,
            exact: None,
            breakpoints: &self.breakpoints,
            shade: self.opts.shading.as_ref().map(|model| RayShading {
                model,
                gradients: self.gradients,
                spacing: self.place.spacing.as_vec3(),
                view: (d_v * self.place.spacing).normalize_or_zero().as_vec3(),
            }),
        }
    }

    /// The f64 ground truth: exact classification, pieces split at voxel boundaries.
    fn reference(&self, o_v: DVec3, d_v: DVec3, t0: f64, t1: f64, unit: f64) -> RayIntegral {
        let breaks = voxel_crossings(o_v, d_v, t0, t1);
        let p = Integrator::REFERENCE;
        let p = AdaptiveParams {
            h0: p.h0 * unit,
            hmin: p.hmin * unit,
            hmax: p.hmax * unit,
            ..p
        };
        let mut medium = GridRay {
            exact: Some(&self.tf),
            ..self.medium(o_v, d_v)
        };
        adaptive_simpson_pieces(&mut medium, &breaks, &p)
    }

    /// A fixed-step rule over the ray's occupied spans, stopping at the early-termination
    /// opacity.
    fn fixed(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        ends: (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        rule: FixedRule,
    ) -> RayIntegral {
        let stop_depth = match self.opts.early_termination {
            Some(a) if a < 1.0 => -(1.0 - f64::from(a)).ln(),
            _ => f64::INFINITY,
        };
        fixed_intervals(&mut self.medium(o_v, d_v), spans, ends, h, rule, stop_depth)
    }

    /// Adaptive parameters with the steps in world units and the render's early termination.
    fn adaptive_in_world(&self, p: &AdaptiveParams) -> AdaptiveParams {
        let unit = self.place.spacing.min_element();
        AdaptiveParams {
            h0: p.h0 * unit,
            hmin: p.hmin * unit,
            hmax: p.hmax * unit,
            early_termination: self.opts.early_termination.map(f64::from),
            ..*p
        }
    }

    /// The tile at (`x0`, `y0`), one ray after the other.
    fn tile_ray_by_ray(&self, x0: usize, y0: usize) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let mut px = Vec::with_capacity(TILE * TILE);
        let mut spans = Vec::new();
        for y in y0..(y0 + TILE).min(h) {
            for x in x0..(x0 + TILE).min(w) {
                let ray = self.rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                let jitter = if self.opts.jitter {
                    pixel_hash(x, y)
                } else {
                    0.0
                };
                px.push(if self.opts.mip {
                    self.mip(ray.origin, ray.dir)
                } else {
                    self.cast(ray.origin, ray.dir, jitter, &mut spans)
                });
            }
        }
        px
    }

    /// The step table when rays take the fast Riemann path: tiles are then rendered by the
    /// lane stream (`stream.rs`).
    fn packet_table(&self) -> Option<&LaneTable> {
        match self.opts.integrator {
            Integrator::Riemann { .. } if self.streams() => self.lane_table.as_ref(),
            _ => None,
        }
    }

    /// The pre-integration table when rays take the lane stream.
    fn preintegrated_stream_table(&self) -> Option<&PreintegrationTable> {
        match self.opts.integrator {
            Integrator::Preintegrated { .. } if self.streams() => self.preintegration,
            _ => None,
        }
    }

    /// The trapezoid rule when rays take the lane stream (emission only).
    fn trapezoid_stream_rule(&self) -> Option<TrapezoidRule<'_>> {
        match self.opts.integrator {
            Integrator::Trapezoid { step } if self.streams() && self.opts.shading.is_none() => {
                Some(TrapezoidRule {
                    table: self.lane_table.as_ref()?,
                    h: (step * self.place.spacing.min_element()) as f32,
                })
            }
            _ => None,
        }
    }

    /// Whether fixed-step rays can take the lane stream: no isosurfaces, no MIP, and shading
    /// only with the cached gradient volume (on-the-fly gradients are taken ray by ray).
    fn streams(&self) -> bool {
        self.opts.isosurfaces.is_empty()
            && !self.opts.mip
            && (self.opts.shading.is_none() || self.gradients.is_some())
    }

    /// The left Riemann sum (eq. 2.14) of lit rays (shading or isosurfaces), one sample at a
    /// time with early ray termination; emission-only rays take the lane stream (`stream.rs`),
    /// which computes the same sums. Samples sit on the lattice `t0 + (i + jitter) h` whatever
    /// the skipped spans, so skipping empty space changes nothing in the image.
    fn riemann(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        (t0, t1): (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        jitter: f64,
    ) -> PixelOut {
        let (o_v, d_v) = (o_v.as_vec3(), d_v.as_vec3());
        let stop = self.opts.early_termination.unwrap_or(2.0);
        let view = (d_v * self.place.spacing.as_vec3()).normalize_or_zero();
        let mut acc = RayAccumulator::default();
        let mut n = 0u64;
        let mut prev: Option<(f64, f32)> = None;
        let mut crossings = Vec::new();
        let start = t0 + jitter * h;
        'spans: for &(a, b) in spans {
            let mut i = ((a - start) / h).ceil().max(0.0) as u64;
            loop {
                let t = start + h * i as f64;
                if t >= b {
                    break;
                }
                let p = o_v + d_v * t as f32;
                match self.field.sample(p) {
                    Some(v) => {
                        self.isosurfaces_between(
                            prev,
                            (t, v),
                            (o_v, d_v),
                            &mut crossings,
                            &mut acc,
                        );
                        let c = self.lit_sample(self.table.lookup(v), p, view);
                        riemann_step(&mut acc, c, h.min(t1 - t) as f32);
                        prev = Some((t, v));
                    }
                    None => prev = None,
                }
                n += 1;
                i += 1;
                if acc.alpha() >= stop {
                    break 'spans;
                }
            }
        }
        PixelOut::composited(&acc, n)
    }

    /// A classified sample at voxel position `p` on a ray of world direction `view`, lit when
    /// shading is on and the sample is not transparent.
    fn lit_sample(&self, mut c: Classified, p: Vec3, view: Vec3) -> Classified {
        if let (Some(sh), true) = (&self.opts.shading, c.tau > 0.0) {
            c.rgb = sh.shade(c.rgb, self.gradient(p), view);
        }
        c
    }

    /// A pre-integrated segment's premultiplied RGBA `e`, its average colour lit with the
    /// gradient at its middle `mid` when shading is on.
    fn lit_segment(&self, e: [f32; 4], mid: Vec3, view: Vec3) -> [f32; 4] {
        match (&self.opts.shading, e[3] > 0.0) {
            (Some(model), true) => {
                let c = [e[0] / e[3], e[1] / e[3], e[2] / e[3]];
                let lit = model.shade(c, self.gradient(mid), view);
                [lit[0] * e[3], lit[1] * e[3], lit[2] * e[3], e[3]]
            }
            _ => e,
        }
    }

    /// The world-space gradient at voxel position `p`.
    fn gradient(&self, p: Vec3) -> Vec3 {
        match self.gradients {
            Some(g) => g.gradient(p),
            None => shading::gradient(self.field, p, self.place.spacing.as_vec3()),
        }
    }

    /// Composites the isosurfaces crossed between the previous sample and `(t, v)`, lit when
    /// shading is on (`000`/`001`: surfaces located between samples by root refinement).
    fn isosurfaces_between(
        &self,
        prev: Option<(f64, f32)>,
        (t, v): (f64, f32),
        (o_v, d_v): (Vec3, Vec3),
        crossings: &mut Vec<Crossing>,
        acc: &mut RayAccumulator,
    ) {
        let (Some((tp, vp)), false) = (prev, self.opts.isosurfaces.is_empty()) else {
            return;
        };
        crossings.clear();
        let sample = |tt: f64| self.field.sample(o_v + d_v * tt as f32).unwrap_or(f32::NAN);
        let view = (d_v * self.place.spacing.as_vec3()).normalize_or_zero();
        self.opts
            .isosurfaces
            .crossings(tp, vp, t, v, sample, crossings);
        for c in crossings.iter() {
            let iso = self.opts.isosurfaces.as_slice()[c.iso_index];
            let mut rgb = [iso.rgba[0], iso.rgba[1], iso.rgba[2]];
            if let Some(sh) = &self.opts.shading {
                rgb = sh.shade(rgb, self.gradient(o_v + d_v * c.t as f32), view);
            }
            acc.under(rgb, iso.rgba[3]);
        }
    }

    /// Maximum intensity projection along one ray: the TF colour of the largest value, opaque.
    fn mip(&self, origin: DVec3, dir: DVec3) -> PixelOut {
        let Some(ray) = self.mip_ray(origin, dir) else {
            return PixelOut::default();
        };
        let mut n = 0u64;
        let best = mip::max_along(ray.t0, ray.t1, ray.step, |t| {
            n += 1;
            self.field.sample64(ray.o_v + ray.d_v * t).map(|v| v as f32)
        });
        self.mip_pixel(best.map(|b| b.0), n)
    }

    /// A MIP ray's voxel-space origin and direction, extent and step; `None` if it misses.
    fn mip_ray(&self, origin: DVec3, dir: DVec3) -> Option<MipRay> {
        let place = &self.place;
        let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
        let step = match self.opts.integrator {
            Integrator::Riemann { step } | Integrator::Preintegrated { step } => step,
            _ => 0.5,
        } * place.spacing.min_element();
        let (o_v, d_v) = ((origin - place.origin) / place.spacing, dir / place.spacing);
        Some(MipRay {
            o_v,
            d_v,
            t0,
            t1,
            step,
        })
    }

    /// The pixel of a MIP ray whose maximum is `best` (`None`: no defined sample), after
    /// `samples` samples.
    fn mip_pixel(&self, best: Option<f32>, samples: u64) -> PixelOut {
        let rgba = best.map_or([0.0; 4], |v| {
            let c = self.tf.color_at(v as f64);
            [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
        });
        PixelOut {
            rgba,
            samples,
            hit: true,
            ..PixelOut::default()
        }
    }
}

/// A ray of maximum intensity projection: voxel-space origin and direction, the extent and
/// the step of its sample lattice (world units).
#[derive(Clone, Copy, Debug, Default)]
struct MipRay {
    o_v: DVec3,
    d_v: DVec3,
    t0: f64,
    t1: f64,
    step: f64,
}

impl<F: Field> RayContext<'_, F> {
    /// Pre-integrated classification: segments `[t_i, t_i + h]` on the same lattice as the
    /// Riemann sum, each composited with the table entry for its front and back values; a
    /// shortened last segment takes the fraction of the optical depth it covers. Segments
    /// entirely inside skipped (transparent) space are not visited.
    fn preintegrated(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        (t0, t1): (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        jitter: f64,
    ) -> PixelOut {
        let Some(table) = self.preintegration else {
            return PixelOut::default();
        };
        let stop = self.opts.early_termination.unwrap_or(2.0);
        let start = (t0 + jitter * h - h).max(t0 - h);
        let value = |t: f64| self.field.sample((o_v + d_v * t.clamp(t0, t1)).as_vec3());
        let mut acc = RayAccumulator::default();
        let (mut n, mut next) = (0u64, 0u64);
        'spans: for &(a, b) in spans {
            let mut i = (((a - start) / h).floor().max(0.0) as u64).max(next);
            let mut front = None;
            loop {
                let (ta, tb) = (
                    (start + h * i as f64).max(t0),
                    (start + h * (i + 1) as f64).min(t1),
                );
                if ta >= b || ta >= t1 {
                    break;
                }
                if tb <= ta {
                    // Rounding put the lattice point before `t0` on it: nothing to integrate.
                    i += 1;
                    continue;
                }
                let f = match front {
                    Some(f) => f,
                    None => {
                        n += 1;
                        value(ta)
                    }
                };
                let back = value(tb);
                n += 1;
                if let (Some(sf), Some(sb)) = (f, back) {
                    let mid = (o_v + d_v * (0.5 * (ta + tb))).as_vec3();
                    let view = (d_v * self.place.spacing).normalize_or_zero().as_vec3();
                    let e = self.lit_segment(table.lookup(sf, sb), mid, view);
                    under_partial(&mut acc, e, ((tb - ta) / h) as f32);
                }
                front = Some(back);
                i += 1;
                next = i;
                if acc.alpha() >= stop {
                    break 'spans;
                }
            }
        }
        PixelOut::composited(&acc, n)
    }
}

/// The reference's classification: the TF evaluated exactly, in f64.
#[inline(never)]
fn classify_exact(tf: &TransferFunction, v: f64) -> Medium {
    Medium {
        rgb: tf.color_at(v),
        tau: tf.tau_per_world(v),
        value: v,
    }
}

/// A deterministic pseudo-random number in [0, 1) for pixel (x, y) (a 32-bit integer hash), so
/// jittered images do not depend on the thread count.
fn pixel_hash(x: usize, y: usize) -> f64 {
    let mut v = (x as u32).wrapping_mul(0x9E37_79B9) ^ (y as u32).wrapping_mul(0x85EB_CA6B);
    v ^= v >> 16;
    v = v.wrapping_mul(0x7FEB_352D);
    v ^= v >> 15;
    v = v.wrapping_mul(0x846C_A68B);
    v ^= v >> 16;
    v as f64 / 4_294_967_296.0
}

fn pixel(r: &RayIntegral) -> PixelOut {
    PixelOut {
        rgba: r.rgba.map(|v| v as f32),
        samples: r.samples,
        error: r.error as f32,
        missed: r.tolerance_missed,
        hit: true,
    }
}

/// Distances in `[t0, t1]` where the voxel-space ray `o_v + t d_v` crosses an integer plane
/// (a voxel boundary), with `t0` and `t1`, sorted.
pub fn voxel_crossings(o_v: DVec3, d_v: DVec3, t0: f64, t1: f64) -> Vec<f64> {
    let mut ts = vec![t0, t1];
    for a in 0..3 {
        if d_v[a].abs() < 1e-300 {
            continue;
        }
        let (x0, x1) = (o_v[a] + d_v[a] * t0, o_v[a] + d_v[a] * t1);
        let (lo, hi) = (x0.min(x1).ceil() as i64, x0.max(x1).floor() as i64);
        ts.extend(
            (lo..=hi)
                .map(|k| (k as f64 - o_v[a]) / d_v[a])
                .filter(|t| *t > t0 && *t < t1),
        );
    }
    ts.sort_by(f64::total_cmp);
    ts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    ts
}

/// The voxel-space position of a world point (for tests and tools).
pub fn to_voxel(place: &Placement, p: DVec3) -> Vec3 {
    ((p - place.origin) / place.spacing).as_vec3()
}

mod adaptive_stream;
mod mip_stream;
mod stream;
#[cfg(test)]
mod tests;
