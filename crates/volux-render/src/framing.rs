//! What a scene makes visible, for a camera to frame and for a front end to warn about: the
//! world box of the cells whose values the transfer function (or an isosurface) shows, and
//! the reason when nothing is.
//!
//! Grids are tested macrocell by macrocell ([`MacrocellGrid`], the min/max blocks of
//! empty-space skipping), meshes cell by cell (a tetrahedron's values span the range of its
//! vertices'), so the box is conservative: it holds every sample a renderer can see.
use glam::DVec3;
use volux_core::sculpt::SculptMask;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::{Aabb, Camera, Grid, Projection, TetMesh};

use crate::bricked::BrickedVolume;
use crate::classify::ClassifyTable;
use crate::macrocell::MacrocellGrid;
use crate::scene::{Appearance, Scene, Volume};

/// Why a scene shows nothing.
#[derive(Clone, Debug, PartialEq)]
pub enum Invisible {
    /// Every scalar has the same value.
    Constant(f64),
    /// The transfer function's extinction is zero over the data's range and no isosurface
    /// crosses it.
    Transparent {
        /// The data's range.
        range: [f64; 2],
        /// Where the transfer function's extinction is non-zero (`None`: nowhere).
        opaque: Option<[f64; 2]>,
    },
    /// The transfer function shows values, but the clip planes and the sculpt mask remove
    /// every cell that holds them.
    CutAway,
}

impl std::fmt::Display for Invisible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::CutAway => write!(
                f,
                "the clip planes and the mask remove everything the transfer function shows"
            ),
            Self::Constant(v) => write!(
                f,
                "every value is {} (a constant field): there is no structure to show",
                round(*v)
            ),
            Self::Transparent { range, opaque } => {
                let [a, b] = range.map(round);
                write!(
                    f,
                    "the transfer function is transparent over the data range [{a}, {b}]"
                )?;
                match opaque {
                    Some(o) => write!(
                        f,
                        " (its extinction is non-zero over [{}, {}])",
                        round(o[0]),
                        round(o[1])
                    ),
                    None => write!(f, " (its extinction is zero everywhere)"),
                }
            }
        }
    }
}

/// `v` as people read it: the shortest text of its nearest `f32` (seven digits at most),
/// in exponent form when tiny or huge.
fn round(v: f64) -> String {
    let v = v as f32;
    if v != 0.0 && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The world box of what `scene` shows of `volume`: what its transfer function and
/// isosurfaces make visible ([`visible_bounds`]) and what its clip planes and sculpt mask
/// leave (grids; seed `004` ch. 4-6), so that a camera frames a cut head, not the box it was
/// cut from. Macrocells wholly on the removed side of a plane, or wholly removed by the
/// mask, are left out; the box is then cut by the planes.
pub fn visible_bounds_of(volume: &Volume, scene: &Scene) -> Result<Aabb, Invisible> {
    let (planes, mask, appearance) = (&scene.clip_planes, scene.mask.as_deref(), &scene.appearance);
    let Volume::Grid(g) = volume else {
        return visible_bounds(volume, appearance);
    };
    if planes.is_empty() && mask.is_none() {
        return visible_bounds(volume, appearance);
    }
    let range = volume.range();
    if range[0] == range[1] {
        return Err(Invisible::Constant(range[0]));
    }
    let boxed = if appearance.mip {
        cut_cells_box(g, |_, _| true, planes, mask)
    } else {
        let (table, isovalues) = classify(volume, appearance);
        cut_cells_box(g, shows(&table, &isovalues), planes, mask)
    };
    let Some(boxed) = boxed else {
        // Nothing left: the TF's own reason when it shows nothing uncut, else the cuts.
        visible_bounds(volume, appearance)?;
        return Err(Invisible::CutAway);
    };
    // The planes cut the box of the cells they cross.
    let Ok(mut voi) = ConvexVoi::from_aabb(&boxed) else {
        return Ok(boxed);
    };
    for plane in planes {
        if voi.cut(plane).is_err() {
            return Err(Invisible::CutAway);
        }
    }
    Ok(Aabb::from_points(voi.vertices().iter().copied()).unwrap_or(boxed))
}

/// Whether a value range `[lo, hi]` shows: the TF's extinction is not zero over it, or an
/// isovalue lies in it.
fn shows<'a>(table: &'a ClassifyTable, isovalues: &'a [f32]) -> impl Fn(f32, f32) -> bool + 'a {
    move |lo, hi| !table.is_transparent(lo, hi) || isovalues.iter().any(|v| (lo..=hi).contains(v))
}

/// The classification table of `appearance` over `volume`'s range, and its isovalues.
fn classify(volume: &Volume, appearance: &Appearance) -> (ClassifyTable, Vec<f32>) {
    let tf = appearance.effective_tf();
    let table = ClassifyTable::new(&tf, volume.range(), ClassifyTable::DEFAULT_SIZE);
    let isovalues = appearance
        .isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect();
    (table, isovalues)
}

/// The world box of the macrocells of `g` that hold visible values (`visible`), are not
/// wholly on the removed side of a plane and keep a voxel of `mask`; `None` when none does
/// (the whole grid's box when the macrocells do not fit in the memory budget).
fn cut_cells_box(
    g: &Grid,
    visible: impl Fn(f32, f32) -> bool,
    planes: &[ClipPlane],
    mask: Option<&SculptMask>,
) -> Option<Aabb> {
    let dims = g.dims();
    if MacrocellGrid::check_within(volux_core::limits::memory_budget(), dims).is_err() {
        return Some(g.bounds());
    }
    let cells = volux_core::with_samples!(g.samples(), |s| MacrocellGrid::build(s, dims));
    let counts = cells.counts();
    let block = cells.block();
    let index = |i: [usize; 3]| DVec3::from(i.map(|v| v as f64));
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for (m, r) in cells.ranges().iter().enumerate() {
        if !(r[0].is_finite() && visible(r[0], r[1])) {
            continue;
        }
        let c = [
            m % counts[0],
            (m / counts[0]) % counts[1],
            m / (counts[0] * counts[1]),
        ];
        let first: [usize; 3] = std::array::from_fn(|a| c[a] * block[a]);
        let last: [usize; 3] = std::array::from_fn(|a| ((c[a] + 1) * block[a]).min(dims[a] - 1));
        let corners = Aabb {
            min: index(first),
            max: index(last),
        }
        .corners()
        .map(|p| g.index_to_world(p));
        if planes
            .iter()
            .any(|p| corners.iter().all(|&q| p.distance(q) < 0.0))
        {
            continue;
        }
        if let Some(mask) = mask {
            let kept = (first[2]..=last[2]).any(|k| {
                (first[1]..=last[1]).any(|j| (first[0]..=last[0]).any(|i| mask.voxel(i, j, k)))
            });
            if !kept {
                continue;
            }
        }
        for a in 0..3 {
            lo[a] = lo[a].min(first[a]);
            hi[a] = hi[a].max(last[a]);
        }
    }
    if lo[0] == usize::MAX {
        return None;
    }
    // Macrocells are 8 voxels wide: shrink the box face by face to the voxel cells that
    // are visible and kept, so a cut or a small structure is framed to the voxel.
    let cell_shown = |c: [usize; 3]| {
        let corner = |o: usize| [c[0] + (o & 1), c[1] + ((o >> 1) & 1), c[2] + (o >> 2)];
        let samples = g.samples();
        let (mut vlo, mut vhi) = (f32::INFINITY, f32::NEG_INFINITY);
        for o in 0..8 {
            let [i, j, k] = corner(o);
            let v = samples.get_f32(i + dims[0] * (j + dims[1] * k));
            vlo = vlo.min(v);
            vhi = vhi.max(v);
        }
        if !(vlo.is_finite() && visible(vlo, vhi)) {
            return false;
        }
        if !planes.is_empty() {
            let points: [DVec3; 8] = std::array::from_fn(|o| g.index_to_world(index(corner(o))));
            if planes
                .iter()
                .any(|p| points.iter().all(|&q| p.distance(q) < 0.0))
            {
                return false;
            }
        }
        mask.is_none_or(|m| {
            (0..8).any(|o| {
                let [i, j, k] = corner(o);
                m.voxel(i, j, k)
            })
        })
    };
    if dims.iter().all(|&d| d > 1) {
        tighten(&mut lo, &mut hi, cell_shown);
    }
    let visible = Aabb {
        min: index(lo),
        max: index(hi),
    };
    Aabb::from_points(visible.corners().map(|c| g.index_to_world(c)))
}

/// Shrinks the voxel index box `lo..=hi` (cells `lo..hi` per axis) face by face while the
/// layer of cells on a face has none that `shown` (the cell with that lowest corner) keeps.
/// Leaves the box as it is when no cell is shown.
fn tighten(lo: &mut [usize; 3], hi: &mut [usize; 3], shown: impl Fn([usize; 3]) -> bool) {
    let layer_shown = |lo: &[usize; 3], hi: &[usize; 3], axis: usize, at: usize| {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        (lo[u]..hi[u].max(lo[u] + 1)).any(|a| {
            (lo[v]..hi[v].max(lo[v] + 1)).any(|b| {
                let mut c = [0; 3];
                c[axis] = at;
                c[u] = a;
                c[v] = b;
                shown(c)
            })
        })
    };
    for axis in 0..3 {
        let (start, end) = (lo[axis], hi[axis]);
        while lo[axis] + 1 < hi[axis] && !layer_shown(lo, hi, axis, lo[axis]) {
            lo[axis] += 1;
        }
        while hi[axis] > lo[axis] + 1 && !layer_shown(lo, hi, axis, hi[axis] - 1) {
            hi[axis] -= 1;
        }
        if lo[axis] + 1 == hi[axis] && !layer_shown(lo, hi, axis, lo[axis]) {
            // Nothing shown after all (the macrocell ranges were conservative): as it was.
            (lo[axis], hi[axis]) = (start, end);
        }
    }
}

/// The world box of what `appearance` makes visible in `volume` (MIP shows the whole
/// volume), or why nothing is. Clip planes and masks are not applied: see
/// [`visible_bounds_of`].
pub fn visible_bounds(volume: &Volume, appearance: &Appearance) -> Result<Aabb, Invisible> {
    let range = volume.range();
    if range[0] == range[1] {
        return Err(Invisible::Constant(range[0]));
    }
    if appearance.mip {
        return Ok(volume.bounds());
    }
    let (table, isovalues) = classify(volume, appearance);
    let visible = shows(&table, &isovalues);
    let found = match volume {
        Volume::Grid(g) => cut_cells_box(g, visible, &[], None),
        Volume::Mesh(m) => mesh_box(m, visible),
        Volume::Bricked(b, _) => bricked_box(b, visible),
    };
    found.ok_or_else(|| Invisible::Transparent {
        range,
        opaque: opaque_span(&appearance.effective_tf().resolved(range)),
    })
}

/// The world box of the voxel cells of a bricked volume's full level that hold visible
/// values, as [`cut_cells_box`] finds it in a grid held whole, so that a store framed out of
/// core is framed as the same data in memory: the chunks whose recorded ranges (widened by
/// their neighbours' first samples, [`BrickedVolume::chunk_cells`]) are visible give the
/// box, which [`tighten`] shrinks to the voxel cells, reading the full level's samples
/// through its brick cache (the chunks on the box's faces, within the memory budget). The
/// whole box when the store records no chunk ranges (a foreign store: finding them would
/// read it all); `None` when no chunk is visible.
fn bricked_box(b: &BrickedVolume, visible: impl Fn(f32, f32) -> bool) -> Option<Aabb> {
    let (Some(cells), Some(cache)) = (b.chunk_cells(0), b.cache(0)) else {
        return Some(b.bounds());
    };
    let layout = cache.layout().clone();
    let (dims, chunk) = (layout.dims, layout.chunk);
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for (m, r) in cells.ranges().iter().enumerate() {
        if !(r[0].is_finite() && visible(r[0], r[1])) {
            continue;
        }
        let c = layout.chunk_coords(m);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a] * chunk[a]);
            hi[a] = hi[a].max(((c[a] + 1) * chunk[a]).min(dims[a] - 1));
        }
    }
    if lo[0] == usize::MAX {
        return None;
    }
    // A sample through the cache; a chunk that cannot be read counts as visible (the box
    // stays larger, never cuts data away).
    let sample = |v: [usize; 3]| -> Option<f32> {
        let c: [usize; 3] = std::array::from_fn(|a| v[a] / chunk[a]);
        cache.get(c).ok().map(|brick| brick.at(v[0], v[1], v[2]))
    };
    let cell_shown = |c: [usize; 3]| {
        let (mut vlo, mut vhi) = (f32::INFINITY, f32::NEG_INFINITY);
        for o in 0..8 {
            let corner = [c[0] + (o & 1), c[1] + ((o >> 1) & 1), c[2] + (o >> 2)];
            let Some(v) = sample(corner) else {
                return true;
            };
            vlo = vlo.min(v);
            vhi = vhi.max(v);
        }
        vlo.is_finite() && visible(vlo, vhi)
    };
    if dims.iter().all(|&d| d > 1) {
        tighten(&mut lo, &mut hi, cell_shown);
    }
    let (origin, spacing) = (layout.origin_vec(), layout.spacing_vec());
    let at = |i: [usize; 3]| origin + spacing * DVec3::from(i.map(|v| v as f64));
    Some(Aabb {
        min: at(lo).min(at(hi)),
        max: at(lo).max(at(hi)),
    })
}

/// The span of the breakpoint intervals where the extinction is non-zero.
fn opaque_span(tf: &volux_core::TransferFunction) -> Option<[f64; 2]> {
    let bp = tf.breakpoints();
    let positive = |s: f64| tf.tau_per_world(s) > 0.0;
    let lo = bp.iter().copied().find(|&s| positive(s))?;
    let hi = bp.iter().rev().copied().find(|&s| positive(s))?;
    // Extend to the zero breakpoints around them, where the ramp starts and ends.
    let before = bp.iter().rev().copied().find(|&s| s < lo).unwrap_or(lo);
    let after = bp.iter().copied().find(|&s| s > hi).unwrap_or(hi);
    Some([before, after])
}

/// The box of the visible tetrahedra of `m`.
fn mesh_box(m: &TetMesh, visible: impl Fn(f32, f32) -> bool) -> Option<Aabb> {
    let (p, s) = (m.positions(), m.scalars());
    let points = m.tets().iter().flat_map(|t| {
        let v = t.map(|i| s[i as usize]);
        let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let keep = visible(lo, hi);
        t.iter()
            .filter(move |_| keep)
            .map(|&i| p[i as usize].as_dvec3())
    });
    Aabb::from_points(points)
}

/// `camera` moved so that the eight corners of `bounds` fill the image of aspect `aspect`
/// (width / height) to [`FIT_MARGIN`] on the tighter side, centred, then zoomed by `zoom`:
/// perspective cameras move along and across the view (the target shifts so that the
/// projected box is centred), orthographic ones are resized. The view direction and up stay;
/// the bounding sphere a plain fit uses leaves a box a third of the frame.
pub fn fit_to_box(camera: &Camera, bounds: &Aabb, aspect: f64, zoom: f64) -> Camera {
    let (right, up, forward) = camera.basis();
    let corners = bounds.corners().into_iter();
    let mut fitted = *camera;
    match camera.projection {
        Projection::Perspective { fov_y_deg } => {
            let ty = (fov_y_deg.to_radians() * 0.5).tan() * FIT_MARGIN;
            let tx = ty * aspect;
            // The distance behind `target` at which every corner fits: |x| / depth <= tx and
            // |y| / depth <= ty, depth = distance + z.
            let distance = |target: DVec3| {
                corners
                    .clone()
                    .map(|p| {
                        let d = p - target;
                        let (x, y, z) = (d.dot(right), d.dot(up), d.dot(forward));
                        (x.abs() / tx).max(y.abs() / ty) - z
                    })
                    .fold(0.0f64, f64::max)
            };
            // Perspective makes the near side larger: shift the target across the view so
            // that the projected box is centred, then fit again (a few rounds converge).
            let mut target = camera.target;
            for _ in 0..4 {
                let dist = distance(target);
                if !(dist > 0.0 && dist.is_finite()) {
                    break;
                }
                let eye = target - forward * dist;
                let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
                for p in corners.clone() {
                    let d = p - eye;
                    let depth = d.dot(forward).max(1e-12);
                    let t = [d.dot(right) / depth, d.dot(up) / depth];
                    lo = [lo[0].min(t[0]), lo[1].min(t[1])];
                    hi = [hi[0].max(t[0]), hi[1].max(t[1])];
                }
                let centre = [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5];
                target += (right * centre[0] + up * centre[1]) * dist;
            }
            let dist = distance(target);
            if dist > 0.0 && dist.is_finite() {
                fitted.target = target;
                fitted.eye = target - forward * (dist / zoom);
            }
        }
        Projection::Orthographic { .. } => {
            let half = corners
                .map(|p| {
                    let d = p - camera.target;
                    (d.dot(right).abs() / aspect).max(d.dot(up).abs())
                })
                .fold(0.0f64, f64::max);
            if half > 0.0 && half.is_finite() {
                fitted.projection = Projection::Orthographic {
                    height: 2.0 * half / FIT_MARGIN / zoom,
                };
            }
        }
    }
    fitted
}

/// The share of the image a fitted box fills on its tighter side.
pub const FIT_MARGIN: f64 = 0.92;

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::grid::{Buffer, Samples};
    use volux_core::TransferFunction;

    fn tf(json: &str) -> TransferFunction {
        TransferFunction::from_json(json).unwrap()
    }

    /// A sphere's distance field: values below 10 lie in a ball of radius 10 around the centre.
    fn grid(n: usize, values: Vec<f32>) -> Volume {
        let samples = Samples::F32(Buffer::owned(values));
        Volume::from(Grid::new([n, n, n], [1.0; 3], [0.0; 3], samples).unwrap())
    }

    fn sphere() -> Volume {
        let n = 64usize;
        let values: Vec<f32> = (0..n * n * n)
            .map(|i| {
                let p = DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64);
                (p - DVec3::splat(31.5)).length() as f32
            })
            .collect();
        grid(n, values)
    }

    #[test]
    fn the_box_holds_the_visible_ball_and_little_more() {
        let v = sphere();
        let a = Appearance::new(tf(
            r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1], [10, 1], [10.5, 0]]}"#,
        ));
        let b = visible_bounds(&v, &a).unwrap();
        for axis in 0..3 {
            // The ball spans 21.5..41.5; macrocells of 8 voxels round that out to 16..48.
            assert!(b.min[axis] <= 21.5 && b.min[axis] >= 16.0, "{b:?}");
            assert!(b.max[axis] >= 41.5 && b.max[axis] <= 48.0, "{b:?}");
        }
        let whole = Appearance {
            mip: true,
            ..a.clone()
        };
        assert_eq!(visible_bounds(&v, &whole).unwrap(), v.bounds());
    }

    #[test]
    fn a_transparent_tf_and_a_constant_field_say_why() {
        let v = sphere();
        let far = Appearance::new(tf(
            r#"{"color": [[0, 1, 1, 1]], "extinction": [[100, 0], [200, 1], [300, 0]]}"#,
        ));
        let e = visible_bounds(&v, &far).unwrap_err();
        let Invisible::Transparent { opaque, .. } = &e else {
            panic!("{e:?}")
        };
        assert_eq!(*opaque, Some([100.0, 300.0]));
        assert!(e.to_string().contains("[100, 300]"), "{e}");
        // An isosurface inside the range makes it visible again.
        let mut iso = far.clone();
        iso.isosurfaces =
            crate::isosurface::Isosurfaces::new(vec![
                crate::isosurface::parse_iso("5:1,1,1,1").unwrap()
            ])
            .unwrap();
        assert!(visible_bounds(&v, &iso).is_ok());
        let flat = grid(4, vec![2.5; 64]);
        let e = visible_bounds(&flat, &far).unwrap_err();
        assert_eq!(e, Invisible::Constant(2.5));
        assert!(e.to_string().contains("every value is 2.5"), "{e}");
    }

    #[test]
    fn mesh_boxes_keep_the_visible_cells() {
        let v = Volume::from(volux_core::synth::generate_mesh("tets-smooth", 2000).unwrap());
        let r = v.range();
        let mid = 0.5 * (r[0] + r[1]);
        let a = Appearance::new(tf(&format!(
            r#"{{"color": [[0, 1, 1, 1]], "extinction": [[{mid}, 0], [{}, 1]]}}"#,
            r[1] + 1.0
        )));
        let b = visible_bounds(&v, &a).unwrap();
        let all = v.bounds();
        assert!(
            b.diagonal() < all.diagonal() && b.diagonal() > 0.0,
            "{b:?} {all:?}"
        );
    }

    #[test]
    fn a_fitted_box_fills_the_frame_to_the_margin() {
        let b = Aabb {
            min: DVec3::new(-1.0, -2.0, -0.5),
            max: DVec3::new(3.0, 2.0, 0.5),
        };
        for (projection, aspect) in [
            ("perspective", 1.0),
            ("perspective", 2.0),
            ("orthographic", 0.5),
        ] {
            let spec = volux_core::CameraSpec {
                projection: Some(projection.into()),
                azimuth: Some(30.0),
                elevation: Some(20.0),
                ..Default::default()
            };
            let cam = fit_to_box(&spec.resolve(&b).unwrap(), &b, aspect, 1.0);
            let (w, h) = ((200.0 * aspect) as usize, 200);
            let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
            for p in b.corners() {
                let (x, y, _) = cam.project(p, w, h);
                lo = [lo[0].min(x), lo[1].min(y)];
                hi = [hi[0].max(x), hi[1].max(y)];
            }
            // Inside the image, and filling the margin on the tighter side (the box is
            // centred on the target, so its projection is about centred too).
            assert!(lo[0] >= 0.0 && lo[1] >= 0.0, "{projection} {lo:?}");
            assert!(
                hi[0] <= w as f64 && hi[1] <= h as f64,
                "{projection} {hi:?}"
            );
            let fill = ((hi[0] - lo[0]) / w as f64).max((hi[1] - lo[1]) / h as f64);
            assert!(
                fill > 0.8 && fill <= 1.0,
                "{projection} aspect {aspect}: fill {fill}"
            );
        }
    }
}
