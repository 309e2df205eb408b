//! The first visible cell of every ray, found per tile by splatting the visible cells onto
//! its pixels instead of one hierarchy query per ray (the entry step of Garrity's walk, seed
//! `000` §2.4, over the visible cells of [`super::skip`]).
//!
//! Per frame ([`TileBins`]): each visible cell is projected to the image, its four vertices
//! giving a pixel rectangle (widened far above the rounding of the projection and of the
//! rays) and its smallest view depth, and it is binned to the tiles its rectangle meets. A
//! cell wholly behind the eye plane is met by no ray and left out; a cell across the plane
//! of a perspective eye has no bounded rectangle, and then the frame queries the hierarchy
//! per ray instead (as it does when the bins would not fit in the memory budget). Per tile ([`FirstHits`]): in order of depth, each of its cells is
//! clipped ([`Geometry::clip`]) against the rays of the pixels of its rectangle whose best hit
//! so far does not start before the cell's depth, and a hit replaces the pixel's best when it
//! starts first (ties by cell index, [`Hit::before`]). The tile's reach (how far its rays may
//! meet a visible cell, which ends their walks) is the farthest corner of its cells' boxes.
//!
//! That is [`Bvh::nearest_from`]'s answer from `t = 0`, exactly: the answer is the least
//! `(start, cell)` over the visible cells whose clip reaches past 0, and every such cell is
//! in the ray's tile and clipped for the pixel unless its depth proves that it starts after
//! the pixel's best hit. Rays of pixels without a hit meet no visible cell and are not
//! walked. The pixels are independent of each other and of the thread count; the depth
//! order only saves clips (a cell behind a pixel's first hit is rejected with one
//! comparison).
use glam::DVec3;
use rayon::prelude::*;
use volux_core::camera::Ray;
use volux_core::limits::check_alloc_within;
use volux_core::{Camera, Projection, RayGenerator, TetMesh};

use super::bvh::{Bvh, Hit};
use super::geom::Geometry;
use crate::tiles::{Rect, TileGrid};

/// Margin in pixels around a cell's projected rectangle (the projection's and the rays'
/// rounding are below `1e-9` pixels).
const PIXEL_MARGIN: f64 = 1e-4;

/// Relative margin on the tile's reach (far above the rounding of the distances).
pub(crate) const REACH_MARGIN: f64 = 1e-9;

/// World points to continuous pixel coordinates of a frame's rays (the inverse of
/// [`RayGenerator::ray`], as [`Camera::project`] computes it, with the basis computed once).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    eye: DVec3,
    basis: (DVec3, DVec3, DVec3),
    size: (f64, f64),
    /// `tan(fov / 2)` (perspective) or half the view height (orthographic), per unit of the
    /// normalized image coordinates.
    scale: f64,
    perspective: bool,
}

impl Projector {
    /// The projection of `camera`'s `w` x `h` rays.
    pub fn new(camera: &Camera, w: usize, h: usize) -> Self {
        let (scale, perspective) = match camera.projection {
            Projection::Perspective { fov_y_deg } => ((fov_y_deg.to_radians() * 0.5).tan(), true),
            Projection::Orthographic { height } => (height * 0.5, false),
        };
        Self {
            eye: camera.eye,
            basis: camera.basis(),
            size: (w as f64, h as f64),
            scale,
            perspective,
        }
    }

    /// The depth of `p` along the view direction (from the eye plane).
    #[inline]
    fn depth(&self, p: DVec3) -> f64 {
        (p - self.eye).dot(self.basis.2)
    }

    /// Continuous pixel coordinates of `p`; `None` behind a perspective eye or when not
    /// finite.
    #[inline]
    fn pixel(&self, p: DVec3) -> Option<(f64, f64)> {
        let (r, u, f) = self.basis;
        let (w, h) = self.size;
        let d = p - self.eye;
        let div = if self.perspective {
            let z = d.dot(f);
            // NaN included: not in front of the eye.
            if z.is_nan() || z <= 0.0 {
                return None;
            }
            z * self.scale
        } else {
            self.scale
        };
        let (nx, ny) = (d.dot(r) / div, d.dot(u) / div);
        let px = (nx * (h / w) + 1.0) * 0.5 * w;
        let py = (1.0 - ny) * 0.5 * h;
        (px.is_finite() && py.is_finite()).then_some((px, py))
    }
}

/// A visible cell on the image: its pixel rectangle (`[x0, x1) x [y0, y1)`, the pixels whose
/// centres it may cover), its smallest view depth, and its index in the hierarchy.
#[derive(Clone, Copy, Debug)]
struct Splat {
    tet: u32,
    prim: u32,
    rect: [u32; 4],
    depth: f64,
}

/// Where a visible cell lies on the image.
enum Place {
    /// It may cover the pixel centres of this splat.
    On(Splat),
    /// No ray meets it (behind the eye plane, or between pixel centres).
    Off,
    /// Across a perspective eye's plane: no bounded rectangle.
    Across,
}

/// The visible cells of a frame binned to the tiles their rectangles meet.
pub(crate) struct TileBins {
    /// Tile `i`'s cells are `cells[offsets[i]..offsets[i + 1]]`, near to far (by depth,
    /// then index).
    offsets: Vec<usize>,
    cells: Vec<Splat>,
}

impl TileBins {
    /// The visible cells of `bvh` (cells of `mesh`) binned to the tiles of `grid` for the
    /// projection `proj`; `None` when a cell lies across a perspective eye's plane, or when
    /// the bins (one entry per cell and tile it meets) would take more than `budget` bytes:
    /// the per-ray hierarchy query needs no bins. `margin` (world units) is far above the
    /// rounding of a depth.
    pub fn new(
        budget: u64,
        bvh: &Bvh,
        mesh: &TetMesh,
        proj: &Projector,
        grid: &TileGrid,
        margin: f64,
    ) -> Option<Self> {
        let places: Vec<Place> = (0..bvh.len())
            .into_par_iter()
            .map(|i| place(mesh, proj, grid, bvh.prim(i), i as u32, margin))
            .collect();
        let mut on = Vec::with_capacity(places.len());
        for p in places {
            match p {
                Place::On(s) => on.push(s),
                Place::Off => {}
                Place::Across => return None,
            }
        }
        // Near to far (each tile's cells stay in this order).
        on.par_sort_unstable_by(|a, b| a.depth.total_cmp(&b.depth).then(a.tet.cmp(&b.tet)));
        let tiles = |s: &Splat| {
            let side = grid.side as u32;
            let [x0, y0, x1, y1] = s.rect;
            (
                x0 / side..(x1 - 1) / side + 1,
                y0 / side..(y1 - 1) / side + 1,
            )
        };
        let mut offsets = vec![0usize; grid.count() + 1];
        for s in &on {
            let (xs, ys) = tiles(s);
            for ty in ys {
                for tx in xs.clone() {
                    offsets[ty as usize * grid.cols + tx as usize + 1] += 1;
                }
            }
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let entries = offsets[grid.count()] as u64;
        let entry_bytes = std::mem::size_of::<Splat>() as u64;
        if check_alloc_within(budget, "the tile bins", entries, entry_bytes).is_err() {
            return None;
        }
        let mut fill = offsets.clone();
        let none = Splat {
            tet: 0,
            prim: 0,
            rect: [0; 4],
            depth: 0.0,
        };
        let mut cells = vec![none; offsets[grid.count()]];
        for s in &on {
            let (xs, ys) = tiles(s);
            for ty in ys {
                for tx in xs.clone() {
                    let slot = &mut fill[ty as usize * grid.cols + tx as usize];
                    cells[*slot] = *s;
                    *slot += 1;
                }
            }
        }
        Some(Self { offsets, cells })
    }

    /// The cells of tile `i`.
    fn tile(&self, i: usize) -> &[Splat] {
        self.offsets
            .get(i..i + 2)
            .map_or(&[], |r| &self.cells[r[0]..r[1]])
    }
}

/// Where cell `tet` (primitive `prim` of the hierarchy) lies on the image of `grid`.
fn place(
    mesh: &TetMesh,
    proj: &Projector,
    grid: &TileGrid,
    tet: u32,
    prim: u32,
    margin: f64,
) -> Place {
    let p = mesh.tet_positions(tet as usize).map(|v| v.as_dvec3());
    let z = p.map(|v| proj.depth(v));
    let depth = z.iter().copied().fold(f64::INFINITY, f64::min);
    if z.iter().all(|&z| z < -margin) {
        // Rays start at the eye plane and move away from it.
        return Place::Off;
    }
    let mut lo = (f64::INFINITY, f64::INFINITY);
    let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for v in p {
        let Some((x, y)) = proj.pixel(v) else {
            return Place::Across;
        };
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    // Pixel `i` has its centre at `i + 0.5`.
    let first = |v: f64, n: usize| {
        let m = PIXEL_MARGIN + 1e-9 * v.abs();
        (v - m - 0.5).ceil().clamp(0.0, n as f64) as u32
    };
    let end = |v: f64, n: usize| {
        let m = PIXEL_MARGIN + 1e-9 * v.abs();
        ((v + m - 0.5).floor() + 1.0).clamp(0.0, n as f64) as u32
    };
    let rect = [
        first(lo.0, grid.width),
        first(lo.1, grid.height),
        end(hi.0, grid.width),
        end(hi.1, grid.height),
    ];
    if rect[0] >= rect[2] || rect[1] >= rect[3] || depth.is_nan() {
        return Place::Off;
    }
    Place::On(Splat {
        tet,
        prim,
        rect,
        depth,
    })
}

/// One pixel's ray and its best hit so far.
#[derive(Clone, Copy, Debug)]
struct PixelRay {
    ray: Ray,
    /// Depth of the ray's origin and the depth gained per unit of `t` (`origin_depth` is
    /// infinite when the ray does not advance in depth, which disables the depth test).
    origin_depth: f64,
    depth_rate: f64,
    best: Option<Hit>,
    /// The depth at the start of `best`, widened by a relative `1e-9` (infinite without
    /// one): a cell wholly deeper starts after it.
    limit: f64,
}

/// The rays of one tile with their first visible cells and the tile's reach.
pub(crate) struct FirstHits {
    rect: Rect,
    pixels: Vec<PixelRay>,
    /// The origin the reach is measured from, and the reach.
    from: DVec3,
    reach: f64,
}

impl FirstHits {
    /// The first visible cells of the rays of `rays` through the pixel centres of tile `i`
    /// (`rect`) of `bins` (cells of `geo`, primitives of `bvh`).
    pub fn new(
        bins: &TileBins,
        bvh: &Bvh,
        geo: &Geometry,
        proj: &Projector,
        rays: &RayGenerator,
        (i, rect): (usize, Rect),
    ) -> Self {
        let cells = bins.tile(i);
        let centre = (
            0.5 * (rect.x0 + rect.x1) as f64,
            0.5 * (rect.y0 + rect.y1) as f64,
        );
        let from = rays.ray(centre.0, centre.1).origin;
        let reach = cells
            .iter()
            .map(|s| bvh.far_corner(s.prim as usize, from))
            .fold(f64::NEG_INFINITY, f64::max);
        let f = proj.basis.2;
        let mut pixels = Vec::with_capacity(if cells.is_empty() { 0 } else { rect.area() });
        if !cells.is_empty() {
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let ray = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                    let rate = ray.dir.dot(f);
                    let origin_depth = if rate > 0.0 {
                        proj.depth(ray.origin)
                    } else {
                        f64::INFINITY
                    };
                    pixels.push(PixelRay {
                        ray,
                        origin_depth,
                        depth_rate: rate,
                        best: None,
                        limit: f64::INFINITY,
                    });
                }
            }
        }
        let mut hits = Self {
            rect,
            pixels,
            from,
            reach,
        };
        let margin = 1e-9 * geo.scale;
        for s in cells {
            hits.draw(geo, s, margin);
        }
        hits
    }

    /// Clips splat `s`'s cell against the rays of its rectangle whose best hit may start
    /// after it (`margin`: world units on the depth test).
    fn draw(&mut self, geo: &Geometry, s: &Splat, margin: f64) {
        let (r, width) = (self.rect, self.rect.width());
        let [x0, y0, x1, y1] = s.rect.map(|v| v as usize);
        let near = s.depth - margin;
        let (x0, x1) = (x0.max(r.x0) - r.x0, x1.min(r.x1) - r.x0);
        for y in y0.max(r.y0) - r.y0..y1.min(r.y1) - r.y0 {
            for px in &mut self.pixels[y * width + x0..y * width + x1] {
                // Every point of the cell lies at depth `s.depth` or more, so at `t` of at
                // least `(s.depth - origin_depth) / depth_rate`.
                if near > px.limit {
                    continue;
                }
                let Some(clip) = geo.clip(s.tet as usize, px.ray.origin, px.ray.dir) else {
                    continue;
                };
                let hit = Hit { tet: s.tet, clip };
                if clip.t_out > 0.0 && px.best.is_none_or(|b| hit.before(&b, 0.0)) {
                    let depth = px.origin_depth + hit.key(0.0) * px.depth_rate;
                    px.limit = depth + 1e-9 * depth.abs();
                    px.best = Some(hit);
                }
            }
        }
    }

    /// The ray of pixel `(x, y)` of the tile, the largest ray parameter at which it may meet
    /// a visible cell, and its first visible cell; `None` when it meets none.
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> Option<(Ray, f64, Hit)> {
        let i = (y - self.rect.y0) * self.rect.width() + (x - self.rect.x0);
        let px = self.pixels.get(i)?;
        let first = px.best?;
        Some((px.ray, t_limit(self.reach, self.from, &px.ray), first))
    }
}

/// The largest parameter at which `ray` may meet a visible cell when none lies farther than
/// `reach` from `from` (a tile's reach); infinite when that is not a number.
#[inline]
pub(crate) fn t_limit(reach: f64, from: DVec3, ray: &Ray) -> f64 {
    let t = (reach + (ray.origin - from).length()) / ray.dir.length() * (1.0 + REACH_MARGIN);
    if t.is_nan() {
        f64::INFINITY
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use volux_core::{synth, Camera, CameraSpec, Projection, TetMesh, TransferFunction};

    use super::super::render::TetRayCaster;
    use super::super::skip::Visibility;
    use super::super::tables::Tables;
    use super::super::tests::{band_tf, gappy_tf, lattice};
    use super::*;
    use crate::tiles::TILE;

    /// The visible cells of `mesh` under `tf`, as the renderer builds them.
    fn visibility(
        mesh: &TetMesh,
        caster: &TetRayCaster<&TetMesh>,
        tf: &TransferFunction,
    ) -> Visibility {
        let tables = Tables::new(tf, mesh.range());
        let boxes = |t: u32| {
            let p = mesh.tet_positions(t as usize).map(|v| v.as_dvec3());
            (
                p[0].min(p[1]).min(p[2].min(p[3])),
                p[0].max(p[1]).max(p[2].max(p[3])),
            )
        };
        Visibility::new(
            mesh,
            &caster.geo,
            &tables,
            &[],
            boxes,
            1e-7 * caster.geo.scale,
        )
    }

    /// Checks every pixel of an `n` x `n` frame: the tile's first hit is the hierarchy's
    /// answer from `t = 0` (cell and clip), and no visible cell of the ray's full walk starts
    /// past the tile's reach. Returns the pixels with and without a hit.
    fn check(mesh: &TetMesh, tf: &TransferFunction, camera: Camera, n: usize) -> (usize, usize) {
        let caster = TetRayCaster::new(mesh).unwrap();
        let vis = visibility(mesh, &caster, tf);
        assert!(
            vis.worthwhile(),
            "{} of {} cells visible",
            vis.len(),
            mesh.tets().len()
        );
        let geo = &caster.geo;
        let grid = TileGrid::new(n, n, TILE);
        let proj = Projector::new(&camera, n, n);
        let rays = camera.rays(n, n);
        let bins = TileBins::new(u64::MAX, &vis.bvh, mesh, &proj, &grid, 1e-9 * geo.scale)
            .expect("no visible cell across the eye plane");
        let (mut hit, mut miss) = (0, 0);
        for i in 0..grid.count() {
            let r = grid.rect(i);
            let hits = FirstHits::new(&bins, &vis.bvh, geo, &proj, &rays, (i, r));
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    let ray = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                    let want = vis.bvh.nearest(geo, ray.origin, ray.dir, 0.0);
                    let got = hits.at(x, y);
                    assert_eq!(got.map(|g| g.2), want, "pixel ({x}, {y})");
                    let walked = caster.trace(ray.origin, ray.dir).segments;
                    let mut visible = walked.iter().filter(|s| vis.is_visible(s.tet));
                    match got {
                        Some((r, t_limit, _)) => {
                            assert_eq!(r, ray);
                            hit += 1;
                            assert!(visible.all(|s| s.t_in <= t_limit), "pixel ({x}, {y})");
                        }
                        None => {
                            miss += 1;
                            assert!(visible.next().is_none(), "pixel ({x}, {y})");
                        }
                    }
                }
            }
        }
        (hit, miss)
    }

    fn orbit(proj: &str, az: f64, el: f64, mesh: &TetMesh) -> Camera {
        let spec = CameraSpec {
            projection: Some(proj.into()),
            azimuth: Some(az),
            elevation: Some(el),
            ..Default::default()
        };
        spec.resolve(&mesh.bounds()).unwrap()
    }

    #[test]
    fn first_hits_equal_the_hierarchy_query() {
        let smooth = synth::smooth_tets(3000).unwrap();
        let torus = synth::torus_tets(24).unwrap();
        let grid = lattice(5);
        let cases = [
            (
                &smooth,
                gappy_tf(),
                orbit("perspective", 10.0, 25.0, &smooth),
            ),
            (
                &smooth,
                gappy_tf(),
                orbit("orthographic", -60.0, 45.0, &smooth),
            ),
            (&torus, band_tf(), orbit("perspective", 30.0, 60.0, &torus)),
            // Axis-aligned: rays through the lattice's vertices and edges and in its faces.
            (&grid, band_tf(), orbit("orthographic", 0.0, 0.0, &grid)),
            (&grid, band_tf(), orbit("perspective", 0.0, 0.0, &grid)),
        ];
        for (c, (mesh, tf, camera)) in cases.into_iter().enumerate() {
            let (hit, miss) = check(mesh, &tf, camera, 40);
            eprintln!("case {c}: {hit} pixels with a first visible cell, {miss} without");
            assert!(hit > 100 && miss > 0, "case {c}: {hit} / {miss}");
        }
    }

    #[test]
    fn a_visible_cell_across_the_eye_plane_leaves_the_frame_to_the_hierarchy() {
        let mesh = synth::smooth_tets(3000).unwrap();
        let caster = TetRayCaster::new(&mesh).unwrap();
        let vis = visibility(&mesh, &caster, &gappy_tf());
        let inside = Camera {
            eye: DVec3::new(0.43, 0.31, 0.57),
            target: DVec3::new(0.9, 0.7, 0.2),
            up: DVec3::Z,
            projection: Projection::Perspective { fov_y_deg: 70.0 },
        };
        let grid = TileGrid::new(32, 32, TILE);
        let bins = |camera: &Camera| {
            let proj = Projector::new(camera, 32, 32);
            TileBins::new(
                u64::MAX,
                &vis.bvh,
                &mesh,
                &proj,
                &grid,
                1e-9 * caster.geo.scale,
            )
        };
        assert!(bins(&inside).is_none());
        let outside = orbit("perspective", 10.0, 25.0, &mesh);
        assert!(bins(&outside).is_some_and(|b| !b.cells.is_empty()));
    }

    #[test]
    fn bins_over_the_memory_budget_leave_the_frame_to_the_hierarchy() {
        let mesh = synth::smooth_tets(3000).unwrap();
        let caster = TetRayCaster::new(&mesh).unwrap();
        let vis = visibility(&mesh, &caster, &gappy_tf());
        let camera = orbit("perspective", 10.0, 25.0, &mesh);
        let grid = TileGrid::new(64, 64, TILE);
        let proj = Projector::new(&camera, 64, 64);
        let margin = 1e-9 * caster.geo.scale;
        let bins = |budget| TileBins::new(budget, &vis.bvh, &mesh, &proj, &grid, margin);
        let full = bins(u64::MAX).expect("bins within an unlimited budget");
        let bytes = (full.cells.len() * std::mem::size_of::<Splat>()) as u64;
        assert!(bytes > 0);
        assert!(bins(bytes).is_some());
        assert!(bins(bytes - 1).is_none());
    }
}
