//! Perspective and orthographic cameras, look-at or orbit, with a JSON form.
//!
//! World z is "up" by default (the slice axis of medical volumes). Orbit angles: azimuth turns
//! around the up axis, elevation raises the eye; azimuth 0, elevation 0 looks along +y.
use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::aabb::Aabb;
use crate::error::{Error, Result};
use crate::json_shape;

/// The projection of a camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Projection {
    /// Pinhole perspective with a vertical field of view in degrees.
    Perspective {
        /// Vertical field of view, degrees.
        fov_y_deg: f64,
    },
    /// Parallel projection showing `height` world units vertically.
    Orthographic {
        /// Visible world height.
        height: f64,
    },
}

/// A resolved camera: eye, target, up and projection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Approximate up direction.
    pub up: DVec3,
    /// Projection.
    pub projection: Projection,
}

/// A ray in world space with unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
}

/// The rays of one image size for one camera (see [`Camera::rays`]).
#[derive(Clone, Copy, Debug)]
pub struct RayGenerator {
    eye: DVec3,
    basis: (DVec3, DVec3, DVec3),
    size: (f64, f64),
    projection: RayProjection,
}

/// The projection with its constants precomputed.
#[derive(Clone, Copy, Debug)]
enum RayProjection {
    /// Tangent of half the vertical field of view.
    Perspective(f64),
    /// View height in world units.
    Orthographic(f64),
}

impl RayGenerator {
    /// The ray through continuous pixel coordinates (`px`, `py`) (pixel centres at +0.5, row
    /// 0 at the top).
    #[inline]
    pub fn ray(&self, px: f64, py: f64) -> Ray {
        let (r, u, f) = self.basis;
        let (w, h) = self.size;
        let aspect = w / h;
        let nx = (2.0 * px / w - 1.0) * aspect;
        let ny = 1.0 - 2.0 * py / h;
        match self.projection {
            RayProjection::Perspective(t) => Ray {
                origin: self.eye,
                dir: (f + r * (nx * t) + u * (ny * t)).normalize(),
            },
            RayProjection::Orthographic(height) => Ray {
                origin: self.eye + (r * nx + u * ny) * (height * 0.5),
                dir: f,
            },
        }
    }
}

/// The JSON form of a camera: either `eye`/`target` (look-at) or orbit angles around the
/// data's centre. Missing fields take defaults that fit the data's bounding box.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// `"perspective"` (default) or `"orthographic"`.
    pub projection: Option<String>,
    /// Vertical field of view for perspective, degrees (default 30).
    pub fov_y_deg: Option<f64>,
    /// Eye position (look-at form).
    pub eye: Option<[f64; 3]>,
    /// Target (default: centre of the data).
    pub target: Option<[f64; 3]>,
    /// Up vector (default +z).
    pub up: Option<[f64; 3]>,
    /// Orbit azimuth in degrees (default 0).
    pub azimuth: Option<f64>,
    /// Orbit elevation in degrees (default 0).
    pub elevation: Option<f64>,
    /// Orbit distance (default: fits the bounding box).
    pub distance: Option<f64>,
    /// Zoom factor (default 1; 2 shows the data twice as large).
    pub zoom: Option<f64>,
}

impl CameraSpec {
    /// Parses the JSON form.
    ///
    /// A wrong shape is an [`Error::InvalidCamera`] naming the field and the expected shape
    /// (e.g. `eye: expected [x, y, z] (3 numbers), got 2 numbers`); malformed JSON is an
    /// [`Error::Json`] with serde's line and column. `null` counts as a missing field.
    pub fn from_json(text: &str) -> Result<Self> {
        let mut obj = json_shape::parse_object(text, &FIELDS, Error::InvalidCamera)?;
        obj.retain(|_, v| !v.is_null());
        check_shape(&obj).map_err(Error::InvalidCamera)?;
        Ok(serde_json::from_value(serde_json::Value::Object(obj))?)
    }

    /// Resolves the spec against the data's bounding box.
    pub fn resolve(&self, bounds: &Aabb) -> Result<Camera> {
        let zoom = self.zoom.unwrap_or(1.0);
        let fov = self.fov_y_deg.unwrap_or(30.0);
        if !(zoom.is_finite() && zoom > 0.0) {
            return Err(Error::InvalidCamera(format!("zoom {zoom} must be > 0")));
        }
        if !(fov > 0.0 && fov < 179.0) {
            return Err(Error::InvalidCamera(format!(
                "fov_y_deg {fov} must be in (0, 179)"
            )));
        }
        let radius = (bounds.diagonal() * 0.5).max(1e-9);
        let target = self.target.map(DVec3::from).unwrap_or(bounds.center());
        let slab = self.eye.is_none()
            && self.azimuth.is_none()
            && self.elevation.is_none()
            && self.up.is_none()
            && is_thin_in_z(bounds);
        if slab {
            // A few slices (a scout series, a thin slab): look along the slice axis, rows
            // running down the screen, as a radiologist sees an axial image.
            let fit = radius / (fov.to_radians() * 0.5).sin() / zoom;
            let eye = target - DVec3::Z * self.distance.unwrap_or(fit);
            let cam = Camera {
                eye,
                target,
                up: -DVec3::Y,
                projection: self.projection(fov, radius, zoom)?,
            };
            cam.validate()?;
            return Ok(cam);
        }
        let up = self.up.map(DVec3::from).unwrap_or(DVec3::Z);
        let eye = match self.eye {
            Some(e) => DVec3::from(e),
            None => {
                let az = self.azimuth.unwrap_or(0.0).to_radians();
                let el = self.elevation.unwrap_or(0.0).to_radians();
                let fit = radius / (fov.to_radians() * 0.5).sin() / zoom;
                let dist = self.distance.unwrap_or(fit);
                let (right, fwd) = orbit_basis(up);
                let dir =
                    (right * az.sin() - fwd * az.cos()) * el.cos() + up.normalize() * el.sin();
                target + dir * dist
            }
        };
        let projection = self.projection(fov, radius, zoom)?;
        let cam = Camera {
            eye,
            target,
            up,
            projection,
        };
        cam.validate()?;
        Ok(cam)
    }
}

impl CameraSpec {
    fn projection(&self, fov: f64, radius: f64, zoom: f64) -> Result<Projection> {
        match self.projection.as_deref().unwrap_or("perspective") {
            "perspective" => Ok(Projection::Perspective { fov_y_deg: fov }),
            "orthographic" => Ok(Projection::Orthographic {
                height: 2.0 * radius / zoom,
            }),
            other => Err(Error::InvalidCamera(format!(
                "unknown projection '{other}' (perspective, orthographic)"
            ))),
        }
    }
}

/// The fields of the JSON form of [`CameraSpec`].
const FIELDS: [&str; 9] = [
    "projection",
    "fov_y_deg",
    "eye",
    "target",
    "up",
    "azimuth",
    "elevation",
    "distance",
    "zoom",
];

/// Checks the shape of every field of the camera's JSON form, naming the field.
fn check_shape(obj: &json_shape::Object) -> std::result::Result<(), String> {
    use json_shape::{check_number, NumberKind};
    json_shape::check_known(obj, &FIELDS)?;
    json_shape::check_choice(obj, "projection", &["perspective", "orthographic"])?;
    for field in ["eye", "target", "up"] {
        if let Some(v) = obj.get(field) {
            json_shape::check_tuple(field, v, 3, "[x, y, z]")?;
        }
    }
    for field in ["fov_y_deg", "azimuth", "elevation"] {
        check_number(obj, field, NumberKind::Any)?;
    }
    check_number(obj, "distance", NumberKind::Positive)?;
    check_number(obj, "zoom", NumberKind::Positive)
}

/// Whether the box is a thin slab across z (z extent under a fifth of both others).
fn is_thin_in_z(b: &Aabb) -> bool {
    let e = b.max - b.min;
    e.z < 0.2 * e.x.min(e.y)
}

/// A right/forward pair perpendicular to `up` (forward is +y for up = +z).
pub(crate) fn orbit_basis(up: DVec3) -> (DVec3, DVec3) {
    let up = up.normalize();
    let guess = if up.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
    let fwd = (guess - up * guess.dot(up)).normalize();
    let right = fwd.cross(up);
    (right, fwd)
}

impl Camera {
    /// The default camera fitting `bounds`, perspective, looking along +y with z up.
    pub fn fit(bounds: &Aabb) -> Self {
        CameraSpec::default()
            .resolve(bounds)
            .expect("default spec is valid")
    }

    /// Checks the camera is usable: finite, eye != target, up not parallel to the view.
    pub fn validate(&self) -> Result<()> {
        let v = self.target - self.eye;
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(Error::InvalidCamera("non-finite eye, target or up".into()));
        }
        if v.length() < 1e-12 {
            return Err(Error::InvalidCamera("eye and target coincide".into()));
        }
        if v.normalize().cross(self.up.normalize_or_zero()).length() < 1e-9 {
            return Err(Error::InvalidCamera(
                "up is parallel to the view direction".into(),
            ));
        }
        Ok(())
    }

    /// The camera zoomed by `zoom` about its target, as [`CameraSpec::zoom`] zooms: a
    /// perspective eye `zoom` times nearer, an orthographic view `zoom` times narrower (its
    /// eye stays, so that rays still start outside the data).
    pub fn zoomed(&self, zoom: f64) -> Result<Self> {
        if !(zoom.is_finite() && zoom > 0.0) {
            return Err(Error::InvalidCamera(format!("zoom {zoom} must be > 0")));
        }
        let mut out = *self;
        match &mut out.projection {
            Projection::Perspective { .. } => {
                out.eye = self.target + (self.eye - self.target) / zoom;
            }
            Projection::Orthographic { height } => *height /= zoom,
        }
        Ok(out)
    }

    /// Orthonormal camera basis (right, true up, forward).
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let f = (self.target - self.eye).normalize();
        let r = f.cross(self.up).normalize();
        let u = r.cross(f);
        (r, u, f)
    }

    /// The ray through continuous pixel coordinates (`px`, `py`) of a `w` x `h` image
    /// (pixel centres at +0.5, row 0 at the top).
    pub fn ray(&self, px: f64, py: f64, w: usize, h: usize) -> Ray {
        self.rays(w, h).ray(px, py)
    }

    /// The rays of a `w` x `h` image, with the camera basis computed once (renderers cast
    /// one ray per pixel); [`Camera::ray`] gives the same rays.
    pub fn rays(&self, w: usize, h: usize) -> RayGenerator {
        let (r, u, f) = self.basis();
        RayGenerator {
            eye: self.eye,
            basis: (r, u, f),
            size: (w as f64, h as f64),
            projection: match self.projection {
                Projection::Perspective { fov_y_deg } => {
                    RayProjection::Perspective((fov_y_deg.to_radians() * 0.5).tan())
                }
                Projection::Orthographic { height } => RayProjection::Orthographic(height),
            },
        }
    }

    /// Projects a world point to continuous pixel coordinates and view depth (distance along
    /// the forward axis). Inverse of [`Camera::ray`].
    pub fn project(&self, p: DVec3, w: usize, h: usize) -> (f64, f64, f64) {
        let (r, u, f) = self.basis();
        let d = p - self.eye;
        let depth = d.dot(f);
        let (x, y) = match self.projection {
            Projection::Perspective { fov_y_deg } => {
                let t = (fov_y_deg.to_radians() * 0.5).tan();
                (d.dot(r) / (depth * t), d.dot(u) / (depth * t))
            }
            Projection::Orthographic { height } => {
                (d.dot(r) / (height * 0.5), d.dot(u) / (height * 0.5))
            }
        };
        let aspect = w as f64 / h as f64;
        let px = (x / aspect + 1.0) * 0.5 * w as f64;
        let py = (1.0 - y) * 0.5 * h as f64;
        (px, py, depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        }
    }

    #[test]
    fn zooming_a_camera_is_zooming_its_spec() {
        for projection in [None, Some("orthographic".to_string())] {
            let spec = |zoom| CameraSpec {
                projection: projection.clone(),
                azimuth: Some(30.0),
                zoom: Some(zoom),
                ..CameraSpec::default()
            };
            let plain = spec(1.0).resolve(&unit_box()).unwrap();
            let want = spec(2.5).resolve(&unit_box()).unwrap();
            let got = plain.zoomed(2.5).unwrap();
            // An orthographic picture does not depend on the eye's distance: the eye stays
            // (outside the data), where the spec moves it nearer.
            let eye = if projection.is_some() {
                plain.eye
            } else {
                want.eye
            };
            assert!((got.eye - eye).length() < 1e-9, "{projection:?}");
            assert_eq!(got.target, want.target);
            match (got.projection, want.projection) {
                (
                    Projection::Orthographic { height: a },
                    Projection::Orthographic { height: b },
                ) => assert!((a - b).abs() < 1e-12),
                (a, b) => assert_eq!(a, b),
            }
        }
        assert!(Camera::fit(&unit_box()).zoomed(0.0).is_err());
        assert!(Camera::fit(&unit_box()).zoomed(f64::NAN).is_err());
    }

    #[test]
    fn default_looks_along_plus_y() {
        let c = Camera::fit(&unit_box());
        let (_, _, f) = c.basis();
        assert!((f - DVec3::Y).length() < 1e-9);
        let ray = c.ray(50.0, 50.0, 100, 100);
        assert!((ray.dir - DVec3::Y).length() < 1e-9);
    }

    #[test]
    fn project_inverts_ray() {
        for proj in ["perspective", "orthographic"] {
            let spec = CameraSpec {
                projection: Some(proj.into()),
                azimuth: Some(30.0),
                elevation: Some(20.0),
                ..Default::default()
            };
            let c = spec.resolve(&unit_box()).unwrap();
            let ray = c.ray(13.0, 77.0, 160, 100);
            let p = ray.origin + ray.dir * 2.5;
            let (x, y, _) = c.project(p, 160, 100);
            assert!(
                (x - 13.0).abs() < 1e-6 && (y - 77.0).abs() < 1e-6,
                "{proj}: {x} {y}"
            );
        }
    }

    #[test]
    fn thin_slabs_are_seen_along_z_by_default() {
        let slab = Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(500.0, 500.0, 24.0),
        };
        let (_, u, f) = Camera::fit(&slab).basis();
        assert!((f - DVec3::Z).length() < 1e-9 && (u + DVec3::Y).length() < 1e-9);
        // An explicit angle keeps the orbit.
        let spec = CameraSpec {
            azimuth: Some(0.0),
            ..Default::default()
        };
        let (_, _, f) = spec.resolve(&slab).unwrap().basis();
        assert!((f - DVec3::Y).length() < 1e-9);
    }

    #[test]
    fn json_shape_errors_name_the_field() {
        let cases = [
            (
                r#"{"eye": [1, 2]}"#,
                "eye: expected [x, y, z] (3 numbers), got 2 numbers",
            ),
            (
                r#"{"target": "centre"}"#,
                r#"target: expected [x, y, z] (3 numbers), got "centre""#,
            ),
            (
                r#"{"up": [0, 0, "z"]}"#,
                r#"up: expected [x, y, z] (3 numbers), got [0,0,"z"]"#,
            ),
            (
                r#"{"projection": "fisheye"}"#,
                r#"projection: expected "perspective" or "orthographic", got "fisheye""#,
            ),
            (r#"{"azimuth": "90"}"#, r#"azimuth: expected a number, got "90""#),
            (r#"{"zoom": 0}"#, "zoom: expected a positive number, got 0"),
            (r#"{"distance": -2}"#, "distance: expected a positive number, got -2"),
            (
                r#"{"bogus": 1}"#,
                "unknown field \"bogus\" (expected one of projection, fov_y_deg, eye, target, up, azimuth, elevation, distance, zoom)",
            ),
            ("3", "expected a JSON object with fields projection"),
        ];
        for (text, want) in cases {
            let e = CameraSpec::from_json(text).unwrap_err().to_string();
            assert!(e.starts_with("invalid camera: "), "{e}");
            assert!(e.contains(want), "{text}: got {e}, want {want}");
        }
        let e = CameraSpec::from_json(r#"{"zoom": 2,}"#)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("JSON: ") && e.contains("line 1 column"),
            "{e}"
        );
        let s = CameraSpec::from_json(
            r#"{"eye": null, "up": [0, 1, 0], "projection": "orthographic"}"#,
        )
        .unwrap();
        assert_eq!((s.eye, s.up), (None, Some([0.0, 1.0, 0.0])));
    }

    #[test]
    fn json_and_errors() {
        let s = CameraSpec::from_json(r#"{"azimuth": 90, "zoom": 2}"#).unwrap();
        assert!(s.resolve(&unit_box()).is_ok());
        assert!(CameraSpec::from_json(r#"{"bogus": 1}"#).is_err());
        let bad = CameraSpec {
            zoom: Some(0.0),
            ..Default::default()
        };
        assert!(bad.resolve(&unit_box()).is_err());
        let bad = CameraSpec {
            eye: Some([0.0, 0.0, 5.0]),
            target: Some([0.0, 0.0, 0.0]),
            ..Default::default()
        };
        assert!(bad.resolve(&unit_box()).is_err());
    }
}
