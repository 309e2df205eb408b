//! The view-dependent part of the per-tetrahedron pass: vertex projection and the screen
//! geometry of every tetrahedron's fan (seed `000` §4.1, seed `002` §4.1).
//!
//! # Vertex projection
//!
//! [`ViewProjection::new`] projects every mesh vertex once per view (a mesh has about a fifth
//! as many vertices as tetrahedra, so this is cheaper than projecting four vertices per
//! tetrahedron as the seeds' first pass does). Screen positions are *snapped* to a grid of
//! `1/SUBPIXEL` pixel and stored exactly in `f32`: the orientation tests of
//! [`classify`](super::classify), the fixed-point edge functions of the rasterizer and the
//! attribute interpolation all see the same coordinates, so a face shared by two tetrahedra
//! is the same triangle for both (no cracks, no double blending), and nearly degenerate
//! tetrahedra classify the same way in every frame in which their snapped vertices do not
//! move (no flicker).
//!
//! # Thick vertex attributes
//!
//! [`fan_vertices`] turns the classification of a tetrahedron into the five points of its fan
//! with, at each, the front and back depth, scalar and gradient of the ray through it. The
//! thin vertices have equal front and back. The thick vertex's front and back points come from
//! the screen-space parameters of [`ThickKind`], converted to 3D with the vertices' view
//! depths: under a perspective projection `1/z` is linear in screen space, so a point at
//! screen-space weights `β_i` of vertices at depths `z_i` has depth `z = 1 / Σ β_i / z_i` and
//! scalar `s = z Σ β_i s_i / z_i` (exact for the linear field of the cell); under an
//! orthographic projection the weights are the 3D ones. The seeds interpolate `s_f`, `s_b` and
//! `l` linearly in screen space, which is exact only in orthographic views; here the
//! rasterizer interpolates front and back attributes perspective-correctly and measures `l`
//! along each pixel's own ray.
use glam::{DVec2, DVec3, Vec3};
use volux_core::{camera::Projection, Camera, TetMesh};

use super::classify::{Classification, ThickKind};

/// Sub-pixel grid of snapped screen positions (8 bits, as GPU rasterizers).
pub const SUBPIXEL: f32 = 256.0;

/// Vertices farther than this many pixels from the image (the guard band) or closer to the
/// eye than [`NEAR_FRACTION`] of the scene size are not projected; tetrahedra using them are
/// skipped and counted as clipped.
pub const GUARD_BAND: f32 = 1.0e6;

/// Near-plane distance as a fraction of the distance from the eye to the target.
pub const NEAR_FRACTION: f64 = 1.0e-4;

/// Every mesh vertex projected for one view: snapped pixel coordinates (row 0 at the top,
/// pixel centres at `+0.5`) and view depth (distance along the camera's forward axis).
#[derive(Clone, Debug)]
pub struct ViewProjection {
    /// `[x, y, depth]` per vertex; `x` is NaN for vertices that could not be projected.
    pub vertices: Vec<[f32; 3]>,
    /// Whether the projection is perspective (depth-dependent attribute interpolation).
    pub perspective: bool,
    /// `tan(fov_y / 2)` of a perspective camera (1 for orthographic).
    pub tan_half_fov: f64,
    /// Image size the projection was made for.
    pub size: (usize, usize),
}

impl ViewProjection {
    /// Projects the mesh's vertices for `camera` and a `width x height` image, in parallel.
    pub fn new(mesh: &TetMesh, camera: &Camera, width: usize, height: usize) -> Self {
        use rayon::prelude::*;
        let (r, u, f) = camera.basis();
        let eye = camera.eye;
        let near = (camera.target - camera.eye).length() * NEAR_FRACTION;
        let aspect = width as f64 / height as f64;
        let (perspective, scale) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (true, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (false, height * 0.5),
        };
        let (w, h) = (width as f64, height as f64);
        let vertices = mesh
            .positions()
            .par_iter()
            .with_min_len(4096)
            .map(|p| {
                let d = p.as_dvec3() - eye;
                let depth = d.dot(f);
                let div = if perspective { depth * scale } else { scale };
                if perspective && (depth.is_nan() || depth <= near) {
                    return [f32::NAN, f32::NAN, depth as f32];
                }
                let (x, y) = (d.dot(r) / div, d.dot(u) / div);
                let px = (x / aspect + 1.0) * 0.5 * w;
                let py = (1.0 - y) * 0.5 * h;
                [snap(px), snap(py), depth as f32]
            })
            .collect();
        Self {
            vertices,
            perspective,
            tan_half_fov: if perspective { scale } else { 1.0 },
            size: (width, height),
        }
    }

    /// The four projected vertices of `tet`, or `None` if one could not be projected.
    #[inline]
    pub fn tet(&self, tet: &[u32; 4]) -> Option<[[f32; 3]; 4]> {
        let v = tet.map(|i| self.vertices.get(i as usize).copied());
        let v = [v[0]?, v[1]?, v[2]?, v[3]?];
        v.iter().all(|p| p[0].is_finite()).then_some(v)
    }

    /// Bytes held per vertex.
    pub const BYTES_PER_VERTEX: usize = 12;
}

/// Snaps a pixel coordinate to the sub-pixel grid; NaN outside the guard band.
#[inline]
fn snap(x: f64) -> f32 {
    let g = f64::from(GUARD_BAND);
    if x.is_finite() && x.abs() <= g {
        ((x * f64::from(SUBPIXEL)).round() / f64::from(SUBPIXEL)) as f32
    } else {
        f32::NAN
    }
}

/// Snaps a computed point (the class 2 thick vertex) like the vertices.
#[inline]
pub fn snap_point(p: DVec2) -> [f32; 2] {
    [snap(p.x), snap(p.y)]
}

/// One point of a tetrahedron's fan with what the ray through it sees.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FanVertex {
    /// Snapped screen position.
    pub xy: [f32; 2],
    /// View depth of the front point.
    pub z_f: f32,
    /// Scalar at the front point.
    pub s_f: f32,
    /// View depth of the back point.
    pub z_b: f32,
    /// Scalar at the back point.
    pub s_b: f32,
    /// Field gradient at the front point (zero when gradients are not needed).
    pub g_f: Vec3,
    /// Field gradient at the back point.
    pub g_b: Vec3,
}

/// A point of the tetrahedron at screen-space weights `w` of its vertices `idx`.
#[derive(Clone, Copy, Debug)]
struct Point {
    z: f32,
    s: f32,
    g: Vec3,
}

/// What the fan construction needs of one tetrahedron.
#[derive(Clone, Copy, Debug)]
pub struct TetVertices<'a> {
    /// Projected `[x, y, depth]` of the four vertices.
    pub screen: [[f32; 3]; 4],
    /// Scalars of the four vertices.
    pub scalars: [f32; 4],
    /// Gradients of the four vertices (all zero when not needed).
    pub gradients: [Vec3; 4],
    /// Perspective or orthographic.
    pub perspective: bool,
    /// Marker lifetime for borrowed callers.
    pub _marker: std::marker::PhantomData<&'a ()>,
}

impl TetVertices<'_> {
    /// The point at screen-space weights `w` over the vertices `idx` (weights sum to 1).
    #[inline(always)]
    fn point<const N: usize, const GRAD: bool>(&self, idx: [u8; N], w: [f64; N]) -> Point {
        let mut inv_z = 0.0f64;
        let mut s = 0.0f64;
        let mut g = DVec3::ZERO;
        let mut z = 0.0f64;
        for (&i, &wi) in idx.iter().zip(&w) {
            let i = usize::from(i) & 3;
            let zi = f64::from(self.screen[i][2]);
            let k = if self.perspective { wi / zi } else { wi };
            inv_z += k;
            z += wi * zi;
            s += k * f64::from(self.scalars[i]);
            if GRAD {
                g += k * self.gradients[i].as_dvec3();
            }
        }
        if self.perspective {
            if inv_z.is_nan() || inv_z <= 0.0 {
                inv_z = f64::MIN_POSITIVE;
            }
            z = 1.0 / inv_z;
            Point {
                z: z as f32,
                s: (s * z) as f32,
                g: (g * z).as_vec3(),
            }
        } else {
            Point {
                z: z as f32,
                s: s as f32,
                g: g.as_vec3(),
            }
        }
    }

    fn vertex(&self, i: u8) -> Point {
        let i = usize::from(i) & 3;
        Point {
            z: self.screen[i][2],
            s: self.scalars[i],
            g: self.gradients[i],
        }
    }
}

/// The five fan points `[v_0, v_1, v_2, v_3, v_t]` of a classified tetrahedron; `None` when
/// the projection is degenerate (nothing to draw).
pub fn fan_vertices(tet: &TetVertices<'_>, c: &Classification) -> Option<[FanVertex; 5]> {
    fan_vertices_with::<true>(tet, c)
}

/// [`fan_vertices`]; with `GRAD = false` the gradients are taken as zero without being read
/// (the other attributes are the same).
#[inline(always)]
pub fn fan_vertices_with<const GRAD: bool>(
    tet: &TetVertices<'_>,
    c: &Classification,
) -> Option<[FanVertex; 5]> {
    let thick = c.thick?;
    let (a, b) = match thick.kind {
        ThickKind::Interior {
            vertex,
            face,
            barycentric,
        } => (tet.vertex(vertex), tet.point::<3, GRAD>(face, barycentric)),
        ThickKind::Crossing { edges, params } => {
            let [[e0, e1], [e2, e3]] = edges;
            let (u, v) = (params[0], params[1]);
            (
                tet.point::<2, GRAD>([e0, e1], [1.0 - u, u]),
                tet.point::<2, GRAD>([e2, e3], [1.0 - v, v]),
            )
        }
        ThickKind::OnEdge {
            vertex, edge, t, ..
        } => (tet.vertex(vertex), tet.point::<2, GRAD>(edge, [1.0 - t, t])),
        ThickKind::Coincident { pair } => (tet.vertex(pair[0]), tet.vertex(pair[1])),
    };
    let (front, back) = if a.z <= b.z { (a, b) } else { (b, a) };
    let thin = |i: usize| {
        let [x, y, z] = tet.screen[i];
        FanVertex {
            xy: [x, y],
            z_f: z,
            s_f: tet.scalars[i],
            z_b: z,
            s_b: tet.scalars[i],
            g_f: tet.gradients[i],
            g_b: tet.gradients[i],
        }
    };
    let xy = match thick.kind {
        ThickKind::Crossing { .. } => snap_point(thick.position),
        _ => [thick.position.x as f32, thick.position.y as f32],
    };
    Some([
        thin(0),
        thin(1),
        thin(2),
        thin(3),
        FanVertex {
            xy,
            z_f: front.z,
            s_f: front.s,
            z_b: back.z,
            s_b: back.s,
            g_f: front.g,
            g_b: back.g,
        },
    ])
}

/// The screen positions of a tetrahedron's projected vertices, as the classifier wants them.
#[inline]
pub fn screen_points(screen: &[[f32; 3]; 4]) -> [DVec2; 4] {
    screen.map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])))
}

/// The view depth of a tetrahedron's centroid: the mean of its vertices' depths (depth is
/// affine, so this is exactly the centroid's depth), the key of the seeds' centroid sort.
#[inline]
pub fn centroid_depth(screen: &[[f32; 3]; 4]) -> f32 {
    0.25 * (screen[0][2] + screen[1][2] + screen[2][2] + screen[3][2])
}

/// The secant of the angle between a pixel's ray and the forward axis (1 for orthographic):
/// a segment between view depths `z_f` and `z_b` along that ray has length
/// `(z_b - z_f) * secant`.
#[inline]
pub fn pixel_secant(proj: &ViewProjection, px: f32, py: f32) -> f32 {
    if !proj.perspective {
        return 1.0;
    }
    let (w, h) = (proj.size.0 as f32, proj.size.1 as f32);
    let t = proj.tan_half_fov as f32;
    let nx = (2.0 * px / w - 1.0) * (w / h) * t;
    let ny = (1.0 - 2.0 * py / h) * t;
    (1.0 + nx * nx + ny * ny).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pt::classify::classify;
    use volux_core::CameraSpec;

    fn one_tet() -> TetMesh {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        TetMesh::new(p, vec![0.0, 1.0, 2.0, 3.0], vec![[0, 1, 2, 3]]).unwrap()
    }

    fn camera(mesh: &TetMesh, ortho: bool) -> Camera {
        let spec = CameraSpec {
            azimuth: Some(30.0),
            elevation: Some(20.0),
            projection: ortho.then(|| "orthographic".to_string()),
            ..Default::default()
        };
        spec.resolve(&mesh.bounds()).unwrap()
    }

    #[test]
    fn projection_inverts_camera_rays() {
        let mesh = one_tet();
        for ortho in [false, true] {
            let cam = camera(&mesh, ortho);
            let proj = ViewProjection::new(&mesh, &cam, 64, 48);
            for (i, p) in mesh.positions().iter().enumerate() {
                let [x, y, z] = proj.vertices[i];
                let (px, py, depth) = cam.project(p.as_dvec3(), 64, 48);
                assert!((f64::from(x) - px).abs() <= 0.5 / f64::from(SUBPIXEL) + 1e-9);
                assert!((f64::from(y) - py).abs() <= 0.5 / f64::from(SUBPIXEL) + 1e-9);
                assert!((f64::from(z) - depth).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn thick_vertex_matches_ray_through_it() {
        // The ray through the thick vertex enters the tet at depth z_f with scalar s_f and
        // leaves at z_b with s_b: check against the linear field along that ray.
        let mesh = one_tet();
        for ortho in [false, true] {
            let cam = camera(&mesh, ortho);
            let proj = ViewProjection::new(&mesh, &cam, 64, 64);
            let screen = proj.tet(&mesh.tets()[0]).unwrap();
            let c = classify(screen_points(&screen));
            let tv = TetVertices {
                screen,
                scalars: mesh.tets()[0].map(|i| mesh.scalars()[i as usize]),
                gradients: [Vec3::ZERO; 4],
                perspective: proj.perspective,
                _marker: std::marker::PhantomData,
            };
            let fan = fan_vertices(&tv, &c).expect("not degenerate");
            let t = fan[4];
            let ray = cam.ray(f64::from(t.xy[0]), f64::from(t.xy[1]), 64, 64);
            let (_, _, f) = cam.basis();
            let cos = ray.dir.dot(f);
            for (z, s) in [(t.z_f, t.s_f), (t.z_b, t.s_b)] {
                let p =
                    ray.origin + ray.dir * ((f64::from(z) - (ray.origin - cam.eye).dot(f)) / cos);
                // Field s = x + 2y + 3z on this tet.
                let exact = p.x + 2.0 * p.y + 3.0 * p.z;
                assert!(
                    (exact - f64::from(s)).abs() < 2e-3,
                    "{exact} vs {s} ortho={ortho}"
                );
            }
            assert!(t.z_b > t.z_f);
        }
    }
}
