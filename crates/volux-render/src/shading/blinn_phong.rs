//! The two-sided Blinn-Phong lighting model and its light.
use crate::error::{Setting, SettingError};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Where the light comes from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Light {
    /// A light at the eye: the light direction is the view direction.
    Headlight,
    /// A directional light; the vector points *from the scene towards the light*, in world
    /// space (need not be normalized).
    Direction(Vec3),
}

/// Blinn-Phong shading along the field gradient (seed `002` §4.6), two-sided.
///
/// `out = rgb * (ambient + diffuse * max(N.L, 0)) + specular * max(N.H, 0)^shininess`, with
/// `N` the unit gradient flipped to face the viewer, `L` the unit light direction and `H` the
/// half vector of `L` and the direction to the viewer; the specular term is white and present
/// only where the surface faces the light (`N.L > 0`). The result is not clamped (the image
/// writer clamps).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BlinnPhong {
    /// Ambient coefficient (fraction of the colour kept regardless of the light).
    pub ambient: f32,
    /// Diffuse (Lambert) coefficient.
    pub diffuse: f32,
    /// Specular coefficient (white highlight).
    pub specular: f32,
    /// Specular exponent.
    pub shininess: f32,
    /// The light.
    pub light: Light,
    /// Gradient magnitude (data units per world unit) below which a sample is not lit: its
    /// colour is returned unchanged (emission only), so flat and noisy regions, whose gradient
    /// direction means nothing, do not flicker. The default, 1e-3, only guards regions flat to
    /// rounding; for real data use [`BlinnPhong::relative_min_gradient`] (e.g. 1 % of the data
    /// range per voxel) or a few times the noise level divided by the spacing.
    pub min_gradient: f32,
}

impl Default for BlinnPhong {
    /// Ambient 0.3, diffuse 0.7, specular 0.3, shininess 32, headlight, `min_gradient` 1e-3.
    fn default() -> Self {
        Self {
            ambient: 0.3,
            diffuse: 0.7,
            specular: 0.3,
            shininess: 32.0,
            light: Light::Headlight,
            min_gradient: 1e-3,
        }
    }
}

impl BlinnPhong {
    /// A gradient threshold of `fraction` of the data range per voxel (of the smallest
    /// spacing): `fraction * (range[1] - range[0]) / min(spacing)`, in data units per world
    /// unit. Returns 0 when the inputs are not finite or the spacing is not positive.
    pub fn relative_min_gradient(range: [f64; 2], spacing: Vec3, fraction: f32) -> f32 {
        let r =
            ((range[1] - range[0]).abs() * fraction as f64 / spacing.min_element() as f64) as f32;
        if r.is_finite() && r > 0.0 {
            r
        } else {
            0.0
        }
    }

    /// Checks that the coefficients are finite and non-negative and the light direction is a
    /// finite non-zero vector.
    pub fn validate(&self) -> Result<(), SettingError> {
        for (setting, v) in [
            (Setting::Ambient, self.ambient),
            (Setting::Diffuse, self.diffuse),
            (Setting::Specular, self.specular),
            (Setting::Shininess, self.shininess),
            (Setting::MinGradient, self.min_gradient),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SettingError::new(setting, v, "finite and >= 0"));
            }
        }
        if let Light::Direction(d) = self.light {
            if !(d.is_finite() && d.length_squared() > 0.0) {
                return Err(SettingError::new(
                    Setting::LightDirection,
                    d,
                    "finite and non-zero",
                ));
            }
        }
        Ok(())
    }

    /// Shades a sample of colour `rgb` with field gradient `gradient` (world units) seen along
    /// `view_dir`, the ray direction from the eye into the volume (need not be normalized).
    ///
    /// Returns `rgb` unchanged (emission only) when the gradient magnitude is below
    /// [`min_gradient`](Self::min_gradient) or not finite, or when the view direction is zero or
    /// not finite. Two-sided: the normal is the gradient or its opposite, whichever faces the
    /// viewer, so both sides of a surface are lit alike. An invalid directional light (zero or
    /// non-finite) leaves ambient light only.
    #[inline]
    pub fn shade(&self, rgb: [f32; 3], gradient: Vec3, view_dir: Vec3) -> [f32; 3] {
        let len = gradient.length();
        let to_eye = -view_dir.normalize_or_zero();
        if !(len >= self.min_gradient && len > 0.0 && len.is_finite()) || to_eye == Vec3::ZERO {
            return rgb;
        }
        let mut n = gradient / len;
        if n.dot(to_eye) < 0.0 {
            n = -n;
        }
        let l = match self.light {
            Light::Headlight => to_eye,
            Light::Direction(d) => d.normalize_or_zero(),
        };
        let n_l = n.dot(l);
        let (diffuse, specular) = if n_l > 0.0 {
            let h = (l + to_eye).normalize_or_zero();
            let n_h = n.dot(h).max(0.0);
            (n_l, n_h.powf(self.shininess))
        } else {
            (0.0, 0.0)
        };
        let k = self.ambient + self.diffuse * diffuse;
        let s = self.specular * specular;
        rgb.map(|c| c * k + s)
    }
}
