//! Tests of the convex VOI: Euler's formula, a half-space test of every vertex against every
//! plane, exact volumes of analytic cuts, a brute-force point count, and the degenerate cuts.
use super::*;

fn unit_box() -> ConvexVoi {
    ConvexVoi::from_aabb(&Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    })
    .unwrap()
}

fn plane(a: f64, b: f64, c: f64, d: f64) -> ClipPlane {
    ClipPlane::new(a, b, c, d).unwrap()
}

/// Euler's formula, every loop a valid polygon, every edge shared by exactly two faces in
/// opposite directions, and every vertex on the kept side of every face plane and on its own
/// faces' planes.
fn check_valid(voi: &ConvexVoi) {
    let (v, e, f) = (voi.vertices().len(), voi.edge_count(), voi.faces().len());
    assert_eq!(v + f, e + 2, "Euler: V {v} E {e} F {f}");
    let mut edges = HashMap::new();
    for face in voi.faces() {
        let n = face.vertices.len();
        assert!(n >= 3, "a face with {n} vertices");
        for k in 0..n {
            let (a, b) = (face.vertices[k], face.vertices[(k + 1) % n]);
            assert!(edges.insert((a, b), ()).is_none(), "edge {a}-{b} twice");
            let p = voi.vertices()[a as usize];
            assert!(
                face.plane.distance(p).abs() < 1e-9,
                "vertex {a} off its face"
            );
        }
    }
    for &(a, b) in edges.keys() {
        assert!(edges.contains_key(&(b, a)), "edge {a}-{b} has one face");
    }
    for (i, &p) in voi.vertices().iter().enumerate() {
        for pl in voi.planes() {
            assert!(pl.distance(p) >= -1e-9, "vertex {i} outside a plane");
        }
    }
}

#[test]
fn a_box_is_a_valid_polyhedron_with_its_volume() {
    let voi = ConvexVoi::from_aabb(&Aabb {
        min: DVec3::new(-1.0, 2.0, 0.0),
        max: DVec3::new(3.0, 2.5, 7.0),
    })
    .unwrap();
    check_valid(&voi);
    assert_eq!(
        (voi.vertices().len(), voi.edge_count(), voi.faces().len()),
        (8, 12, 6)
    );
    assert!((voi.volume() - 4.0 * 0.5 * 7.0).abs() < 1e-12);
}

#[test]
fn cutting_a_corner_off_makes_a_seven_faced_solid() {
    let mut voi = unit_box();
    // Keeps x + y + z <= 0.5 ... the complement: removes the corner at the origin.
    assert_eq!(voi.cut(&plane(1.0, 1.0, 1.0, -0.5)).unwrap(), Cut::Cut);
    check_valid(&voi);
    assert_eq!(
        (voi.vertices().len(), voi.edge_count(), voi.faces().len()),
        (10, 15, 7)
    );
    // The corner removed is the tetrahedron with legs 0.5: volume 0.5^3 / 6.
    assert!((voi.volume() - (1.0 - 0.125 / 6.0)).abs() < 1e-12);
}

#[test]
fn a_cut_through_an_edge_leaves_a_prism() {
    let mut voi = unit_box();
    // x - y >= 0: the plane holds the edges (0,0,z) and (1,1,z).
    assert_eq!(voi.cut(&plane(1.0, -1.0, 0.0, 0.0)).unwrap(), Cut::Cut);
    check_valid(&voi);
    assert_eq!(
        (voi.vertices().len(), voi.edge_count(), voi.faces().len()),
        (6, 9, 5)
    );
    assert!((voi.volume() - 0.5).abs() < 1e-12);
}

#[test]
fn planes_that_remove_nothing_leave_the_voi_unchanged() {
    for p in [
        plane(-1.0, -1.0, -1.0, 3.0), // touches the vertex (1,1,1)
        plane(-1.0, 0.0, 0.0, 1.0),   // along the face x = 1
        plane(-1.0, -1.0, 0.0, 2.0),  // along the edge x = y = 1
        plane(1.0, 0.0, 0.0, 5.0),    // far away
    ] {
        let mut voi = unit_box();
        assert_eq!(voi.cut(&p).unwrap(), Cut::Unchanged, "{p:?}");
        assert_eq!(voi, unit_box());
    }
}

#[test]
fn planes_that_leave_no_volume_are_refused_and_change_nothing() {
    for p in [
        plane(1.0, 0.0, 0.0, -2.0), // everything removed
        plane(1.0, 0.0, 0.0, -1.0), // only the face x = 1 left
        plane(1.0, 1.0, 0.0, -2.0), // only the edge x = y = 1 left
        plane(1.0, 1.0, 1.0, -3.0), // only the vertex (1,1,1) left
    ] {
        let mut voi = unit_box();
        let err = voi.cut(&p).unwrap_err();
        assert!(
            matches!(err, Error::EmptyVolumeOfInterest(_)),
            "{p:?}: {err}"
        );
        assert_eq!(voi, unit_box());
    }
}

#[test]
fn bad_planes_and_flat_boxes_are_errors() {
    assert!(ClipPlane::new(0.0, 0.0, 0.0, 1.0).is_err());
    assert!(ClipPlane::new(f64::NAN, 1.0, 0.0, 1.0).is_err());
    assert!(ClipPlane::new(1.0, 0.0, 0.0, f64::INFINITY).is_err());
    assert!(ClipPlane::new(1e300, 1e300, 0.0, 1.0).is_err());
    let long = ClipPlane {
        normal: DVec3::new(2.0, 0.0, 0.0),
        offset: 1.0,
    };
    assert!(long.check().is_err());
    assert!(plane(2.0, 0.0, 0.0, 1.0).check().is_ok());
    let flat = Aabb {
        min: DVec3::ZERO,
        max: DVec3::new(1.0, 0.0, 1.0),
    };
    assert!(ConvexVoi::from_aabb(&flat).is_err());
}

/// A deterministic generator of planes through points near the centre of the unit box.
struct Planes(u64);

impl Planes {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn next(&mut self) -> ClipPlane {
        let n = DVec3::new(self.unit(), self.unit(), self.unit()) * 2.0 - 1.0;
        let at =
            DVec3::splat(0.5) + (DVec3::new(self.unit(), self.unit(), self.unit()) - 0.5) * 0.9;
        ClipPlane::new(n.x, n.y, n.z, -n.dot(at)).unwrap_or(ClipPlane {
            normal: DVec3::X,
            offset: 0.0,
        })
    }
}

#[test]
fn many_cuts_stay_valid_and_match_a_brute_force_point_count() {
    let mut gen = Planes(17);
    let mut voi = unit_box();
    let mut cuts = vec![];
    for _ in 0..40 {
        let p = gen.next();
        let before = voi.clone();
        match voi.cut(&p) {
            Ok(_) => cuts.push(p),
            Err(_) => assert_eq!(voi, before),
        }
        check_valid(&voi);
    }
    assert!(cuts.len() >= 10, "only {} cuts kept", cuts.len());
    // The VOI is the box and the kept half-spaces: count grid points in both.
    let n = 60;
    let (mut inside, mut half_spaces) = (0usize, 0usize);
    for i in 0..n * n * n {
        let p =
            (DVec3::new((i % n) as f64, (i / n % n) as f64, (i / n / n) as f64) + 0.5) / n as f64;
        inside += usize::from(voi.contains(p));
        half_spaces += usize::from(cuts.iter().all(|c| c.distance(p) >= 0.0));
    }
    assert_eq!(
        inside, half_spaces,
        "containment differs from the half-spaces"
    );
    let counted = inside as f64 / (n * n * n) as f64;
    assert!(
        (counted - voi.volume()).abs() < 0.01,
        "volume {} against the point count {counted}",
        voi.volume()
    );
}

#[test]
fn segments_are_clipped_to_the_voi() {
    let mut voi = unit_box();
    voi.cut(&plane(1.0, 1.0, 1.0, -0.5)).unwrap();
    // Along the main diagonal from (-1,-1,-1): enters at x+y+z = 0.5 and leaves at (1,1,1).
    let dir = DVec3::ONE;
    let (t0, t1) = voi
        .clip_segment(DVec3::splat(-1.0), dir, 0.0, 10.0)
        .unwrap();
    assert!((t0 - (1.0 + 0.5 / 3.0)).abs() < 1e-12 && (t1 - 2.0).abs() < 1e-12);
    assert!(voi
        .clip_segment(DVec3::splat(-1.0), -dir, 0.0, 10.0)
        .is_none());
    assert!(voi
        .clip_segment(DVec3::new(2.0, 0.5, 0.5), DVec3::Y, 0.0, 1.0)
        .is_none());
}

/// The area of a planar polygon and its normal direction (the vector area).
fn vector_area(poly: &[DVec3]) -> DVec3 {
    let mut a = DVec3::ZERO;
    for k in 1..poly.len().saturating_sub(1) {
        a += (poly[k] - poly[0]).cross(poly[k + 1] - poly[0]);
    }
    a * 0.5
}

#[test]
fn the_sweep_matches_direct_sections_and_integrates_to_the_volume() {
    let mut gen = Planes(5);
    let mut voi = unit_box();
    for _ in 0..12 {
        let _ = voi.cut(&gen.next());
    }
    let k = DVec3::new(0.3, -0.5, 0.8);
    let dir = k.normalize();
    let step = 0.004;
    let slices = voi.sweep(k, step).unwrap();
    let lo = voi
        .vertices()
        .iter()
        .map(|&v| dir.dot(v))
        .fold(f64::INFINITY, f64::min);
    let mut volume = 0.0;
    for (i, poly) in slices.iter().enumerate() {
        let d = lo + i as f64 * step;
        let direct = voi.section(&ClipPlane {
            normal: dir,
            offset: -d,
        });
        assert_eq!(poly.len(), direct.len(), "slice {i}");
        // The same polygon: the same points, possibly starting elsewhere in the loop.
        if let Some(first) = direct.first() {
            let shift = poly.iter().position(|p| p.distance(*first) < 1e-9);
            let shift = shift.unwrap_or_else(|| panic!("slice {i}: no common start"));
            for (j, p) in direct.iter().enumerate() {
                assert!(
                    poly[(j + shift) % poly.len()].distance(*p) < 1e-9,
                    "slice {i}"
                );
            }
        }
        for p in poly {
            assert!((dir.dot(*p) - d).abs() < 1e-9 && voi.contains(*p));
        }
        // Counter-clockwise about -k.
        let a = vector_area(poly);
        assert!(
            poly.is_empty() || a.dot(dir) < 0.0,
            "slice {i} turns the wrong way"
        );
        volume += a.length() * step;
    }
    assert!(
        (volume - voi.volume()).abs() < 0.01 * voi.volume(),
        "slices give {volume}, the polyhedron {}",
        voi.volume()
    );
}

#[test]
fn bad_sweeps_are_errors() {
    let voi = unit_box();
    assert!(voi.sweep(DVec3::ZERO, 0.1).is_err());
    for step in [0.0, -1.0, f64::NAN, 1e-12] {
        let err = voi.sweep(DVec3::X, step).unwrap_err();
        assert!(matches!(err, Error::InvalidSweep(_)), "step {step}: {err}");
    }
    assert_eq!(voi.sweep(DVec3::X, 0.25).unwrap().len(), 5);
}
