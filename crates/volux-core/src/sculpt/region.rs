//! The regions the sculpting tools remove: the eraser's disc swept along a stroke on the
//! screen, through the whole depth (seed `004` sec. 4.4), and the digger's ball (sec. 4.5).
//! A region answers for a box of voxel centres whether it covers all, none or some of them,
//! so that the mask tests voxel by voxel only the bricks it crosses.
use glam::{DMat3, DVec2, DVec3};

use crate::camera::{Camera, Projection};
use crate::error::{Error, Result};
use crate::grid::Grid;

/// How a region covers the voxel centres of a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// None of them.
    None,
    /// Some of them, perhaps: test each.
    Some,
    /// All of them.
    All,
}

/// A set of voxels a tool removes.
pub trait Region: Sync {
    /// The voxel index box (inclusive, within `dims`) outside which the region holds no voxel;
    /// `None` when it holds none.
    fn index_bounds(&self, dims: [usize; 3]) -> Option<([usize; 3], [usize; 3])>;
    /// How the region covers the voxel centres in the index box `[lo, hi]` (inclusive).
    fn coverage(&self, lo: [f64; 3], hi: [f64; 3]) -> Coverage;
    /// Whether the region holds voxel `ijk`.
    fn contains(&self, ijk: [usize; 3]) -> bool;
    /// The voxels `i0..=i1` (at most 64) of row (`j`, `k`) the region holds, bit `i - i0`
    /// each ([`Region::contains`] voxel by voxel unless a region has a faster way).
    fn contains_row(&self, i0: usize, i1: usize, j: usize, k: usize) -> u64 {
        (i0..=i1).fold(0, |bits, i| {
            bits | u64::from(self.contains([i, j, k])) << (i - i0)
        })
    }
}

/// Where a grid's voxels lie in the world: `origin + D (spacing ∘ index)`
/// ([`Grid::index_to_world`]), with the direction `D` orthonormal, so that a world distance
/// is the length of the index difference scaled by the spacing (anisotropic voxels are
/// measured in millimetres, not in voxels: the seed's texture-space distances, sec. 4.5.1, are
/// not used).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelFrame {
    /// Samples per axis.
    pub dims: [usize; 3],
    origin: DVec3,
    spacing: DVec3,
    direction: DMat3,
}

impl VoxelFrame {
    /// The frame of `grid`.
    pub fn of(grid: &Grid) -> Self {
        Self {
            dims: grid.dims(),
            origin: grid.origin(),
            spacing: grid.spacing(),
            direction: grid.direction(),
        }
    }

    /// The world point of continuous index `ijk`.
    #[inline]
    pub fn world(&self, ijk: DVec3) -> DVec3 {
        self.origin + self.direction * (self.spacing * ijk)
    }

    /// The continuous index of world point `p`.
    pub fn index(&self, p: DVec3) -> DVec3 {
        (self.direction.transpose() * (p - self.origin)) / self.spacing
    }

    /// The spacing per axis (world units).
    pub fn spacing(&self) -> DVec3 {
        self.spacing
    }
}

/// The digger's ball (seed `004` sec. 4.5): the voxels whose centres lie within `radius` world
/// units of `centre`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    centre: DVec3,
    radius: f64,
    frame: VoxelFrame,
    /// The centre in index space.
    centre_index: DVec3,
}

impl Ball {
    /// The ball of `radius` (world units, > 0) about world point `centre`, in `frame`.
    pub fn new(centre: DVec3, radius: f64, frame: VoxelFrame) -> Result<Self> {
        if !(centre.is_finite() && radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidSculpt(format!(
                "a ball needs a finite centre and a positive radius, got {centre} and {radius}"
            )));
        }
        Ok(Self {
            centre,
            radius,
            frame,
            centre_index: frame.index(centre),
        })
    }

    /// The world distance between voxel index `v` and the centre.
    #[inline]
    fn distance(&self, v: DVec3) -> f64 {
        ((v - self.centre_index) * self.frame.spacing).length()
    }
}

impl Region for Ball {
    fn index_bounds(&self, dims: [usize; 3]) -> Option<([usize; 3], [usize; 3])> {
        let reach = DVec3::splat(self.radius) / self.frame.spacing;
        index_box(self.centre_index - reach, self.centre_index + reach, dims)
    }

    fn coverage(&self, lo: [f64; 3], hi: [f64; 3]) -> Coverage {
        let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
        let near = self.centre_index.clamp(lo, hi);
        if self.distance(near) > self.radius {
            return Coverage::None;
        }
        let far_offset = (lo - self.centre_index)
            .abs()
            .max((hi - self.centre_index).abs());
        if (far_offset * self.frame.spacing).length() <= self.radius {
            Coverage::All
        } else {
            Coverage::Some
        }
    }

    #[inline]
    fn contains(&self, ijk: [usize; 3]) -> bool {
        self.distance(DVec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64)) <= self.radius
    }
}

/// The index box (clamped to `dims`) of the continuous index range `[lo, hi]`, or `None`
/// when it misses the grid.
fn index_box(lo: DVec3, hi: DVec3, dims: [usize; 3]) -> Option<([usize; 3], [usize; 3])> {
    let mut out = ([0usize; 3], [0usize; 3]);
    for a in 0..3 {
        let top = (dims[a] - 1) as f64;
        let (l, h) = (lo[a].ceil().max(0.0), hi[a].floor().min(top));
        // NaN bounds (an unusable region) fall through to None as well.
        if l.partial_cmp(&h)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
        {
            return None;
        }
        out.0[a] = l as usize;
        out.1[a] = h as usize;
    }
    Some(out)
}

/// The eraser (seed `004` sec. 4.4): a disc of `radius` pixels swept along a stroke of pixel
/// positions on the screen of a camera and image size (x to the right, y down from the
/// top-left, as in the image), removing every voxel whose centre projects within the swept
/// disc, through the whole depth (in perspective, a cone from the eye: voxels behind the eye
/// are not touched). One point is a disc; a stroke is the union of the capsules between its
/// successive points, not a chain of separate discs.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenStroke {
    capsules: Vec<Capsule>,
    radius: f64,
    projector: Projector,
}

impl ScreenStroke {
    /// The stroke through `points` (pixels) with a disc of `radius` pixels (> 0), seen by
    /// `camera` in a `width` x `height` image, over the voxels of `frame`.
    pub fn new(
        camera: &Camera,
        (width, height): (usize, usize),
        points: &[[f64; 2]],
        radius: f64,
        frame: VoxelFrame,
    ) -> Result<Self> {
        let finite = points.iter().flatten().all(|v| v.is_finite());
        if points.is_empty() || !finite || !(radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidSculpt(format!(
                "an eraser stroke needs at least one finite point and a positive radius, got \
                 {} points and radius {radius}",
                points.len()
            )));
        }
        if width == 0 || height == 0 {
            return Err(Error::InvalidSculpt(
                "an eraser needs a non-empty image".into(),
            ));
        }
        camera.validate()?;
        let points: Vec<DVec2> = points.iter().map(|&p| DVec2::from(p)).collect();
        let capsules = match points.as_slice() {
            [p] => vec![Capsule::new(*p, *p)],
            _ => points
                .windows(2)
                .map(|w| Capsule::new(w[0], w[1]))
                .collect(),
        };
        Ok(Self {
            capsules,
            radius,
            projector: Projector::new(camera, width, height, &frame),
        })
    }

    fn inside(&self, q: DVec2) -> bool {
        let r2 = self.radius * self.radius;
        self.capsules.iter().any(|c| c.distance2(q) <= r2)
    }
}

/// One segment of a stroke (both ends equal for a single point), with what its distance
/// needs computed once.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Capsule {
    a: DVec2,
    ab: DVec2,
    /// `1 / |ab|²`, or 0 for a point.
    inv_len2: f64,
}

impl Capsule {
    fn new(a: DVec2, b: DVec2) -> Self {
        let ab = b - a;
        let len2 = ab.length_squared();
        let inv_len2 = if len2 > 0.0 { 1.0 / len2 } else { 0.0 };
        Self { a, ab, inv_len2 }
    }

    /// The squared distance from `q` to the segment.
    #[inline]
    fn distance2(&self, q: DVec2) -> f64 {
        let t = ((q - self.a).dot(self.ab) * self.inv_len2).clamp(0.0, 1.0);
        (q - (self.a + self.ab * t)).length_squared()
    }

    /// The segment's bounding box grown by `r`.
    fn bounds(&self, r: f64) -> (DVec2, DVec2) {
        let b = self.a + self.ab;
        (
            self.a.min(b) - DVec2::splat(r),
            self.a.max(b) + DVec2::splat(r),
        )
    }
}

impl Region for ScreenStroke {
    fn index_bounds(&self, dims: [usize; 3]) -> Option<([usize; 3], [usize; 3])> {
        Some(([0; 3], dims.map(|d| d - 1)))
    }

    fn coverage(&self, lo: [f64; 3], hi: [f64; 3]) -> Coverage {
        let mut corners = [DVec2::ZERO; 8];
        let mut behind = 0;
        for (c, q) in corners.iter_mut().enumerate() {
            let ijk = DVec3::new(
                if c & 1 == 0 { lo[0] } else { hi[0] },
                if c & 2 == 0 { lo[1] } else { hi[1] },
                if c & 4 == 0 { lo[2] } else { hi[2] },
            );
            match self.projector.pixel(ijk) {
                Some(p) => *q = p,
                None => behind += 1,
            }
        }
        match behind {
            8 => return Coverage::None,
            1.. => return Coverage::Some,
            _ => {}
        }
        // The projection of a box in front of the eye is the convex hull of its corners; a
        // capsule is convex: all corners in one capsule put the whole box in it.
        let r2 = self.radius * self.radius;
        if self
            .capsules
            .iter()
            .any(|c| corners.iter().all(|&q| c.distance2(q) <= r2))
        {
            return Coverage::All;
        }
        let (min, max) = corners
            .iter()
            .fold((corners[0], corners[0]), |(lo, hi), &q| {
                (lo.min(q), hi.max(q))
            });
        let near = self.capsules.iter().any(|c| {
            let (smin, smax) = c.bounds(self.radius);
            smin.x <= max.x && smin.y <= max.y && min.x <= smax.x && min.y <= smax.y
        });
        if near {
            Coverage::Some
        } else {
            Coverage::None
        }
    }

    fn contains(&self, ijk: [usize; 3]) -> bool {
        let v = DVec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64);
        self.projector.pixel(v).is_some_and(|q| self.inside(q))
    }

    /// The row's view coordinates one step apart (an addition per voxel instead of the
    /// matrix product).
    fn contains_row(&self, i0: usize, i1: usize, j: usize, k: usize) -> u64 {
        let p = &self.projector;
        let base = p.to_view * DVec3::new(0.0, j as f64, k as f64) + p.view_origin;
        (i0..=i1).fold(0, |bits, i| {
            let v = base + p.to_view.x_axis * i as f64;
            let inside = p.view_pixel(v).is_some_and(|q| self.inside(q));
            bits | u64::from(inside) << (i - i0)
        })
    }
}

/// [`Camera::project`] of voxel indices, with the camera's basis and the voxel frame folded
/// into one affine map from index to view coordinates (right, up, depth).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Projector {
    to_view: DMat3,
    view_origin: DVec3,
    /// Tangent of half the field of view (perspective) or half the view height (orthographic).
    half: f64,
    perspective: bool,
    size: (f64, f64),
}

impl Projector {
    fn new(camera: &Camera, w: usize, h: usize, frame: &VoxelFrame) -> Self {
        let (perspective, half) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (true, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (false, height * 0.5),
        };
        let (r, u, f) = camera.basis();
        let rows = DMat3::from_cols(r, u, f).transpose();
        Self {
            to_view: rows * frame.direction * DMat3::from_diagonal(frame.spacing),
            view_origin: rows * (frame.origin - camera.eye),
            half,
            perspective,
            size: (w as f64, h as f64),
        }
    }

    /// The pixel position of voxel index `ijk`, `None` at or behind the eye in perspective.
    #[inline]
    fn pixel(&self, ijk: DVec3) -> Option<DVec2> {
        self.view_pixel(self.to_view * ijk + self.view_origin)
    }

    /// The pixel position of view coordinates `v`, `None` at or behind the eye in
    /// perspective.
    #[inline]
    fn view_pixel(&self, v: DVec3) -> Option<DVec2> {
        let scale = if self.perspective {
            if v.z <= 0.0 {
                return None;
            }
            v.z * self.half
        } else {
            self.half
        };
        let (w, h) = self.size;
        let (x, y) = (v.x / scale, v.y / scale);
        Some(DVec2::new((x * h / w + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h))
    }
}
