//! What the grid ray caster's paths share: the per-render context of every ray
//! ([`RayContext`]), the medium along one ray ([`GridRay`]), a pixel's result, the derived
//! data a render uses and the classification renderers keep between frames.
use glam::{DVec3, Vec3};
use volux_core::camera::{Ray, RayGenerator};
use volux_core::transfer::TransferFunction;
use volux_core::voi::ClipPlane;

use super::options::{Placement, RenderOptions};
use crate::classify::{BreakpointRanks, ClassifyTable, LaneTable};
use crate::composite::RayAccumulator;
use crate::data_colour::DataColour;
use crate::integrate::integrator::Integrator;
use crate::integrate::medium::RayIntegral;
use crate::integrate::preintegrated::PreintegrationTable;
use crate::intervals::IntervalSource;
use crate::macrocell::{CellClass, MacrocellGrid, Occupancy};
use crate::sculpt::labels::LabelVolume;
use crate::shading::blinn_phong::BlinnPhong;
use crate::shading::cut_faces::CutFaces;
use crate::shading::gradient::GradientVolume;

/// One pixel's result.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PixelOut {
    pub(crate) rgba: [f32; 4],
    pub(crate) samples: u64,
    pub(crate) error: f32,
    pub(crate) missed: bool,
    pub(crate) hit: bool,
}

impl PixelOut {
    /// A hit ray composited into `acc` with `samples` samples (no error estimate).
    pub(crate) fn composited(acc: &RayAccumulator, samples: u64) -> Self {
        Self {
            rgba: acc.pixel(),
            samples,
            error: 0.0,
            missed: false,
            hit: true,
        }
    }
}

/// Data derived from the volume and the TF that a render uses, built (and cached) by the caller.
#[derive(Clone, Copy, Default)]
pub(crate) struct Derived<'a> {
    pub(crate) macrocells: Option<&'a MacrocellGrid>,
    /// The classification, when the caller keeps one (built here otherwise).
    pub(crate) classification: Option<&'a Classification>,
    /// The caller's intervals (a bricked grid's), instead of the macrocells'.
    pub(crate) intervals: Option<&'a dyn IntervalSource>,
    pub(crate) preintegration: Option<&'a PreintegrationTable>,
    pub(crate) gradients: Option<&'a GradientVolume>,
    /// Whether tiles may take the lane paths.
    pub(crate) lanes: bool,
}

/// The classification of a render, what depends on the transfer function: its table and
/// the macrocells' classes, skipped where empty (zero extinction over a macrocell's range
/// and no isovalue in it). A renderer keeps it between frames ([`Classification::is_for`]).
pub(crate) struct Classification {
    /// What it was built from: the TF as given, the data range, the isovalues.
    pub(crate) tf: TransferFunction,
    pub(crate) range: [f64; 2],
    pub(crate) isovalues: Vec<f32>,
    pub(crate) table: ClassifyTable,
    /// The class of each macrocell, skipped or sampled (when built for a macrocell grid).
    pub(crate) classes: Option<Vec<CellClass>>,
}

impl Classification {
    /// Classifies with `opts`' TF over `range`, and flags the empty macrocells of `cells`.
    pub(crate) fn new(
        opts: &RenderOptions,
        range: [f64; 2],
        cells: Option<&MacrocellGrid>,
    ) -> Self {
        let table = ClassifyTable::new(&opts.tf, range, ClassifyTable::DEFAULT_SIZE);
        let isovalues = isovalues(opts);
        let classes = cells.map(|m| {
            let empty = m.empty_flags(&table, &isovalues);
            empty.into_iter().map(CellClass::of_empty).collect()
        });
        Self {
            tf: opts.tf.clone(),
            range,
            isovalues,
            table,
            classes,
        }
    }

    /// Whether this was built for `opts`' TF and isovalues, `range`, and (when `cells` is
    /// given) has the macrocell classes.
    pub(crate) fn is_for(
        &self,
        opts: &RenderOptions,
        range: [f64; 2],
        cells: Option<&MacrocellGrid>,
    ) -> bool {
        self.tf == opts.tf
            && self.range == range
            && self.isovalues == isovalues(opts)
            && (cells.is_none() || self.classes.is_some())
    }
}

pub(crate) fn isovalues(opts: &RenderOptions) -> Vec<f32> {
    opts.isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect()
}

/// Everything a ray needs, shared by all rays of a render.
pub(crate) struct RayContext<'a, F> {
    pub(crate) field: &'a F,
    pub(crate) place: Placement,
    pub(crate) table: &'a ClassifyTable,
    /// Where rays sample (`None`: everywhere between entry and exit).
    pub(crate) intervals: Option<&'a dyn IntervalSource>,
    /// The macrocells, when their classes tell where the sculpt mask hides nothing (the
    /// intervals are then theirs, split where that changes): the lane stream samples the
    /// data without the mask there.
    pub(crate) mask_classes: Option<&'a Occupancy<'a>>,
    pub(crate) preintegration: Option<&'a PreintegrationTable>,
    pub(crate) gradients: Option<&'a GradientVolume>,
    /// The classification for the lane-wise paths: per-slab colour and opacity for the
    /// Riemann step (no `exp` per sample), colour and extinction for adaptive Simpson.
    pub(crate) lane_table: Option<LaneTable>,
    /// Breakpoint counts per lane-table entry, for adaptive Simpson's hidden-peak test.
    pub(crate) breakpoint_ranks: Option<BreakpointRanks>,
    pub(crate) tf: TransferFunction,
    pub(crate) breakpoints: Vec<f64>,
    /// The camera's rays for this image size, in the grid's local frame.
    pub(crate) rays: LocalRays,
    /// The clipping planes in the grid's local frame ([`local_clip_planes`]).
    pub(crate) clip: Vec<ClipPlane>,
    /// The faces the clip planes and the sculpt mask expose, when shading lights them.
    pub(crate) cut_faces: Option<CutFaces<'a>>,
    pub(crate) opts: &'a RenderOptions,
}

/// The depth behind a clip plane that [`CutFaces`] lights with the plane's normal, world
/// units: one step of the sample lattice, and at least one voxel (of the smallest spacing),
/// so that every ray through a cut face has a sample in it.
pub fn cut_layer(opts: &RenderOptions, place: &Placement) -> f64 {
    let voxels = match opts.integrator {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Simpson { step }
        | Integrator::Preintegrated { step } => step,
        Integrator::AdaptiveSimpson(p) => p.h0,
        Integrator::Reference => 1.0,
    };
    voxels.max(1.0) * place.spacing.min_element()
}

/// The cut faces of a render ([`CutFaces`]): `None` without shading or without cuts.
pub(crate) fn cut_faces<'a>(
    opts: &'a RenderOptions,
    place: &Placement,
    local_planes: &[ClipPlane],
) -> Option<CutFaces<'a>> {
    let model = opts.shading.as_ref()?;
    CutFaces::new(
        local_planes,
        opts.mask.as_deref(),
        (place.origin, place.spacing),
        model,
        cut_layer(opts, place),
    )
}

/// World clipping planes in a grid's local frame: a world point is `o + R (p - o)` for the
/// local point `p` (`o` the origin, `R` the direction), so `n . x + d` becomes
/// `(Rᵀ n) . p + d + n . o - (Rᵀ n) . o`. `R` is orthonormal: the normal stays a unit vector
/// and distances along rays are unchanged.
pub fn local_clip_planes(place: &Placement, planes: &[ClipPlane]) -> Vec<ClipPlane> {
    planes
        .iter()
        .map(|p| {
            let n = place.vector_to_local(p.normal);
            ClipPlane {
                normal: n,
                offset: p.offset + p.normal.dot(place.origin) - n.dot(place.origin),
            }
        })
        .collect()
}

/// The camera's world rays turned into a grid's local frame ([`Placement`]): the one place
/// where rays enter the grid, so every path (lane streams, ray by ray, MIP) clips them against
/// the axis-aligned box and samples in index space unchanged.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalRays {
    pub(crate) world: RayGenerator,
    pub(crate) place: Placement,
}

impl LocalRays {
    /// The ray through pixel coordinates (`px`, `py`), in the local frame (the world ray
    /// itself for an axis-aligned grid).
    #[inline]
    pub(crate) fn ray(&self, px: f64, py: f64) -> Ray {
        let r = self.world.ray(px, py);
        Ray {
            origin: self.place.point_to_local(r.origin),
            dir: self.place.vector_to_local(r.dir),
        }
    }
}

/// The classified medium along one ray through a grid, in voxel space.
pub(crate) struct GridRay<'a, F> {
    pub(crate) field: &'a F,
    pub(crate) o_v: DVec3,
    pub(crate) d_v: DVec3,
    pub(crate) table: &'a ClassifyTable,
    /// Classify exactly with this TF instead of the table (the reference path).
    pub(crate) exact: Option<&'a TransferFunction>,
    pub(crate) breakpoints: &'a [f64],
    /// Region labels coloured in place of the TF's colour.
    pub(crate) labels: Option<&'a LabelVolume>,
    /// An RGB grid's own colour in place of the TF's (under the labels).
    pub(crate) data_colour: Option<&'a DataColour>,
    /// Shading of the emitted colour: the lighting model and the ray's context.
    pub(crate) shade: Option<RayShading<'a>>,
}

/// What a [`GridRay`] needs to light its samples.
pub(crate) struct RayShading<'a> {
    pub(crate) model: &'a BlinnPhong,
    pub(crate) gradients: Option<&'a GradientVolume>,
    /// The cut faces, lit with the cut's normal.
    pub(crate) cut_faces: Option<&'a CutFaces<'a>>,
    pub(crate) spacing: Vec3,
    pub(crate) view: Vec3,
}

/// A ray of maximum intensity projection: voxel-space origin and direction, the extent and
/// the step of its sample lattice (world units).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MipRay {
    pub(crate) o_v: DVec3,
    pub(crate) d_v: DVec3,
    pub(crate) t0: f64,
    pub(crate) t1: f64,
    pub(crate) step: f64,
}

/// The first index `i >= 0` of the sample lattice `start + i h` with `start + i h >= b`, by
/// exact comparisons: spans that touch share their boundary sample neither twice nor never.
pub(crate) fn first_at_or_after(start: f64, h: f64, b: f64) -> i32 {
    let t = |i: i32| start + h * f64::from(i);
    let mut k = ceil_index((b - start) / h);
    while k > 0 && t(k - 1) >= b {
        k -= 1;
    }
    while t(k) < b {
        k += 1;
    }
    k
}

/// `ceil(x)` clamped to `[0, i32::MAX / 2]`, without `f64::ceil` (a library call on
/// baseline x86-64, paid per ray and span).
pub(crate) fn ceil_index(x: f64) -> i32 {
    let x = x.clamp(0.0, f64::from(i32::MAX / 2));
    let c = x as i32;
    c + i32::from(f64::from(c) < x)
}

/// A deterministic pseudo-random number in [0, 1) for pixel (x, y) (a 32-bit integer hash), so
/// jittered images do not depend on the thread count.
pub(crate) fn pixel_hash(x: usize, y: usize) -> f64 {
    let mut v = (x as u32).wrapping_mul(0x9E37_79B9) ^ (y as u32).wrapping_mul(0x85EB_CA6B);
    v ^= v >> 16;
    v = v.wrapping_mul(0x7FEB_352D);
    v ^= v >> 15;
    v = v.wrapping_mul(0x846C_A68B);
    v ^= v >> 16;
    v as f64 / 4_294_967_296.0
}

pub(crate) fn pixel(r: &RayIntegral) -> PixelOut {
    PixelOut {
        rgba: r.rgba.map(|v| v as f32),
        samples: r.samples,
        error: r.error as f32,
        missed: r.tolerance_missed,
        hit: true,
    }
}
