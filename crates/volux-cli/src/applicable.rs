//! Which `volux render` options apply to the method and data they are used with. An option
//! typed on the command line that would change nothing is an error saying why, never a
//! silent no-op (the library's own refusals, [`Method::check_appearance`], cover MIP and
//! volume shading).
use volux_render::integrate::{Integrator, SegmentRule};
use volux_render::scene::Method;

use crate::cli::{IntegratorArg, MethodArg, RenderArgs};
use crate::commands::common::CmdError;

/// The adaptive integrator's own options.
const ADAPTIVE: [&str; 5] = ["tol", "h0", "hmin", "hmax", "decoupled"];
/// The lighting options.
const LIGHTING: [&str; 5] = ["ambient", "diffuse", "specular", "shininess", "light"];
/// The options of the orbit camera, which a camera file replaces.
const ORBIT: [&str; 6] = ["azimuth", "elevation", "zoom", "orthographic", "view", "up"];

/// Checks the options that do not depend on the data: pairs that contradict or need each
/// other.
pub fn check_options(args: &RenderArgs) -> Result<(), CmdError> {
    if args.no_write && args.orbit.is_none() {
        return Err("--no-write goes with --orbit (a single render always writes its PNG)".into());
    }
    if let (Some(_), Some(_)) = (&args.orbit, &args.error_map) {
        return Err(
            "--error-map writes one map; render the frame of interest without --orbit".into(),
        );
    }
    if !args.measure.is_empty() && (args.orbit.is_some() || args.json) {
        return Err(
            "--measure draws on one picture and prints its length as text; measure \
                    without --orbit and --json (`volux measure --json` prints JSON)"
                .into(),
        );
    }
    if args.given("json") && !args.stats {
        return Err("--json prints the --stats figures as JSON; add --stats".into());
    }
    if args.given("sort-violations") && !args.stats {
        return Err(
            "--sort-violations adds a diagnostic to the --stats figures; add --stats".into(),
        );
    }
    if args.view_args.camera.is_some() {
        if let Some(o) = ORBIT.iter().find(|o| args.given(o)) {
            return Err(format!(
                "--{o} sets the orbit camera, which --camera FILE replaces; put it in the file \
                 (see `volux help camera`)"
            )
            .into());
        }
    }
    for flag in ["opacity-scale", "no-early-termination"] {
        if args.mip && args.given(flag) {
            return Err(format!(
                "--{flag} does not apply to --mip: maximum intensity projection shows each \
                 ray's largest value in the transfer function's colour, with no opacity"
            )
            .into());
        }
    }
    if args.mip && args.error_map.is_some() {
        return Err(
            "--error-map shows the integration error of compositing; maximum \
                    intensity projection (--mip) integrates nothing"
                .into(),
        );
    }
    let lit = args.shade || !args.view_args.isos.is_empty();
    if let Some(l) = LIGHTING.iter().find(|l| args.given(l)) {
        if !lit {
            return Err(format!(
                "--{l} lights shaded volumes (--shade) and isosurfaces (--iso); this render has \
                 neither"
            )
            .into());
        }
    }
    Ok(())
}

/// Checks the options against the method chosen for the data (`loaded_grid`: the file held
/// a grid, which `--as-tets` may have split into tetrahedra).
pub fn check_method(args: &RenderArgs, method: &Method, loaded_grid: bool) -> Result<(), CmdError> {
    let what = describe(method);
    let refuse = |flag: &str, why: &str| -> Result<(), CmdError> {
        Err(format!("--{flag} does not apply to {what}: {why}").into())
    };
    if args.given("as-tets") && !loaded_grid {
        return refuse("as-tets", "the data is a tetrahedral mesh already");
    }
    if args.given("as-tets") && !matches!(args.method, MethodArg::Auto | MethodArg::Pt) {
        return refuse(
            "as-tets",
            "it splits a grid for Projected Tetrahedra (--method pt)",
        );
    }
    if args.given("resample") && !matches!(method, Method::Resample { .. }) {
        return refuse("resample", "it sizes the grid of --method resample");
    }
    if args.given("sort") && !matches!(method, Method::ProjectedTetrahedra(_)) {
        return refuse("sort", "it orders the cells of Projected Tetrahedra");
    }
    if args.given("sort-violations") && !matches!(method, Method::ProjectedTetrahedra(_)) {
        return refuse(
            "sort-violations",
            "it counts the face pairs Projected Tetrahedra draws out of order",
        );
    }
    match method {
        Method::ProjectedTetrahedra(_) => check_pt(args, &refuse),
        Method::TetRaycast(rule) => check_tet_ray(args, *rule, &refuse),
        Method::GridRaycast(g) => check_grid(args, &g.integrator, &refuse),
        Method::Resample { raycast, .. } => check_grid(args, &raycast.integrator, &refuse),
        Method::Slicing(_) => check_slicing(args, &refuse),
        _ => Ok(()),
    }
}

type Refuse<'a> = dyn Fn(&str, &str) -> Result<(), CmdError> + 'a;

/// Projected Tetrahedra: exact segments per cell, colour from `--color`.
fn check_pt(args: &RenderArgs, refuse: &Refuse<'_>) -> Result<(), CmdError> {
    let why = "it integrates each cell's segment in closed form (colour from --color)";
    for flag in [
        "integrator",
        "step",
        "reconstruction",
        "jitter",
        "error-map",
    ]
    .iter()
    .chain(ADAPTIVE.iter())
    {
        if args.given(flag) {
            return refuse(flag, why);
        }
    }
    Ok(())
}

/// Mesh ray casting: segments by `--integrator exact|psi|adaptive-simpson` or `--color`.
fn check_tet_ray(
    args: &RenderArgs,
    rule: SegmentRule,
    refuse: &Refuse<'_>,
) -> Result<(), CmdError> {
    if args.given("integrator")
        && !matches!(
            args.integrator,
            IntegratorArg::Exact | IntegratorArg::Psi | IntegratorArg::AdaptiveSimpson
        )
    {
        return refuse(
            "integrator",
            "it integrates cell segments with exact, psi or adaptive-simpson",
        );
    }
    if args.given("integrator") && args.given("color") {
        return refuse(
            "color",
            "--integrator already sets the segment colour of mesh ray casting; give one",
        );
    }
    let why = "it walks cell to cell, integrating each segment whole";
    for flag in ["step", "reconstruction", "jitter"] {
        if args.given(flag) {
            return refuse(flag, why);
        }
    }
    let adaptive = matches!(rule, SegmentRule::AdaptiveSimpson(_));
    adaptive_only(args, adaptive, refuse)
}

/// Grid ray casting (also of a resampled mesh).
fn check_grid(
    args: &RenderArgs,
    integrator: &Integrator,
    refuse: &Refuse<'_>,
) -> Result<(), CmdError> {
    if args.given("color") {
        return refuse(
            "color",
            "it colours the cell segments of tetrahedral meshes (--integrator chooses how a \
             grid's rays are integrated)",
        );
    }
    let fixed = !matches!(
        integrator,
        Integrator::AdaptiveSimpson(_) | Integrator::Reference
    );
    for flag in ["step", "jitter"] {
        if args.given(flag) && !fixed {
            return refuse(
                flag,
                &format!(
                    "the {} integrator chooses its own steps (fixed steps: riemann, trapezoid, \
                     simpson, preintegrated)",
                    args.integrator.name()
                ),
            );
        }
    }
    let adaptive = matches!(integrator, Integrator::AdaptiveSimpson(_));
    adaptive_only(args, adaptive, refuse)
}

/// Texture slicing: slices `--step` apart, trilinear, classified per slab.
fn check_slicing(args: &RenderArgs, refuse: &Refuse<'_>) -> Result<(), CmdError> {
    let why = "texture slicing samples trilinearly on slices --step apart";
    for flag in ["integrator", "reconstruction", "jitter", "color"] {
        if args.given(flag) {
            return refuse(flag, why);
        }
    }
    adaptive_only(args, false, refuse)
}

/// The options of adaptive Simpson, and its error map.
fn adaptive_only(args: &RenderArgs, adaptive: bool, refuse: &Refuse<'_>) -> Result<(), CmdError> {
    if adaptive {
        return Ok(());
    }
    for flag in ADAPTIVE.iter().chain(["error-map"].iter()) {
        if args.given(flag) {
            return refuse(
                flag,
                "it belongs to the error-controlled integrator (--integrator adaptive-simpson)",
            );
        }
    }
    Ok(())
}

/// The method in words, for messages.
fn describe(method: &Method) -> String {
    match method {
        Method::ProjectedTetrahedra(_) => "Projected Tetrahedra".into(),
        Method::TetRaycast(_) => "mesh ray casting".into(),
        Method::GridRaycast(g) => format!("grid ray casting ({})", g.integrator.name()),
        Method::Resample { raycast, .. } => {
            format!("a resampled mesh ray cast ({})", raycast.integrator.name())
        }
        other => other.name().into(),
    }
}
