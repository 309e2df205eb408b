//! The renderer: per-pixel walks over 16 x 16 tiles in parallel, segments integrated and
//! composited front to back (or the whole ray integrated adaptively, or its maximum taken).
use std::ops::Deref;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::mesh::{FACES, NO_NEIGHBOR};
use volux_core::{Camera, Image, Projection, TetMesh, TransferFunction};

use super::bvh::Bvh;
use super::first::{FirstHits, Projector, TileBins};
use super::geom::Geometry;
use super::options::TetRayOptions;
use super::pixel::{PixelContext, PixelOut};
use super::skip::Visibility;
use super::tables::Tables;
use super::walk::{Scratch, VisibleRay, WalkOutcome, WalkSegment, Walker};
use crate::error::RenderError;
use crate::frame::{Frame, MethodStats, Rebuilt, TetRayStats};
use crate::integrate::psi::PsiTable;
use crate::integrate::SegmentRule;
use crate::renderer::{frame, wrong_method, Renderer};
use crate::scene::{Method, Scene, MESH_UNITS_PER_DIAGONAL};
use crate::tiles::{render_tiles, Control, TileGrid, TILE};

impl TetRayStats {
    /// Counts one ray's pixel and walk.
    fn add_ray(&mut self, px: &PixelOut, walk: &WalkOutcome) {
        self.rays += 1;
        self.segments += walk.segments;
        self.reentries += walk.reentries;
        self.recovered += walk.recovered;
        self.local_searches += walk.local_searches;
        self.abandoned += u64::from(walk.abandoned);
        self.skips += walk.skips;
        self.samples += px.samples;
        self.rays_over_tolerance += u64::from(px.missed);
    }

    /// Adds another tile's counters.
    fn add(&mut self, s: &TetRayStats) {
        self.rays += s.rays;
        self.segments += s.segments;
        self.reentries += s.reentries;
        self.recovered += s.recovered;
        self.local_searches += s.local_searches;
        self.abandoned += s.abandoned;
        self.skips += s.skips;
        self.samples += s.samples;
        self.rays_over_tolerance += s.rays_over_tolerance;
    }
}

/// A ray-cast image with its statistics.
#[derive(Clone, Debug)]
pub struct TetRayRendered {
    /// Premultiplied linear RGBA.
    pub image: Image,
    /// Estimated absolute error per pixel (largest channel), row-major: the adaptive rule's
    /// estimate; 0 for the other colours, which do not estimate it.
    pub error_map: Vec<f32>,
    /// Statistics.
    pub stats: TetRayStats,
}

/// One ray's segments and outcome ([`TetRayCaster::trace`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TracedRay {
    /// The segments, front to back.
    pub segments: Vec<WalkSegment>,
    /// What happened.
    pub outcome: WalkOutcome,
}

/// A ray caster for one mesh: face planes, adjacency, cell fields and the boundary
/// hierarchy, built once ([`TetRayCaster::new`]) and shared by every frame.
pub struct TetRayCaster<M: Deref<Target = TetMesh> = Arc<TetMesh>> {
    mesh: M,
    pub(crate) geo: Geometry,
    pub(crate) boundary: Bvh,
    pad: f64,
    /// Vertex gradients for isosurface normals, computed on first use.
    gradients: OnceLock<Vec<Vec3>>,
    /// The ψ table (it depends on nothing), built on the first ψ frame.
    psi: OnceLock<PsiTable>,
    /// The classification of the last frame's TF.
    tables: Mutex<Option<Arc<Tables>>>,
    /// The visible cells of the last skipping frame's TF and isovalues.
    visible: Mutex<Option<Arc<Visibility>>>,
    /// The start cells of the last frame's camera.
    start: Mutex<Option<(Camera, Arc<Bvh>)>>,
    /// Whether the first frame is still to come (it reports the structures as built).
    first: AtomicBool,
}

/// Bounding box of tet `t`.
fn tet_box(mesh: &TetMesh, t: u32) -> (DVec3, DVec3) {
    let p = mesh.tet_positions(t as usize).map(|v| v.as_dvec3());
    let lo = p[0].min(p[1]).min(p[2].min(p[3]));
    let hi = p[0].max(p[1]).max(p[2].max(p[3]));
    (lo, hi)
}

/// Peak bytes of the structures [`TetRayCaster::new`] builds for a mesh of `tets` cells and
/// `vertices` vertices: the face planes with their build keys, adjacency and cell fields,
/// the boundary hierarchy (every cell counted) and a flag per vertex.
pub fn structure_bytes(tets: usize, vertices: usize) -> u64 {
    let per_tet = Geometry::build_bytes_per_tet() + Bvh::build_bytes_per_cell();
    (tets as u64)
        .saturating_mul(per_tet)
        .saturating_add(vertices as u64)
}

impl<M: Deref<Target = TetMesh>> TetRayCaster<M> {
    /// Builds the structures of `mesh` (`O(n log n)`), after checking that they fit in the
    /// process's memory budget (the error names them, their size and the budget).
    pub fn new(mesh: M) -> Result<Self, RenderError> {
        let m = &*mesh;
        volux_core::limits::check_alloc(
            "the tet ray caster's acceleration structures",
            structure_bytes(m.tets().len(), m.positions().len()),
            1,
        )?;
        let geo = Geometry::new(m);
        let pad = 1e-7 * geo.scale;
        // Cells owning a boundary face, and every cell with a vertex on the boundary: a ray
        // entering the mesh exactly through a boundary edge or vertex may continue in a cell
        // that only touches the boundary there.
        let mut on_boundary = vec![false; m.positions().len()];
        for (t, adj) in geo.cells.iter().map(|c| c.adj).enumerate() {
            for (f, &nb) in adj.iter().enumerate() {
                if nb == NO_NEIGHBOR {
                    for s in FACES[f] {
                        on_boundary[m.tets()[t][s] as usize] = true;
                    }
                }
            }
        }
        let owners: Vec<u32> = (0..m.tets().len() as u32)
            .filter(|&t| {
                geo.usable(t as usize)
                    && m.tets()[t as usize]
                        .iter()
                        .any(|&v| on_boundary[v as usize])
            })
            .collect();
        let boundary = Bvh::build(owners, |t| tet_box(m, t), pad);
        Ok(Self {
            mesh,
            geo,
            boundary,
            pad,
            gradients: OnceLock::new(),
            psi: OnceLock::new(),
            tables: Mutex::new(None),
            visible: Mutex::new(None),
            start: Mutex::new(None),
            first: AtomicBool::new(true),
        })
    }

    /// The mesh's vertex gradients ([`TetMesh::vertex_gradients`]), computed on first use.
    pub fn vertex_gradients(&self) -> &[Vec3] {
        self.gradients.get_or_init(|| self.mesh.vertex_gradients())
    }

    /// The mesh.
    pub fn mesh(&self) -> &TetMesh {
        &self.mesh
    }

    /// Bytes of the acceleration structures (face planes, cell-to-face table, adjacency,
    /// cell fields, boundary hierarchy) per tet, not counting the mesh itself.
    pub fn bytes_per_tet(&self) -> f64 {
        (self.geo.bytes() + self.boundary.bytes()) as f64 / self.mesh.tets().len() as f64
    }

    fn max_steps(&self) -> usize {
        4 * self.mesh.tets().len() + 64
    }

    /// The cells around the ray origins of `camera`: those whose box holds a perspective eye
    /// or that straddle an orthographic camera's eye plane (`O(n)`, in parallel).
    fn start_set(&self, camera: &Camera) -> Bvh {
        let mesh = self.mesh();
        let eye = camera.eye;
        let (_, _, f) = camera.basis();
        let pad = self.pad;
        let b = mesh.bounds();
        let candidates: Vec<u32> = match camera.projection {
            Projection::Perspective { .. } => {
                let inside = (eye.cmpge(b.min - pad) & eye.cmple(b.max + pad)).all();
                if !inside {
                    return Bvh::default();
                }
                (0..mesh.tets().len() as u32)
                    .into_par_iter()
                    .filter(|&t| {
                        let (lo, hi) = tet_box(mesh, t);
                        (eye.cmpge(lo - pad) & eye.cmple(hi + pad)).all()
                    })
                    .collect()
            }
            Projection::Orthographic { .. } => {
                let depth = |p: DVec3| (p - eye).dot(f);
                if b.corners().into_iter().map(depth).all(|z| z > pad) {
                    return Bvh::default();
                }
                (0..mesh.tets().len() as u32)
                    .into_par_iter()
                    .filter(|&t| {
                        let z = mesh.tet_positions(t as usize).map(|p| depth(p.as_dvec3()));
                        let lo = z.iter().copied().fold(f64::INFINITY, f64::min);
                        let hi = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        lo <= pad && hi >= -pad
                    })
                    .collect()
            }
        };
        let candidates = candidates
            .into_iter()
            .filter(|&t| self.geo.usable(t as usize))
            .collect();
        Bvh::build(candidates, |t| tet_box(mesh, t), pad)
    }

    /// The classification tables of `tf`, kept while it does not change.
    fn tables(&self, tf: &TransferFunction, rebuilt: &mut Rebuilt) -> Arc<Tables> {
        let mut cache = self.tables.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(t) = cache.as_ref().filter(|t| t.source == *tf) {
            return t.clone();
        }
        rebuilt.classification = true;
        let t = Arc::new(Tables::new(tf, self.mesh.range()));
        *cache = Some(t.clone());
        t
    }

    /// The visible cells of the frame ([`super::skip`]), kept while the TF and the isovalues
    /// do not change; `None` when the frame does not skip (MIP, the adaptive rule,
    /// [`TetRayOptions::skip_empty`] off) or skipping does not pay.
    fn visibility(
        &self,
        opts: &TetRayOptions,
        tables: &Tables,
        rebuilt: &mut Rebuilt,
    ) -> Option<Arc<Visibility>> {
        let per_segment = !opts.mip && !matches!(opts.color, SegmentRule::AdaptiveSimpson(_));
        if !(opts.skip_empty && per_segment) {
            return None;
        }
        let isos = opts.isosurfaces.as_slice();
        let mut cache = self.visible.lock().unwrap_or_else(|e| e.into_inner());
        let same = |v: &&Arc<Visibility>| {
            v.source == opts.tf && v.isovalues.iter().copied().eq(isos.iter().map(|i| i.value))
        };
        let vis = match cache.as_ref().filter(same) {
            Some(v) => v.clone(),
            None => {
                rebuilt.classification = true;
                let mesh = self.mesh();
                let v = Arc::new(Visibility::new(
                    mesh,
                    &self.geo,
                    tables,
                    isos,
                    |t| tet_box(mesh, t),
                    self.pad,
                ));
                *cache = Some(v.clone());
                v
            }
        };
        vis.worthwhile().then_some(vis)
    }

    /// The start cells of `camera`'s rays, kept while the camera does not move.
    fn start_set_for(&self, camera: &Camera, rebuilt: &mut Rebuilt) -> Arc<Bvh> {
        let mut cache = self.start.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, s)) = cache.as_ref().filter(|(c, _)| c == camera) {
            return s.clone();
        }
        rebuilt.view = true;
        let s = Arc::new(self.start_set(camera));
        *cache = Some((*camera, s.clone()));
        s
    }

    /// Walks one ray `origin + t dir` (`t >= 0`; `t` in units of `|dir|`) through the mesh
    /// and returns its segments. The origin may lie inside the mesh (cells around it are
    /// found by an `O(n)` scan, so this is for tests and tools, not for frames).
    pub fn trace(&self, origin: DVec3, dir: DVec3) -> TracedRay {
        let camera = Camera {
            eye: origin,
            target: origin + dir,
            up: if dir.cross(DVec3::Z).length() > 1e-6 * dir.length() {
                DVec3::Z
            } else {
                DVec3::X
            },
            projection: Projection::Perspective { fov_y_deg: 30.0 },
        };
        let start = if origin.is_finite() {
            self.start_set(&camera)
        } else {
            Bvh::default()
        };
        let walker = Walker {
            geo: &self.geo,
            boundary: &self.boundary,
            start: &start,
            max_steps: self.max_steps(),
        };
        let mut segments = Vec::new();
        let outcome = walker.trace(origin, dir, &mut Scratch::default(), |s| {
            segments.push(*s);
            true
        });
        TracedRay { segments, outcome }
    }

    /// Renders one frame: one ray per pixel centre ([`Camera::ray`]), premultiplied RGBA.
    pub(crate) fn render_with(&self, opts: &TetRayOptions) -> Result<TetRayRendered, RenderError> {
        opts.validate()?;
        opts.control.check()?;
        let start_time = Instant::now();
        let (w, h) = (opts.width, opts.height);
        let mut rebuilt = Rebuilt {
            data: self.first.swap(false, Ordering::Relaxed),
            ..Rebuilt::default()
        };
        let tables = self.tables(&opts.tf, &mut rebuilt);
        let visible = self.visibility(opts, &tables, &mut rebuilt);
        let visible = visible.as_deref();
        let start = match visible {
            // The hierarchy of visible cells also finds those around the eye.
            Some(_) => Arc::new(Bvh::default()),
            None => self.start_set_for(&opts.camera, &mut rebuilt),
        };
        let walker = Walker {
            geo: &self.geo,
            boundary: &self.boundary,
            start: &start,
            max_steps: self.max_steps(),
        };
        let gradients = if opts.isosurfaces.is_empty() || opts.mip {
            &[][..]
        } else {
            rebuilt.data |= self.gradients.get().is_none();
            self.vertex_gradients()
        };
        let tiny;
        let psi = if opts.color == SegmentRule::Psi && !opts.mip {
            rebuilt.data |= self.psi.get().is_none();
            self.psi.get_or_init(PsiTable::new)
        } else {
            tiny = PsiTable::with_size(2);
            &tiny
        };
        let ctx = PixelContext::new(&self.mesh, opts, &tables, gradients, psi);
        let rays = opts.camera.rays(w, h);
        let proj = Projector::new(&opts.camera, w, h);
        let (mesh, geo) = (self.mesh(), &self.geo);
        let grid = TileGrid::new(w, h, TILE);
        let margin = 1e-9 * geo.scale;
        let budget = volux_core::limits::memory_limit();
        let bins = visible.and_then(|v| TileBins::new(budget, &v.bvh, mesh, &proj, &grid, margin));
        let tiled = render_tiles(&grid, &opts.control, |i, r| {
            let mut out = Vec::with_capacity(r.area());
            let mut stats = TetRayStats::default();
            let mut scratch = Scratch::default();
            let mut segments = Vec::new();
            let hits = visible
                .zip(bins.as_ref())
                .map(|(v, bins)| FirstHits::new(bins, &v.bvh, geo, &proj, &rays, (i, r)));
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    let (ray, start) = match (visible, &hits) {
                        (Some(vis), Some(hits)) => match hits.at(x, y) {
                            Some((ray, t_limit, first)) => {
                                let first = Some(first);
                                (
                                    ray,
                                    Some(VisibleRay {
                                        vis,
                                        t_limit,
                                        first,
                                    }),
                                )
                            }
                            None => {
                                // The ray meets no visible cell: nothing to walk.
                                stats.add_ray(&PixelOut::default(), &WalkOutcome::default());
                                out.push(PixelOut::default());
                                continue;
                            }
                        },
                        (Some(vis), None) => {
                            let ray = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                            let t_limit = f64::INFINITY;
                            let (o, d) = (ray.origin, ray.dir);
                            let first = walker.first_visible(vis, t_limit, o, d, &mut scratch);
                            (
                                ray,
                                Some(VisibleRay {
                                    vis,
                                    t_limit,
                                    first,
                                }),
                            )
                        }
                        (None, _) => (rays.ray(x as f64 + 0.5, y as f64 + 0.5), None),
                    };
                    let (px, outcome) = ctx.pixel(
                        &walker,
                        start,
                        ray.origin,
                        ray.dir,
                        &mut scratch,
                        &mut segments,
                    );
                    stats.add_ray(&px, &outcome);
                    out.push(px);
                }
            }
            (out, stats)
        })?;
        let mut stats = TetRayStats::default();
        for s in &tiled.per_tile {
            stats.add(s);
        }
        let pixels = tiled.pixels.iter().map(|p| p.rgba).collect();
        let error_map = tiled.pixels.iter().map(|p| p.error).collect();
        stats.start_cells = start.len();
        stats.visible_cells = visible.map_or(0, Visibility::len);
        stats.rebuilt = rebuilt;
        stats.tets = self.mesh.tets().len();
        stats.bytes_per_tet = self.bytes_per_tet();
        stats.seconds = start_time.elapsed().as_secs_f64();
        Ok(TetRayRendered {
            image: Image::from_pixels(w, h, pixels)?,
            error_map,
            stats,
        })
    }
}

impl<M: Deref<Target = TetMesh> + Send + Sync> Renderer for TetRayCaster<M> {
    fn name(&self) -> &'static str {
        "tet-raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let rule = match scene.method {
            Method::TetRaycast(rule) => rule,
            other => return Err(wrong_method("tet-raycast", &other)),
        };
        scene.validate()?;
        crate::renderer::no_voxel_layers("tet-raycast", scene)?;
        let unit = self.mesh.bounds().diagonal() / MESH_UNITS_PER_DIAGONAL;
        let opts = TetRayOptions::from_scene(scene, rule, unit, control);
        let r = self.render_with(&opts)?;
        let estimates = matches!(rule, SegmentRule::AdaptiveSimpson(_)) && !opts.mip;
        let rebuilt = r.stats.rebuilt;
        Ok(frame(
            r.image,
            estimates.then_some(r.error_map),
            started,
            rebuilt,
            MethodStats::TetRaycast(r.stats),
        ))
    }
}
