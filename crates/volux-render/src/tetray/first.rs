//! The first visible cell of every ray of a tile, found once per tile by splatting the
//! visible cells onto its pixels instead of one hierarchy query per ray (the entry step of
//! Garrity's walk, seed `000` §2.4, over the visible cells of [`super::skip`]).
//!
//! Per tile: the visible cells whose box may meet the tile's frustum are gathered from the
//! hierarchy of visible cells ([`Bvh::gather`]; the same test that culls a tile, so every
//! cell a ray of the tile hits is among them, and their farthest box corner is the tile's
//! [`Bvh::reach`]). Each is projected to the image: its four vertices give a pixel rectangle
//! (widened far above the rounding of the projection and of the rays; the whole tile when a
//! vertex lies behind a perspective eye) and its smallest view depth. In order of that depth,
//! each cell is clipped ([`Geometry::clip`]) against the rays of the pixels of its rectangle
//! whose best hit so far does not start before the cell's depth, and a hit replaces the
//! pixel's best when it starts first (ties by cell index, [`Hit::before`]).
//!
//! That is [`Bvh::nearest_from`]'s answer from `t = 0`, exactly: the answer is the least
//! `(start, cell)` over the visible cells whose clip reaches past 0, and every such cell is
//! clipped for the pixel unless its depth proves that it starts after the pixel's best hit.
//! Rays of pixels without a hit meet no visible cell and are not walked. The pixels are
//! independent of each other and of the thread count. The depth order only saves clips: a
//! cell behind a pixel's first hit is rejected with one comparison.
use glam::DVec3;
use volux_core::camera::Ray;
use volux_core::{Camera, Projection, RayGenerator, TetMesh};

use super::bvh::{Bvh, Frustum, Hit};
use super::geom::Geometry;
use crate::tiles::Rect;

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
            if !(z > 0.0) {
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

/// A gathered cell: its pixel rectangle in the tile (`[x0, x1) x [y0, y1)`, tile-local) and
/// its smallest view depth.
#[derive(Clone, Copy, Debug)]
struct Splat {
    tet: u32,
    rect: [u16; 4],
    depth: f64,
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
    /// The start of `best` (infinite without one).
    key: f64,
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
    /// The first visible cells (hierarchy `bvh` over cells of `geo` and `mesh`) of the rays
    /// of `rays` through the pixel centres of tile `rect`; `None` when the tile's frustum
    /// cannot be built (the caller queries per ray).
    pub fn new(
        bvh: &Bvh,
        geo: &Geometry,
        mesh: &TetMesh,
        proj: &Projector,
        rays: &RayGenerator,
        rect: Rect,
    ) -> Option<Self> {
        let tile = [rect.x0, rect.y0, rect.x1, rect.y1].map(|v| v as f64);
        let frustum = Frustum::of_block(rays, tile)?;
        let from = rays
            .ray(0.5 * (tile[0] + tile[2]), 0.5 * (tile[1] + tile[3]))
            .origin;
        let mut gathered = Vec::new();
        bvh.gather(&frustum, from, &mut gathered);
        let reach = gathered
            .iter()
            .map(|&(_, far)| far)
            .fold(f64::NEG_INFINITY, f64::max);
        let f = proj.basis.2;
        let mut pixels = Vec::with_capacity(if gathered.is_empty() { 0 } else { rect.area() });
        if !gathered.is_empty() {
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
                        key: f64::INFINITY,
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
        let mut splats: Vec<Splat> = gathered
            .iter()
            .map(|&(t, _)| hits.splat_of(mesh, proj, t))
            .collect();
        splats.sort_unstable_by(|a, b| a.depth.total_cmp(&b.depth).then(a.tet.cmp(&b.tet)));
        let margin = 1e-9 * geo.scale;
        for s in &splats {
            hits.draw(geo, s, margin);
        }
        Some(hits)
    }

    /// Cell `t`'s rectangle in the tile and smallest depth.
    fn splat_of(&self, mesh: &TetMesh, proj: &Projector, t: u32) -> Splat {
        let p = mesh.tet_positions(t as usize).map(|v| v.as_dvec3());
        let depth = p
            .iter()
            .map(|&v| proj.depth(v))
            .fold(f64::INFINITY, f64::min);
        let (w, h) = (self.rect.width() as f64, self.rect.height() as f64);
        let mut lo = (f64::INFINITY, f64::INFINITY);
        let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for v in p {
            let Some((x, y)) = proj.pixel(v) else {
                lo = (f64::NEG_INFINITY, f64::NEG_INFINITY);
                hi = (f64::INFINITY, f64::INFINITY);
                break;
            };
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        // Pixel `i` (tile-local) has its centre at `x0 + i + 0.5`.
        let (x0, y0) = (self.rect.x0 as f64 + 0.5, self.rect.y0 as f64 + 0.5);
        let first = |v: f64, o: f64, n: f64| {
            let m = PIXEL_MARGIN + 1e-9 * v.abs();
            (v - m - o).ceil().clamp(0.0, n) as u16
        };
        let end = |v: f64, o: f64, n: f64| {
            let m = PIXEL_MARGIN + 1e-9 * v.abs();
            ((v + m - o).floor() + 1.0).clamp(0.0, n) as u16
        };
        Splat {
            tet: t,
            rect: [
                first(lo.0, x0, w),
                first(lo.1, y0, h),
                end(hi.0, x0, w),
                end(hi.1, y0, h),
            ],
            depth,
        }
    }

    /// Clips splat `s`'s cell against the rays of its rectangle whose best hit may start
    /// after it (`margin`: world units on the depth test).
    fn draw(&mut self, geo: &Geometry, s: &Splat, margin: f64) {
        let width = self.rect.width();
        let [x0, y0, x1, y1] = s.rect.map(usize::from);
        for y in y0..y1 {
            for px in &mut self.pixels[y * width + x0..y * width + x1] {
                // Every point of the cell lies at depth `s.depth` or more, so at `t` of at
                // least `(s.depth - origin_depth) / depth_rate`.
                let bound = px.origin_depth + px.key * px.depth_rate;
                if s.depth - margin > bound + 1e-9 * bound.abs() {
                    continue;
                }
                let Some(clip) = geo.clip(s.tet as usize, px.ray.origin, px.ray.dir) else {
                    continue;
                };
                let hit = Hit { tet: s.tet, clip };
                if clip.t_out > 0.0 && px.best.is_none_or(|b| hit.before(&b, 0.0)) {
                    px.key = hit.key(0.0);
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
/// `reach` from `from` ([`Bvh::reach`]); infinite when that is not a number.
#[inline]
pub(crate) fn t_limit(reach: f64, from: DVec3, ray: &Ray) -> f64 {
    let t = (reach + (ray.origin - from).length()) / ray.dir.length() * (1.0 + REACH_MARGIN);
    if t.is_nan() {
        f64::INFINITY
    } else {
        t
    }
}
