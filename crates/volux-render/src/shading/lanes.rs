//! Blinn-Phong shading of [`LANES`] samples at once, for the lane stream: gradients looked up
//! in a [`GradientVolume`] lane by lane, the lighting computed lane-wise, the specular power by
//! a polynomial `ln` and `exp` ([`pow_lanes`]). The same model as [`BlinnPhong::shade`]
//! (tested against it).
//!
//! The lighting of a sample is returned as a factor `k` and a highlight `s`, the lit colour
//! being `rgb k + s`: a premultiplied colour `rgb a` becomes `rgb a k + s a`, so the stream
//! lights its table entries without dividing by the opacity.
use glam::Vec3;

use super::blinn_phong::{BlinnPhong, Light};
use super::gradient::GradientVolume;
use crate::integrate::adaptive::lanes::exp_lanes;
use crate::sampling::{clamped_cell, FLOOR_SMALL_LIMIT, LANES};

/// Lane-wise vectors: `[axis][lane]`.
pub type Lanes3 = [[f32; LANES]; 3];

/// What lighting depends on along one ray: the direction to the eye, the light direction and
/// their half vector; `None` where [`BlinnPhong::shade`] leaves colours unlit (a zero view).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayLight {
    /// Unit vector towards the eye.
    pub to_eye: Vec3,
    /// Unit vector towards the light.
    pub light: Vec3,
    /// Unit half vector of the two (zero if they are opposite).
    pub half: Vec3,
}

impl BlinnPhong {
    /// The lighting directions of a ray of direction `view_dir` (from the eye, need not be
    /// normalized); `None` when the ray is not lit (zero or non-finite direction).
    pub fn ray_light(&self, view_dir: Vec3) -> Option<RayLight> {
        let to_eye = -view_dir.normalize_or_zero();
        if to_eye == Vec3::ZERO {
            return None;
        }
        let light = match self.light {
            Light::Headlight => to_eye,
            Light::Direction(d) => d.normalize_or_zero(),
        };
        Some(RayLight {
            to_eye,
            light,
            half: (light + to_eye).normalize_or_zero(),
        })
    }

    /// The lighting `(k, s)` of each lane (see the module docs): gradient `g` (world units),
    /// the lane's ray directions `to_eye`, `light`, `half`, and `lit` false where the ray is not
    /// lit. Unlit samples (gradient below the threshold or not finite) get `(1, 0)`.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub fn light_lanes(
        &self,
        g: &Lanes3,
        dirs: (&Lanes3, &Lanes3, &Lanes3),
        lit: &[bool; LANES],
    ) -> ([f32; LANES], [f32; LANES]) {
        let (to_eye, light, half) = dirs;
        // Plain f32 arithmetic and selects, no booleans kept across loops: that vectorizes.
        let (mut diffuse, mut n_h, mut inv) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        for l in 0..LANES {
            let len = (g[0][l] * g[0][l] + g[1][l] * g[1][l] + g[2][l] * g[2][l]).sqrt();
            let ok = lit[l] & (len >= self.min_gradient) & (len > 0.0) & (len < f32::INFINITY);
            // 0 marks an unlit lane.
            inv[l] = if ok { 1.0 / len } else { 0.0 };
        }
        for l in 0..LANES {
            let n = [g[0][l] * inv[l], g[1][l] * inv[l], g[2][l] * inv[l]];
            // Two-sided: the normal faces the viewer (`copysign` and `max` keep this loop
            // free of branches).
            let side = n[0] * to_eye[0][l] + n[1] * to_eye[1][l] + n[2] * to_eye[2][l];
            let sign = 1.0f32.copysign(side);
            let n_l = sign * (n[0] * light[0][l] + n[1] * light[1][l] + n[2] * light[2][l]);
            let n_hl = sign * (n[0] * half[0][l] + n[1] * half[1][l] + n[2] * half[2][l]);
            diffuse[l] = n_l.max(0.0);
            // The highlight counts only where the surface faces the light (below).
            n_h[l] = n_hl.max(0.0);
        }
        let spec = pow_lanes(n_h, self.shininess);
        let (mut k, mut s) = ([1.0f32; LANES], [0.0f32; LANES]);
        for l in 0..LANES {
            let kd = self.ambient + self.diffuse * diffuse[l];
            let ks = if diffuse[l] > 0.0 {
                self.specular * spec[l]
            } else {
                0.0
            };
            k[l] = if inv[l] > 0.0 { kd } else { 1.0 };
            s[l] = if inv[l] > 0.0 { ks } else { 0.0 };
        }
        (k, s)
    }
}

impl GradientVolume {
    /// [`GradientVolume::gradient`] at the voxel positions `p` of every lane.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub fn gradient_lanes(&self, p: &Lanes3) -> Lanes3 {
        let [nx, ny, nz] = self.key.dims;
        if self
            .key
            .dims
            .iter()
            .any(|&n| n as f64 >= f64::from(FLOOR_SMALL_LIMIT))
        {
            // Axes too long for the cast-free floor: one lane at a time.
            let mut out = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                let g = self.gradient(Vec3::new(p[0][l], p[1][l], p[2][l]));
                for a in 0..3 {
                    out[a][l] = g[a];
                }
            }
            return out;
        }
        let mut index = [0usize; LANES];
        let mut frac = [[0.0f32; LANES]; 3];
        let strides = [1, nx, nx * ny];
        for a in 0..3 {
            let n = self.key.dims[a];
            // Positions clamped into the grid (NaN to 0), cells to the last pair.
            let (hi, last_cell) = if n < 2 {
                (0.0, 0)
            } else {
                ((n - 1) as f32, n as i32 - 2)
            };
            for l in 0..LANES {
                let (i, f) = clamped_cell(p[a][l], hi, last_cell);
                frac[a][l] = f;
                index[l] += i as usize * strides[a];
            }
        }
        let dx = usize::from(nx > 1);
        let sy = if ny > 1 { nx } else { 0 };
        let sz = if nz > 1 { nx * ny } else { 0 };
        let offsets = [0, dx, sy, sy + dx, sz, sz + dx, sz + sy, sz + sy + dx];
        let mut out = [[0.0f32; LANES]; 3];
        for l in 0..LANES {
            // Each corner's x, y, z (and pad) in one load; the lerps run over the components.
            // In bounds: cells are clamped to the grid, and a corner adds at most one stride
            // per axis that has two or more samples.
            let corner = |o: usize| -> [f32; 4] {
                let q = self.data[index[l] + o];
                [q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32]
            };
            let lerp = |a: [f32; 4], b: [f32; 4], f: f32| -> [f32; 4] {
                [
                    a[0] + (b[0] - a[0]) * f,
                    a[1] + (b[1] - a[1]) * f,
                    a[2] + (b[2] - a[2]) * f,
                    a[3] + (b[3] - a[3]) * f,
                ]
            };
            let (fx, fy, fz) = (frac[0][l], frac[1][l], frac[2][l]);
            let [o0, o1, o2, o3, o4, o5, o6, o7] = offsets;
            let c00 = lerp(corner(o0), corner(o1), fx);
            let c10 = lerp(corner(o2), corner(o3), fx);
            let c01 = lerp(corner(o4), corner(o5), fx);
            let c11 = lerp(corner(o6), corner(o7), fx);
            let v = lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
            for a in 0..3 {
                out[a][l] = v[a] * self.to_world[a];
            }
        }
        out
    }
}

/// `x^y` of every lane for `x` in `[0, 1]` and `y >= 0` (the specular power): `exp(y ln x)`
/// with [`ln_lanes`] and [`exp_lanes`]; `0^y` is 0 and `x^0` is 1, as `powf`. Relative error
/// about 1e-6 times `y |ln x|`, and results below `exp(-80)` are 0.
#[inline(always)]
pub fn pow_lanes(x: [f32; LANES], y: f32) -> [f32; LANES] {
    if y == 0.0 {
        return [1.0; LANES];
    }
    let mut e = ln_lanes(x);
    for (e, &x) in e.iter_mut().zip(&x) {
        *e = if x > 0.0 { y * *e } else { -100.0 };
    }
    exp_lanes(&mut e);
    e
}

/// Natural logarithm of every lane for finite `x > 0` (other lanes: unspecified): Cephes'
/// `logf` (the exponent from the bits, a degree-8 polynomial on the mantissa), without
/// branches or float-to-int casts, so that it runs lane-wise. Relative error below 1e-6 for
/// normal numbers.
#[allow(clippy::excessive_precision)]
#[inline(always)]
pub fn ln_lanes(x: [f32; LANES]) -> [f32; LANES] {
    const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;
    let mut out = [0.0f32; LANES];
    for (o, &x) in out.iter_mut().zip(&x) {
        let bits = x.to_bits();
        // x = m 2^e with m in [0.5, 1).
        let e = ((bits >> 23) & 0xff) as i32 - 126;
        let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
        let small = m < SQRT_HALF;
        let e = (e - i32::from(small)) as f32;
        let f = if small { m + m - 1.0 } else { m - 1.0 };
        let z = f * f;
        let mut y = 7.037_683_629_2e-2;
        for c in [
            -1.151_461_031_0e-1,
            1.167_699_874_0e-1,
            -1.242_014_084_6e-1,
            1.424_932_278_7e-1,
            -1.666_805_766_5e-1,
            2.000_071_476_5e-1,
            -2.499_999_399_3e-1,
            3.333_333_117_4e-1,
        ] {
            y = y * f + c;
        }
        let y = y * f * z + e * -2.121_944_40e-4 - 0.5 * z;
        *o = f + y + e * 0.693_359_375;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Trilinear;

    #[test]
    fn ln_and_pow_lanes_match_the_library() {
        let mut worst_ln = 0.0f32;
        let mut worst_pow = 0.0f32;
        let mut x = [0.0f32; LANES];
        for k in 0..4000 {
            for (l, x) in x.iter_mut().enumerate() {
                // From 1e-30 to 1, densely near 1 (where highlights are).
                let u = (k * LANES + l) as f32 / (4000 * LANES) as f32;
                *x = if k % 2 == 0 {
                    10f32.powf(-30.0 * u)
                } else {
                    1.0 - 0.1 * u
                };
            }
            let ln = ln_lanes(x);
            for l in 0..LANES {
                worst_ln = worst_ln.max((ln[l] - x[l].ln()).abs() / x[l].ln().abs().max(1e-3));
            }
            for y in [1.0, 8.0, 32.0, 100.0] {
                let p = pow_lanes(x, y);
                for l in 0..LANES {
                    let want = x[l].powf(y);
                    worst_pow = worst_pow.max((p[l] - want).abs() / want.max(1e-6));
                }
            }
        }
        assert!(worst_ln < 2e-6, "ln: {worst_ln}");
        assert!(worst_pow < 2e-4, "pow: {worst_pow}");
        let mut edge = [0.5f32; LANES];
        edge[0] = 0.0;
        edge[1] = 1.0;
        let p = pow_lanes(edge, 32.0);
        assert_eq!((p[0], p[1]), (0.0, 1.0));
        assert_eq!(pow_lanes(edge, 0.0), [1.0; LANES]);
    }

    #[test]
    fn gradient_lanes_handle_axes_too_long_for_the_lane_floor() {
        let n = FLOOR_SMALL_LIMIT as usize + 3;
        let v: Vec<u8> = (0..n).map(|i| (i % 7) as u8).collect();
        let volume = GradientVolume::build(&Trilinear::new(&v[..], [n, 1, 1]), Vec3::ONE, 0);
        let volume = volume.unwrap();
        let mut p = [[0.0f32; LANES]; 3];
        for (l, x) in p[0].iter_mut().enumerate() {
            *x = (n - 1) as f32 - 0.37 * l as f32;
        }
        let g = volume.gradient_lanes(&p);
        for l in 0..LANES {
            let want = volume.gradient(Vec3::new(p[0][l], 0.0, 0.0));
            assert_eq!([g[0][l], g[1][l], g[2][l]], want.to_array(), "lane {l}");
        }
    }

    #[test]
    fn lane_lighting_matches_shade() {
        // A field with gradients in every direction, flat zones and a bright light.
        let dims = [9, 7, 6];
        let mut v = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let (x, y, z) = (i as f32, j as f32, k as f32);
                    v.push(if x < 2.0 {
                        1.0
                    } else {
                        (0.7 * x).sin() * y - 0.3 * z * z
                    });
                }
            }
        }
        let spacing = Vec3::new(1.0, 0.5, 2.0);
        let field = Trilinear::new(&v[..], dims);
        let volume = GradientVolume::build(&field, spacing, 0).unwrap();
        let models = [
            BlinnPhong::default(),
            BlinnPhong {
                light: Light::Direction(Vec3::new(1.0, -2.0, 0.5)),
                shininess: 7.5,
                min_gradient: 0.05,
                ..BlinnPhong::default()
            },
            BlinnPhong {
                shininess: 0.0,
                ..BlinnPhong::default()
            },
        ];
        let views = [
            Vec3::new(0.3, 1.0, -0.2),
            Vec3::new(-1.0, 0.1, 0.4),
            Vec3::ZERO,
        ];
        let mut worst = 0.0f32;
        for model in models {
            for (n, view) in views.into_iter().enumerate() {
                let ray = model.ray_light(view);
                let mut p = [[0.0f32; LANES]; 3];
                let mut dirs = [[[0.0f32; LANES]; 3]; 3];
                let lit = [ray.is_some(); LANES];
                for l in 0..LANES {
                    let t = (l + 16 * n) as f32;
                    let q = [0.37 * t % 9.5 - 0.2, 0.61 * t % 6.8, 0.23 * t % 5.2];
                    let r = ray.unwrap_or_default();
                    for a in 0..3 {
                        p[a][l] = q[a];
                        dirs[0][a][l] = r.to_eye[a];
                        dirs[1][a][l] = r.light[a];
                        dirs[2][a][l] = r.half[a];
                    }
                }
                let g = volume.gradient_lanes(&p);
                let (k, s) = model.light_lanes(&g, (&dirs[0], &dirs[1], &dirs[2]), &lit);
                for l in 0..LANES {
                    let q = Vec3::new(p[0][l], p[1][l], p[2][l]);
                    let gs = volume.gradient(q);
                    assert!((gs - Vec3::new(g[0][l], g[1][l], g[2][l])).length() < 1e-4);
                    let rgb = [0.2, 0.5, 0.9];
                    let want = model.shade(rgb, gs, view);
                    for c in 0..3 {
                        worst = worst.max((rgb[c] * k[l] + s[l] - want[c]).abs());
                    }
                }
            }
        }
        assert!(worst < 1e-5, "lane lighting differs by {worst}");
    }
}
