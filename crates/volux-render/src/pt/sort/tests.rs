use std::cmp::Ordering;
use std::time::Instant;

use glam::{DVec3, Vec3};
use volux_core::synth::{smooth_tets, torus_tets};
use volux_core::tetrahedralize::{lattice_tets, orient_positive};
use volux_core::TetMesh;
use volux_testkit::TestRng;

use super::*;

/// The documented order of depths, written independently of `depth_key`: numeric, -0 == +0,
/// NaN after everything.
fn reference_cmp(a: f32, b: f32) -> Ordering {
    match (a.is_nan(), b.is_nan()) {
        (true, true) => Ordering::Equal,
        (true, false) => Ordering::Greater,
        (false, true) => Ordering::Less,
        _ => a.partial_cmp(&b).unwrap(),
    }
}

fn check_against_std(depths: &[f32], ids: &[u32]) {
    // `depths` is indexed by tet id here; centroid_order takes one depth per id.
    let d: Vec<f32> = ids.iter().map(|&t| depths[t as usize]).collect();
    let got = centroid_order(&d, ids);
    let mut want = ids.to_vec();
    want.sort_by(|&a, &b| reference_cmp(depths[a as usize], depths[b as usize]));
    assert_eq!(got, want, "n = {}", ids.len());
}

#[test]
fn radix_sort_equals_stable_std_sort() {
    let mut rng = TestRng::new(7);
    for n in [0usize, 1, 5, 255, 256, 257, 1000, 100_000] {
        let depths: Vec<f32> = (0..n)
            .map(|_| match rng.below(10) {
                0 => f32::INFINITY,
                1 => f32::NEG_INFINITY,
                2 => f32::NAN,
                3 => -0.0,
                4 => 0.0,
                5 => rng.int(-3, 3) as f32,
                // Any bit pattern: subnormals, huge values, negative NaN.
                6 => f32::from_bits((rng.next_u64() >> 32) as u32),
                _ => (rng.unit() * 2000.0 - 1000.0) as f32,
            })
            .collect();
        let mut ids: Vec<u32> = (0..n as u32).collect();
        check_against_std(&depths, &ids);
        rng.shuffle(&mut ids);
        check_against_std(&depths, &ids);
        let subset: Vec<u32> = ids.iter().copied().filter(|t| t % 3 != 1).collect();
        check_against_std(&depths, &subset);
    }
}

#[test]
fn radix_sort_skips_constant_digits_correctly() {
    let mut rng = TestRng::new(11);
    // Depths in [1, 1.0001): the top digits are constant and their passes skipped.
    let narrow: Vec<f32> = (0..50_000)
        .map(|_| 1.0 + (rng.unit() * 1e-4) as f32)
        .collect();
    let mut ids: Vec<u32> = (0..narrow.len() as u32).collect();
    rng.shuffle(&mut ids);
    check_against_std(&narrow, &ids);
    // All equal: every pass is skipped and the input order is kept.
    let same = vec![2.5f32; 10_000];
    assert_eq!(
        centroid_order(&same, &ids[..10_000]),
        ids[..10_000].to_vec()
    );
}

#[test]
fn depth_key_is_monotone() {
    let xs = [
        f32::NEG_INFINITY,
        -1e30,
        -1.0,
        -f32::MIN_POSITIVE,
        -1e-45,
        0.0,
        1e-45,
        f32::MIN_POSITIVE,
        1.0,
        1e30,
        f32::INFINITY,
        f32::NAN,
    ];
    for w in xs.windows(2) {
        assert!(depth_key(w[0]) < depth_key(w[1]), "{} {}", w[0], w[1]);
    }
    assert_eq!(depth_key(-0.0), depth_key(0.0));
}

fn is_permutation_of(order: &[u32], ids: impl IntoIterator<Item = u32>) -> bool {
    let mut a = order.to_vec();
    let mut b: Vec<u32> = ids.into_iter().collect();
    a.sort_unstable();
    b.sort_unstable();
    a == b
}

/// Views of the unit cube: close and far perspective, inside, oblique and axis-aligned
/// parallel views (the last makes many face planes contain the view direction).
fn cube_views() -> Vec<SortView> {
    let c = DVec3::splat(0.5);
    let persp = |eye: DVec3| SortView::perspective(eye, c - eye);
    vec![
        persp(DVec3::new(0.5, -0.4, 0.7)),
        persp(DVec3::new(1.3, 1.2, -0.2)),
        persp(DVec3::new(-8.0, 5.0, 3.0)),
        persp(DVec3::new(0.37, 0.52, 0.41)),
        SortView::orthographic(DVec3::new(3.0, 2.0, 1.0), DVec3::new(-1.0, -0.7, -0.3)),
        SortView::orthographic(DVec3::new(0.5, -2.0, 0.5), DVec3::Y),
    ]
}

#[test]
fn mpvo_is_exact_on_a_convex_lattice() {
    let mesh = smooth_tets(5000).unwrap();
    assert!(is_convex(&mesh));
    let adj = mesh.face_adjacency();
    let all: Vec<u32> = (0..mesh.tets().len() as u32).collect();
    let (mut centroid_errors, mut distance_errors, mut z_errors) = (0, 0, 0);
    for view in cube_views() {
        let r = mpvo(&mesh, &adj, &view, None).unwrap();
        let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
        assert_eq!(r.cycles_broken, 0, "{view:?}");
        assert!(is_permutation_of(&r.order, all.iter().copied()));
        assert_eq!(faces.count_violations(&r.order), 0, "{view:?}");
        assert!(r.constraints > 0 && r.constraints == faces.constraints());
        // The reversed order breaks every constraint: the counter sees them all.
        let reversed: Vec<u32> = r.order.iter().rev().copied().collect();
        assert_eq!(faces.count_violations(&reversed), r.constraints);
        assert_eq!(
            count_violations(&reversed, &adj, &mesh, &view),
            r.constraints
        );
        let centroid = centroid_order(&centroid_keys(&mesh, &view), &all);
        centroid_errors += faces.count_violations(&centroid);
        if view.perspective {
            distance_errors += faces.count_violations(&centroid);
            let z: Vec<f32> = mesh
                .tets()
                .iter()
                .map(|t| {
                    let p = t.map(|v| mesh.positions()[v as usize].as_dvec3());
                    let c = (p[0] + p[1] + p[2] + p[3]) * 0.25;
                    (c - view.eye).dot(view.forward) as f32
                })
                .collect();
            z_errors += faces.count_violations(&centroid_order(&z, &all));
        }
        // MPVO is the centroid order corrected: where nothing was reordered they agree.
        if r.reordered == 0 {
            assert_eq!(r.order, centroid);
        }
    }
    eprintln!(
        "centroid violations over the views: {centroid_errors}; perspective views: distance \
         key {distance_errors}, view z key {z_errors}"
    );
    // The reason for the distance key under perspective (module documentation).
    assert!(z_errors > 0 && distance_errors <= z_errors);
}

#[test]
fn mpvo_keeps_discarded_cells_in_the_graph() {
    let mesh = smooth_tets(5000).unwrap();
    let adj = mesh.face_adjacency();
    let view = cube_views()[0];
    let full = mpvo(&mesh, &adj, &view, None).unwrap();
    let mut kept: Vec<u32> = (0..mesh.tets().len() as u32)
        .filter(|t| t % 3 != 0)
        .collect();
    kept.reverse();
    let sub = mpvo(&mesh, &adj, &view, Some(&kept)).unwrap();
    assert!(is_permutation_of(&sub.order, kept.iter().copied()));
    let filtered: Vec<u32> = full.order.iter().copied().filter(|t| t % 3 != 0).collect();
    assert_eq!(sub.order, filtered);
    let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
    assert_eq!(faces.count_violations(&sub.order), 0);
    // Deterministic.
    assert_eq!(
        mpvo_order(&mesh, &adj, &view, Some(&kept)).unwrap(),
        sub.order
    );
}

#[test]
fn both_cells_of_a_face_see_opposite_relations() {
    let mesh = smooth_tets(2000).unwrap();
    let adj = mesh.face_adjacency();
    let mut rng = TestRng::new(3);
    for i in 0..8 {
        let eye = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 3.0 - 1.0;
        let fwd = DVec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5;
        let view = if i % 2 == 0 {
            SortView::perspective(eye, fwd)
        } else {
            SortView::orthographic(eye, fwd)
        };
        for (t, nb) in adj.iter().enumerate() {
            for (f, &u) in nb.iter().enumerate() {
                if u == volux_core::mesh::NO_NEIGHBOR {
                    continue;
                }
                let g = adj[u as usize]
                    .iter()
                    .position(|&x| x as usize == t)
                    .unwrap();
                let here = face_precedence(mesh.positions(), &mesh.tets()[t], f, &view);
                let there = face_precedence(mesh.positions(), &mesh.tets()[u as usize], g, &view);
                assert_eq!(here, there.flip());
            }
        }
    }
}

/// Two tets sharing the triangle (0,0,0), (1,0,0), (0,1,0): tet 0 long and thin above it,
/// reaching x = 60, tet 1 small below it.
fn thin_and_small() -> TetMesh {
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(60.0, 0.3, 0.05),
        Vec3::new(0.2, 0.2, -0.3),
    ];
    TetMesh::new(p, vec![0.0; 5], vec![[0, 1, 2, 3], [0, 1, 2, 4]]).unwrap()
}

#[test]
fn centroid_order_fails_where_mpvo_does_not() {
    let mesh = thin_and_small();
    let adj = mesh.face_adjacency();
    let eye = DVec3::new(0.2, 0.2, 1.0);
    let fwd = DVec3::new(1.0, 0.0, -1.0);
    // The eye is above the shared face (on the thin tet's side), rays go down and right:
    // the thin tet is in front, but its centroid is 15 units away and the small one's ~1.
    for view in [
        SortView::perspective(eye, fwd),
        SortView::orthographic(eye, fwd),
    ] {
        let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
        assert_eq!(faces.constraints(), 1);
        assert_eq!(faces.in_degree(1), 1);
        assert_eq!(faces.in_degree(0), 0);
        let centroid = centroid_order(&centroid_keys(&mesh, &view), &[0, 1]);
        assert_eq!(centroid, vec![1, 0]);
        assert_eq!(faces.count_violations(&centroid), 1);
        let r = mpvo(&mesh, &adj, &view, None).unwrap();
        assert_eq!(r.order, vec![0, 1]);
        assert_eq!((r.reordered, r.cycles_broken), (1, 0));
        assert_eq!(faces.count_violations(&r.order), 0);
    }
    // Seen from below, the small tet is in front and the centroid order is right.
    let below = SortView::perspective(DVec3::new(0.2, 0.2, -2.0), DVec3::Z);
    assert_eq!(mpvo_order(&mesh, &adj, &below, None).unwrap(), vec![1, 0]);
}

#[test]
fn eye_in_a_face_plane_leaves_the_pair_free() {
    let mesh = thin_and_small();
    let adj = mesh.face_adjacency();
    for view in [
        SortView::perspective(DVec3::new(0.4, 0.3, 0.0), DVec3::X),
        SortView::perspective(DVec3::new(-5.0, 7.0, 0.0), DVec3::X),
        SortView::orthographic(DVec3::new(0.0, 0.0, 5.0), DVec3::new(1.0, 2.0, 0.0)),
    ] {
        let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
        assert_eq!(faces.constraints(), 0, "{view:?}");
        for f in 0..4 {
            assert_eq!(faces.precedence(0, f), Precedence::Free);
        }
        assert_eq!(faces.count_violations(&[0, 1]), 0);
        assert_eq!(faces.count_violations(&[1, 0]), 0);
        let r = mpvo(&mesh, &adj, &view, None).unwrap();
        assert_eq!(
            r.order,
            centroid_order(&centroid_keys(&mesh, &view), &[0, 1])
        );
    }
}

#[test]
fn cycles_are_broken_at_the_nearest_cell() {
    // Three separate unit tets along x and a hand-made adjacency chosen, face by face, so
    // that the relations form the cycle 0 -> 1 -> 2 -> 0 (-> is "composited before").
    let base = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let p: Vec<Vec3> = (0..3)
        .flat_map(|i| base.map(|b| b + Vec3::new(3.0 * i as f32, 0.0, 0.0)))
        .collect();
    let tets: Vec<[u32; 4]> = (0..3u32).map(|i| [0, 1, 2, 3].map(|v| 4 * i + v)).collect();
    let mesh = TetMesh::new(p, vec![0.0; 12], tets).unwrap();
    let view = SortView::perspective(DVec3::new(4.3, -5.0, 0.4), DVec3::Y);
    let prec = |t: usize, f: usize| face_precedence(mesh.positions(), &mesh.tets()[t], f, &view);
    let face_with = |t: usize, want: Precedence, not: Option<usize>| {
        (0..4)
            .find(|&f| prec(t, f) == want && Some(f) != not)
            .unwrap()
    };
    let back0 = face_with(0, Precedence::TetFirst, None); // 0 before its neighbour (1)
    let front0 = face_with(0, Precedence::NeighbourFirst, None); // neighbour (2) before 0
    let back1 = face_with(1, Precedence::TetFirst, None); // 1 before its neighbour (2)
    let other1 = (0..4).find(|&f| f != back1).unwrap();
    let nb = volux_core::mesh::NO_NEIGHBOR;
    let mut adj = vec![[nb; 4]; 3];
    adj[0][back0] = 1;
    adj[1][other1] = 0;
    adj[0][front0] = 2;
    adj[2][0] = 0;
    adj[1][back1] = 2;
    adj[2][1] = 1;
    let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
    assert_eq!(faces.constraints(), 3);
    assert!((0..3).all(|t| faces.in_degree(t) == 1));
    let depths = centroid_keys(&mesh, &view);
    let nearest = centroid_order(&depths, &[0, 1, 2])[0];
    assert_eq!(nearest, 1, "the eye is closest to the middle tet");
    let r = mpvo(&mesh, &adj, &view, None).unwrap();
    assert_eq!(r.cycles_broken, 1);
    assert_eq!(r.order, vec![1, 2, 0]);
    assert_eq!(faces.count_violations(&r.order), 1);
    // With tet 1 discarded the cycle still has to be broken (it is in the graph).
    let r = mpvo(&mesh, &adj, &view, Some(&[0, 2])).unwrap();
    assert_eq!((r.order, r.cycles_broken), (vec![2, 0], 1));
}

#[test]
fn bad_inputs_are_errors() {
    let mesh = thin_and_small();
    let adj = mesh.face_adjacency();
    let view = SortView::perspective(DVec3::new(0.2, 0.2, 1.0), -DVec3::Z);
    assert!(matches!(
        mpvo(&mesh, &adj[..1], &view, None),
        Err(SortError::LengthMismatch { .. })
    ));
    let mut bad = adj.clone();
    let f = bad[1].iter().position(|&u| u == 0).unwrap();
    bad[1][f] = volux_core::mesh::NO_NEIGHBOR;
    assert_eq!(
        FaceOrder::new(&mesh, &bad, &view).unwrap_err(),
        SortError::AsymmetricAdjacency {
            tet: 0,
            face: adj[0].iter().position(|&u| u == 1).unwrap() as u8,
            neighbour: 1
        }
    );
    let mut bad = adj.clone();
    let g = bad[0].iter().position(|&u| u == 1).unwrap();
    bad[0][g] = 7;
    assert_eq!(
        FaceOrder::new(&mesh, &bad, &view).unwrap_err(),
        SortError::NeighbourOutOfRange {
            tet: 0,
            face: g as u8,
            neighbour: 7
        }
    );
    assert_eq!(
        mpvo(&mesh, &adj, &view, Some(&[0, 2])).unwrap_err(),
        SortError::KeptOutOfRange { id: 2, tets: 2 }
    );
    assert_eq!(
        mpvo(&mesh, &adj, &view, Some(&[1, 1])).unwrap_err(),
        SortError::DuplicateKept(1)
    );
    let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
    assert!(mpvo_with(&faces, &[1.0], None).is_err());
    assert!(mpvo(&mesh, &adj, &view, Some(&[]))
        .unwrap()
        .order
        .is_empty());
}

#[test]
fn view_from_camera() {
    let bounds = volux_core::Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let cam = volux_core::Camera::fit(&bounds);
    let v = SortView::from_camera(&cam);
    assert!(v.perspective && v.eye == cam.eye);
    assert!((v.forward - DVec3::Y).length() < 1e-12);
    let ortho = volux_core::Camera {
        projection: volux_core::Projection::Orthographic { height: 2.0 },
        ..cam
    };
    let v = SortView::from_camera(&ortho);
    assert!(!v.perspective);
    assert!((v.depth(cam.eye + DVec3::new(3.0, 2.0, 5.0)) - 2.0).abs() < 1e-12);
}

/// A `c`^3 lattice box on [0, c]^3, skipping cells where `keep_cell` is false and tets
/// where `drop` is true (given the vertex numbering `i + (c+1) (j + (c+1) k)`).
fn box_mesh(
    c: usize,
    keep_cell: impl Fn(usize, usize, usize) -> bool,
    drop: impl Fn(&[u32; 4]) -> bool,
) -> TetMesh {
    let n = c + 1;
    let id = |i: usize, j: usize, k: usize| (i + n * (j + n * k)) as u32;
    let mut pos = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                pos.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    let mut tets = lattice_tets([c; 3], id, keep_cell);
    tets.retain(|t| !drop(t));
    orient_positive(&pos, &mut tets);
    let len = pos.len();
    TetMesh::new(pos, vec![0.0; len], tets).unwrap()
}

#[test]
fn convexity_of_boxes_and_tori() {
    let all = |_: usize, _: usize, _: usize| true;
    let none = |_: &[u32; 4]| false;
    let full = Convexity::of_mesh(&box_mesh(3, all, none));
    assert!(full.is_convex(), "{full:?}");
    assert_eq!((full.components, full.euler_characteristic), (1, 2));
    assert!(is_convex(&smooth_tets(3000).unwrap()));

    // The corner (3, 0, 0) has odd parity and lies in one corner tet: removing it cuts the
    // corner off with a plane, a truncated cube is still convex.
    let corner = 3u32;
    let cut = box_mesh(3, all, |t| t.contains(&corner));
    assert_eq!(cut.tets().len(), 3 * 3 * 3 * 5 - 1);
    assert!(is_convex(&cut));

    // A whole corner cell removed: a notch with reflex edges.
    let notch = Convexity::of_mesh(&box_mesh(3, |i, j, k| i + j + k > 0, none));
    assert!(!notch.is_convex());
    assert!(
        notch.concave_edges > 0 && notch.nonmanifold_edges == 0,
        "{notch:?}"
    );
    assert_eq!((notch.components, notch.euler_characteristic), (1, 2));

    // The central tet of the corner cell (0,0,0) (corners 0, 3, 5, 6): a cavity touching
    // the outer surface along three edges, which become non-manifold.
    let central = [0u32, 5, 17, 20];
    let pit = Convexity::of_mesh(&box_mesh(3, all, |t| {
        let mut s = *t;
        s.sort_unstable();
        s == central
    }));
    assert!(!pit.is_convex() && pit.nonmanifold_edges > 0, "{pit:?}");

    // The middle cell removed: an inner cavity, a second boundary component.
    let hollow = Convexity::of_mesh(&box_mesh(3, |i, j, k| (i, j, k) != (1, 1, 1), none));
    assert!(!hollow.is_convex());
    assert_eq!(hollow.components, 2);

    let torus = Convexity::of_mesh(&torus_tets(16).unwrap());
    assert!(!torus.is_convex());
    assert_eq!(torus.euler_characteristic, 0);
    assert!(torus.concave_edges > 0);
}

#[test]
fn convexity_of_two_tets() {
    let pair = |apex: Vec3| {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.3, 0.3, 1.0), apex];
        TetMesh::new(p, vec![0.0; 5], vec![[0, 1, 2, 3], [0, 1, 2, 4]]).unwrap()
    };
    let single = TetMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        vec![0.0; 4],
        vec![[0, 1, 2, 3]],
    )
    .unwrap();
    assert!(is_convex(&single));
    // The segment between the apexes crosses the shared triangle: a convex bipyramid.
    assert!(is_convex(&pair(Vec3::new(0.3, 0.3, -1.0))));
    // It passes beside the triangle: reflex edge.
    let c = Convexity::of_mesh(&pair(Vec3::new(2.0, 2.0, -0.1)));
    assert!(!c.is_convex() && c.concave_edges > 0, "{c:?}");
    // Coplanar neighbours (apex in the plane of a face) are within the tolerance.
    assert!(is_convex(&pair(Vec3::new(0.25, -0.0, -1.0))));
}

/// Timings on 1.25M tets: `cargo test --release -p volux-render sort_timings -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn sort_timings() {
    let mesh = smooth_tets(1_250_000).unwrap();
    let n = mesh.tets().len();
    let adj = mesh.face_adjacency();
    let all: Vec<u32> = (0..n as u32).collect();
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    eprintln!("{n} tets");
    for view in [
        cube_views()[0],
        SortView::perspective(DVec3::new(0.5, -1.5, 0.5), DVec3::Y),
        cube_views()[4],
    ] {
        for _ in 0..2 {
            let t = Instant::now();
            let depths = centroid_keys(&mesh, &view);
            let t_keys = ms(t);
            let t = Instant::now();
            let centroid = centroid_order(&depths, &all);
            let t_sort = ms(t);
            let t = Instant::now();
            let mut std_sorted = all.clone();
            std_sorted.sort_by(|&a, &b| reference_cmp(depths[a as usize], depths[b as usize]));
            let t_std = ms(t);
            assert_eq!(std_sorted, centroid);
            let t = Instant::now();
            let faces = FaceOrder::new(&mesh, &adj, &view).unwrap();
            let t_faces = ms(t);
            let t = Instant::now();
            let r = mpvo_with(&faces, &depths, None).unwrap();
            let t_kahn = ms(t);
            let t = Instant::now();
            let r2 = mpvo(&mesh, &adj, &view, None).unwrap();
            let t_mpvo = ms(t);
            assert_eq!(r.order, r2.order);
            let t = Instant::now();
            let v_centroid = faces.count_violations(&centroid);
            let t_count = ms(t);
            // The seeds' key: view depth along the forward axis.
            let pos = mesh.positions();
            let z: Vec<f32> = mesh
                .tets()
                .iter()
                .map(|t| {
                    let c = t.iter().map(|&v| pos[v as usize].as_dvec3()).sum::<DVec3>() * 0.25;
                    (c - view.eye).dot(view.forward) as f32
                })
                .collect();
            let v_z = faces.count_violations(&centroid_order(&z, &all));
            eprintln!(
                "persp {}: keys {t_keys:.1} ms, radix {t_sort:.1} ms (std {t_std:.1}), faces \
                 {t_faces:.1} ms, kahn {t_kahn:.1} ms, mpvo total {t_mpvo:.1} ms, count \
                 {t_count:.1} ms; constraints {}, reordered {}, cycles {}, violations: \
                 distance {v_centroid}, view z {v_z}, mpvo {}",
                view.perspective,
                r.constraints,
                r.reordered,
                r.cycles_broken,
                faces.count_violations(&r.order)
            );
        }
    }
    let t = Instant::now();
    let c = Convexity::of_mesh(&mesh);
    eprintln!("convexity {:.1} ms: {c:?}", ms(t));
}
