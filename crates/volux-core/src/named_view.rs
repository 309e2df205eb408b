//! Named views: the six anatomical views of a patient scan and the six axis views of any data,
//! each a side the camera looks from and the up a reader expects. One table for every front
//! end (the CLI's `--view`, the viewer's view buttons, the Python bindings).
//!
//! World coordinates are LPS ([`crate::orientation`]): +x the patient's left, +y posterior,
//! +z superior. A named anatomical view follows 3D Slicer's convention: the view from the
//! **Left** puts the camera on the patient's left (+x) and shows the patient's left side.
//! The side views keep superior up; the superior and inferior views keep anterior up, so the
//! inferior view is the radiological axial view (seen from the feet: the patient's left on the
//! screen's right, anterior at the top).
use glam::DVec3;

use crate::error::{Error, Result};

/// A named view: the side of the data the camera sits on, and the screen's up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NamedView {
    /// From the patient's left (camera on +x), superior up.
    Left,
    /// From the patient's right (camera on -x), superior up.
    Right,
    /// From the front (camera on -y), superior up.
    Anterior,
    /// From behind (camera on +y), superior up.
    Posterior,
    /// From above the head (camera on +z), anterior up.
    Superior,
    /// From the feet (camera on -z), anterior up: the radiological axial view.
    Inferior,
    /// Camera on +x, z up.
    PlusX,
    /// Camera on -x, z up.
    MinusX,
    /// Camera on +y, z up.
    PlusY,
    /// Camera on -y, z up.
    MinusY,
    /// Camera on +z, y up.
    PlusZ,
    /// Camera on -z, y up.
    MinusZ,
}

impl NamedView {
    /// The anatomical views, in the order of the viewer's toolbar.
    pub const ANATOMICAL: [NamedView; 6] = [
        Self::Left,
        Self::Right,
        Self::Posterior,
        Self::Anterior,
        Self::Superior,
        Self::Inferior,
    ];

    /// The axis views, in the same order as [`Self::ANATOMICAL`] (the same sides).
    pub const AXES: [NamedView; 6] = [
        Self::PlusX,
        Self::MinusX,
        Self::PlusY,
        Self::MinusY,
        Self::PlusZ,
        Self::MinusZ,
    ];

    /// The unit world direction from the target towards the eye.
    pub fn side(self) -> DVec3 {
        match self {
            Self::Left | Self::PlusX => DVec3::X,
            Self::Right | Self::MinusX => -DVec3::X,
            Self::Posterior | Self::PlusY => DVec3::Y,
            Self::Anterior | Self::MinusY => -DVec3::Y,
            Self::Superior | Self::PlusZ => DVec3::Z,
            Self::Inferior | Self::MinusZ => -DVec3::Z,
        }
    }

    /// The screen's up of the view.
    pub fn up(self) -> DVec3 {
        match self {
            Self::Superior | Self::Inferior => -DVec3::Y,
            Self::PlusZ | Self::MinusZ => DVec3::Y,
            _ => DVec3::Z,
        }
    }

    /// The short label: the patient letter (L, R, A, P, S, I) or the axis (+X ... -Z).
    pub fn label(self) -> &'static str {
        match self {
            Self::Left => "L",
            Self::Right => "R",
            Self::Anterior => "A",
            Self::Posterior => "P",
            Self::Superior => "S",
            Self::Inferior => "I",
            Self::PlusX => "+X",
            Self::MinusX => "-X",
            Self::PlusY => "+Y",
            Self::MinusY => "-Y",
            Self::PlusZ => "+Z",
            Self::MinusZ => "-Z",
        }
    }

    /// The view as an orbit about `up` (the view's own up when `None`): the azimuth and
    /// elevation in degrees that [`crate::CameraSpec`] turns the camera by to put it on
    /// [`Self::side`], and the up. An `up` along the view direction has no screen direction
    /// and is refused ([`Error::InvalidCamera`]).
    pub fn orbit(self, up: Option<DVec3>) -> Result<Orbit> {
        let up = up.unwrap_or(self.up());
        let side = self.side();
        if !up.is_finite() || up.length() == 0.0 {
            return Err(Error::InvalidCamera(format!("up {up} is not a direction")));
        }
        let u = up.normalize();
        if u.dot(side).abs() > 1.0 - 1e-9 {
            return Err(Error::InvalidCamera(format!(
                "up {up} lies along the view from {} ({side}): it gives the screen no up",
                self.label()
            )));
        }
        let (right, fwd) = crate::camera::orbit_basis(u);
        let azimuth = side.dot(right).atan2(-side.dot(fwd)).to_degrees();
        let elevation = side.dot(u).clamp(-1.0, 1.0).asin().to_degrees();
        Ok(Orbit {
            azimuth,
            elevation,
            up: up.to_array(),
        })
    }
}

/// A view as [`crate::CameraSpec`]'s orbit: azimuth and elevation in degrees about `up`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Degrees about the up axis.
    pub azimuth: f64,
    /// Degrees above the plane normal to up.
    pub elevation: f64,
    /// The up axis.
    pub up: [f64; 3],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Aabb, CameraSpec};

    fn resolve(view: NamedView, up: Option<DVec3>) -> crate::Camera {
        let o = view.orbit(up).unwrap();
        let spec = CameraSpec {
            azimuth: Some(o.azimuth),
            elevation: Some(o.elevation),
            up: Some(o.up),
            ..Default::default()
        };
        let b = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        spec.resolve(&b).unwrap()
    }

    /// Every view puts the eye on its side, with its up on the screen's up.
    #[test]
    fn views_sit_on_their_sides_with_their_up() {
        for v in NamedView::ANATOMICAL.into_iter().chain(NamedView::AXES) {
            let cam = resolve(v, None);
            let dir = (cam.eye - cam.target).normalize();
            assert!((dir - v.side()).length() < 1e-9, "{v:?}: eye towards {dir}");
            let (_, up, _) = cam.basis();
            assert!((up - v.up()).length() < 1e-9, "{v:?}: up {up}");
        }
    }

    /// Slicer's convention: the view from the left shows the patient's left side, and the
    /// inferior view is the radiological axial view (patient's left on the screen's right,
    /// anterior at the top).
    #[test]
    fn anatomical_views_show_the_named_side() {
        let cam = resolve(NamedView::Left, None);
        // A marker on the patient's left (+x) is nearer the eye than one on the right.
        let left = DVec3::new(1.0, 0.0, 0.0);
        let right = DVec3::new(-1.0, 0.0, 0.0);
        assert!((cam.eye - left).length() < (cam.eye - right).length());
        let (r, u, _) = resolve(NamedView::Inferior, None).basis();
        assert!((r - DVec3::X).length() < 1e-9, "screen right {r}");
        assert!((u + DVec3::Y).length() < 1e-9, "screen up {u}");
        let (_, u, _) = resolve(NamedView::Superior, None).basis();
        assert!((u + DVec3::Y).length() < 1e-9, "screen up {u}");
    }

    /// `up` refines a view: the eye stays on the side, the screen's up follows.
    #[test]
    fn up_refines_a_view_and_is_refused_along_it() {
        let cam = resolve(NamedView::Anterior, Some(DVec3::X));
        let dir = (cam.eye - cam.target).normalize();
        assert!((dir + DVec3::Y).length() < 1e-9, "{dir}");
        assert!((cam.basis().1 - DVec3::X).length() < 1e-9);
        // An oblique up is projected onto the screen.
        let cam = resolve(NamedView::Superior, Some(DVec3::new(0.0, -1.0, 1.0)));
        let dir = (cam.eye - cam.target).normalize();
        assert!((dir - DVec3::Z).length() < 1e-9, "{dir}");
        assert!((cam.basis().1 + DVec3::Y).length() < 1e-9);
        let e = NamedView::Superior.orbit(Some(DVec3::Z)).unwrap_err();
        assert!(e.to_string().contains("lies along the view"), "{e}");
    }
}
