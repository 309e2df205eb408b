//! What a scene makes visible, for a camera to frame and for a front end to warn about: the
//! world box of the cells whose values the transfer function (or an isosurface) shows, and
//! the reason when nothing is.
//!
//! Grids are tested macrocell by macrocell ([`MacrocellGrid`], the min/max blocks of
//! empty-space skipping), meshes cell by cell (a tetrahedron's values span the range of its
//! vertices'), so the box is conservative: it holds every sample a renderer can see.
use glam::DVec3;
use volux_core::{Aabb, Grid, TetMesh};

use crate::classify::ClassifyTable;
use crate::macrocell::MacrocellGrid;
use crate::scene::{Appearance, Volume};

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
}

impl std::fmt::Display for Invisible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
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

/// `v` as people read it: the shortest text of its nearest `f32` (seven digits at most).
fn round(v: f64) -> String {
    format!("{}", v as f32)
}

/// The world box of what `appearance` makes visible in `volume` (MIP shows the whole
/// volume), or why nothing is.
pub fn visible_bounds(volume: &Volume, appearance: &Appearance) -> Result<Aabb, Invisible> {
    let range = volume.range();
    if range[0] == range[1] {
        return Err(Invisible::Constant(range[0]));
    }
    if appearance.mip {
        return Ok(volume.bounds());
    }
    let tf = appearance.effective_tf();
    let table = ClassifyTable::new(&tf, range, ClassifyTable::DEFAULT_SIZE);
    let isovalues: Vec<f32> = appearance
        .isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect();
    let visible = |lo: f32, hi: f32| {
        !table.is_transparent(lo, hi) || isovalues.iter().any(|v| (lo..=hi).contains(v))
    };
    let found = match volume {
        Volume::Grid(g) => grid_box(g, visible),
        Volume::Mesh(m) => mesh_box(m, visible),
    };
    found.ok_or_else(|| Invisible::Transparent {
        range,
        opaque: opaque_span(&tf.resolved(range)),
    })
}

/// The span of the breakpoint intervals where the extinction is non-zero.
fn opaque_span(tf: &volux_core::TransferFunction) -> Option<[f64; 2]> {
    let bp = tf.breakpoints();
    let positive = |s: f64| tf.tau_per_world(s) > 0.0;
    let lo = bp.iter().copied().find(|&s| positive(s))?;
    let hi = bp.iter().rev().copied().find(|&s| positive(s))?;
    // Extend to the zero breakpoints around them, where the ramp starts and ends.
    let before = bp.iter().copied().filter(|&s| s < lo).last().unwrap_or(lo);
    let after = bp.iter().copied().find(|&s| s > hi).unwrap_or(hi);
    Some([before, after])
}

/// The box of the visible macrocells of `g`.
fn grid_box(g: &Grid, visible: impl Fn(f32, f32) -> bool) -> Option<Aabb> {
    let dims = g.dims();
    let cells = volux_core::with_samples!(g.samples(), |s| MacrocellGrid::build(s, dims));
    let counts = cells.counts();
    let (origin, spacing) = (g.origin(), g.spacing());
    let corner = |i: [usize; 3]| origin + DVec3::from(i.map(|v| v as f64)) * spacing;
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
        for a in 0..3 {
            lo[a] = lo[a].min(c[a] * MacrocellGrid::BLOCK);
            hi[a] = hi[a].max(((c[a] + 1) * MacrocellGrid::BLOCK).min(dims[a] - 1));
        }
    }
    (lo[0] != usize::MAX).then(|| Aabb {
        min: corner(lo),
        max: corner(hi),
    })
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
}
