use super::*;
use crate::integrate::segment::SegmentIntegrator;
use volux_testkit::reference::max_diff;
use volux_testkit::tf::{random_tf, tf};
use volux_testkit::TestRng;

/// Bilinear interpolation of `f` sampled at nodes uniform in `u`, `depth(u)` the thickness.
struct Grid {
    n: usize,
    vals: Vec<f64>,
}
impl Grid {
    fn new(n: usize, depth: &dyn Fn(f64) -> f64) -> Self {
        let d: Vec<f64> = (0..n).map(|i| depth(i as f64 / (n - 1) as f64)).collect();
        let mut vals = vec![0.0; n * n];
        vals.par_chunks_mut(n).enumerate().for_each(|(i, row)| {
            for (j, e) in row.iter_mut().enumerate() {
                *e = (psi_exact(d[i], d[j]) as f32) as f64;
            }
        });
        Self { n, vals }
    }
    fn at(&self, u: f64, v: f64) -> f64 {
        let last = (self.n - 1) as f64;
        let p = |x: f64| {
            let x = x.clamp(0.0, 1.0) * last;
            let i = (x as usize).min(self.n - 2);
            (i, x - i as f64)
        };
        let ((i, fi), (j, fj)) = (p(u), p(v));
        let e = |i: usize, j: usize| self.vals[i * self.n + j];
        let a = e(i, j) + (e(i, j + 1) - e(i, j)) * fj;
        let b = e(i + 1, j) + (e(i + 1, j + 1) - e(i + 1, j)) * fj;
        a + (b - a) * fi
    }
}

/// The measurement behind the table's node placement (module documentation): maximum
/// bilinear error of `psi` with nodes uniform in `gamma` (Moreland and Angel) and in
/// `1 - sqrt(1 - gamma)`, for 256, 512 and 1024 nodes per axis. About 3 s:
/// `cargo test -p volux-render explore_table -- --ignored --nocapture`.
#[test]
#[ignore]
fn explore_table_parametrizations() {
    let gamma_depth = |g: f64| {
        if g >= 1.0 {
            f64::INFINITY
        } else {
            g / (1.0 - g)
        }
    };
    let sqrt_depth = |v: f64| {
        if v >= 1.0 {
            f64::INFINITY
        } else {
            let r = 1.0 - v;
            (1.0 - r * r) / (r * r)
        }
    };
    let gamma_coord = |d: f64| d / (1.0 + d);
    let sqrt_coord = |d: f64| {
        let r = (1.0 + d).sqrt();
        d / (r * (r + 1.0))
    };
    for n in [256usize, 512, 1024] {
        for (name, depth, coord) in [
            (
                "gamma",
                &gamma_depth as &dyn Fn(f64) -> f64,
                &gamma_coord as &dyn Fn(f64) -> f64,
            ),
            ("sqrt", &sqrt_depth, &sqrt_coord),
        ] {
            let g = Grid::new(n, depth);
            let mut rng = TestRng::new(5);
            let (mut worst, mut wat) = (0.0f64, (0.0, 0.0));
            // random thicknesses: log-uniform in [1e-4, 1e6] plus uniform in coordinate
            for k in 0..200_000 {
                let (a, b) = if k % 2 == 0 {
                    (
                        10f64.powf(rng.unit() * 10.0 - 4.0),
                        10f64.powf(rng.unit() * 10.0 - 4.0),
                    )
                } else {
                    (depth(rng.unit()), depth(rng.unit()))
                };
                let e = (g.at(coord(a), coord(b)) - psi_exact(a, b)).abs();
                if e > worst {
                    worst = e;
                    wat = (a, b);
                }
            }
            let mut centre = 0.0f64;
            let h = 1.0 / (n - 1) as f64;
            let mut cat = (0, 0);
            for i in 0..n - 1 {
                for j in 0..n - 1 {
                    let (u, v) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
                    let e = (g.at(u, v) - psi_exact(depth(u), depth(v))).abs();
                    if e > centre {
                        centre = e;
                        cat = (i, j);
                    }
                }
            }
            eprintln!(
                "n {n} {name}: random {worst:.2e} at {wat:?}, centres {centre:.2e} at {cat:?}"
            );
        }
    }
}

fn widen(v: [f32; 4]) -> [f64; 4] {
    v.map(f64::from)
}

/// Brute force `psi`: composite Simpson with `m` steps.
fn psi_simpson(a: f64, b: f64, m: usize) -> f64 {
    let f = |x: f64| (-(a * x + 0.5 * (b - a) * x * x)).exp();
    let h = 1.0 / m as f64;
    (0..m)
        .map(|i| {
            let x = i as f64 * h;
            h / 6.0 * (f(x) + 4.0 * f(x + 0.5 * h) + f(x + h))
        })
        .sum()
}

/// Thickness log-uniform in `[10^lo, 10^hi]`, or exactly 0 one time in ten.
fn log_depth(rng: &mut TestRng, lo: f64, hi: f64) -> f64 {
    if rng.unit() < 0.1 {
        0.0
    } else {
        10f64.powf(lo + (hi - lo) * rng.unit())
    }
}

#[test]
fn psi_exact_matches_brute_force() {
    let mut rng = TestRng::new(1);
    let mut worst = 0.0f64;
    for _ in 0..60 {
        let (a, b) = (
            log_depth(&mut rng, -6.0, 3.0),
            log_depth(&mut rng, -6.0, 3.0),
        );
        let (got, want) = (psi_exact(a, b), psi_simpson(a, b, 200_000));
        worst = worst.max((got - want).abs() / want);
    }
    eprintln!("psi_exact vs Simpson 2e5 (thickness <= 1e3): max relative error {worst:.2e}");
    assert!(worst < 1e-11, "{worst}");
    // Constant extinction: psi = (1 - exp(-a)) / a, over the whole range.
    let mut worst_const = 0.0f64;
    for e in -120..=120 {
        let a = 10f64.powf(e as f64 / 10.0);
        let want = -(-a).exp_m1() / a;
        worst_const = worst_const.max((psi_exact(a, a) - want).abs() / want);
    }
    eprintln!("psi_exact, constant extinction 1e-12..1e12: max relative error {worst_const:.2e}");
    assert!(worst_const < 1e-14, "{worst_const}");
    // Splitting the segment at m: psi(a, b) = m psi(a m, c m) + (1 - m) exp(-q(m))
    // psi(c (1 - m), b (1 - m)), c = a + (b - a) m the thickness at the split. Checks large
    // and very unequal thicknesses, where brute force is slow.
    let mut worst_split = 0.0f64;
    for _ in 0..400 {
        let (a, b) = (
            log_depth(&mut rng, -8.0, 9.0),
            log_depth(&mut rng, -8.0, 9.0),
        );
        let m = rng.unit();
        let c = a + (b - a) * m;
        let q = a * m + 0.5 * (b - a) * m * m;
        let split = m * psi_exact(a * m, c * m)
            + (1.0 - m) * (-q).exp() * psi_exact(c * (1.0 - m), b * (1.0 - m));
        let whole = psi_exact(a, b);
        worst_split = worst_split.max((split - whole).abs() / whole);
    }
    eprintln!(
        "psi_exact split identity, thickness up to 1e9: max relative error {worst_split:.2e}"
    );
    assert!(worst_split < 1e-12, "{worst_split}");
}

#[test]
fn psi_exact_edge_cases() {
    assert_eq!(psi_exact(0.0, 0.0), 1.0);
    assert_eq!(psi_exact(-3.0, -1.0), 1.0);
    assert_eq!(psi_exact(f64::INFINITY, 1.0), 0.0);
    assert_eq!(psi_exact(1.0, f64::INFINITY), 0.0);
    assert!(psi_exact(f64::NAN, 1.0).is_nan());
    // Only the back end absorbs: psi = int exp(-b x^2 / 2) -> sqrt(pi / (2 b)) for large b.
    let b = 1e8;
    let want = (std::f64::consts::PI / (2.0 * b)).sqrt();
    assert!((psi_exact(0.0, b) / want - 1.0).abs() < 1e-12);
    // Only the front end absorbs: for large a, psi ~ 1 / a (1 + 1 / a + ...).
    let a = 1e8;
    assert!((psi_exact(a, 0.0) * a - 1.0).abs() < 2e-8);
    // psi lies between the end transparency zeta and 1, and decreases in both arguments.
    let mut rng = TestRng::new(2);
    for _ in 0..1000 {
        let (a, b) = (
            log_depth(&mut rng, -4.0, 4.0),
            log_depth(&mut rng, -4.0, 4.0),
        );
        let p = psi_exact(a, b);
        let zeta = (-0.5 * (a + b)).exp();
        assert!(p >= zeta && p <= 1.0, "{a} {b} {p}");
        assert!(psi_exact(a * 1.1 + 1e-3, b) < p && psi_exact(a, b * 1.1 + 1e-3) < p);
    }
}

/// A resolved TF that is linear in colour and extinction on `[lo, hi]`.
fn linear_tf(rng: &mut TestRng, lo: f64, hi: f64, tau_max: f64) -> TransferFunction {
    let c = |rng: &mut TestRng, x: f64| [x, rng.unit(), rng.unit(), rng.unit()];
    let t = |rng: &mut TestRng, x: f64| [x, tau_max * rng.unit() * rng.unit()];
    let color = vec![c(rng, lo), c(rng, hi)];
    let extinction = vec![t(rng, lo), t(rng, hi)];
    let t = TransferFunction {
        space: volux_core::transfer::Space::Value,
        color,
        extinction,
        opacity: Vec::new(),
        opacity_step: 1.0,
        opacity_scale: 1.0,
        unit_length: 1.0,
    };
    t.validate().unwrap();
    t
}

#[test]
fn psi_colour_is_exact_for_linear_tfs() {
    let mut rng = TestRng::new(3);
    let (mut worst64, mut worst32, mut worst_avg) = (0.0f64, 0.0f64, 0.0f64);
    let table = PsiTable::new();
    for case in 0..400 {
        let t = linear_tf(&mut rng, 0.0, 100.0, [0.1, 1.0, 10.0, 100.0][case % 4]);
        let seg = SegmentIntegrator::new(&t);
        let cls = CellClassifier::new(&t, [0.0, 100.0]);
        let (s_f, s_b) = (100.0 * rng.unit(), 100.0 * rng.unit());
        let l = 10f64.powf(rng.unit() * 4.0 - 3.0);
        let want = seg.integrate(s_f, s_b, l);
        let (cf, cb) = (t.color_at(s_f), t.color_at(s_b));
        let (tf_, tb) = (t.tau_per_world(s_f), t.tau_per_world(s_b));
        worst64 = worst64.max(max_diff(psi_segment(cf, tf_, cb, tb, l), want));
        let got = psi_fragment(&cls, &table, s_f as f32, s_b as f32, l as f32);
        worst32 = worst32.max(max_diff(widen(got), want));
        let avg = average_fragment(&cls, s_f as f32, s_b as f32, l as f32);
        worst_avg = worst_avg.max(max_diff(widen(avg), want));
        // Same opacity in both models (the trapezoid depth is exact for linear extinction).
        assert!(
            (avg[3] - got[3]).abs() <= 1e-6 * got[3].max(1e-30),
            "{avg:?} {got:?}"
        );
    }
    eprintln!(
        "linear TF, 400 random segments vs SegmentIntegrator: psi_segment (f64) {worst64:.2e}, \
         psi_fragment (f32, table) {worst32:.2e}, average_fragment {worst_avg:.2e}"
    );
    assert!(worst64 < 1e-12, "{worst64}");
    assert!(worst32 < 1e-4, "{worst32}");
    // The average model is wrong by O(1) here: the psi model must beat it clearly.
    assert!(worst_avg > 100.0 * worst32, "{worst_avg} {worst32}");
}

/// Composites front to back `[C, A]` pieces.
fn composite(pieces: &[[f64; 4]]) -> [f64; 4] {
    crate::composite::composite64(pieces.iter().copied())
}

#[test]
fn breakpoints_inside_the_segment() {
    // The psi model sees the TF only at s_f and s_b: breakpoints in between are missed.
    // Report how much, and check that splitting at the breakpoints restores exactness.
    let mut rng = TestRng::new(4);
    let table = PsiTable::new();
    let (mut worst_psi, mut worst_avg, mut worst_split) = (0.0f64, 0.0f64, 0.0f64);
    let (mut sum_psi, mut sum_avg, mut count) = (0.0f64, 0.0f64, 0);
    for _ in 0..300 {
        let t = random_tf(&mut rng, 3);
        let seg = SegmentIntegrator::new(&t);
        let cls = CellClassifier::with_size(&t, [0.0, 100.0], 1 << 16);
        let (s_f, s_b) = (100.0 * rng.unit(), 100.0 * rng.unit());
        let l = 10f64.powf(rng.unit() * 2.0 - 0.5);
        let inside: Vec<f64> = t
            .breakpoints()
            .into_iter()
            .filter(|&x| x > s_f.min(s_b) && x < s_f.max(s_b))
            .collect();
        if inside.is_empty() {
            continue;
        }
        let want = seg.integrate(s_f, s_b, l);
        let psi = widen(psi_fragment(&cls, &table, s_f as f32, s_b as f32, l as f32));
        let avg = widen(average_fragment(&cls, s_f as f32, s_b as f32, l as f32));
        let (ep, ea) = (max_diff(psi, want), max_diff(avg, want));
        (worst_psi, worst_avg) = (worst_psi.max(ep), worst_avg.max(ea));
        (sum_psi, sum_avg, count) = (sum_psi + ep, sum_avg + ea, count + 1);
        // Split at the breakpoints (in ray order) and composite psi_segment pieces.
        let mut cuts = vec![s_f];
        if s_b > s_f {
            cuts.extend(inside.iter().copied());
        } else {
            cuts.extend(inside.iter().rev().copied());
        }
        cuts.push(s_b);
        let pieces: Vec<[f64; 4]> = cuts
            .windows(2)
            .map(|w| {
                // Evaluate the TF inside each piece so jumps at breakpoints are respected.
                let (x, y) = (w[0] + 1e-9 * (w[1] - w[0]), w[1] - 1e-9 * (w[1] - w[0]));
                let len = l * (w[1] - w[0]) / (s_b - s_f);
                psi_segment(
                    t.color_at(x),
                    t.tau_per_world(x),
                    t.color_at(y),
                    t.tau_per_world(y),
                    len,
                )
            })
            .collect();
        worst_split = worst_split.max(max_diff(composite(&pieces), want));
    }
    eprintln!(
        "breakpoints inside ({count} segments): psi_fragment max {worst_psi:.3} mean {:.3}, \
         average max {worst_avg:.3} mean {:.3}; psi split at breakpoints {worst_split:.2e}",
        sum_psi / count as f64,
        sum_avg / count as f64
    );
    assert!(count > 100);
    assert!(
        worst_psi > 1e-2,
        "the test should contain segments the model gets wrong"
    );
    assert!(worst_split < 1e-6, "{worst_split}");
}

#[test]
fn average_is_exact_for_a_constant_medium() {
    let mut rng = TestRng::new(6);
    let mut worst = 0.0f64;
    for _ in 0..200 {
        let t = random_tf(&mut rng, 3);
        let seg = SegmentIntegrator::new(&t);
        let cls = CellClassifier::with_size(&t, [0.0, 100.0], 1 << 16);
        // A table node value, so the classifier reproduces the TF up to f32 rounding.
        let s = (100.0 * rng.unit() * 65535.0).round() / 65535.0;
        let l = 10f64.powf(rng.unit() * 5.0 - 3.0);
        let want = seg.integrate(s, s, l);
        let (c, tau) = (t.color_at(s), t.tau_per_world(s));
        assert!(max_diff(average_segment(c, tau, c, tau, l), want) < 1e-15);
        assert!(max_diff(psi_segment(c, tau, c, tau, l), want) < 1e-14);
        let got = widen(average_fragment(&cls, s as f32, s as f32, l as f32));
        worst = worst.max(max_diff(got, want));
    }
    // Not exact in f32: the classifier's index arithmetic moves s by a few 1e-6.
    eprintln!("average_fragment, s_f == s_b: max |error| {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn average_converges_at_first_order_as_l_vanishes() {
    // Expanding in l with dc = c_b - c_f, dtau = tau_b - tau_f: the exact colour is
    // l int_0^1 c tau dx + O(l^2) = l (c_f tau_f + (c_f dtau + tau_f dc) / 2 + dc dtau / 3),
    // the average's l (c_f + c_b)(tau_f + tau_b) / 4 has dc dtau / 4 in place of dc dtau / 3:
    // the error is -l dc dtau / 12 + O(l^2).
    let mut rng = TestRng::new(8);
    let table = PsiTable::new();
    for _ in 0..50 {
        let t = linear_tf(&mut rng, 0.0, 100.0, 5.0);
        let seg = SegmentIntegrator::new(&t);
        let cls = CellClassifier::new(&t, [0.0, 100.0]);
        let (s_f, s_b) = (100.0 * rng.unit(), 100.0 * rng.unit());
        let (cf, cb) = (t.color_at(s_f), t.color_at(s_b));
        let (tf_, tb) = (t.tau_per_world(s_f), t.tau_per_world(s_b));
        let coef = [0, 1, 2].map(|k| -(cb[k] - cf[k]) * (tb - tf_) / 12.0);
        for l in [1e-2, 1e-3, 1e-4] {
            let want = seg.integrate(s_f, s_b, l);
            let got = average_segment(cf, tf_, cb, tb, l);
            for k in 0..3 {
                // The O(l^2) term: |c| <= 1 and tau <= 5 bound its coefficient by about 25.
                let rest = ((got[k] - want[k]) / l - coef[k]).abs();
                assert!(rest < 25.0 * l, "l {l}: {rest} vs coefficient {}", coef[k]);
            }
        }
        // The f32 fragments converge too (absolute error -> 0 with l), the psi one faster.
        let l = 1e-3f32;
        let want = seg.integrate(s_f, s_b, l as f64);
        let avg = widen(average_fragment(&cls, s_f as f32, s_b as f32, l));
        let psi = widen(psi_fragment(&cls, &table, s_f as f32, s_b as f32, l));
        let bound = coef.iter().fold(0.0f64, |m, c| m.max(c.abs())) * 1e-3;
        assert!(max_diff(avg, want) <= bound + 3e-5, "{avg:?} {want:?}");
        assert!(max_diff(psi, want) < 1e-6 * want[3], "{psi:?} {want:?}");
    }
}

#[test]
fn psi_table_error_is_bounded() {
    let start = std::time::Instant::now();
    let table = PsiTable::new();
    eprintln!(
        "psi table n = {}: built in {:.1} ms",
        table.size(),
        start.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!(table.size(), PSI_TABLE_SIZE);
    let n = table.size();
    let depth = |v: f64| {
        if v >= 1.0 {
            f64::INFINITY
        } else {
            (1.0 - (1.0 - v).powi(2)) / (1.0 - v).powi(2)
        }
    };
    let lookup = |a: f64, b: f64| table.psi_of_depths(a as f32, b as f32) as f64;
    // Nodes.
    let mut nodes = 0.0f64;
    for i in (0..n).step_by(7).chain([n - 1]) {
        for j in (0..n).step_by(5).chain([n - 1]) {
            let (a, b) = (
                depth(i as f64 / (n - 1) as f64),
                depth(j as f64 / (n - 1) as f64),
            );
            let got = lookup(a, b);
            nodes = nodes.max((got - psi_exact(a, b)).abs());
        }
    }
    // Cell centres (in table coordinates), everywhere and for thickness <= 100.
    let (mut centres, mut centres_100) = (0.0f64, 0.0f64);
    let h = 1.0 / (n - 1) as f64;
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let (a, b) = (depth((i as f64 + 0.5) * h), depth((j as f64 + 0.5) * h));
            let e = (lookup(a, b) - psi_exact(a, b)).abs();
            centres = centres.max(e);
            if a.max(b) <= 100.0 {
                centres_100 = centres_100.max(e);
            }
        }
    }
    // Random thicknesses, log-uniform over [1e-4, 1e6] (and 0).
    let mut rng = TestRng::new(9);
    let (mut random, mut random_100, mut thin_rel) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..100_000 {
        let (a, b) = (
            log_depth(&mut rng, -4.0, 6.0),
            log_depth(&mut rng, -4.0, 6.0),
        );
        let (a, b) = ((a as f32) as f64, (b as f32) as f64);
        let exact = psi_exact(a, b);
        let e = (lookup(a, b) - exact).abs();
        random = random.max(e);
        if a.max(b) <= 100.0 {
            random_100 = random_100.max(e);
        }
        // Thin cells: relative error of 1 - psi, the weight of the front colour.
        if a + b < 0.1 && a + b > 0.0 {
            let got = table.one_minus_psi_of_depths(a as f32, b as f32) as f64;
            thin_rel = thin_rel.max((got - (1.0 - exact)).abs() / (1.0 - exact));
        }
    }
    // The gamma interface (f32 gamma loses the thickness as gamma -> 1, so up to 0.999).
    let mut by_gamma = 0.0f64;
    for _ in 0..20_000 {
        let (gf, gb) = ((0.999 * rng.unit()) as f32, (0.999 * rng.unit()) as f32);
        let d = |g: f32| g as f64 / (1.0 - g as f64);
        let e = (table.psi(gf, gb) as f64 - psi_exact(d(gf), d(gb))).abs();
        by_gamma = by_gamma.max(e);
    }
    eprintln!("psi table by gamma in [0, 0.999]: max |error| {by_gamma:.2e}");
    assert!(by_gamma < 2e-5, "{by_gamma}");
    eprintln!(
        "psi table n = {n} vs psi_exact: nodes {nodes:.2e}; cell centres {centres:.2e} \
         ({centres_100:.2e} for thickness <= 100); 1e5 random points {random:.2e} \
         ({random_100:.2e} for thickness <= 100); thin cells (depth < 0.1) relative error of \
         1 - psi {thin_rel:.2e}"
    );
    assert!(nodes < 5e-7, "{nodes}");
    assert!(centres < 2.5e-4 && random < 2.5e-4, "{centres} {random}");
    assert!(
        centres_100 < 2e-5 && random_100 < 2e-5,
        "{centres_100} {random_100}"
    );
    assert!(thin_rel < 4e-3, "{thin_rel}");
}

#[test]
fn classifier_error_is_bounded_by_the_kinks() {
    let t = tf(
        r#"{"color": [[0,0,0,0],[31.3,0.9,0.4,0.1],[70.7,0.2,0.5,1],[100,1,1,1]],
            "extinction": [[0,0],[20.05,0],[40.11,3],[45.07,0],[60,0.8],[100,2]]}"#,
    );
    for size in [1024usize, 4096] {
        let cls = CellClassifier::with_size(&t, [0.0, 100.0], size);
        let h = 100.0 / (size - 1) as f64;
        let mut worst = [0.0f64; 4];
        for k in 0..=200_000 {
            let s = 100.0 * k as f64 / 200_000.0;
            let got = cls.lookup(s as f32);
            let c = t.color_at(s);
            let want = [c[0], c[1], c[2], t.tau_per_world(s)];
            for ch in 0..4 {
                worst[ch] = worst[ch].max((got[ch] as f64 - want[ch]).abs());
            }
        }
        // Largest slope change at a breakpoint: colour 0.9/31.3 + 0.7/39.4 (red at 31.3),
        // extinction 3/20.06 + 3/4.96 (at 40.11); error <= h |jump| / 4 (+ f32 rounding).
        let colour_bound = h * (0.9 / 31.3 + 0.7 / 39.4) / 4.0 + 1e-6;
        let tau_bound = h * (3.0 / 20.06 + 3.0 / 4.96) / 4.0 + 1e-6;
        eprintln!(
            "classifier n = {size}: max |error| rgb {:.2e} {:.2e} {:.2e} (bound {colour_bound:.2e}), \
             tau {:.2e} (bound {tau_bound:.2e})",
            worst[0], worst[1], worst[2], worst[3]
        );
        assert!(worst[..3].iter().all(|&e| e <= colour_bound), "{worst:?}");
        assert!(worst[3] <= tau_bound, "{worst:?}");
        assert!(worst[3] > 0.1 * tau_bound, "the kinks should show");
    }
    // Outside the domain the lookups clamp, and transparency is reported.
    let cls = CellClassifier::new(&t, [0.0, 100.0]);
    assert_eq!(cls.lookup(-50.0), cls.lookup(0.0));
    assert_eq!(cls.lookup(1e30), cls.lookup(100.0));
    assert!(cls.is_transparent(0.0, 20.0));
    assert!(cls.is_transparent(20.0, -10.0));
    assert!(!cls.is_transparent(0.0, 30.0));
    assert!(!cls.is_transparent(f32::NAN, 30.0));
    assert_eq!(cls.domain(), [0.0, 100.0]);
    // The domain covers breakpoints outside the data range; normalized TFs are resolved.
    let wide = tf(r#"{"color": [[-50,1,1,1]], "extinction": [[0,0],[300,1]]}"#);
    let d = CellClassifier::new(&wide, [0.0, 100.0]).domain();
    assert!(
        (d[0] + 50.0).abs() < 1e-4 && (d[1] - 300.0).abs() < 1e-3,
        "{d:?}"
    );
    let norm = tf(r#"{"space": "normalized", "color": [[0,1,1,1]], "extinction": [[0,0],[1,2]]}"#);
    let cls = CellClassifier::new(&norm, [10.0, 20.0]);
    assert!((cls.lookup(15.0)[3] - 1.0).abs() < 1e-5);
}

#[test]
fn linear_pieces_are_exact_between_breakpoints() {
    // On a value range without breakpoints inside, `linear_on` gives the TF exactly (to f32),
    // including next to the breakpoints where the table blends; with one inside, nothing.
    let mut rng = TestRng::new(11);
    let (mut worst, mut some, mut none) = (0.0f64, 0, 0);
    for _ in 0..200 {
        // Breakpoints exact in f32 (otherwise their rounding shows next to steep kinks).
        let mut t = random_tf(&mut rng, 3);
        let snap = |x: f64| (x * 64.0).round() / 64.0;
        t.color.iter_mut().for_each(|p| p[0] = snap(p[0]));
        t.extinction.iter_mut().for_each(|p| p[0] = snap(p[0]));
        let cls = CellClassifier::new(&t, [0.0, 100.0]);
        let bp = t.breakpoints();
        for _ in 0..50 {
            let (a, b) = (rng.unit() * 120.0 - 10.0, rng.unit() * 120.0 - 10.0);
            let (lo, hi) = if rng.unit() < 0.5 {
                (a.min(b), a.max(b))
            } else {
                // Short ranges, often ending next to a breakpoint.
                let k = bp[(rng.unit() * bp.len() as f64) as usize];
                let w = 1e-3 + rng.unit() * 2.0;
                if rng.unit() < 0.5 {
                    (k, k + w)
                } else {
                    (k - w, k)
                }
            };
            let (lo32, hi32) = (lo as f32, hi as f32);
            let inside = bp.iter().any(|&k| (k as f32) > lo32 && (k as f32) < hi32);
            let Some(piece) = cls.linear_on(lo32, hi32) else {
                assert!(inside, "{lo} {hi} {bp:?}");
                none += 1;
                continue;
            };
            assert!(!inside, "{lo} {hi} {bp:?}");
            some += 1;
            // Inside the range (the TF may jump at a breakpoint at its end).
            for j in 0..9 {
                let s = lo32 + (hi32 - lo32) * (j as f32 + 0.5) / 9.0;
                let got = piece.at(s);
                let c = t.color_at(f64::from(s));
                let want = [c[0], c[1], c[2], t.tau_per_world(f64::from(s))];
                for ch in 0..4 {
                    worst = worst.max((f64::from(got[ch]) - want[ch]).abs());
                }
            }
        }
    }
    eprintln!("linear pieces: {some} ranges linear, {none} not; max |error| {worst:.2e}");
    assert!(worst < 1e-6, "{worst}");
    assert!(some > 1000 && none > 1000, "{some} {none}");
    let t = tf(r#"{"color": [[0,1,0.5,0.2]], "extinction": [[0,1],[1,3]]}"#);
    let cls = CellClassifier::new(&t, [0.0, 1.0]);
    assert!(cls.linear_on(f32::NAN, 1.0).is_none());
    assert!(cls.linear_on(0.8, 0.2).is_none());
    assert_eq!(
        cls.linear_on(-5.0, -1.0).map(|p| p.at(-3.0)),
        Some(cls.lookup(0.0))
    );
    assert_eq!(
        cls.linear_on(0.0, 1.0).map(|p| p.at(0.5)),
        Some(cls.lookup(0.5))
    );
}

#[test]
fn bad_inputs_give_transparent_black() {
    let t = tf(r#"{"color": [[0,1,0.5,0.2]], "extinction": [[0,1],[1,3]]}"#);
    let cls = CellClassifier::new(&t, [0.0, 1.0]);
    let table = PsiTable::with_size(16);
    for (s_f, s_b, l) in [
        (f32::NAN, 0.5, 1.0),
        (0.5, f32::NAN, 1.0),
        (0.5, 0.5, f32::NAN),
        (0.5, 0.5, 0.0),
        (0.5, 0.5, -1.0),
        (0.5, 0.5, f32::INFINITY),
        (f32::INFINITY, 0.5, 1.0),
    ] {
        assert_eq!(psi_fragment(&cls, &table, s_f, s_b, l), [0.0; 4]);
        assert_eq!(average_fragment(&cls, s_f, s_b, l), [0.0; 4]);
    }
    let c = [1.0, 0.5, 0.2];
    for (tf_, tb, l) in [
        (f64::NAN, 1.0, 1.0),
        (1.0, 1.0, 0.0),
        (1.0, f64::INFINITY, 1.0),
    ] {
        assert_eq!(psi_segment(c, tf_, c, tb, l), [0.0; 4]);
        assert_eq!(average_segment(c, tf_, c, tb, l), [0.0; 4]);
    }
    // No extinction at either end: transparent, in both models.
    let clear = tf(r#"{"color": [[0,1,1,1]], "extinction": [[0,0],[1,0]]}"#);
    let cls0 = CellClassifier::new(&clear, [0.0, 1.0]);
    assert_eq!(psi_fragment(&cls0, &table, 0.2, 0.9, 5.0), [0.0; 4]);
    assert_eq!(average_fragment(&cls0, 0.2, 0.9, 5.0), [0.0; 4]);
    // Huge extinction or length: opaque, the front colour, finite.
    let thick = tf(r#"{"color": [[0,1,0,0],[1,0,0,1]], "extinction": [[0,1e30],[1,1e30]]}"#);
    let cls1 = CellClassifier::new(&thick, [0.0, 1.0]);
    for l in [1.0, 1e30, f32::MAX] {
        let v = psi_fragment(&cls1, &PsiTable::new(), 0.0, 1.0, l);
        assert!(
            (v[0] - 1.0).abs() < 1e-6 && v[2].abs() < 1e-6 && v[3] == 1.0,
            "{v:?}"
        );
        let v = average_fragment(&cls1, 0.0, 1.0, l);
        assert!((v[0] - 0.5).abs() < 1e-6 && v[3] == 1.0, "{v:?}");
    }
    // Table lookups out of range or NaN never panic.
    assert!(table.psi(f32::NAN, 0.5).is_nan());
    assert_eq!(table.psi(-1.0, -5.0), 1.0);
    assert_eq!(table.psi(2.0, 0.3), 0.0);
    assert_eq!(table.psi_of_depths(f32::INFINITY, 1.0), 0.0);
    assert_eq!(gamma(f32::INFINITY), 1.0);
    assert_eq!(gamma(f32::NAN), 0.0);
    assert_eq!(PsiTable::with_size(0).size(), 2);
    assert_eq!(PsiTable::with_size(usize::MAX).size(), MAX_PSI_TABLE_SIZE);
}

#[test]
fn thin_segments_use_an_accurate_series() {
    let mut rng = TestRng::new(12);
    let mut worst = 0.0f64;
    for _ in 0..100_000 {
        let (a, b) = (
            log_depth(&mut rng, -8.0, -0.9),
            log_depth(&mut rng, -8.0, -0.9),
        );
        let (a, b) = ((a as f32) as f64, (b as f32) as f64);
        if !(a + b < THIN as f64 && a + b > 0.0) {
            continue;
        }
        let want = 1.0 - psi_exact(a, b);
        let got = one_minus_psi_series(a as f32, b as f32) as f64;
        worst = worst.max((got - want).abs() / want);
    }
    eprintln!("1 - psi by series for a + b < {THIN}: max relative error {worst:.2e}");
    assert!(worst < 5e-7, "{worst}");
}

#[test]
fn opacity_keeps_relative_precision() {
    let mut worst = 0.0f64;
    let mut worst_at = 0.0;
    for e in -3000..=2000 {
        for m in [1.0, 1.234_567, 3.3, 7.77] {
            let d = ((m * 10f64.powf(e as f64 / 100.0)) as f32) as f64;
            let want = -(-d).exp_m1();
            let rel = (opacity(d as f32) as f64 - want).abs() / want;
            if rel > worst {
                (worst, worst_at) = (rel, d);
            }
        }
    }
    // Every k of the range reduction, at its ends.
    for k in 0..126 {
        for off in [-0.346f64, 0.0, 0.346] {
            let d = (((k as f64 + off) * std::f64::consts::LN_2).max(1e-9) as f32) as f64;
            let want = -(-d).exp_m1();
            worst = worst.max((opacity(d as f32) as f64 - want).abs() / want);
        }
    }
    eprintln!(
        "f32 opacity 1 - exp(-d), d in 1e-30..8e20: max relative error {worst:.2e} at {worst_at:e}"
    );
    assert!(worst < 3e-7, "{worst}");
    assert_eq!(opacity(0.0), 0.0);
    assert_eq!(opacity(-1.0), 0.0);
    assert_eq!(opacity(f32::NAN), 0.0);
    assert_eq!(opacity(f32::INFINITY), 1.0);
    assert_eq!(opacity(200.0), 1.0);
}

/// Release-mode timing: `cargo test --release -p volux-render psi_fragment_timing --
/// --ignored --nocapture`.
#[test]
#[ignore]
fn psi_fragment_timing() {
    use std::hint::black_box;
    let t = tf(
        r#"{"color": [[0,0,0,0],[30,0.9,0.4,0.1],[70,0.2,0.5,1],[100,1,1,1]],
            "extinction": [[0,0],[20,0],[40,3],[45,0],[60,0.8],[100,2]]}"#,
    );
    let cls = CellClassifier::new(&t, [0.0, 100.0]);
    let table = PsiTable::new();
    let mut rng = TestRng::new(10);
    let n = 1 << 20;
    let random: Vec<[f32; 3]> = (0..n)
        .map(|_| {
            let l = 10f64.powf(rng.unit() * 3.0 - 2.0);
            [
                (100.0 * rng.unit()) as f32,
                (100.0 * rng.unit()) as f32,
                l as f32,
            ]
        })
        .collect();
    // Coherent: neighbouring fragments of one cell vary slowly, as in rasterization.
    let coherent: Vec<[f32; 3]> = (0..n)
        .map(|i| {
            let x = i as f32 / n as f32;
            [
                30.0 + 20.0 * x,
                35.0 + 10.0 * x,
                0.05 + 0.5 * (x * 97.0).fract(),
            ]
        })
        .collect();
    fn best_ns(inputs: &[[f32; 3]], f: impl Fn(f32, f32, f32) -> [f32; 4]) -> f64 {
        let mut best = f64::INFINITY;
        for _ in 0..7 {
            let start = std::time::Instant::now();
            let mut acc = [0.0f32; 4];
            for &[s_f, s_b, l] in inputs {
                let v = f(black_box(s_f), black_box(s_b), black_box(l));
                for k in 0..4 {
                    acc[k] += v[k];
                }
            }
            black_box(acc);
            best = best.min(start.elapsed().as_secs_f64() * 1e9 / inputs.len() as f64);
        }
        best
    }
    for (name, inputs) in [("random", &random), ("coherent", &coherent)] {
        let p = best_ns(inputs, |a, b, l| psi_fragment(&cls, &table, a, b, l));
        let a = best_ns(inputs, |a, b, l| average_fragment(&cls, a, b, l));
        eprintln!("{name} inputs: psi_fragment {p:.2} ns per call, average_fragment {a:.2} ns");
    }
}
