//! Camera gestures of the 3D view, as 3D Slicer, ParaView and f3d map them: orbit about the
//! target (left drag), pan across the view (middle drag or shift + left drag), dolly (wheel),
//! reset, standard views, perspective/orthographic. Pure functions on [`Camera`], so the
//! window, the tests and the benchmark's scripted orbit move the camera the same way.
use glam::{DMat3, DVec3};
use volux_core::{Aabb, Camera, NamedView, Projection};
use volux_render::framing::fit_to_box;

/// Degrees of orbit per pixel dragged.
pub const ORBIT_DEG_PER_PIXEL: f64 = 0.4;

/// Perspective field of view of the viewer's cameras (degrees).
pub const FOV_Y_DEG: f64 = 30.0;

/// The camera turned about its target: `dx` pixels to the right turn the scene about the
/// camera's up (a turntable: the world stays upright), `dy` pixels down tilt it about the
/// camera's right axis. The view never flips over a pole.
pub fn orbit(camera: &Camera, dx: f64, dy: f64) -> Camera {
    let (right, up, _) = camera.basis();
    let yaw = DMat3::from_axis_angle(up, (-dx * ORBIT_DEG_PER_PIXEL).to_radians());
    let offset = yaw * (camera.eye - camera.target);
    let right = yaw * right;
    let pitch = DMat3::from_axis_angle(right, (-dy * ORBIT_DEG_PER_PIXEL).to_radians());
    let new_offset = pitch * offset;
    let new_up = pitch * (yaw * up);
    Camera {
        eye: camera.target + new_offset,
        up: new_up,
        ..*camera
    }
}

/// The camera moved across the view so that the scene follows a drag of (`dx`, `dy`) pixels
/// in an image `height` pixels tall.
pub fn pan(camera: &Camera, dx: f64, dy: f64, height: f64) -> Camera {
    let (right, up, forward) = camera.basis();
    let world_per_pixel = visible_height(camera, forward) / height.max(1.0);
    let shift = (-right * dx + up * dy) * world_per_pixel;
    Camera {
        eye: camera.eye + shift,
        target: camera.target + shift,
        ..*camera
    }
}

/// World height the view shows at the target's depth.
fn visible_height(camera: &Camera, forward: DVec3) -> f64 {
    match camera.projection {
        Projection::Perspective { fov_y_deg } => {
            let depth = (camera.target - camera.eye).dot(forward);
            2.0 * depth * (fov_y_deg.to_radians() * 0.5).tan()
        }
        Projection::Orthographic { height } => height,
    }
}

/// The camera moved towards the target by the factor `factor` (> 1 zooms in): perspective
/// cameras dolly (never through the target), orthographic ones shrink their view.
pub fn zoom(camera: &Camera, factor: f64) -> Camera {
    let factor = if factor.is_finite() && factor > 0.0 {
        factor
    } else {
        1.0
    };
    match camera.projection {
        Projection::Perspective { .. } => {
            let offset = (camera.eye - camera.target) / factor;
            let min = 1e-6 * offset.length().max(1e-12) * factor;
            let offset = if offset.length() < min {
                offset.normalize() * min
            } else {
                offset
            };
            Camera {
                eye: camera.target + offset,
                ..*camera
            }
        }
        Projection::Orthographic { height } => Camera {
            projection: Projection::Orthographic {
                height: height / factor,
            },
            ..*camera
        },
    }
}

/// The same view with the other projection, showing the same world height at the target.
pub fn toggle_projection(camera: &Camera) -> Camera {
    let (_, _, forward) = camera.basis();
    let distance = (camera.target - camera.eye).dot(forward);
    let half = (FOV_Y_DEG.to_radians() * 0.5).tan();
    let projection = match camera.projection {
        Projection::Perspective { .. } => Projection::Orthographic {
            height: visible_height(camera, forward),
        },
        Projection::Orthographic { height } => {
            let distance_for_height = height * 0.5 / half;
            return Camera {
                eye: camera.target - forward * distance_for_height.max(distance * 1e-6),
                projection: Projection::Perspective {
                    fov_y_deg: FOV_Y_DEG,
                },
                ..*camera
            };
        }
    };
    Camera {
        projection,
        ..*camera
    }
}

/// The camera looking at the centre of `bounds` from the side `view` names (the patient's
/// sides for patient data: [`NamedView`] holds the table the CLI's `--view` uses too), with the
/// projection of `like`, fitted to the image (aspect = width / height).
pub fn standard_view(like: &Camera, view: NamedView, bounds: &Aabb, aspect: f64) -> Camera {
    let (side, up) = (view.side(), view.up());
    let centre = bounds.center();
    let radius = bounds.diagonal().max(1e-9);
    let camera = Camera {
        eye: centre + side * radius * 2.0,
        target: centre,
        up,
        projection: like.projection,
    };
    fit_to_box(&camera, bounds, aspect, 1.0)
}

/// The first camera on a dataset: a three-quarter view from the front (-y) and above, z up,
/// perspective, fitted to `bounds`.
pub fn home(bounds: &Aabb, aspect: f64) -> Camera {
    let centre = bounds.center();
    let radius = bounds.diagonal().max(1e-9);
    let side = DVec3::new(0.5, -1.0, 0.45).normalize();
    let camera = Camera {
        eye: centre + side * radius * 2.0,
        target: centre,
        up: DVec3::Z,
        projection: Projection::Perspective {
            fov_y_deg: FOV_Y_DEG,
        },
    };
    fit_to_box(&camera, bounds, aspect, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        }
    }

    /// Orbiting keeps the distance to the target, and a full turn of drags comes back.
    #[test]
    fn orbit_keeps_distance_and_closes() {
        let c = home(&unit_box(), 1.0);
        let d0 = (c.eye - c.target).length();
        let steps = (360.0 / ORBIT_DEG_PER_PIXEL / 10.0) as usize;
        let mut o = c;
        for _ in 0..steps {
            o = orbit(&o, 10.0, 0.0);
            assert!(((o.eye - o.target).length() - d0).abs() < 1e-9 * d0);
        }
        assert!(
            (o.eye - c.eye).length() < 1e-9 * d0,
            "{:?} vs {:?}",
            o.eye,
            c.eye
        );
        let tilted = orbit(&c, 0.0, 50.0);
        assert!((tilted.eye - c.eye).length() > 0.1 * d0);
    }

    /// A pan moves eye and target alike, by the dragged pixels at the target's depth.
    #[test]
    fn pan_follows_the_pointer() {
        let c = home(&unit_box(), 1.0);
        let p = pan(&c, 100.0, 0.0, 400.0);
        assert!(((p.eye - c.eye) - (p.target - c.target)).length() < 1e-12);
        let (x0, y0, _) = c.project(c.target, 400, 400);
        let (x1, y1, _) = p.project(c.target, 400, 400);
        assert!((x1 - x0 - 100.0).abs() < 1e-6 && (y1 - y0).abs() < 1e-6);
    }

    /// Zoom in then out is the identity; orthographic zoom scales the height.
    #[test]
    fn zoom_is_invertible() {
        let c = home(&unit_box(), 1.0);
        let z = zoom(&zoom(&c, 1.25), 0.8);
        assert!((z.eye - c.eye).length() < 1e-9);
        let o = toggle_projection(&c);
        let Projection::Orthographic { height } = o.projection else {
            panic!("not orthographic")
        };
        let Projection::Orthographic { height: h2 } = zoom(&o, 2.0).projection else {
            panic!()
        };
        assert!((h2 - height / 2.0).abs() < 1e-12);
        let back = toggle_projection(&o);
        assert!((back.eye - c.eye).length() < 1e-6 * (c.eye - c.target).length());
    }

    /// Each standard view looks at the centre from its side, with its up.
    #[test]
    fn standard_views_sit_on_their_axes() {
        let c = home(&unit_box(), 1.0);
        for v in NamedView::ANATOMICAL.into_iter().chain(NamedView::AXES) {
            let s = standard_view(&c, v, &unit_box(), 1.0);
            assert!(
                (s.eye - s.target).normalize().dot(v.side()) > 0.999,
                "{v:?}"
            );
            assert_eq!(s.up, v.up());
        }
        assert_eq!(NamedView::Anterior.label(), "A");
    }
}
