//! Distributed renders (1 to 5 ranks on threads) against the single-process bricked render
//! with early termination off: every integrator the bricked path supports, shading, MIP,
//! isosurfaces, an oblique camera grazing a region face; the k-d split, the visibility order from many
//! viewpoints, and the chunks each rank reads.
use std::sync::Arc;

use glam::DVec3;
use volux_core::bricked::{ChunkSource, GridChunks, Multiscale};
use volux_core::camera::{Camera, Projection};
use volux_core::{CameraSpec, Grid, Image};

use super::error::DistributedError;
use super::exchange::{Exchange, ThreadExchange};
use super::kdtree::{KdSplit, ViewPoint};
use super::reads::{CountedChunks, ReadStats};
use crate::bricked::fixtures::{grid, tf, CHUNK};
use crate::bricked::{
    level_placement, render_cache_frame, render_level, BrickCache, BrickedVolume,
};
use crate::integrate::Integrator;
use crate::isosurface::{Isosurfaces, Isovalue};
use crate::raycast::RenderOptions;
use crate::shading::BlinnPhong;

fn chunks(g: &Grid) -> Arc<dyn ChunkSource> {
    Arc::new(GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap())
}

fn options(g: &Grid, spec: &str) -> RenderOptions {
    let cam = CameraSpec::from_json(spec)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap();
    let mut o = RenderOptions::new(cam, tf());
    (o.width, o.height) = (40, 36);
    o
}

/// The single-process bricked render, early termination off.
fn single(g: &Grid, opts: &RenderOptions) -> Image {
    let mut o = opts.clone();
    o.early_termination = None;
    if let Integrator::AdaptiveSimpson(p) = &mut o.integrator {
        p.early_termination = None;
    }
    single_as_is(g, &o)
}

/// The single-process bricked render of `opts` as they are.
fn single_as_is(g: &Grid, opts: &RenderOptions) -> Image {
    let ms = Multiscale::new("test", vec![chunks(g)]).unwrap();
    let v = BrickedVolume::open(ms, 1 << 30).unwrap();
    render_level(&v, 0, opts).unwrap().image
}

/// `n` ranks on threads, each with its own cache of a small budget: rank 0's image, and
/// what each rank read.
fn distributed(
    g: &Grid,
    n: usize,
    opts: &RenderOptions,
) -> Result<(Image, Vec<ReadStats>), DistributedError> {
    let source = chunks(g);
    let split = KdSplit::new(source.layout(), n)?;
    let range = g.range();
    let results: Vec<Result<(Option<Image>, ReadStats), DistributedError>> =
        std::thread::scope(|s| {
            let handles: Vec<_> = ThreadExchange::group(n)
                .into_iter()
                .map(|mut ex| {
                    let (split, source) = (&split, source.clone());
                    s.spawn(move || {
                        let r = ex.rank();
                        let counted = Arc::new(CountedChunks::new(source, split.regions()[r]));
                        let cache = BrickCache::new(counted.clone(), 4 * 8 * 5 * 4 * 4);
                        let view = ViewPoint::of(&opts.camera, &level_placement(&cache));
                        let order = split.visibility_order(view);
                        let (image, _) =
                            render_cache_frame(&cache, range, (split, r), opts, &mut ex, &order)?;
                        Ok((image, counted.stats()))
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
    let mut reads = Vec::new();
    let mut image = None;
    for r in results {
        let (i, s) = r?;
        reads.push(s);
        image = image.or(i);
    }
    Ok((image.expect("rank 0 has the image"), reads))
}

fn max_diff(a: &Image, b: &Image) -> f32 {
    a.pixels()
        .iter()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

fn exact_cases(g: &Grid) -> Vec<(String, RenderOptions)> {
    let mut cases = Vec::new();
    for integrator in [
        Integrator::Riemann { step: 0.4 },
        Integrator::Trapezoid { step: 0.4 },
        Integrator::Simpson { step: 0.5 },
        Integrator::Preintegrated { step: 0.4 },
    ] {
        let mut o = options(g, r#"{"azimuth": 33, "elevation": 21}"#);
        o.integrator = integrator;
        cases.push((integrator.name().to_string(), o.clone()));
        // Shaded: the ray-by-ray paths (gradients read across faces).
        o.shading = Some(BlinnPhong::default());
        o.camera = CameraSpec::from_json(r#"{"azimuth": 200, "elevation": -40}"#)
            .unwrap()
            .resolve(&g.bounds())
            .unwrap();
        cases.push((format!("{} shaded", integrator.name()), o));
    }
    let mut ortho = options(
        g,
        r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
    );
    ortho.integrator = Integrator::Preintegrated { step: 0.3 };
    cases.push(("preintegrated orthographic".into(), ortho));
    cases
}

#[test]
fn one_to_five_ranks_equal_the_single_process_render_for_the_exact_integrators() {
    let g = grid();
    for (name, o) in exact_cases(&g) {
        let want = single(&g, &o);
        assert!(
            want.coverage(0.01) > 0.2,
            "{name}: the picture shows something"
        );
        for n in 1..=5 {
            let (got, reads) = distributed(&g, n, &o).unwrap();
            let d = max_diff(&got, &want);
            assert!(d <= 1e-6, "{name}, {n} ranks: max difference {d}");
            for (r, s) in reads.iter().enumerate() {
                assert!(s.own > 0, "{name}, {n} ranks: rank {r} read {s:?}");
                // A rank reads its chunks and its face neighbours only.
                assert_eq!(s.other, 0, "{name}, {n} ranks: rank {r} read {s:?}");
            }
        }
    }
}

/// Options for a camera a hair off the first region's face of a split into `n`, looking
/// along it with a tilt of a tenth of a degree (48 x 40 pixels).
fn grazing(g: &Grid, n: usize) -> RenderOptions {
    let place = crate::raycast::Placement::of(g);
    let split = KdSplit::new(chunks(g).layout(), n).unwrap();
    // The first plane: the boundary between the first region's box and the rest.
    let first = split.regions()[0];
    let axis = (0..3)
        .find(|&a| first.hi[a] < split.chunks_per_axis()[a])
        .unwrap();
    let plane = place.origin[axis] + (first.hi[axis] * CHUNK[axis]) as f64 * place.spacing[axis];
    let centre = g.bounds().center();
    let mut eye = centre;
    eye[axis] = plane + 1e-3;
    let along = (axis + 1) % 3;
    eye[along] -= 60.0;
    let mut target = centre;
    target[axis] = plane + 1e-3 - 60.0 * 0.1f64.to_radians().tan();
    let up = DVec3::from(std::array::from_fn::<f64, 3, _>(|a| {
        f64::from(a == (axis + 2) % 3)
    }));
    let camera = Camera {
        eye,
        target,
        up,
        projection: Projection::Perspective { fov_y_deg: 20.0 },
    };
    let mut o = RenderOptions::new(camera, tf());
    (o.width, o.height) = (48, 40);
    o
}

#[test]
fn an_oblique_camera_grazing_a_region_face_changes_nothing() {
    let g = grid();
    for n in [2, 3, 4, 5] {
        for integrator in [
            Integrator::Riemann { step: 0.5 },
            Integrator::Preintegrated { step: 0.5 },
            Integrator::Trapezoid { step: 0.5 },
        ] {
            let mut o = grazing(&g, n);
            o.integrator = integrator;
            let want = single(&g, &o);
            assert!(
                want.coverage(0.01) > 0.1,
                "the grazing view shows something"
            );
            let (got, _) = distributed(&g, n, &o).unwrap();
            let d = max_diff(&got, &want);
            assert!(
                d <= 1e-6,
                "{n} ranks, {}: max difference {d}",
                integrator.name()
            );
        }
    }
}

/// MIP: the ranks' largest lattice samples reduced by maximum, the winner's refined value
/// coloured on rank 0, equals the single-process MIP (lane stream, f32 lattice), with the
/// step of each integrator, a clipping plane, and the grazing camera.
#[test]
fn mip_on_one_to_five_ranks_equals_the_single_process_mip() {
    let g = grid();
    let mut cases = Vec::new();
    for (integrator, spec) in [
        (
            Integrator::Riemann { step: 0.4 },
            r#"{"azimuth": 33, "elevation": 21}"#,
        ),
        (
            Integrator::Preintegrated { step: 0.7 },
            r#"{"azimuth": 200, "elevation": -40}"#,
        ),
        (
            Integrator::Trapezoid { step: 0.4 },
            r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
        ),
    ] {
        let mut o = options(&g, spec);
        (o.integrator, o.mip) = (integrator, true);
        cases.push(o);
    }
    let mut clipped = cases[0].clone();
    clipped.clip_planes = vec![volux_core::voi::ClipPlane {
        normal: DVec3::new(0.6, -0.8, 0.0),
        offset: g.bounds().center().dot(DVec3::new(-0.6, 0.8, 0.0)) + 1.3,
    }];
    cases.push(clipped);
    let mut worst = 0.0f32;
    for o in &cases {
        let want = single(&g, o);
        assert!(want.coverage(0.01) > 0.2, "the MIP shows something");
        for n in 1..=5 {
            let (got, reads) = distributed(&g, n, o).unwrap();
            let d = max_diff(&got, &want);
            assert!(
                d <= 1e-6,
                "MIP {}, {n} ranks: max difference {d}",
                o.integrator.name()
            );
            assert!(reads.iter().all(|s| s.other == 0), "{n} ranks: {reads:?}");
            worst = worst.max(d);
        }
    }
    for n in [2, 3, 4, 5] {
        let mut o = grazing(&g, n);
        o.mip = true;
        let want = single(&g, &o);
        let (got, _) = distributed(&g, n, &o).unwrap();
        let d = max_diff(&got, &want);
        assert!(d <= 1e-6, "grazing MIP, {n} ranks: max difference {d}");
        worst = worst.max(d);
    }
    eprintln!("MIP: largest difference {worst:e}");
}

/// Isosurfaces: a crossing between the last sample of one region and the first of the next
/// is found once, by the front region (it reads the next sample across its face), and
/// refined at the same point as in one process; several isovalues, unlit and lit, the
/// volume emission-only and shaded, three steps, and the grazing camera.
#[test]
fn isosurfaces_on_one_to_five_ranks_equal_the_single_process_render() {
    let g = grid();
    let isos = Isosurfaces::new(vec![
        Isovalue {
            value: 55.0,
            rgba: [0.9, 0.3, 0.2, 0.35],
        },
        Isovalue {
            value: 72.5,
            rgba: [0.2, 0.8, 0.3, 0.5],
        },
        Isovalue {
            value: 93.0,
            rgba: [0.3, 0.4, 1.0, 0.7],
        },
    ])
    .unwrap();
    let with_isos = |mut o: RenderOptions, step: f64, lit: bool, shaded: bool| {
        o.integrator = Integrator::Riemann { step };
        o.isosurfaces = isos.clone();
        o.iso_lighting = lit.then(BlinnPhong::default);
        o.shading = shaded.then(BlinnPhong::default);
        o
    };
    let mut cases = Vec::new();
    for (step, spec, lit, shaded) in [
        (0.4, r#"{"azimuth": 33, "elevation": 21}"#, false, false),
        (0.7, r#"{"azimuth": 200, "elevation": -40}"#, true, false),
        (
            0.5,
            r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
            true,
            true,
        ),
    ] {
        let o = with_isos(options(&g, spec), step, lit, shaded);
        for n in 1..=5 {
            cases.push((
                format!("step {step}, lit {lit}, shaded {shaded}"),
                n,
                o.clone(),
            ));
        }
    }
    for n in [2, 3, 4, 5] {
        cases.push((
            "grazing".into(),
            n,
            with_isos(grazing(&g, n), 0.5, true, false),
        ));
    }
    let mut worst = 0.0f32;
    for (name, n, o) in &cases {
        let want = single(&g, o);
        assert!(
            want.coverage(0.01) > 0.1,
            "{name}: the picture shows something"
        );
        let (got, reads) = distributed(&g, *n, o).unwrap();
        let d = max_diff(&got, &want);
        assert!(
            d <= 1e-6,
            "isosurfaces {name}, {n} ranks: max difference {d}"
        );
        assert!(reads.iter().all(|s| s.other == 0), "{n} ranks: {reads:?}");
        worst = worst.max(d);
    }
    eprintln!("isosurfaces: largest difference {worst:e}");
}

#[test]
fn the_reference_integrator_is_refused() {
    let g = grid();
    let mut o = options(&g, "{}");
    o.integrator = Integrator::Reference;
    assert!(matches!(
        distributed(&g, 2, &o),
        Err(DistributedError::Unsupported(_))
    ));
}

#[test]
fn the_split_partitions_the_chunks_in_balanced_boxes() {
    let layout = chunks(&grid()).layout().clone();
    let total = layout.chunk_count();
    for n in 1..=12 {
        let split = KdSplit::new(&layout, n).unwrap();
        assert_eq!(split.len(), n);
        let counts: Vec<usize> = split.regions().iter().map(|b| b.count()).collect();
        assert_eq!(counts.iter().sum::<usize>(), total, "{n}: {counts:?}");
        for i in 0..layout.chunk_count() {
            let c = layout.chunk_coords(i);
            let owners = split.regions().iter().filter(|b| b.contains(c)).count();
            assert_eq!(owners, 1, "{n}: chunk {c:?}");
        }
        let (lo, hi) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
        assert!(*lo >= 1 && *hi <= 2 * lo + 4, "{n} ranks: {counts:?}");
    }
    assert!(matches!(
        KdSplit::new(&layout, total + 1),
        Err(DistributedError::Split { .. })
    ));
    assert!(matches!(
        KdSplit::new(&layout, 0),
        Err(DistributedError::Split { .. })
    ));
}

/// Brute force: along many rays from each viewpoint, the regions a ray crosses (by where
/// the ray's part in each begins) come in the visibility order, and the parts partition the
/// ray.
#[test]
fn the_visibility_order_is_the_order_rays_meet_the_regions() {
    let layout = chunks(&grid()).layout().clone();
    let size = DVec3::from(layout.dims.map(|d| (d - 1) as f64));
    let eyes = [
        DVec3::new(-30.0, 8.0, 6.0),
        DVec3::new(50.0, -20.0, 30.0),
        DVec3::new(11.0, 8.0, -40.0),
        DVec3::new(5.0, 40.0, 7.0),
        DVec3::new(11.5, 8.2, 6.1), // inside the volume
        DVec3::new(-7.0, -9.0, -11.0),
    ];
    for n in [2, 3, 5, 7, 8] {
        let split = KdSplit::new(&layout, n).unwrap();
        for eye in eyes {
            let order = split.visibility_order(ViewPoint::Eye(eye));
            check_rays(&split, &order, n, |i| {
                let target = size * DVec3::new(hash(i, 1), hash(i, 2), hash(i, 3));
                (eye, (target - eye).normalize())
            });
        }
        for d in [
            DVec3::new(1.0, 0.3, -0.2),
            DVec3::new(-0.2, -1.0, 0.5),
            DVec3::new(0.1, 0.2, -1.0),
        ] {
            let order = split.visibility_order(ViewPoint::Direction(d));
            check_rays(&split, &order, n, |i| {
                let p = size * DVec3::new(hash(i, 1), hash(i, 2), hash(i, 3));
                (p - d * 100.0, d)
            });
        }
    }
}

fn check_rays(split: &KdSplit, order: &[usize], n: usize, ray: impl Fn(usize) -> (DVec3, DVec3)) {
    let rank_in_order = |r: usize| order.iter().position(|&x| x == r).unwrap();
    for i in 0..500 {
        let (o, d) = ray(i);
        let (t0, t1) = (0.0, 1e3);
        let mut parts: Vec<(f64, f64, usize)> = (0..n)
            .filter_map(|r| split.clip_ray(r, o, d, t0, t1).map(|(a, b)| (a, b, r)))
            .collect();
        parts.sort_by(|x, y| x.0.total_cmp(&y.0));
        for w in parts.windows(2) {
            assert!(
                rank_in_order(w[0].2) < rank_in_order(w[1].2),
                "order {order:?}, parts {parts:?}"
            );
            assert_eq!(w[0].1, w[1].0, "the parts touch exactly: {parts:?}");
        }
        assert_eq!(parts.first().map(|p| p.0), Some(t0));
        assert_eq!(parts.last().map(|p| p.1), Some(t1));
    }
}

/// A deterministic number in [0, 1).
fn hash(i: usize, salt: u32) -> f64 {
    let mut v = (i as u32).wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    v ^= v >> 16;
    v = v.wrapping_mul(0x7FEB_352D);
    v ^= v >> 15;
    v as f64 / 4_294_967_296.0
}

mod adaptive;

/// Long rays (about 600 samples through a 72³ grid, opacity up to 0.9): the ranks' parts of
/// a ray, composited, equal the whole ray within 3e-7 (the issue asks for 1e-6) for every
/// integrator the swap composites. Summed in one `f32` chain per ray, the pictures differed
/// by up to 1.19e-6 (48 x 48, step 0.25); with the lanes' blocks unbounded (one `f32` chain
/// per span, folded into `f64`), by 5.4e-7 to 7.2e-7; with blocks of 32 steps, 1.2e-7.
#[test]
fn long_rays_composited_by_the_ranks_equal_the_whole_rays_within_3e_7() {
    let n = 72usize;
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let [x, y, z] = [i, j, k].map(|c| c as f32 / 71.0);
                v.push(60.0 + 10.0 * (9.0 * x).sin() * (7.0 * y).cos() + 8.0 * (11.0 * z).sin());
            }
        }
    }
    let samples = volux_core::grid::Samples::F32(volux_core::grid::Buffer::owned(v));
    let g = Grid::new([n; 3], [1.0; 3], [0.0; 3], samples).unwrap();
    let tf = volux_core::TransferFunction::from_json(
        r#"{"color": [[40,0.2,0.4,1],[60,1,0.8,0.3],[80,1,1,1]],
            "extinction": [[40,0.006],[60,0.03],[80,0.012]]}"#,
    )
    .unwrap();
    let cam = CameraSpec::from_json(r#"{"azimuth": 33, "elevation": 21}"#)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap();
    for integrator in [
        Integrator::Riemann { step: 0.2 },
        Integrator::Trapezoid { step: 0.2 },
        Integrator::Simpson { step: 0.2 },
        Integrator::Preintegrated { step: 0.2 },
    ] {
        let mut o = RenderOptions::new(cam, tf.clone());
        (o.width, o.height) = (48, 48);
        o.integrator = integrator;
        let want = single(&g, &o);
        let opacity = want.pixels().iter().map(|p| p[3]).fold(0.0, f32::max);
        assert!(opacity > 0.85, "{}: opacity {opacity}", integrator.name());
        for ranks in [2, 3, 4] {
            let (got, _) = distributed(&g, ranks, &o).unwrap();
            let d = max_diff(&got, &want);
            assert!(d <= 3e-7, "{}, {ranks} ranks: {d:e}", integrator.name());
        }
    }
}
