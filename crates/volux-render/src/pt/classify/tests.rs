//! Tests of the PT classification: every table entry against brute-force geometry, the fan's
//! coverage of the convex hull, degenerate and non-finite input (the orientation predicate has
//! its own tests, in `geometry/orient/tests.rs`).
use super::*;
use volux_testkit::TestRng;

// -------------------------------------------------------------------------------------------
// Helpers
// -------------------------------------------------------------------------------------------

fn v2(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn pts(c: [(i64, i64); 4]) -> [DVec2; 4] {
    c.map(|(x, y)| v2(x as f64, y as f64))
}

// -------------------------------------------------------------------------------------------
// The table
// -------------------------------------------------------------------------------------------

#[test]
fn codes_roundtrip() {
    for code in 0..81u8 {
        let t = decode_code(code).unwrap();
        assert_eq!(ternary_code(t), code);
        assert_eq!(TERNARY_TABLE[usize::from(code)].code, code);
        assert_eq!(TERNARY_TABLE[usize::from(code)].tests, t);
    }
    assert_eq!(decode_code(81), None);
    assert_eq!(decode_code(255), None);
    for s in [Sign::Negative, Sign::Zero, Sign::Positive] {
        assert_eq!(Sign::from_ternary(s.ternary()), Some(s));
    }
}

/// The seeds' counts: 14 cases of classes 1 and 2 (Wylie et al.), 24 of class 3, 12 of
/// class 4, 50 valid; our derivation splits the other 31 into 1 collinear and 30
/// inconsistent codes, among them all 8 codes with exactly three zero tests.
#[test]
fn table_counts_match_the_seed() {
    let mut by_class = [0usize; 5];
    let (mut collinear, mut inconsistent, mut three_zero_inconsistent) = (0, 0, 0);
    for e in &TERNARY_TABLE {
        let zeros = e.tests.iter().filter(|&&s| s == Sign::Zero).count();
        match e.class {
            ProjectionClass::Degenerate(DegenerateReason::Collinear) => {
                assert_eq!(zeros, 4);
                collinear += 1;
            }
            ProjectionClass::Degenerate(DegenerateReason::Inconsistent) => {
                inconsistent += 1;
                if zeros == 3 {
                    three_zero_inconsistent += 1;
                }
            }
            ProjectionClass::Degenerate(DegenerateReason::NonFinite) => {
                panic!("no table entry is non-finite")
            }
            c => {
                let n = usize::from(c.number().unwrap());
                by_class[n] += 1;
                // The seeds' rule: zero tests 0 → class 1 or 2, 1 → class 3, 2 → class 4.
                let expected_zeros = match n {
                    1 | 2 => 0,
                    3 => 1,
                    _ => 2,
                };
                assert_eq!(zeros, expected_zeros, "code {}", e.code);
            }
        }
    }
    assert_eq!(by_class[1], 8);
    assert_eq!(by_class[2], 6);
    assert_eq!(by_class[1] + by_class[2], 14, "Wylie's 14 cases");
    assert_eq!(by_class[3], 24);
    assert_eq!(by_class[4], 12);
    let valid: usize = by_class.iter().sum();
    assert_eq!(valid, 50);
    assert_eq!(TERNARY_TABLE.iter().filter(|e| e.is_valid()).count(), 50);
    assert_eq!(collinear, 1);
    assert_eq!(inconsistent, 30);
    assert_eq!(
        three_zero_inconsistent, 8,
        "every three-zero code is unrealizable"
    );
    assert_eq!(
        TERNARY_TABLE
            .iter()
            .filter(|e| e.tests.iter().filter(|&&s| s == Sign::Zero).count() == 3)
            .count(),
        8
    );
}

/// The rows printed in table 4.1 of seed `000` and the examples of its figure 4.4.
#[test]
fn table_reproduces_the_seed_rows() {
    let row = |code: usize| &TERNARY_TABLE[code];
    // id 0, 0000, case 12 (class 2), RGBA 0-3-2-1.
    assert_eq!(row(0).class, ProjectionClass::Class2);
    assert_eq!(row(0).order, Some([0, 3, 2, 1]));
    assert_eq!(
        row(0).thick,
        ThickTopology::Crossing {
            edges: [[0, 2], [1, 3]]
        }
    );
    // id 1, 0001, case 18 (class 3), RGBA 0-3-2-1.
    assert_eq!(row(1).class, ProjectionClass::Class3);
    assert_eq!(row(1).order, Some([0, 3, 2, 1]));
    // id 2, 0002, case 6 (class 1), RGBA 0-3-2-1.
    assert_eq!(row(2).class, ProjectionClass::Class1);
    assert_eq!(row(2).order, Some([0, 3, 2, 1]));
    assert_eq!(
        row(2).thick,
        ThickTopology::Interior {
            vertex: 2,
            face: [0, 1, 3]
        }
    );
    // id 3, 0010, case 25 (class 3), RGBA 1-0-3-2.
    assert_eq!(row(3).class, ProjectionClass::Class3);
    assert_eq!(row(3).order, Some([1, 0, 3, 2]));
    // id 4, 0011, case 40 (class 4), RGBA 2-3-1-0: vec_2 ∥ vec_3 and vec_4 ∥ vec_5, v_2 = v_3.
    assert_eq!(row(4).class, ProjectionClass::Class4);
    assert_eq!(row(4).order, Some([2, 3, 1, 0]));
    assert_eq!(row(4).thick, ThickTopology::Coincident { pair: [2, 3] });
    // id 80, 2222, case 11 (class 1 or 2; ours: class 2), RGBA 0-1-2-3.
    assert_eq!(row(80).class, ProjectionClass::Class2);
    assert_eq!(row(80).order, Some([0, 1, 2, 3]));
    // id 13, 0111: "four collinear vertices" in the seed; unreachable with exact signs.
    assert_eq!(
        row(13).class,
        ProjectionClass::Degenerate(DegenerateReason::Inconsistent)
    );
    // id 40, 1111: the collinear entry.
    assert_eq!(
        row(40).class,
        ProjectionClass::Degenerate(DegenerateReason::Collinear)
    );
}

/// Structure of every entry: fan sizes per class, fan starting at the thick vertex, closed
/// rims for classes 1 and 2, order consistent with the thick topology.
#[test]
fn table_entries_are_well_formed() {
    for e in &TERNARY_TABLE {
        let fan = e.fan;
        assert_eq!(
            fan.triangle_count(),
            e.class.triangle_count(),
            "code {}",
            e.code
        );
        assert_eq!(fan.triangles().count(), fan.triangle_count());
        assert_eq!(fan.indices().len(), fan.vertex_count());
        if !e.is_valid() {
            assert_eq!(fan, Fan::EMPTY);
            assert_eq!(e.thick, ThickTopology::None);
            assert_eq!(e.order, None);
            continue;
        }
        let idx = fan.indices();
        assert_eq!(idx[0], 4);
        assert!(idx[1..].iter().all(|&i| i < 4));
        let order = e.order.unwrap();
        let mut sorted = order;
        sorted.sort_unstable();
        assert_eq!(sorted, [0, 1, 2, 3], "order must be a permutation");
        match e.thick {
            ThickTopology::Interior { vertex, face } => {
                assert_eq!(order[2], vertex);
                assert_eq!(idx[1], idx[4], "class 1 rim is closed");
                assert!(face.windows(2).all(|w| w[0] < w[1]));
                assert!(!idx.contains(&vertex));
            }
            ThickTopology::Crossing { edges } => {
                assert_eq!(idx[1], idx[5], "class 2 rim is closed");
                assert_eq!(sorted2(order[0], order[2]), edges[0]);
                assert_eq!(sorted2(order[1], order[3]), edges[1]);
            }
            ThickTopology::OnEdge { vertex, edge, apex } => {
                assert_eq!(order[0], apex);
                assert_eq!(order[2], vertex);
                assert_eq!(sorted2(order[1], order[3]), edge);
                assert!(!idx.contains(&vertex));
            }
            ThickTopology::Coincident { pair } => {
                assert_eq!([order[0], order[1]], pair);
                assert!(!idx[1..].contains(&pair[0]) && !idx[1..].contains(&pair[1]));
            }
            ThickTopology::None => panic!("valid entry without thick vertex"),
        }
    }
}

// -------------------------------------------------------------------------------------------
// Brute-force geometric classification (independent of the table's sign analysis)
// -------------------------------------------------------------------------------------------

/// Classifies by direct geometry: collinearity of all four, coincident pairs, a vertex
/// strictly between two others on a line, a vertex strictly inside the triangle of the
/// others, or two crossing segments.
fn brute_force(v: [DVec2; 4]) -> (ProjectionClass, ThickTopology) {
    let o = |i: usize, j: usize, k: usize| orient2d(v[i], v[j], v[k]);
    let triples = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)];
    if triples.iter().all(|&(i, j, k)| o(i, j, k) == Sign::Zero) {
        return (
            ProjectionClass::Degenerate(DegenerateReason::Collinear),
            ThickTopology::None,
        );
    }
    let mut coincident = vec![];
    for i in 0..4 {
        for j in i + 1..4 {
            if v[i] == v[j] {
                coincident.push([i as u8, j as u8]);
            }
        }
    }
    if !coincident.is_empty() {
        assert_eq!(
            coincident.len(),
            1,
            "two coincident pairs imply collinear: {v:?}"
        );
        return (
            ProjectionClass::Class4,
            ThickTopology::Coincident {
                pair: coincident[0],
            },
        );
    }
    // Strictly between, for distinct collinear points: coordinate comparisons are exact.
    let between = |m: DVec2, e: DVec2, f: DVec2| {
        m.x >= e.x.min(f.x) && m.x <= e.x.max(f.x) && m.y >= e.y.min(f.y) && m.y <= e.y.max(f.y)
    };
    let mut on_edge = vec![];
    for m in 0..4 {
        for e in 0..4 {
            for f in e + 1..4 {
                if m == e || m == f || o(e, f, m) != Sign::Zero {
                    continue;
                }
                if between(v[m], v[e], v[f]) {
                    let apex = 6 - m - e - f;
                    on_edge.push(ThickTopology::OnEdge {
                        vertex: m as u8,
                        edge: [e as u8, f as u8],
                        apex: apex as u8,
                    });
                }
            }
        }
    }
    if !on_edge.is_empty() {
        assert_eq!(on_edge.len(), 1, "{v:?}");
        return (ProjectionClass::Class3, on_edge[0]);
    }
    // General position: no three collinear.
    let inside = |k: usize, i: usize, j: usize, l: usize| {
        let s = o(i, j, l);
        o(k, i, j) == s && o(k, j, l) == s && o(k, l, i) == s
    };
    let mut interior = vec![];
    for k in 0..4 {
        let others: Vec<usize> = (0..4).filter(|&x| x != k).collect();
        if inside(k, others[0], others[1], others[2]) {
            interior.push(ThickTopology::Interior {
                vertex: k as u8,
                face: [others[0] as u8, others[1] as u8, others[2] as u8],
            });
        }
    }
    if !interior.is_empty() {
        assert_eq!(interior.len(), 1, "{v:?}");
        return (ProjectionClass::Class1, interior[0]);
    }
    let cross = |a: usize, b: usize, c: usize, d: usize| {
        o(a, b, c) != o(a, b, d) && o(c, d, a) != o(c, d, b)
    };
    let pairings = [[[0, 1], [2, 3]], [[0, 2], [1, 3]], [[0, 3], [1, 2]]];
    let crossing: Vec<_> = pairings
        .iter()
        .filter(|p| cross(p[0][0], p[0][1], p[1][0], p[1][1]))
        .collect();
    assert_eq!(crossing.len(), 1, "{v:?}");
    let p = crossing[0];
    (
        ProjectionClass::Class2,
        ThickTopology::Crossing {
            edges: [
                [p[0][0] as u8, p[0][1] as u8],
                [p[1][0] as u8, p[1][1] as u8],
            ],
        },
    )
}

/// Twice the signed area of a fan triangle.
fn tri_area2(p: &[DVec2; 5], t: [u8; 3]) -> f64 {
    let [a, b, c] = t.map(|i| p[usize::from(i)]);
    (b - a).perp_dot(c - a)
}

/// The convex hull, counter-clockwise (Andrew's monotone chain with the exact predicate).
fn hull(v: &[DVec2; 4]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = v.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut lower: Vec<DVec2> = vec![];
    for &q in &p {
        while lower.len() >= 2
            && orient2d(lower[lower.len() - 2], lower[lower.len() - 1], q) != Sign::Positive
        {
            lower.pop();
        }
        lower.push(q);
    }
    let mut upper: Vec<DVec2> = vec![];
    for &q in p.iter().rev() {
        while upper.len() >= 2
            && orient2d(upper[upper.len() - 2], upper[upper.len() - 1], q) != Sign::Positive
        {
            upper.pop();
        }
        upper.push(q);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

fn polygon_area2(h: &[DVec2]) -> f64 {
    let n = h.len();
    (1..n.saturating_sub(1))
        .map(|i| (h[i] - h[0]).perp_dot(h[i + 1] - h[0]))
        .sum()
}

/// Checks one projection against the brute force, the fan against the hull, and the thick
/// vertex's parameters; returns the code.
fn check(v: [DVec2; 4]) -> u8 {
    let c = classify(v);
    let code = c.code.expect("finite input has a code");
    let entry = c.entry().unwrap();
    let (class, topology) = brute_force(v);
    assert_eq!(c.class, class, "code {code}, {v:?}");
    assert_eq!(entry.class, class);
    assert_eq!(entry.thick, topology, "code {code}, {v:?}");
    assert_eq!(c.fan, entry.fan);
    assert_eq!(c.fan.triangle_count(), class.triangle_count());
    let Some(thick) = c.thick else {
        assert!(class.is_degenerate());
        assert_eq!(c.fan.triangle_count(), 0);
        return code;
    };
    assert_eq!(thick.kind.topology(), topology);
    let p = c.points(v);
    assert_eq!(p[4], thick.position);
    // Orientation: exact for the fan triangles whose thick vertex is a projected vertex; for
    // class 2, every three consecutive rim vertices turn counter-clockwise (convex rim).
    let idx = c.fan.indices();
    if class == ProjectionClass::Class2 {
        for i in 0..4 {
            let [a, b, d] = [idx[1 + i], idx[1 + (i + 1) % 4], idx[1 + (i + 2) % 4]];
            let s = orient2d(p[usize::from(a)], p[usize::from(b)], p[usize::from(d)]);
            assert_eq!(s, Sign::Positive, "code {code}, {v:?}");
        }
    } else {
        for t in c.fan.triangles() {
            let [a, b, d] = t.map(|i| p[usize::from(i)]);
            assert_eq!(orient2d(a, b, d), Sign::Positive, "code {code}, {v:?}");
        }
    }
    // Area: the fan's triangles tile the hull.
    let h = hull(&v);
    let hull_area = polygon_area2(&h);
    let fan_area: f64 = c.fan.triangles().map(|t| tri_area2(&p, t)).sum();
    let fan_abs: f64 = c.fan.triangles().map(|t| tri_area2(&p, t).abs()).sum();
    let lo = v.iter().fold(DVec2::splat(f64::INFINITY), |m, x| m.min(*x));
    let hi = v
        .iter()
        .fold(DVec2::splat(f64::NEG_INFINITY), |m, x| m.max(*x));
    let extent = (hi - lo).max_element();
    let tol = 1e-9 * hull_area + 1e-13 * extent * extent;
    assert!(h.len() >= 3, "a non-degenerate projection has a 2D hull");
    assert!(
        (fan_area - hull_area).abs() <= tol,
        "{fan_area} vs {hull_area}"
    );
    assert!(
        (fan_abs - hull_area).abs() <= tol,
        "{fan_abs} vs {hull_area}"
    );
    for t in c.fan.triangles() {
        assert!(tri_area2(&p, t) >= -tol);
    }
    // Parameters reproduce the thick vertex (when the hull is not a sliver: the crossing of
    // two nearly parallel segments is ill-conditioned, only its range is checked then).
    let well_conditioned = hull_area > 1e-6 * extent * extent;
    let close =
        |a: DVec2, b: DVec2| !well_conditioned || (a - b).abs().max_element() <= 1e-9 * extent;
    match thick.kind {
        ThickKind::Interior {
            vertex,
            face,
            barycentric,
        } => {
            assert!(barycentric.iter().all(|&b| (0.0..=1.0).contains(&b)));
            assert!((barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let q: DVec2 = (0..3)
                .map(|i| p[usize::from(face[i])] * barycentric[i])
                .sum();
            assert_eq!(thick.position, v[usize::from(vertex)]);
            assert!(close(q, thick.position), "{q} vs {}", thick.position);
        }
        ThickKind::Crossing { edges, params } => {
            let [[a, b], [d, e]] = edges.map(|e| e.map(|i| v[usize::from(i)]));
            assert!(params.iter().all(|&u| (0.0..=1.0).contains(&u)));
            let x = a + (b - a) * params[0];
            let y = d + (e - d) * params[1];
            assert!(close(x, thick.position) && close(y, thick.position));
        }
        ThickKind::OnEdge {
            vertex, edge, t, ..
        } => {
            assert!((0.0..=1.0).contains(&t));
            let [e, f] = edge.map(|i| v[usize::from(i)]);
            assert_eq!(thick.position, v[usize::from(vertex)]);
            assert!(close(e + (f - e) * t, thick.position));
        }
        ThickKind::Coincident { pair } => {
            assert_eq!(thick.position, v[usize::from(pair[0])]);
            assert_eq!(thick.position, v[usize::from(pair[1])]);
        }
    }
    code
}

/// Random points of the bounding box: strictly inside the hull, each lies in exactly one fan
/// triangle; strictly outside, in none (points on an edge are skipped).
fn check_coverage(v: [DVec2; 4], rng: &mut TestRng, samples: usize) {
    let c = classify(v);
    if c.class.is_degenerate() {
        return;
    }
    let p = c.points(v);
    let h = hull(&v);
    let lo = v.iter().fold(DVec2::splat(f64::INFINITY), |m, x| m.min(*x));
    let hi = v
        .iter()
        .fold(DVec2::splat(f64::NEG_INFINITY), |m, x| m.max(*x));
    for _ in 0..samples {
        let s = v2(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y));
        let hs: Vec<Sign> = (0..h.len())
            .map(|i| orient2d(h[i], h[(i + 1) % h.len()], s))
            .collect();
        let mut on_edge = hs.contains(&Sign::Zero);
        let in_hull = hs.iter().all(|&x| x == Sign::Positive);
        let mut count = 0;
        for t in c.fan.triangles() {
            let [a, b, d] = t.map(|i| p[usize::from(i)]);
            let ts = [orient2d(a, b, s), orient2d(b, d, s), orient2d(d, a, s)];
            on_edge |= ts.contains(&Sign::Zero);
            if ts.iter().all(|&x| x == Sign::Positive) {
                count += 1;
            }
        }
        if on_edge {
            continue;
        }
        assert_eq!(count, usize::from(in_hull), "{v:?} sample {s}");
    }
}

/// The 24 permutations of four indices.
fn permutations() -> Vec<[usize; 4]> {
    let mut out = vec![];
    for a in 0..4 {
        for b in 0..4 {
            for c in 0..4 {
                for d in 0..4 {
                    let p = [a, b, c, d];
                    let mut s = p;
                    s.sort_unstable();
                    if s == [0, 1, 2, 3] {
                        out.push(p);
                    }
                }
            }
        }
    }
    out
}

fn realizable_codes() -> Vec<u8> {
    TERNARY_TABLE
        .iter()
        .filter(|e| e.class != ProjectionClass::Degenerate(DegenerateReason::Inconsistent))
        .map(|e| e.code)
        .collect()
}

// -------------------------------------------------------------------------------------------
// All 81 codes against the brute force
// -------------------------------------------------------------------------------------------

/// Every configuration of four points of a 4 × 4 integer grid (65 536, exact coordinates):
/// each one agrees with the brute force, together they produce exactly the 51 realizable
/// codes (50 valid and the collinear one), and none produces any of the 30 inconsistent
/// codes.
#[test]
fn every_code_on_an_exhaustive_grid_matches_brute_force() {
    let grid: Vec<(i64, i64)> = (0..16).map(|i| (i % 4, i / 4)).collect();
    let mut hits = [0usize; 81];
    let mut rng = TestRng::new(3);
    for a in 0..16 {
        for b in 0..16 {
            for c in 0..16 {
                for d in 0..16 {
                    let v = pts([grid[a], grid[b], grid[c], grid[d]]);
                    let code = check(v);
                    hits[usize::from(code)] += 1;
                    if (a * 4096 + b * 256 + c * 16 + d) % 97 == 0 {
                        check_coverage(v, &mut rng, 32);
                    }
                }
            }
        }
    }
    let realizable = realizable_codes();
    assert_eq!(realizable.len(), 51);
    for code in 0..81u8 {
        let n = hits[usize::from(code)];
        if realizable.contains(&code) {
            assert!(n > 0, "code {code} never produced");
        } else {
            assert_eq!(n, 0, "inconsistent code {code} produced");
        }
    }
}

/// Hand-made witnesses: one base configuration per class, under all 24 vertex permutations
/// and a mirror, cover every realizable code; each is checked against the brute force.
#[test]
fn every_code_has_a_hand_made_witness() {
    let bases: [([(i64, i64); 4], ProjectionClass); 5] = [
        ([(0, 0), (6, 0), (0, 6), (1, 2)], ProjectionClass::Class1),
        ([(0, 0), (5, 1), (6, 6), (-1, 4)], ProjectionClass::Class2),
        ([(0, 0), (6, 0), (2, 0), (1, 5)], ProjectionClass::Class3),
        ([(1, 1), (1, 1), (6, 0), (0, 6)], ProjectionClass::Class4),
        (
            [(0, 0), (1, 2), (3, 6), (-2, -4)],
            ProjectionClass::Degenerate(DegenerateReason::Collinear),
        ),
    ];
    let mut covered = [false; 81];
    let mut rng = TestRng::new(17);
    for (base, class) in bases {
        for perm in permutations() {
            for mirror in [false, true] {
                let c: [(i64, i64); 4] = std::array::from_fn(|i| {
                    let (x, y) = base[perm[i]];
                    if mirror {
                        (-x, y)
                    } else {
                        (x, y)
                    }
                });
                let v = pts(c);
                let code = check(v);
                assert_eq!(classify(v).class, class);
                covered[usize::from(code)] = true;
                check_coverage(v, &mut rng, 64);
            }
        }
    }
    for code in realizable_codes() {
        assert!(
            covered[usize::from(code)],
            "code {code} has no hand-made witness"
        );
    }
    // Class 1 and 2 bases under permutations and mirror give 8 + 6 codes, class 3 24, class
    // 4 12: the counts of the table again, now from geometry.
    let count = |class: ProjectionClass| {
        (0..81)
            .filter(|&c| covered[c] && TERNARY_TABLE[c].class == class)
            .count()
    };
    assert_eq!(count(ProjectionClass::Class1), 8);
    assert_eq!(count(ProjectionClass::Class2), 6);
    assert_eq!(count(ProjectionClass::Class3), 24);
    assert_eq!(count(ProjectionClass::Class4), 12);
}

/// 10^5 random tetrahedra (orthographic and perspective projections of random points, random
/// small-integer configurations rich in degeneracies, and near-degenerate ones one ulp away
/// from a degeneracy) agree with the brute force; the fan tiles the hull (area to 1e-9
/// relative, coverage by sampling); every realizable code is met.
#[test]
fn random_tetrahedra_match_brute_force() {
    let mut rng = TestRng::new(0x5eed_1234_abcd_ef01);
    let mut hits = [0usize; 81];
    let mut strictly_relative = 0;
    for n in 0..100_000 {
        let kind = n % 20;
        let v: [DVec2; 4] = match kind {
            // Orthographic projection of random points of [-1, 1]^3.
            0..=7 => std::array::from_fn(|_| v2(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))),
            // Perspective projection of points of a box in front of the eye.
            8..=11 => std::array::from_fn(|_| {
                let z = rng.range(2.0, 6.0);
                v2(rng.range(-1.0, 1.0) / z, rng.range(-1.0, 1.0) / z)
            }),
            // Small integer grid: coincident and collinear vertices are frequent.
            12..=16 => {
                let c: [(i64, i64); 4] = std::array::from_fn(|_| (rng.int(-3, 3), rng.int(-3, 3)));
                pts(c)
            }
            // Near-degenerate: an exact degeneracy (collinear triple or coincident pair)
            // scaled, then moved by one ulp or not at all.
            _ => {
                let a = (rng.int(-50, 50), rng.int(-50, 50));
                let d = (rng.int(-20, 20), rng.int(-20, 20));
                let t = rng.int(-2, 3);
                let m = (a.0 + t * d.0, a.1 + t * d.1);
                let b = (a.0 + d.0, a.1 + d.1);
                let w = (rng.int(-50, 50), rng.int(-50, 50));
                let s = rng.range(0.5, 2.0) * 2f64.powi(rng.int(-30, 30) as i32);
                let mut v = pts([a, b, m, w]).map(|p| p * s);
                match rng.int(0, 4) {
                    0 => v[2].x = v[2].x.next_up(),
                    1 => v[2].y = v[2].y.next_down(),
                    2 => v[1] = v[0],
                    _ => {}
                }
                let perm = permutations()[rng.int(0, 23) as usize];
                std::array::from_fn(|i| v[perm[i]])
            }
        };
        let code = check(v);
        hits[usize::from(code)] += 1;
        if n % 200 == 0 {
            check_coverage(v, &mut rng, 32);
        }
        // General-position random tetrahedra: the fan area equals the hull area to 1e-9
        // relative, with no absolute slack.
        if kind <= 11 {
            let c = classify(v);
            let h = hull(&v);
            let hull_area = polygon_area2(&h);
            if !c.class.is_degenerate() && hull_area > 1e-6 {
                let p = c.points(v);
                let fan: f64 = c.fan.triangles().map(|t| tri_area2(&p, t)).sum();
                assert!(((fan - hull_area) / hull_area).abs() <= 1e-9);
                strictly_relative += 1;
            }
        }
    }
    assert!(strictly_relative > 50_000);
    for code in realizable_codes() {
        assert!(hits[usize::from(code)] > 0, "code {code} never met");
    }
    for (code, &n) in hits.iter().enumerate() {
        if TERNARY_TABLE[code].class == ProjectionClass::Degenerate(DegenerateReason::Inconsistent)
        {
            assert_eq!(n, 0);
        }
    }
}

// -------------------------------------------------------------------------------------------
// Degenerate and hostile input
// -------------------------------------------------------------------------------------------

#[test]
fn collinear_projections_are_degenerate() {
    let cases = [
        [(0, 0), (1, 1), (2, 2), (3, 3)],
        [(0, 0), (0, 0), (0, 0), (0, 0)],
        [(0, 0), (0, 0), (5, 0), (-3, 0)],
        [(1, 2), (1, 2), (3, 4), (3, 4)],
        [(0, 5), (0, -1), (0, 7), (0, 5)],
    ];
    for c in cases {
        for perm in permutations() {
            let v = pts(std::array::from_fn(|i| c[perm[i]]));
            let r = classify(v);
            assert_eq!(
                r.class,
                ProjectionClass::Degenerate(DegenerateReason::Collinear),
                "{v:?}"
            );
            assert_eq!(r.code, Some(40));
            assert_eq!(r.fan.triangle_count(), 0);
            assert!(r.fan.indices().is_empty());
            assert_eq!(r.thick, None);
            assert_eq!(r.points(v)[4], v[0]);
        }
    }
    // Exactly collinear with non-integer coordinates that the naive test calls non-collinear.
    let u = 2f64.powi(-53);
    let v = [
        v2(0.5, 0.5),
        v2(12.0, 12.0),
        v2(24.0, 24.0),
        v2(0.5 + 17.0 * u, 0.5 + 17.0 * u),
    ];
    assert_eq!(
        classify(v).class,
        ProjectionClass::Degenerate(DegenerateReason::Collinear)
    );
}

#[test]
fn non_finite_input_is_degenerate_without_panic() {
    let good = [v2(0.0, 0.0), v2(1.0, 0.0), v2(0.0, 1.0), v2(0.3, 0.3)];
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for i in 0..4 {
            for axis in 0..2 {
                let mut v = good;
                v[i][axis] = bad;
                let c = classify(v);
                assert_eq!(
                    c.class,
                    ProjectionClass::Degenerate(DegenerateReason::NonFinite)
                );
                assert_eq!(c.code, None);
                assert_eq!(c.entry(), None);
                assert_eq!(c.fan.triangle_count(), 0);
                assert_eq!(c.thick, None);
            }
        }
    }
}

/// Huge, tiny, subnormal and mixed-magnitude coordinates: exact classes, finite parameters in
/// range, thick vertex within the bounding box.
#[test]
fn extreme_magnitudes_classify_correctly() {
    let square = [(0, 0), (4, 1), (5, 5), (1, 4)]; // class 2, edges 0-2 and 1-3
    let interior = [(0, 0), (8, 0), (0, 8), (2, 2)]; // class 1
    let on_edge = [(0, 0), (8, 0), (4, 0), (2, 6)]; // class 3
    let pair = [(0, 0), (8, 0), (0, 8), (8, 0)]; // class 4
    for k in [-1074, -1070, -1000, -600, -300, 0, 300, 600, 1000, 1019] {
        let s = 2f64.powi(k / 2) * 2f64.powi(k - k / 2);
        for (base, class) in [
            (square, ProjectionClass::Class2),
            (interior, ProjectionClass::Class1),
            (on_edge, ProjectionClass::Class3),
            (pair, ProjectionClass::Class4),
        ] {
            let v = pts(base).map(|p| p * s);
            assert!(v.iter().all(|p| p.is_finite()));
            let c = classify(v);
            // Scaling by a power of two is exact until the subnormal range rounds the
            // smallest coordinates; at 2^-1074 the points are still exact integers of ulps.
            assert_eq!(c.class, class, "scale 2^{k}");
            let t = c.thick.unwrap();
            assert!(t.position.is_finite());
            let lo = v.iter().fold(DVec2::splat(f64::INFINITY), |m, x| m.min(*x));
            let hi = v
                .iter()
                .fold(DVec2::splat(f64::NEG_INFINITY), |m, x| m.max(*x));
            assert!(t.position.cmpge(lo).all() && t.position.cmple(hi).all());
            match t.kind {
                ThickKind::Crossing { params, .. } => {
                    assert!(params.iter().all(|u| (0.0..=1.0).contains(u)));
                    if (-1000..=1000).contains(&k) {
                        // Edges (0,0)-(5,5) and (4,1)-(1,4) cross at (2.5, 2.5): u = v = 1/2.
                        assert!((params[0] - 0.5).abs() < 1e-12 && (params[1] - 0.5).abs() < 1e-12);
                        let err = (t.position - v2(2.5, 2.5) * s).abs().max_element();
                        assert!(err <= 1e-12 * 5.0 * s);
                    }
                }
                ThickKind::Interior { barycentric, .. } => {
                    assert!((barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                    if (-1000..=1000).contains(&k) {
                        // (2,2) = 1/2 (0,0) + 1/4 (8,0) + 1/4 (0,8).
                        let want = [0.5, 0.25, 0.25];
                        for (b, w) in barycentric.iter().zip(want) {
                            assert!((b - w).abs() < 1e-12);
                        }
                    }
                }
                ThickKind::OnEdge { t: u, .. } => {
                    assert!((0.0..=1.0).contains(&u));
                    if (-1000..=1000).contains(&k) {
                        assert!((u - 0.5).abs() < 1e-12);
                    }
                }
                ThickKind::Coincident { pair } => assert_eq!(pair, [1, 3]),
            }
        }
    }
    // Mixed magnitudes in one tetrahedron: a class 1 whose interior vertex is tiny.
    let v = [
        v2(-1e300, -1e300),
        v2(1e300, -1e300),
        v2(0.0, 1e300),
        v2(1e-300, -1e-300),
    ];
    let c = classify(v);
    assert_eq!(c.class, ProjectionClass::Class1);
    assert_eq!(brute_force(v), (c.class, c.entry().unwrap().thick));
    // Extreme finite coordinates.
    let m = f64::MAX;
    let v = [v2(-m, -m), v2(m, -m), v2(m, m), v2(-m, m)];
    let c = classify(v);
    assert_eq!(c.class, ProjectionClass::Class2);
    assert!(c.thick.unwrap().position.is_finite());
}

/// The fan layout documented in the module: first index 4, closed rims for classes 1 and 2,
/// and the seed's vertex counts (`cnt` = 5, 6, 4, 3).
#[test]
fn fan_layout_per_class() {
    let cases = [
        ([(0, 0), (6, 0), (0, 6), (1, 2)], 5usize),
        ([(0, 0), (5, 1), (6, 6), (-1, 4)], 6),
        ([(0, 0), (6, 0), (2, 0), (1, 5)], 4),
        ([(1, 1), (1, 1), (6, 0), (0, 6)], 3),
    ];
    for (c, cnt) in cases {
        let v = pts(c);
        let r = classify(v);
        assert_eq!(r.fan.vertex_count(), cnt);
        assert_eq!(r.fan.indices()[0], 4);
        assert_eq!(r.fan.triangle(cnt - 2), None);
        let tris: Vec<[u8; 3]> = r.fan.triangles().collect();
        assert_eq!(tris.len(), cnt - 2);
        for (i, t) in tris.iter().enumerate() {
            assert_eq!(Some(*t), r.fan.triangle(i));
            assert_eq!(t[0], 4);
        }
    }
    // Class 1 example: v_3 inside (0, 1, 2), counter-clockwise rim 0 1 2 0.
    let r = classify(pts([(0, 0), (6, 0), (0, 6), (1, 2)]));
    assert_eq!(r.fan.indices(), &[4, 0, 1, 2, 0]);
    assert_eq!(r.thick.unwrap().position, v2(1.0, 2.0));
    // Class 2 example: edges 0-2 and 1-3 cross; rim 0 1 2 3 0.
    let r = classify(pts([(0, 0), (5, 1), (6, 6), (-1, 4)]));
    assert_eq!(r.fan.indices(), &[4, 0, 1, 2, 3, 0]);
}
