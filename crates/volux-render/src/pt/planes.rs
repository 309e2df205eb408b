//! The plane form of a tetrahedron's fragments: each pixel's entry and exit from the cell's
//! face planes, instead of the thick vertex and its fan (seed `000` §4.1 and §4.3, seed
//! `002` §3 and §4.3 compute the same `(s_f, s_b, l)` by interpolating from the thick vertex).
//!
//! # Screen space is affine for the cell
//!
//! Take screen coordinates `(x, y)` and `w = 1 / z` (perspective, `z` the view depth) or
//! `w = z` (orthographic). The projection `(X, Y, Z) -> (x, y, w)` is projective (affine for
//! orthographic), so it maps planes to planes: a tetrahedron stays a tetrahedron in
//! `(x, y, w)`, and each of its faces is a plane `w_j(x, y)` unless it is seen edge-on. The
//! cell's field `s` is linear in world space, so `σ = (s - s_0) w` (perspective) or
//! `σ = s - s_0` (orthographic) is affine in `(x, y, w)`: `σ = α dx + β dy + γ (w - w_0)`,
//! fitted exactly through the four projected vertices (`dx, dy` from vertex 0).
//!
//! # Entry and exit
//!
//! The cell is the intersection of the half-spaces of its faces, so a pixel's ray inside its
//! projection enters at the farthest of the front faces' planes and leaves at the nearest of
//! the back ones. The front faces' projections tile the cell's projection, and so do the back
//! faces' (a closed surface covers every point of its projection twice), so drawing the
//! faces of the smaller side (one triangle for a projected triangle, two for a quadrilateral)
//! with the top-left rule covers each pixel of the projection exactly once, as the fan does;
//! within face `j`'s triangle that side's crossing is `j`'s plane, and the other side's is the
//! extreme of its one to three planes. Which faces are in front is decided by the exact
//! fixed-point signed areas of the projected faces (the two sides of the projection) and the
//! sign of the cell's volume in `(x, y, w)`; a wrong volume sign (only for nearly flat cells)
//! swaps entry and exit, which gives a zero length and a transparent fragment.
use super::project::SUBPIXEL;
use super::raster::fixed;

/// An affine function of the pixel centre: `c + a dx + b dy`, with `(dx, dy)` from the
/// cell's origin (its vertex 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Plane {
    /// Increment per column.
    pub a: f32,
    /// Increment per row.
    pub b: f32,
    /// Value at the origin.
    pub c: f32,
}

impl Plane {
    /// The value at offset `(dx, dy)` from the origin.
    #[inline(always)]
    pub fn at(&self, dx: f32, dy: f32) -> f32 {
        self.c + self.a * dx + self.b * dy
    }
}

/// One face triangle to draw and what its pixels need: the drawn face's plane (`known`) and
/// the other side's planes (`others`, padded by repetition to three).
#[derive(Clone, Copy, Debug)]
pub struct FaceDraw {
    /// Fixed-point positions of the triangle's vertices.
    pub tri: [[i64; 2]; 3],
    /// `w` on the drawn face.
    pub known: Plane,
    /// Whether the drawn face is a front face (its crossing is the entry).
    pub known_front: bool,
    /// `w` on the other side's faces.
    pub others: [Plane; 3],
}

/// A cell's planes in screen space (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct CellPlanes {
    /// The origin: vertex 0's screen position.
    pub origin: [f32; 2],
    /// `w` (`1 / z` or `z`) at vertex 0.
    pub w0: f32,
    /// `α dx + β dy` of `σ`.
    pub sigma: Plane,
    /// `γ` of `σ`.
    pub gamma: f32,
    /// The scalar at vertex 0, added back to `σ / w` (or `σ`).
    pub offset: f32,
    /// `w` on each face `j` (opposite vertex `j`); meaningless for an edge-on face.
    pub faces: [Plane; 4],
    /// Bit `j`: face `j` faces the eye.
    pub front: u8,
    /// Bit `j`: face `j` faces away.
    pub back: u8,
    /// Fixed-point vertex positions.
    pub q: [[i64; 2]; 4],
}

/// The vertices of face `j` (opposite vertex `j`), in increasing order.
const FACE: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Twice the signed area of `a b c` in fixed point (exact for snapped positions).
#[inline(always)]
fn cross(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

impl CellPlanes {
    /// The planes of the cell with projected vertices `screen` (`[x, y, depth]`) and
    /// `scalars`; `None` when it is flat in `(x, y, w)` or its projection has no area
    /// (nothing to draw).
    #[inline]
    pub fn new(screen: &[[f32; 3]; 4], scalars: &[f32; 4], perspective: bool) -> Option<Self> {
        let q = screen.map(|v| fixed([v[0], v[1]]));
        let w = screen.map(|v| {
            let z = f64::from(v[2]);
            if perspective {
                1.0 / z
            } else {
                z
            }
        });
        let (ox, oy) = (f64::from(screen[0][0]), f64::from(screen[0][1]));
        let dv: [[f64; 3]; 4] = std::array::from_fn(|i| {
            [
                f64::from(screen[i][0]) - ox,
                f64::from(screen[i][1]) - oy,
                w[i] - w[0],
            ]
        });
        let d = |i: usize| dv[i];
        let m = [d(1), d(2), d(3)];
        let s0 = f64::from(scalars[0]);
        let r = [1, 2, 3].map(|i| {
            let ds = f64::from(scalars[i]) - s0;
            if perspective {
                ds * w[i]
            } else {
                ds
            }
        });
        // M^-1 = [m2 x m3, m3 x m1, m1 x m2] / det, as columns.
        let adj = [cross3(m[1], m[2]), cross3(m[2], m[0]), cross3(m[0], m[1])];
        let det = dot3(m[0], adj[0]);
        if !(det.is_finite() && det != 0.0) {
            return None;
        }
        let inv = 1.0 / det;
        let solved: [f64; 3] =
            std::array::from_fn(|k| (adj[0][k] * r[0] + adj[1][k] * r[1] + adj[2][k] * r[2]) * inv);
        let (alpha, beta, gamma) = (solved[0], solved[1], solved[2]);
        let sign = if det > 0.0 { 1 } else { -1 };
        // (x, y, w): w grows toward the eye under perspective, away from it otherwise.
        let toward_eye = if perspective { sign } else { -sign };
        let (mut front, mut back) = (0u8, 0u8);
        let mut faces = [Plane::default(); 4];
        for (j, face) in faces.iter_mut().enumerate() {
            let [i, k, l] = FACE[j];
            // The outward orientation of face j is (-1)^j (i, k, l).
            let area = cross(q[i], q[k], q[l]);
            let outward = if j % 2 == 0 { area } else { -area };
            match (outward.signum() * toward_eye).cmp(&0) {
                std::cmp::Ordering::Greater => front |= 1 << j,
                std::cmp::Ordering::Less => back |= 1 << j,
                std::cmp::Ordering::Equal => continue,
            }
            *face = face_plane([d(i), d(k), d(l)], area, w[0]);
        }
        if front == 0 || back == 0 {
            return None;
        }
        Some(Self {
            origin: [screen[0][0], screen[0][1]],
            w0: w[0] as f32,
            sigma: Plane {
                a: alpha as f32,
                b: beta as f32,
                c: 0.0,
            },
            gamma: gamma as f32,
            offset: scalars[0],
            faces,
            front,
            back,
            q,
        })
    }

    /// The face triangles to draw (those of the side with fewer faces) with the planes their
    /// pixels need, in face order.
    pub fn draws(&self) -> impl Iterator<Item = FaceDraw> + '_ {
        let known_front = self.front.count_ones() <= self.back.count_ones();
        let (drawn, other) = if known_front {
            (self.front, self.back)
        } else {
            (self.back, self.front)
        };
        let mut others = [Plane::default(); 3];
        let mut n = 0;
        for j in (0..4).filter(|j| other & (1 << j) != 0) {
            others[n] = self.faces[j];
            n += 1;
        }
        for k in n..3 {
            others[k] = others[0];
        }
        (0..4)
            .filter(move |j| drawn & (1 << j) != 0)
            .map(move |j| FaceDraw {
                tri: FACE[j].map(|i| self.q[i]),
                known: self.faces[j],
                known_front,
                others,
            })
    }
}

/// The cross product `a x b`.
#[inline(always)]
fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The dot product.
#[inline(always)]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The plane `w(dx, dy)` through three points `(dx, dy, w - w0)` (offsets from the origin)
/// whose projection has the fixed-point doubled area `area` (non-zero).
#[inline(always)]
fn face_plane(p: [[f64; 3]; 3], area: i64, w0: f64) -> Plane {
    let (u, v) = (sub(p[1], p[0]), sub(p[2], p[0]));
    // The fixed-point area is exact: SUBPIXEL^2 times the area in pixels.
    let inv = f64::from(SUBPIXEL * SUBPIXEL) / area as f64;
    let a = (u[2] * v[1] - v[2] * u[1]) * inv;
    let b = (u[0] * v[2] - v[0] * u[2]) * inv;
    let c = w0 + p[0][2] - a * p[0][0] - b * p[0][1];
    Plane {
        a: a as f32,
        b: b as f32,
        c: c as f32,
    }
}

#[inline(always)]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg(test)]
mod tests;
