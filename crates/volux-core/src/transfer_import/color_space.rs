//! The colour interpolation of `vtkColorTransferFunction::GetTable` (VTK
//! `Rendering/Core/vtkColorTransferFunction.cxx`) in its colour spaces, with the conversions
//! of `vtkMath` (`Common/Core/vtkMath.cxx`). All colours are VTK display values (sRGB-encoded
//! RGB in 0..1).
use super::blend::Blend;
use std::f64::consts::PI;

/// A `vtkColorTransferFunction` colour space, as ParaView names it in presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// `"RGB"`: each display channel linearly.
    Rgb,
    /// `"HSV"`: hue, saturation, value linearly, the hue the short way round (VTK's
    /// `HSVWrap`, on by default).
    Hsv,
    /// `"Lab"` (also read as `"CIELAB"`): CIE L*a*b* (D65) linearly.
    Lab,
    /// `"Diverging"`: Moreland's diverging interpolation in Msh space.
    Diverging,
    /// `"Step"`: no interpolation; between two nodes the colour of the right one.
    Step,
}

impl ColorSpace {
    /// The space ParaView's `ColorSpace` text names; `None` for names this module does not
    /// interpolate.
    pub fn from_paraview(name: &str) -> Option<ColorSpace> {
        match name {
            "RGB" => Some(ColorSpace::Rgb),
            "HSV" => Some(ColorSpace::Hsv),
            "Lab" | "CIELAB" => Some(ColorSpace::Lab),
            "Diverging" => Some(ColorSpace::Diverging),
            "Step" => Some(ColorSpace::Step),
            _ => None,
        }
    }
}

/// A node of a `vtkColorTransferFunction`: display colour `rgb` at `x`, and the shape of
/// the curve to the next node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VtkColorNode {
    /// Position.
    pub x: f64,
    /// Display colour.
    pub rgb: [f64; 3],
    /// Where (as a fraction of the segment) the interpolation parameter reaches 0.5.
    pub midpoint: f64,
    /// 0 linear, up to 1 a step at the midpoint.
    pub sharpness: f64,
}

/// The colour of a `vtkColorTransferFunction` at `x` with clamping on and no above/below
/// range colours (VTK's defaults): the first node's colour up to it, the last one's after
/// it; between nodes `a` and `b` the segment position is moved so that `a.midpoint` maps to
/// 0.5, then a step at 0.5 (`a.sharpness > 0.99`), the interpolation of `space` (`< 0.01`),
/// or the Hermite curve of the space's coordinates (VTK's sharpened position for Diverging),
/// clamped to 0..1. Nodes must be sorted by `x`; none give black.
pub fn vtk_color_value(nodes: &[VtkColorNode], space: ColorSpace, x: f64) -> [f64; 3] {
    let i = nodes.partition_point(|n| n.x < x);
    match (nodes.first(), nodes.last()) {
        (None, _) | (_, None) => [0.0; 3],
        (Some(first), _) if i == 0 => first.rgb,
        (_, Some(last)) if i == nodes.len() => last.rgb,
        _ => segment_color(&nodes[i - 1], &nodes[i], space, x),
    }
}

/// The colour between nodes `a` and `b` at `x` (see [`vtk_color_value`]).
pub(super) fn segment_color(
    a: &VtkColorNode,
    b: &VtkColorNode,
    space: ColorSpace,
    x: f64,
) -> [f64; 3] {
    let m = a.midpoint.clamp(0.00001, 0.99999);
    let s = if b.x != a.x {
        (x - a.x) / (b.x - a.x)
    } else {
        0.0
    };
    let s = if s < m {
        0.5 * s / m
    } else {
        0.5 + 0.5 * (s - m) / (1.0 - m)
    };
    let blend = Blend::new(s, a.sharpness);
    let mixed = |p: f64, q: f64| blend.mix(p, q);
    match blend {
        Blend::Step { right } => {
            if right {
                b.rgb
            } else {
                a.rgb
            }
        }
        // VTK does not clamp this branch; every conversion back to RGB stays in 0..1.
        Blend::Linear { .. } => interpolate(space, blend.position(), &a.rgb, &b.rgb, mixed),
        Blend::Hermite { .. } => {
            interpolate(space, blend.position(), &a.rgb, &b.rgb, mixed).map(|c| c.clamp(0.0, 1.0))
        }
    }
}

/// Colour between `rgb1` and `rgb2` in `space`, `mix` blending one coordinate (linear or
/// Hermite); `s` is the position Diverging uses (VTK interpolates it linearly in Msh even
/// for sharpness > 0).
fn interpolate(
    space: ColorSpace,
    s: f64,
    rgb1: &[f64; 3],
    rgb2: &[f64; 3],
    mix: impl Fn(f64, f64) -> f64,
) -> [f64; 3] {
    match space {
        ColorSpace::Rgb => [0, 1, 2].map(|k| mix(rgb1[k], rgb2[k])),
        ColorSpace::Step => *rgb2,
        ColorSpace::Hsv => {
            let (mut hsv1, mut hsv2) = (rgb_to_hsv(rgb1), rgb_to_hsv(rgb2));
            if (hsv1[0] - hsv2[0]).abs() > 0.5 {
                if hsv1[0] > hsv2[0] {
                    hsv1[0] -= 1.0;
                } else {
                    hsv2[0] -= 1.0;
                }
            }
            let mut hsv = [0, 1, 2].map(|k| mix(hsv1[k], hsv2[k]));
            if hsv[0] < 0.0 {
                hsv[0] += 1.0;
            }
            hsv_to_rgb(&hsv)
        }
        ColorSpace::Lab => {
            let (lab1, lab2) = (rgb_to_lab(rgb1), rgb_to_lab(rgb2));
            lab_to_rgb(&[0, 1, 2].map(|k| mix(lab1[k], lab2[k])))
        }
        ColorSpace::Diverging => diverging(s, rgb1, rgb2),
    }
}

// ---------------------------------------------------------------------------------------
// vtkMath's conversions.

/// `vtkMath::RGBToHSV`: hue in 0..1 (0 for greys).
pub fn rgb_to_hsv(rgb: &[f64; 3]) -> [f64; 3] {
    let [r, g, b] = *rgb;
    let cmax = r.max(g).max(b);
    let cmin = r.min(g).min(b);
    let v = cmax;
    let s = if v > 0.0 { (cmax - cmin) / cmax } else { 0.0 };
    if s <= 0.0 {
        return [0.0, s, v];
    }
    let d = cmax - cmin;
    let mut h = if r == cmax {
        (g - b) / d / 6.0
    } else if g == cmax {
        1.0 / 3.0 + (b - r) / d / 6.0
    } else {
        2.0 / 3.0 + (r - g) / d / 6.0
    };
    if h < 0.0 {
        h += 1.0;
    }
    [h, s, v]
}

/// `vtkMath::HSVToRGB`.
pub fn hsv_to_rgb(hsv: &[f64; 3]) -> [f64; 3] {
    let [h, s, v] = *hsv;
    let sixth = 1.0 / 6.0;
    let third = 1.0 / 3.0;
    let two_thirds = 2.0 / 3.0;
    let five_sixths = 5.0 / 6.0;
    let hue = if h > sixth && h <= third {
        [(third - h) / sixth, 1.0, 0.0]
    } else if h > third && h <= 0.5 {
        [0.0, 1.0, (h - third) / sixth]
    } else if h > 0.5 && h <= two_thirds {
        [0.0, (two_thirds - h) / sixth, 1.0]
    } else if h > two_thirds && h <= five_sixths {
        [(h - two_thirds) / sixth, 0.0, 1.0]
    } else if h > five_sixths && h <= 1.0 {
        [1.0, 0.0, (1.0 - h) / sixth]
    } else {
        [1.0, h / sixth, 0.0]
    };
    hue.map(|c| (s * c + (1.0 - s)) * v)
}

/// The D65 white of `vtkMath`'s XYZ/Lab conversions.
const WHITE: [f64; 3] = [0.9505, 1.000, 1.089];

/// `vtkMath::RGBToXYZ` (sRGB decoding, then VTK's 4-digit matrix).
pub fn rgb_to_xyz(rgb: &[f64; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(|c| {
        if c > 0.04045 {
            ((c + 0.055) / 1.055).powf(2.4)
        } else {
            c / 12.92
        }
    });
    [
        r * 0.4124 + g * 0.3576 + b * 0.1805,
        r * 0.2126 + g * 0.7152 + b * 0.0722,
        r * 0.0193 + g * 0.1192 + b * 0.9505,
    ]
}

/// `vtkMath::XYZToRGB`: VTK's matrix, sRGB encoding, then out-of-gamut colours scaled down
/// by their largest channel and clamped at 0.
pub fn xyz_to_rgb(xyz: &[f64; 3]) -> [f64; 3] {
    let [x, y, z] = *xyz;
    let lin = [
        x * 3.2406 + y * -1.5372 + z * -0.4986,
        x * -0.9689 + y * 1.8758 + z * 0.0415,
        x * 0.0557 + y * -0.2040 + z * 1.0570,
    ];
    let mut rgb = lin.map(|c| {
        if c > 0.0031308 {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        } else {
            12.92 * c
        }
    });
    let max = rgb[0].max(rgb[1]).max(rgb[2]);
    if max > 1.0 {
        rgb = rgb.map(|c| c / max);
    }
    rgb.map(|c| c.max(0.0))
}

/// `vtkMath::XYZToLab`.
pub fn xyz_to_lab(xyz: &[f64; 3]) -> [f64; 3] {
    let [fx, fy, fz] = [0, 1, 2].map(|k| {
        let v = xyz[k] / WHITE[k];
        if v > 0.008856 {
            v.powf(1.0 / 3.0)
        } else {
            7.787 * v + 16.0 / 116.0
        }
    });
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// `vtkMath::LabToXYZ`.
pub fn lab_to_xyz(lab: &[f64; 3]) -> [f64; 3] {
    let [l, a, b] = *lab;
    let fy = (l + 16.0) / 116.0;
    let f = [a / 500.0 + fy, fy, fy - b / 200.0];
    [0, 1, 2].map(|k| {
        let v = f[k];
        let cube = v.powi(3);
        let v = if cube > 0.008856 {
            cube
        } else {
            (v - 16.0 / 116.0) / 7.787
        };
        WHITE[k] * v
    })
}

/// `vtkMath::RGBToLab`.
pub fn rgb_to_lab(rgb: &[f64; 3]) -> [f64; 3] {
    xyz_to_lab(&rgb_to_xyz(rgb))
}

/// `vtkMath::LabToRGB`.
pub fn lab_to_rgb(lab: &[f64; 3]) -> [f64; 3] {
    xyz_to_rgb(&lab_to_xyz(lab))
}

// ---------------------------------------------------------------------------------------
// Moreland's diverging interpolation (vtkColorTransferFunctionInterpolateDiverging).

/// Lab to Msh (magnitude, saturation angle, hue angle). The cosine is kept in -1..1 against
/// rounding (VTK's `acos` would give NaN there).
fn lab_to_msh(lab: &[f64; 3]) -> [f64; 3] {
    let [l, a, b] = *lab;
    let m = (l * l + a * a + b * b).sqrt();
    let s = if m > 0.001 {
        (l / m).clamp(-1.0, 1.0).acos()
    } else {
        0.0
    };
    let h = if s > 0.001 { b.atan2(a) } else { 0.0 };
    [m, s, h]
}

fn msh_to_lab(msh: &[f64; 3]) -> [f64; 3] {
    let [m, s, h] = *msh;
    [m * s.cos(), m * s.sin() * h.cos(), m * s.sin() * h.sin()]
}

/// `a1 - a2` brought into -pi..pi (`vtkColorTransferFunctionSignedAngleDiff`).
fn signed_angle_diff(a1: f64, a2: f64) -> f64 {
    let mut d = a1 - a2;
    if d >= 0.0 {
        while d >= 2.0 * PI {
            d -= 2.0 * PI;
        }
        if d > PI {
            d = 2.0 * PI - d;
        }
    } else {
        while d <= -2.0 * PI {
            d += 2.0 * PI;
        }
        if d < -PI {
            d += 2.0 * PI;
        }
    }
    d
}

/// A hue for an unsaturated colour of magnitude `unsat_m` next to the saturated `msh`
/// (`vtkColorTransferFunctionAdjustHue`).
fn adjust_hue(msh: &[f64; 3], unsat_m: f64) -> f64 {
    if msh[0] >= unsat_m - 0.1 {
        return msh[2];
    }
    let spin = msh[1] * (unsat_m * unsat_m - msh[0] * msh[0]).sqrt() / (msh[0] * msh[1].sin());
    if msh[2] > -0.3 * PI {
        msh[2] + spin
    } else {
        msh[2] - spin
    }
}

/// The diverging colour at `s` between `rgb1` and `rgb2`: white (magnitude at least 88)
/// inserted halfway between two distinct saturated colours, the hue of an unsaturated end
/// adjusted, then Msh interpolated linearly (the hue along the signed shorter difference,
/// as current VTK does).
pub fn diverging(s: f64, rgb1: &[f64; 3], rgb2: &[f64; 3]) -> [f64; 3] {
    let mut msh1 = lab_to_msh(&rgb_to_lab(rgb1));
    let mut msh2 = lab_to_msh(&rgb_to_lab(rgb2));
    let mut s = s;
    if msh1[1] > 0.05 && msh2[1] > 0.05 && signed_angle_diff(msh1[2], msh2[2]).abs() > 0.33 * PI {
        let mid = msh1[0].max(msh2[0]).max(88.0);
        if s < 0.5 {
            msh2 = [mid, 0.0, 0.0];
            s *= 2.0;
        } else {
            msh1 = [mid, 0.0, 0.0];
            s = 2.0 * s - 1.0;
        }
    }
    if msh1[1] < 0.05 && msh2[1] > 0.05 {
        msh1[2] = adjust_hue(&msh2, msh1[0]);
    } else if msh2[1] < 0.05 && msh1[1] > 0.05 {
        msh2[2] = adjust_hue(&msh1, msh2[0]);
    }
    let msh = [
        (1.0 - s) * msh1[0] + s * msh2[0],
        (1.0 - s) * msh1[1] + s * msh2[1],
        msh1[2] + s * signed_angle_diff(msh2[2], msh1[2]),
    ];
    lab_to_rgb(&msh_to_lab(&msh))
}
