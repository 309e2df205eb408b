//! The brick pool against the whole-texture GPU ray caster and the CPU engine: a pool of a
//! few slots, so that frames take many rounds and bricks are evicted and loaded again, draws
//! the same picture (the same lattice and the same sample values: max 1e-6 against the whole
//! texture, 1e-4 against the CPU), from a grid in memory and from a bricked volume read
//! through its brick cache; transparent bricks are never loaded. Skipped, with a message,
//! without an adapter unless `VOLUX_GPU_REQUIRED=1`.
mod common;

use std::sync::Arc;

use common::{compare, context, cpu, grid, scene};
use glam::DVec3;
use volux_core::bricked::{GridChunks, Multiscale};
use volux_core::voi::ClipPlane;
use volux_core::TransferFunction;
use volux_gpu::{GpuGridRenderer, GpuPoolRenderer, PoolOptions, PoolSource};
use volux_render::bricked::BrickedVolume;
use volux_render::renderer::Renderer;
use volux_render::scene::{GridRaycast, Method};
use volux_render::tiles::Control;

/// Room for six bricks of 8 cells (9^3 samples of 4 bytes).
const SMALL: PoolOptions = PoolOptions {
    brick: 8,
    bytes: 6 * 9 * 9 * 9 * 4,
};

#[test]
fn a_pool_of_six_bricks_draws_the_whole_texture_picture() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut whole = GpuGridRenderer::new(ctx.clone(), g.clone()).unwrap();
    let mut pool = GpuPoolRenderer::new(ctx, PoolSource::Grid(g.clone()), SMALL).unwrap();
    let mut clipped = scene(&g, r#"{"azimuth": 120, "elevation": 10}"#, 0.5);
    let normal = DVec3::new(1.0, 0.4, -0.3).normalize();
    clipped.clip_planes = vec![ClipPlane {
        normal,
        offset: -normal.dot(g.bounds().center()),
    }];
    let mut jittered = scene(&g, r#"{"azimuth": 200, "elevation": -40}"#, 0.3);
    jittered.method = Method::GridRaycast(GridRaycast {
        integrator: volux_render::integrate::Integrator::Riemann { step: 0.3 },
        jitter: true,
        ..GridRaycast::default()
    });
    let cases = [
        (
            "perspective",
            scene(&g, r#"{"azimuth": 33, "elevation": 21}"#, 0.5),
        ),
        (
            "orthographic",
            scene(
                &g,
                r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
                0.7,
            ),
        ),
        ("a clip plane", clipped),
        ("jitter from below", jittered),
    ];
    for (name, s) in &cases {
        let want = whole.render(s, &Control::default()).unwrap().image;
        let got = pool.render(s, &Control::default()).unwrap().image;
        let stats = pool.stats();
        let (mean, max) = compare(&got, &want);
        let (cpu_mean, cpu_max) = compare(&got, &cpu(&g, s));
        eprintln!(
            "{name}: {stats:?}; against the whole texture mean {mean:.1e} max {max:.1e}, \
             against the CPU mean {cpu_mean:.1e} max {cpu_max:.1e}"
        );
        assert!(stats.capacity == 6 && stats.bricks == 60, "{stats:?}");
        assert!(
            stats.rounds > 2 && stats.uploads > 6,
            "bricks were evicted: {stats:?}"
        );
        assert!(
            max <= 1e-6 && mean < 1e-7,
            "{name}: mean {mean:e}, max {max:e}"
        );
        assert!(
            cpu_mean < 1.0 / 255.0 && cpu_max < 1e-4,
            "{name}: {cpu_max:e}"
        );
    }
}

#[test]
fn transparent_bricks_are_never_loaded() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut whole = GpuGridRenderer::new(ctx.clone(), g.clone()).unwrap();
    // Room for every brick: each is loaded at most once.
    let roomy = PoolOptions {
        brick: 8,
        bytes: 64 * 9 * 9 * 9 * 4,
    };
    let mut pool = GpuPoolRenderer::new(ctx, PoolSource::Grid(g.clone()), roomy).unwrap();
    let mut s = scene(&g, r#"{"azimuth": 33, "elevation": 21}"#, 0.5);
    s.appearance.tf = TransferFunction::from_json(
        r#"{"color": [[72,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[40,0],[72,0],[75,0.3],[110,0.4]]}"#,
    )
    .unwrap();
    let want = whole.render(&s, &Control::default()).unwrap().image;
    let got = pool.render(&s, &Control::default()).unwrap().image;
    let stats = pool.stats();
    eprintln!("sparse TF: {stats:?}");
    assert!(stats.empty > 10, "{stats:?}");
    assert!(stats.uploads <= stats.bricks - stats.empty, "{stats:?}");
    let (_, max) = compare(&got, &want);
    assert!(max <= 1e-6, "{max:e}");
}

#[test]
fn a_bricked_volume_is_drawn_through_its_brick_cache() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let chunks = GridChunks::new(g.clone(), [10, 7, 9]).unwrap();
    let multiscale = Multiscale::new("test", vec![Arc::new(chunks)]).unwrap();
    let volume = Arc::new(BrickedVolume::open(multiscale, 1 << 20).unwrap());
    let mut whole = GpuGridRenderer::new(ctx.clone(), g.clone()).unwrap();
    let mut pool = GpuPoolRenderer::new(ctx, PoolSource::Level(volume, 0), SMALL).unwrap();
    let s = scene(&g, r#"{"azimuth": 33, "elevation": 21}"#, 0.5);
    let want = whole.render(&s, &Control::default()).unwrap().image;
    let got = pool.render(&s, &Control::default()).unwrap().image;
    let (mean, max) = compare(&got, &want);
    eprintln!(
        "bricked volume: {:?}; mean {mean:.1e} max {max:.1e}",
        pool.stats()
    );
    assert!(max <= 1e-6, "{max:e}");
}

#[test]
fn what_the_pool_does_not_draw_is_refused_by_name() {
    let g = grid();
    let mut s = scene(&g, "{}", 0.5);
    s.appearance.shade_volume = true;
    let err = GpuPoolRenderer::supports(&s).unwrap_err().to_string();
    assert!(err.contains("shading"), "{err}");
    let mut s = scene(&g, "{}", 0.5);
    s.appearance.mip = true;
    let refusal = GpuPoolRenderer::supports(&s).unwrap_err();
    assert!(refusal.to_string().contains("maximum"), "{refusal}");
    assert_eq!(refusal.remedy, Some(volux_render::Remedy::CpuBackend));
    let bad = PoolOptions {
        brick: 12,
        ..PoolOptions::default()
    };
    if let Some(ctx) = context() {
        let err = GpuPoolRenderer::new(ctx, PoolSource::Grid(Arc::new(g)), bad)
            .err()
            .unwrap();
        assert!(err.to_string().contains("multiple of 8"), "{err}");
    }
}
