//! The Projected Tetrahedra renderer: the stages of [`super`] wired together, with the caches
//! of the seeds' update step (seed `000` §4.2, seed `002` §4.2 and §4.5).
//!
//! Per frame:
//!
//! 1. **discard** (`002` §4.5): the tetrahedra whose scalar interval maps to zero extinction
//!    everywhere and that no isosurface crosses are dropped; the kept set is rebuilt only
//!    when the TF's zero set or the isovalues change;
//! 2. **per-tetrahedron pass** (view changes only): vertex projection
//!    ([`ViewProjection`]), the four exact orientation tests of every kept tetrahedron
//!    (degenerate projections are dropped) and its centroid's sort key (distance from the eye
//!    under perspective, which orders far fewer face pairs wrongly than the view depth of
//!    the seeds; see [`sort`]); with clipping planes, the cells with all four vertices
//!    outside one plane are culled here ([`super::clip`], seed `004` sec. 4);
//! 3. **visibility order** (view changes only): centroid radix sort, or the exact order
//!    (MPVO on a convex mesh; a per-pixel fragment sort otherwise);
//! 4. **binning** of the ordered tetrahedra into screen tiles, by the tile ranges the
//!    per-tetrahedron pass computed;
//! 5. **rasterization and compositing**, tiles in parallel, each compositing its own
//!    fragments front to back in the global order (so the image does not depend on the
//!    number of threads). Cells the lanes of [`super::shade`] can colour are drawn in the
//!    plane form of [`super::planes`]: the triangles of their front or back faces, once each,
//!    with each pixel's entry and exit from the face planes. The others (the exact model,
//!    isosurfaces, non-finite values) take the seeds' path: classification and thick vertex
//!    ([`super::classify`], `fan_vertices`), the fan's triangles, perspective-correct
//!    `(s_f, s_b, l)` and gradients, the fragment colour of [`FragmentShader`]. Both draw
//!    with the top-left rule, so each covers the cell's projection exactly once. With
//!    clipping planes, both paths trim every fragment to its pixel's depth window inside
//!    the planes before colouring it ([`super::clip`]); without planes no plane work is done.
//!
//! A TF change that keeps the zero set re-runs only step 5 (recolouring without
//! re-projecting). Compositing is front to back (the "under" operator, equivalent to the
//! seeds' back-to-front "over" in the reverse order) so that pixels can stop early once
//! opaque.
use std::ops::Deref;
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::voi::ClipPlane;
use volux_core::{Camera, Image, TetMesh, TransferFunction};

use super::classify::{ternary_code, TERNARY_TABLE};
use super::clip::{outside_a_plane, tile_windows, trim_gradients, DepthSpan, Window};
use super::planes::CellPlanes;
use super::project::{fan_vertices_with, pixel_secant, screen_points, FanVertex};
use super::project::{TetVertices, ViewProjection};
use super::raster::{
    bin_by_range, box_holds_centre, fixed, tile_range, tiles, Bins, Triangle, NO_TILES,
};
use super::setup::{classify_fixed, projection_tests_screen};
use super::shade::{Batch, CellColour, CellValues, Gather};
use super::sort;
use crate::composite::under;
use crate::error::{Refusal, Remedy, RenderError};
use crate::frame::{Frame, MethodStats, PtStats};
use crate::integrate::fragment::FragmentShader;
use crate::integrate::fragment::{AverageModel, ColorModel, ExactModel, PsiModel};
use crate::integrate::psi::lanes::LANES;
use crate::integrate::psi::{CellClassifier, PsiTable};
use crate::integrate::segment::SegmentIntegrator;
use crate::integrate::SegmentRule;
use crate::isosurface::Isosurfaces;
use crate::renderer::{frame, wrong_method, Renderer};
use crate::scene::{Method, PtSettings, Scene, SortMode};
use crate::shading::BlinnPhong;
use crate::tiles::Rect;
use crate::tiles::{render_tiles, Control};

/// Options of a PT render.
#[derive(Clone, Debug)]
pub(crate) struct PtOptions {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// The camera.
    pub camera: Camera,
    /// The transfer function (resolved against the mesh's range by the renderer).
    pub tf: TransferFunction,
    /// Visibility order.
    pub sort: SortMode,
    /// Fragment colour.
    pub color: SegmentRule,
    /// Isosurfaces.
    pub isosurfaces: Isosurfaces,
    /// Lighting of the isosurfaces.
    pub shading: BlinnPhong,
    /// Stop compositing a pixel once its opacity reaches this (`None`: never).
    pub early_termination: Option<f32>,
    /// Count the centroid order's violations of the exact face order (`--stats`).
    pub count_violations: bool,
    /// World-space clipping planes ([`Scene::clip_planes`]): fragments are trimmed to each
    /// pixel's window inside them ([`super::clip`], seed `004` sec. 4).
    pub clip_planes: Vec<ClipPlane>,
    /// Cancellation and progress.
    pub control: Control,
}

impl PtOptions {
    /// 512 x 512, centroid order, ψ colour, early termination at
    /// [`DEFAULT_EARLY_TERMINATION`](crate::scene::DEFAULT_EARLY_TERMINATION) (the defaults of [`crate::scene`]).
    #[cfg(test)]
    pub fn new(camera: Camera, tf: TransferFunction) -> Self {
        Self {
            width: 512,
            height: 512,
            camera,
            tf,
            sort: SortMode::Centroid,
            color: SegmentRule::Psi,
            isosurfaces: Isosurfaces::default(),
            shading: BlinnPhong::default(),
            early_termination: Some(crate::scene::DEFAULT_EARLY_TERMINATION),
            count_violations: false,
            clip_planes: Vec::new(),
            control: Control::default(),
        }
    }

    fn validate(&self) -> Result<(), RenderError> {
        crate::error::check_image_size(self.width, self.height)?;
        self.camera.validate()?;
        self.tf.validate()?;
        self.shading.validate()?;
        if let SegmentRule::AdaptiveSimpson(_) = self.color {
            return Err(Refusal::new(
                "Projected Tetrahedra",
                "colours fragments (average, psi, exact); adaptive Simpson integrates whole rays",
                Some(Remedy::Method("tet-raycast")),
            )
            .into());
        }
        for p in &self.clip_planes {
            p.check()?;
        }
        Ok(())
    }
}

/// A PT image with its statistics.
#[derive(Clone, Debug)]
pub struct PtRendered {
    /// Premultiplied linear RGBA.
    pub image: Image,
    /// Statistics.
    pub stats: PtStats,
}

/// The kept set and what it was built from.
struct Kept {
    key: (Vec<u8>, Vec<f32>, Vec<f32>),
    mask: Vec<bool>,
    count: usize,
}

/// The view-dependent data.
struct ViewData {
    key: (Camera, usize, usize, SortMode, u64, Vec<ClipPlane>),
    proj: ViewProjection,
    bins: Bins,
    per_pixel: bool,
    drawn: usize,
    degenerate: usize,
    clipped: usize,
    culled: usize,
    violations: Option<u64>,
    strategy: &'static str,
    cycles: usize,
    order_bytes: usize,
}

/// Bytes per tetrahedron of PT's per-frame buffers, at their peak: the fate of each cell
/// (8), its tile range (8) and again in drawing order for the binning (8), the drawn ids and
/// depths (8), the sorted order and its keys (16), the face adjacency (16) and the
/// visibility sort's work lists (16).
const FRAME_BYTES_PER_TET: u64 = 80;

/// Checks PT's per-frame buffers for `mesh` (the projected vertices and the per-cell lists
/// of [`FRAME_BYTES_PER_TET`]) against the memory budget, before they are allocated.
fn check_frame_memory(mesh: &TetMesh) -> Result<(), RenderError> {
    let vertices =
        (mesh.positions().len() as u64).saturating_mul(ViewProjection::BYTES_PER_VERTEX as u64);
    let bytes = (mesh.tets().len() as u64)
        .saturating_mul(FRAME_BYTES_PER_TET)
        .saturating_add(vertices);
    volux_core::limits::check_alloc("PT's per-frame buffers", bytes, 1)?;
    Ok(())
}

/// A PT renderer for one mesh, holding the caches of the update step.
pub struct PtRenderer<M: Deref<Target = TetMesh> = Arc<TetMesh>> {
    mesh: M,
    adjacency: Option<Vec<[u32; 4]>>,
    gradients: Option<Vec<Vec3>>,
    convex: Option<bool>,
    psi: Option<PsiTable>,
    kept: Option<Kept>,
    kept_version: u64,
    view: Option<ViewData>,
    /// The view before the current one, kept for a preview and a full frame alternating.
    spare_view: Option<ViewData>,
    /// Cull the cells wholly outside a clipping plane (off only in tests, to show that
    /// culling does not change the image).
    cull_outside: bool,
}

impl<M: Deref<Target = TetMesh>> PtRenderer<M> {
    /// A renderer for `mesh` (borrowed or shared); nothing is computed until the first
    /// render.
    pub fn new(mesh: M) -> Self {
        Self {
            mesh,
            adjacency: None,
            gradients: None,
            convex: None,
            psi: None,
            kept: None,
            kept_version: 0,
            view: None,
            spare_view: None,
            cull_outside: true,
        }
    }

    /// The renderer drawing every cell, even those wholly outside a clipping plane (whose
    /// fragments the trim then drops one by one).
    #[cfg(test)]
    pub(crate) fn without_plane_culling(mut self) -> Self {
        self.cull_outside = false;
        self
    }

    /// Renders one frame.
    pub(crate) fn render_with(&mut self, opts: &PtOptions) -> Result<PtRendered, RenderError> {
        opts.validate()?;
        let start = Instant::now();
        let mut stats = PtStats {
            tets: self.mesh.tets().len(),
            ..Default::default()
        };
        let range = self.mesh.range();
        let tf = opts.tf.resolved(range);
        let t = Instant::now();
        let had_adjacency = self.adjacency.is_some();
        stats.rebuilt.classification = self.update_kept(&tf, &opts.isosurfaces);
        stats.discard_s = t.elapsed().as_secs_f64();
        opts.control.check()?;
        stats.rebuilt.view = self.update_view(opts, &mut stats)?;
        opts.control.check()?;
        if !opts.isosurfaces.is_empty() && self.gradients.is_none() {
            self.gradients = Some(self.mesh.vertex_gradients());
            stats.rebuilt.data = true;
        }
        if opts.color == SegmentRule::Psi && self.psi.is_none() {
            self.psi = Some(PsiTable::new());
            stats.rebuilt.data = true;
        }
        stats.rebuilt.data |= self.adjacency.is_some() && !had_adjacency;
        let exact = SegmentIntegrator::new(&tf);
        let classifier = CellClassifier::new(&tf, range);
        // Only the ψ mode reads the table; the others get a trivial one (4 entries).
        let tiny;
        let psi_table = match (&self.psi, opts.color) {
            (Some(p), SegmentRule::Psi) => p,
            _ => {
                tiny = PsiTable::with_size(2);
                &tiny
            }
        };
        let knots: Vec<f32> = tf.breakpoints().iter().map(|&k| k as f32).collect();
        let shader = FragmentShader {
            mode: opts.color,
            exact: &exact,
            classifier: &classifier,
            psi: psi_table,
            knots: &knots,
            isosurfaces: opts.isosurfaces.as_slice(),
            shading: opts.shading,
        };
        let view = self.view.as_ref().expect("view updated above");
        let kept = self.kept.as_ref().expect("kept set updated above");
        let t = Instant::now();
        let ctx = TileContext {
            mesh: &self.mesh,
            proj: &view.proj,
            gradients: self.gradients.as_deref(),
            shader: &shader,
            camera: &opts.camera,
            planes: &opts.clip_planes,
            early: if view.per_pixel {
                None
            } else {
                opts.early_termination
            },
            per_pixel: view.per_pixel,
        };
        let tiled = render_tiles(&tiles(opts.width, opts.height), &opts.control, |i, rect| {
            ctx.render_tile(rect, view.bins.tile(i))
        })?;
        stats.fragments = tiled.per_tile.iter().sum();
        let pixels = tiled.pixels;
        stats.raster_s = t.elapsed().as_secs_f64();
        stats.tets_kept = kept.count;
        stats.tets_drawn = view.drawn;
        stats.degenerate = view.degenerate;
        stats.clipped = view.clipped;
        stats.culled = view.culled;
        stats.sort_violations = view.violations;
        stats.exact_strategy = view.strategy;
        stats.cycles_broken = view.cycles;
        let per_frame = view.proj.vertices.capacity() * ViewProjection::BYTES_PER_VERTEX
            + view.bins.bytes()
            + view.order_bytes;
        stats.bytes_per_tet = per_frame as f64 / stats.tets.max(1) as f64;
        stats.seconds = start.elapsed().as_secs_f64() - stats.diagnostics_s;
        let image = Image::from_pixels(opts.width, opts.height, pixels)?;
        Ok(PtRendered { image, stats })
    }

    /// Rebuilds the kept set if the TF's zero set or the isovalues changed; returns whether
    /// it did.
    fn update_kept(&mut self, tf: &TransferFunction, isos: &Isosurfaces) -> bool {
        let support = Support::new(tf);
        let isovalues: Vec<f32> = isos.as_slice().iter().map(|i| i.value).collect();
        let key = (support.nonzero.clone(), support.knots.clone(), isovalues);
        if self.kept.as_ref().is_some_and(|k| k.key == key) {
            return false;
        }
        let mesh = &*self.mesh;
        let s = mesh.scalars();
        let mask: Vec<bool> = mesh
            .tets()
            .par_iter()
            .with_min_len(4096)
            .map(|t| {
                let v = t.map(|i| s[i as usize]);
                let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                support.visible(lo, hi) || key.2.iter().any(|&iso| lo <= iso && iso <= hi)
            })
            .collect();
        let count = mask.iter().filter(|&&k| k).count();
        self.kept = Some(Kept { key, mask, count });
        self.kept_version += 1;
        true
    }

    /// Makes the view data of `opts` current: kept, swapped in from the spare slot (a
    /// preview and a full frame of one camera alternate), or rebuilt (returns true).
    fn update_view(&mut self, opts: &PtOptions, stats: &mut PtStats) -> Result<bool, RenderError> {
        let key = (
            opts.camera,
            opts.width,
            opts.height,
            opts.sort,
            self.kept_version,
            opts.clip_planes.clone(),
        );
        let counting = opts.count_violations;
        let fits =
            |v: &ViewData| v.key == key && (!counting || v.violations.is_some() || v.per_pixel);
        if self.view.as_ref().is_some_and(fits) {
            return Ok(false);
        }
        if self.spare_view.as_ref().is_some_and(fits) {
            std::mem::swap(&mut self.view, &mut self.spare_view);
            return Ok(false);
        }
        let mesh = &*self.mesh;
        let kept = &self.kept.as_ref().expect("kept set").mask;
        check_frame_memory(mesh)?;
        let t = Instant::now();
        let proj = ViewProjection::new(mesh, &opts.camera, opts.width, opts.height);
        let view_dir = sort::SortView::from_camera(&opts.camera);
        // The per-tetrahedron pass: orientation tests and centroid depth.
        #[derive(Clone, Copy)]
        enum Fate {
            Skip,
            Culled,
            Clipped,
            Degenerate,
            Drawn(f32),
        }
        let tiles = tiles(opts.width, opts.height);
        let (planes, positions) = (&opts.clip_planes[..], mesh.positions());
        let cull = self.cull_outside && !planes.is_empty();
        // Each cell's tile range comes with its fate, for the binning (step 4).
        let (fates, ranges): (Vec<Fate>, Vec<[u16; 4]>) = mesh
            .tets()
            .par_iter()
            .zip(kept.par_iter())
            .with_min_len(4096)
            .map(|(t, &k)| {
                if !k {
                    return (Fate::Skip, NO_TILES);
                }
                if cull && outside_a_plane(planes, &t.map(|i| positions[i as usize].as_dvec3())) {
                    return (Fate::Culled, NO_TILES);
                }
                let Some(v) = proj.tet(t) else {
                    return (Fate::Clipped, NO_TILES);
                };
                let code = ternary_code(projection_tests_screen(&v));
                if TERNARY_TABLE[usize::from(code)].is_valid() {
                    let p = mesh.positions();
                    let c = t
                        .iter()
                        .fold(DVec3::ZERO, |a, &i| a + p[i as usize].as_dvec3());
                    let depth = view_dir.depth(c * 0.25) as f32;
                    (Fate::Drawn(depth), tile_range(Some(v), &tiles))
                } else {
                    (Fate::Degenerate, NO_TILES)
                }
            })
            .unzip();
        let (mut ids, mut depths) = (Vec::new(), Vec::new());
        let (mut degenerate, mut clipped, mut culled) = (0, 0, 0);
        for (i, f) in fates.iter().enumerate() {
            match *f {
                Fate::Drawn(d) => {
                    ids.push(i as u32);
                    depths.push(d);
                }
                Fate::Degenerate => degenerate += 1,
                Fate::Clipped => clipped += 1,
                Fate::Culled => culled += 1,
                Fate::Skip => {}
            }
        }
        drop(fates);
        stats.project_s = t.elapsed().as_secs_f64();
        opts.control.check()?;
        let t = Instant::now();
        let need_exact = opts.sort == SortMode::Exact || counting;
        // What only the violation count needs is timed apart, as diagnostics.
        let mut diagnostics = 0.0;
        if need_exact && self.adjacency.is_none() {
            let ta = Instant::now();
            self.adjacency = Some(mesh.face_adjacency());
            if opts.sort == SortMode::Centroid {
                diagnostics += ta.elapsed().as_secs_f64();
            }
        }
        if opts.sort == SortMode::Exact && self.convex.is_none() {
            self.convex = Some(sort::is_convex(mesh));
        }
        let tc = Instant::now();
        let centroid = (opts.sort == SortMode::Centroid || counting)
            .then(|| sort::centroid_order(&depths, &ids));
        stats.centroid_sort_s = tc.elapsed().as_secs_f64();
        if opts.sort == SortMode::Exact {
            diagnostics += stats.centroid_sort_s;
        }
        let mut strategy = "";
        let mut cycles = 0;
        let mut per_pixel = false;
        let mut exact_order = None;
        if need_exact {
            let adjacency = self.adjacency.as_deref().expect("built above");
            let te = Instant::now();
            let r = sort::mpvo(mesh, adjacency, &view_dir, Some(&ids))
                .map_err(|e| RenderError::Internal(format!("visibility sort: {e}")))?;
            stats.exact_sort_s = te.elapsed().as_secs_f64();
            if opts.sort == SortMode::Centroid {
                diagnostics += stats.exact_sort_s;
            }
            let order = r.order;
            cycles = r.cycles_broken as usize;
            if opts.sort == SortMode::Exact {
                if self.convex == Some(true) && cycles == 0 {
                    strategy = "mpvo";
                } else {
                    strategy = "per-pixel";
                    per_pixel = true;
                }
            }
            exact_order = Some(order);
        }
        let violations = match (&centroid, counting) {
            (Some(c), true) => {
                let adjacency = self.adjacency.as_deref().expect("built above");
                let tv = Instant::now();
                let count = sort::count_violations(c, adjacency, mesh, &view_dir);
                diagnostics += tv.elapsed().as_secs_f64();
                Some(count)
            }
            _ => None,
        };
        let order = match opts.sort {
            SortMode::Centroid => centroid.unwrap_or_default(),
            SortMode::Exact => exact_order.unwrap_or_default(),
        };
        stats.sort_s = t.elapsed().as_secs_f64() - diagnostics;
        stats.diagnostics_s = diagnostics;
        opts.control.check()?;
        let t = Instant::now();
        let bins = bin_by_range(&order, &ranges, &tiles)?;
        drop(ranges);
        stats.bin_s = t.elapsed().as_secs_f64();
        self.spare_view = self.view.take();
        self.view = Some(ViewData {
            key,
            proj,
            bins,
            per_pixel,
            drawn: ids.len(),
            degenerate,
            clipped,
            culled,
            violations,
            strategy,
            cycles,
            order_bytes: 4 * order.capacity(),
        });
        Ok(true)
    }
}

impl PtOptions {
    /// The options of `scene` drawn with `settings`: isosurfaces lit with the scene's
    /// lighting.
    pub fn from_scene(scene: &Scene, settings: &PtSettings, control: &Control) -> Self {
        let a = &scene.appearance;
        Self {
            width: scene.view.width,
            height: scene.view.height,
            camera: scene.view.camera,
            tf: a.effective_tf(),
            sort: settings.sort,
            color: settings.color,
            isosurfaces: a.isosurfaces.clone(),
            shading: a.lighting,
            early_termination: scene.early_termination,
            count_violations: settings.count_violations,
            clip_planes: scene.clip_planes.clone(),
            control: control.clone(),
        }
    }
}

impl<M: Deref<Target = TetMesh> + Send> Renderer for PtRenderer<M> {
    fn name(&self) -> &'static str {
        "pt"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let settings = match scene.method {
            Method::Auto => PtSettings::default(),
            Method::ProjectedTetrahedra(s) => s,
            other => return Err(wrong_method("pt", &other)),
        };
        scene.validate()?;
        crate::renderer::no_voxel_layers("pt", scene)?;
        let r = self.render_with(&PtOptions::from_scene(scene, &settings, control))?;
        let rebuilt = r.stats.rebuilt;
        Ok(frame(
            r.image,
            None,
            started,
            rebuilt,
            MethodStats::ProjectedTetrahedra(r.stats),
        ))
    }
}

/// Where the TF's extinction is non-zero: the pieces between consecutive breakpoints (and
/// the two unbounded ends) on which it is not identically zero.
struct Support {
    knots: Vec<f32>,
    nonzero: Vec<u8>,
    /// Prefix counts of non-zero pieces.
    prefix: Vec<u32>,
}

impl Support {
    fn new(tf: &TransferFunction) -> Self {
        let knots: Vec<f64> = tf
            .breakpoints()
            .into_iter()
            .filter(|x| x.is_finite())
            .collect();
        let tau = |s: f64| {
            let v = tf.tau_per_world(s);
            v.is_finite() && v > 0.0
        };
        let mut nonzero = Vec::with_capacity(knots.len() + 1);
        match knots.first() {
            Some(&k) => nonzero.push(u8::from(tau(k - 1.0) || tau(k))),
            None => nonzero.push(u8::from(tau(0.0))),
        }
        for w in knots.windows(2) {
            let (a, b) = (w[0], w[1]);
            let inner = [0.0, 0.25, 0.5, 0.75, 1.0]
                .iter()
                .any(|f| tau(a + f * (b - a)));
            nonzero.push(u8::from(inner));
        }
        if let Some(&k) = knots.last() {
            nonzero.push(u8::from(tau(k) || tau(k + 1.0)));
        }
        let mut prefix = vec![0u32; nonzero.len() + 1];
        for (i, &z) in nonzero.iter().enumerate() {
            prefix[i + 1] = prefix[i] + u32::from(z);
        }
        Self {
            knots: knots.iter().map(|&k| k as f32).collect(),
            nonzero,
            prefix,
        }
    }

    /// Whether the extinction can be non-zero somewhere in `[lo, hi]` (conservative).
    fn visible(&self, lo: f32, hi: f32) -> bool {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return true;
        }
        // Piece k spans [knots[k-1], knots[k]]; closed ends are shared with neighbours.
        let a = self.knots.partition_point(|&k| k < lo);
        let b = self.knots.partition_point(|&k| k <= hi);
        self.prefix[b + 1] > self.prefix[a]
    }
}

/// What every tile needs to draw.
struct TileContext<'a> {
    mesh: &'a TetMesh,
    proj: &'a ViewProjection,
    gradients: Option<&'a [Vec3]>,
    shader: &'a FragmentShader<'a>,
    camera: &'a Camera,
    /// The clipping planes; empty: no plane work at all.
    planes: &'a [ClipPlane],
    early: Option<f32>,
    per_pixel: bool,
}

/// A fragment kept for per-pixel sorting.
#[derive(Clone, Copy)]
struct Fragment {
    pixel: u32,
    depth: f32,
    rgba: [f32; 4],
}

thread_local! {
    /// A [`Batch`] per thread, reused from tile to tile.
    static SPARE_BATCH: std::cell::Cell<Option<Batch>> = const { std::cell::Cell::new(None) };
}

/// Tetrahedra gathered at a time before drawing: the gather loop's loads are independent of
/// each other, so their cache misses overlap.
const GATHER: usize = 64;

/// What drawing one tetrahedron reads from the mesh and the projection.
#[derive(Clone, Copy)]
struct Gathered {
    id: u32,
    screen: [[f32; 3]; 4],
    scalars: [f32; 4],
}

impl TileContext<'_> {
    /// Draws the tetrahedra `list` (in order) into tile `rect`; returns its pixels and the
    /// number of fragments shaded.
    fn render_tile(&self, rect: Rect, list: &[u32]) -> (Vec<[f32; 4]>, u64) {
        match (self.shader.mode, self.proj.perspective) {
            (SegmentRule::Average, true) => self.render_tile_with::<AverageModel, true>(rect, list),
            (SegmentRule::Average, false) => {
                self.render_tile_with::<AverageModel, false>(rect, list)
            }
            (SegmentRule::Psi, true) => self.render_tile_with::<PsiModel, true>(rect, list),
            (SegmentRule::Psi, false) => self.render_tile_with::<PsiModel, false>(rect, list),
            (_, true) => self.render_tile_with::<ExactModel, true>(rect, list),
            (_, false) => self.render_tile_with::<ExactModel, false>(rect, list),
        }
    }

    /// [`TileContext::render_tile`] for the colour model `M` and the projection `PERSP`.
    fn render_tile_with<M: ColorModel, const PERSP: bool>(
        &self,
        rect: Rect,
        list: &[u32],
    ) -> (Vec<[f32; 4]>, u64) {
        let tw = rect.width();
        let th = rect.height();
        let mut acc = vec![[0.0f32; 4]; tw * th];
        let mut frags: Vec<Fragment> = Vec::new();
        let mut count = 0u64;
        // Padded by a lane group for the gather's whole groups ([`Gather::secant`]).
        let secant: Vec<f32> = (0..tw * th)
            .map(|p| {
                let (x, y) = (rect.x0 + p % tw, rect.y0 + p / tw);
                pixel_secant(self.proj, x as f32 + 0.5, y as f32 + 0.5)
            })
            .chain([1.0; LANES])
            .collect();
        let (right, up, forward) = self.camera.basis();
        let (w, h) = self.proj.size;
        let view_dir = |x: usize, y: usize| -> Vec3 {
            if !self.proj.perspective {
                return forward.as_vec3();
            }
            let t = self.proj.tan_half_fov;
            let nx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * (w as f64 / h as f64) * t;
            let ny = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * t;
            (forward + right * nx + up * ny).as_vec3()
        };
        let tets = self.mesh.tets();
        let scalars = self.mesh.scalars();
        let early = self.early.unwrap_or(f32::INFINITY);
        let shader = self.shader;
        let per_pixel = self.per_pixel;
        let mut gathered: Vec<Gathered> = Vec::with_capacity(GATHER);
        // The batch's buffers (a third of a MiB) are kept per thread, not zeroed per tile.
        let mut batch = SPARE_BATCH.with(|b| b.take()).unwrap_or_default();
        let mut colour = CellColour::default();
        let windows = self.windows(rect);
        let gather = Gather {
            secant: &secant,
            window: windows.as_deref(),
            x0: rect.x0 as i64,
            y0: rect.y0 as i64,
            width: tw as i64,
            early,
        };
        let mut indices = [[0u32; 4]; GATHER];
        for chunk in list.chunks(GATHER) {
            gathered.clear();
            // The cells' vertex indices first, then their vertices: each pass's loads are
            // independent of each other, so their cache misses overlap (a dependent chain
            // tet -> vertex per cell would wait for one miss after the other).
            for (ids, &t) in indices.iter_mut().zip(chunk) {
                *ids = tets[t as usize];
            }
            for (tet, &t) in indices.iter().zip(chunk) {
                let Some(screen) = self.proj.tet(tet) else {
                    continue;
                };
                gathered.push(Gathered {
                    id: t,
                    screen,
                    scalars: tet.map(|i| scalars[i as usize]),
                });
            }
            for g in &gathered {
                if !box_holds_centre(&g.screen, rect) {
                    continue;
                }
                // Every fragment's values lie in the cell's vertex range: where the TF is
                // linear over it, the colour needs no table lookup or breakpoint search.
                let [v0, v1, v2, v3] = g.scalars;
                let (lo, hi) = (v0.min(v1).min(v2.min(v3)), v0.max(v1).max(v2.max(v3)));
                if colour.plan(shader, lo, hi) {
                    if let Some(cell) = CellPlanes::new(&g.screen, &g.scalars, PERSP) {
                        let values = CellValues {
                            offset: cell.offset,
                            lo,
                            hi,
                        };
                        self.draw_batch::<PERSP>(
                            &mut batch, &gather, &colour, &cell, values, rect, &mut acc,
                            &mut frags, &mut count,
                        );
                    }
                    continue;
                }
                let q = g.screen.map(|v| fixed([v[0], v[1]]));
                let c = classify_fixed(screen_points(&g.screen), q);
                let tet = &tets[g.id as usize];
                let tv = TetVertices {
                    screen: g.screen,
                    scalars: g.scalars,
                    gradients: match self.gradients {
                        Some(gr) => tet.map(|i| gr[i as usize]),
                        None => [Vec3::ZERO; 4],
                    },
                    perspective: PERSP,
                    _marker: std::marker::PhantomData,
                };
                let fan = if self.gradients.is_some() {
                    fan_vertices_with::<true>(&tv, &c)
                } else {
                    fan_vertices_with::<false>(&tv, &c)
                };
                let Some(fan) = fan else {
                    continue;
                };
                let pos = [q[0], q[1], q[2], q[3], fixed(fan[4].xy)];
                // Per fan point `1 / z_f` and `1 / z_b` (perspective) or 1, computed once.
                let kf = fan.map(|v| if PERSP { 1.0 / v.z_f } else { 1.0 });
                let kb = fan.map(|v| if PERSP { 1.0 / v.z_b } else { 1.0 });
                let finite = g.scalars.iter().all(|v| v.is_finite());
                let piece = if finite {
                    shader.linear_on(lo, hi)
                } else {
                    None
                };
                for tri in c.fan.triangles() {
                    let idx = tri.map(|k| usize::from(k) % 5);
                    let Some(raster) = Triangle::new(idx.map(|k| pos[k]), rect) else {
                        continue;
                    };
                    let interp = Interpolator {
                        z_f: idx.map(|k| fan[k].z_f),
                        s_f: idx.map(|k| fan[k].s_f),
                        z_b: idx.map(|k| fan[k].z_b),
                        s_b: idx.map(|k| fan[k].s_b),
                        kf: idx.map(|k| kf[k]),
                        kb: idx.map(|k| kb[k]),
                        fan: &fan,
                        idx,
                    };
                    raster.for_each(|x, y, l| {
                        let p = (y - rect.y0) * tw + (x - rect.x0);
                        let a = &mut acc[p];
                        if a[3] >= early {
                            return;
                        }
                        let (z_f, s_f, z_b, s_b) = interp.at::<PERSP>(l);
                        let span = DepthSpan { z_f, s_f, z_b, s_b };
                        let Some((DepthSpan { z_f, s_f, z_b, s_b }, ends)) =
                            trim(span, &windows, p)
                        else {
                            return;
                        };
                        count += 1;
                        let len = ((z_b - z_f) * secant[p]).max(0.0);
                        let rgba = match piece {
                            Some(piece) => shader.segment_linear::<M>(piece, s_f, s_b, len),
                            None => shader.fragment_with::<M>(
                                s_f,
                                s_b,
                                len,
                                || {
                                    let g = interp.gradients(l);
                                    ends.map_or(g, |e| trim_gradients(g, e))
                                },
                                || view_dir(x, y),
                            ),
                        };
                        if per_pixel {
                            frags.push(Fragment {
                                pixel: p as u32,
                                depth: z_f,
                                rgba,
                            });
                        } else {
                            under(a, rgba);
                        }
                    });
                }
            }
        }
        batch.clear();
        SPARE_BATCH.with(|b| b.set(Some(batch)));
        if self.per_pixel {
            frags.sort_unstable_by(|a, b| a.pixel.cmp(&b.pixel).then(a.depth.total_cmp(&b.depth)));
            for f in &frags {
                under(&mut acc[f.pixel as usize], f.rgba);
            }
        }
        (acc, count)
    }
}

/// `span` (of tile pixel `p`) trimmed to the pixel's window, with the fractions of it at its
/// new ends; unchanged, with no fractions, without planes (`windows` is `None`).
#[inline(always)]
fn trim(
    span: DepthSpan,
    windows: &Option<Vec<Window>>,
    p: usize,
) -> Option<(DepthSpan, Option<[f32; 2]>)> {
    match windows {
        None => Some((span, None)),
        Some(w) => span.trim(w[p]).map(|(s, ends)| (s, Some(ends))),
    }
}

impl TileContext<'_> {
    /// The depth windows of the pixels of `rect` ([`super::clip`]); `None` without planes.
    fn windows(&self, rect: Rect) -> Option<Vec<Window>> {
        (!self.planes.is_empty())
            .then(|| tile_windows(self.camera, self.proj.size, self.planes, rect))
    }

    /// Draws one cell through the lanes of [`shade`](super::shade): gathers the fragments of
    /// its drawn face triangles with their entry and exit from its planes `cell`
    /// ([`super::planes`]), colours them with `colour` and composites them (or keeps them
    /// for the per-pixel sort).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn draw_batch<const PERSP: bool>(
        &self,
        batch: &mut Batch,
        gather: &Gather<'_>,
        colour: &CellColour,
        cell: &CellPlanes,
        values: CellValues,
        rect: Rect,
        acc: &mut [[f32; 4]],
        frags: &mut Vec<Fragment>,
        count: &mut u64,
    ) {
        let table = self.shader.psi;
        let per_pixel = self.per_pixel;
        let mut flush = |batch: &mut Batch, acc: &mut [[f32; 4]]| {
            batch.shade::<PERSP>(colour, table, values, gather.window);
            *count += batch.len() as u64;
            if per_pixel {
                frags.extend(batch.fragments().map(|(pixel, depth, rgba)| Fragment {
                    pixel,
                    depth,
                    rgba,
                }));
            } else {
                batch.composite(acc);
            }
            batch.clear();
        };
        for face in cell.draws() {
            let Some(raster) = Triangle::new(face.tri, rect) else {
                continue;
            };
            gather.face::<PERSP>(batch, acc, &raster, cell, &face, &mut flush);
        }
        flush(batch, acc);
    }
}

/// Perspective-correct interpolation of front and back attributes over one fan triangle.
struct Interpolator<'f> {
    /// Per vertex front and back depth and scalar.
    z_f: [f32; 3],
    s_f: [f32; 3],
    z_b: [f32; 3],
    s_b: [f32; 3],
    /// Per vertex `1 / z_f` and `1 / z_b` (perspective) or 1 (orthographic).
    kf: [f32; 3],
    kb: [f32; 3],
    /// The fan points (for the gradients) and the triangle's indices into them.
    fan: &'f [FanVertex; 5],
    idx: [usize; 3],
}

impl Interpolator<'_> {
    /// `(z_f, s_f, z_b, s_b)` at screen barycentrics `l`.
    #[inline(always)]
    fn at<const PERSP: bool>(&self, l: [f32; 3]) -> (f32, f32, f32, f32) {
        if PERSP {
            let wf = [l[0] * self.kf[0], l[1] * self.kf[1], l[2] * self.kf[2]];
            let wb = [l[0] * self.kb[0], l[1] * self.kb[1], l[2] * self.kb[2]];
            let sf = wf[0] + wf[1] + wf[2];
            let sb = wb[0] + wb[1] + wb[2];
            let (z_f, z_b) = (1.0 / sf, 1.0 / sb);
            let s_f = (wf[0] * self.s_f[0] + wf[1] * self.s_f[1] + wf[2] * self.s_f[2]) * z_f;
            let s_b = (wb[0] * self.s_b[0] + wb[1] * self.s_b[1] + wb[2] * self.s_b[2]) * z_b;
            (z_f, s_f, z_b, s_b)
        } else {
            let dot = |a: [f32; 3]| l[0] * a[0] + l[1] * a[1] + l[2] * a[2];
            (dot(self.z_f), dot(self.s_f), dot(self.z_b), dot(self.s_b))
        }
    }

    /// Front and back gradients at screen barycentrics `l`.
    fn gradients(&self, l: [f32; 3]) -> (Vec3, Vec3) {
        let v = self.idx.map(|k| &self.fan[k]);
        let wf = [l[0] * self.kf[0], l[1] * self.kf[1], l[2] * self.kf[2]];
        let wb = [l[0] * self.kb[0], l[1] * self.kb[1], l[2] * self.kb[2]];
        let nf = (wf[0] + wf[1] + wf[2]).max(f32::MIN_POSITIVE);
        let nb = (wb[0] + wb[1] + wb[2]).max(f32::MIN_POSITIVE);
        (
            (v[0].g_f * wf[0] + v[1].g_f * wf[1] + v[2].g_f * wf[2]) / nf,
            (v[0].g_b * wb[0] + v[1].g_b * wb[1] + v[2].g_b * wb[2]) / nb,
        )
    }
}

#[cfg(test)]
mod tests;
