//! Adaptive Simpson through the state pipeline (`001_...txt` ch. 4; seed `003`'s blocks
//! made exact): on 1 to 5 ranks, bit for bit the single-process bricked render, for the
//! f32 lanes (coupled and coupled-standard control at tolerances from `MIN_TOL`) and the
//! f64 integrator (decoupled, smaller tolerances, shaded rays), with early termination on
//! and off, and with the camera grazing a region face.
use super::{distributed, grazing, max_diff, options, single, single_as_is};
use crate::bricked::fixtures::grid;
use crate::integrate::{AdaptiveParams, Integrator, StepControl};
use crate::raycast::RenderOptions;
use crate::shading::BlinnPhong;

fn adaptive(control: StepControl, tol: f64, hmax: f64) -> Integrator {
    Integrator::AdaptiveSimpson(AdaptiveParams {
        tol,
        h0: 0.3,
        hmin: 0.02,
        hmax,
        control,
        early_termination: None,
    })
}

/// The cases: which path each takes is the ray caster's choice (lanes for coupled control
/// at `tol >= 1e-3` unshaded, f64 otherwise).
fn cases() -> Vec<(String, RenderOptions)> {
    let g = grid();
    let mut out = Vec::new();
    for (control, tol, hmax, shaded) in [
        (StepControl::Coupled, 1e-3, 1.0, false),
        (StepControl::CoupledStandard, 1e-3, 4.0, false),
        (StepControl::Decoupled, 1e-3, 1.0, false),
        (StepControl::Coupled, 2e-4, 4.0, false),
        (StepControl::CoupledStandard, 2e-4, 1.0, false),
        (StepControl::Coupled, 1e-3, 2.0, true),
    ] {
        let mut o = options(&g, r#"{"azimuth": 33, "elevation": 21}"#);
        o.integrator = adaptive(control, tol, hmax);
        if shaded {
            o.shading = Some(BlinnPhong::default());
        }
        let name = format!("{control:?} tol {tol} hmax {hmax} shaded {shaded}");
        out.push((name, o));
    }
    out
}

#[test]
fn adaptive_simpson_on_one_to_five_ranks_equals_the_single_process_render() {
    let g = grid();
    let mut worst = 0.0f32;
    for (name, o) in cases() {
        for et in [None, Some(0.9f32)] {
            let mut o = o.clone();
            o.early_termination = et;
            let want = single_as_is(&g, &o);
            assert!(
                want.coverage(0.01) > 0.2,
                "{name}: the picture shows something"
            );
            for n in 1..=5 {
                let (got, reads) = distributed(&g, n, &o).unwrap();
                let d = max_diff(&got, &want);
                assert!(d == 0.0, "{name}, et {et:?}, {n} ranks: max difference {d}");
                assert!(reads.iter().all(|s| s.other == 0), "{n} ranks: {reads:?}");
                worst = worst.max(d);
            }
        }
    }
    eprintln!("adaptive Simpson: largest difference {worst:e}");
}

#[test]
fn adaptive_simpson_with_a_camera_grazing_a_region_face_is_exact() {
    let g = grid();
    for n in [2, 3, 4, 5] {
        for (control, tol) in [
            (StepControl::Coupled, 1e-3),
            (StepControl::Decoupled, 1e-3),
            (StepControl::CoupledStandard, 2e-4),
        ] {
            let mut o = grazing(&g, n);
            o.integrator = adaptive(control, tol, 4.0);
            let want = single(&g, &o);
            assert!(
                want.coverage(0.01) > 0.1,
                "the grazing view shows something"
            );
            let (got, _) = distributed(&g, n, &o).unwrap();
            let d = max_diff(&got, &want);
            assert!(d == 0.0, "{n} ranks, {control:?}: max difference {d}");
        }
    }
}
