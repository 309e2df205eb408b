//! `volux bench --suite gpu`: the GPU backend (issue 20) on the preferred adapter:
//!
//! - grid ray casting: ms/frame and samples/s at 512x512 and 1920x1080 (Riemann, shaded,
//!   pre-integrated, MIP), the upload time of each grid and the device memory it holds, on
//!   Marschner-Lobb at `--grid-size`, a 512^3 Marschner-Lobb (the target: 60 frames/s at
//!   1920x1080 on a data-centre GPU) and the shared CT and MRI heads;
//! - Projected Tetrahedra: ms/frame and tets/s (ψ colour, centroid order) at the same sizes
//!   on the 200K and 1.25M-tet meshes and the shared Blunt Fin and LOx Post (the target:
//!   100 M tets/s on a data-centre GPU), with the upload time.
//!
//! On lavapipe (Mesa's software Vulkan) the figures only prove the path works.
use crate::commands::common::CmdError;

/// Runs the GPU suite; returns the JSON rows.
#[cfg(feature = "gpu")]
pub fn run(
    quick: bool,
    frames: usize,
    n: usize,
    as_json: bool,
    only: Option<&str>,
) -> Result<Vec<serde_json::Value>, CmdError> {
    on_gpu::run(quick, frames, n, as_json, only)
}

/// Without the `gpu` feature: an error saying how to build it.
#[cfg(not(feature = "gpu"))]
pub fn run(
    _: bool,
    _: usize,
    _: usize,
    _: bool,
    _: Option<&str>,
) -> Result<Vec<serde_json::Value>, CmdError> {
    Err(
        "--suite gpu needs the GPU backend: cargo build --release -p volux-cli --features gpu"
            .into(),
    )
}

#[cfg(feature = "gpu")]
mod on_gpu {
    use std::sync::Arc;
    use std::time::Instant;

    use serde_json::json;
    use volux_core::{synth, CameraSpec, Grid, TransferFunction};
    use volux_gpu::{
        GpuContext, GpuGridRenderer, GpuPoolRenderer, GpuPtRenderer, PoolOptions, PoolSource,
    };
    use volux_render::engine::MethodStats;
    use volux_render::integrate::Integrator;
    use volux_render::renderer::Renderer;
    use volux_render::scene::{GridRaycast, Method, PtSettings, Scene, Volume};
    use volux_render::RenderError;

    use super::super::common::{frame, grids, median, meshes, selected};
    use crate::commands::common::CmdError;

    /// The cases of a grid: label, integrator, shaded, MIP.
    const CASES: [(&str, Integrator, bool, bool); 4] = [
        (
            "riemann h=0.5",
            Integrator::Riemann { step: 0.5 },
            false,
            false,
        ),
        (
            "riemann h=0.5 shaded",
            Integrator::Riemann { step: 0.5 },
            true,
            false,
        ),
        (
            "preintegrated h=0.5",
            Integrator::Preintegrated { step: 0.5 },
            false,
            false,
        ),
        (
            "riemann h=0.5 mip",
            Integrator::Riemann { step: 0.5 },
            false,
            true,
        ),
    ];

    pub fn run(
        quick: bool,
        frames: usize,
        n: usize,
        as_json: bool,
        only: Option<&str>,
    ) -> Result<Vec<serde_json::Value>, CmdError> {
        let ctx = Arc::new(GpuContext::new().map_err(RenderError::from)?);
        let adapter = ctx.adapter().to_string();
        let frames = if quick { 1 } else { frames.max(1) };
        let sizes: &[(usize, usize)] = if quick {
            &[(256, 256)]
        } else {
            &[(512, 512), (1920, 1080)]
        };
        let mut datasets = grids(if quick { n.min(64) } else { n })?;
        datasets.retain(|(name, _, _)| !name.starts_with("shepp") && selected(name, only));
        if !quick && n != 512 && selected("marschner-lobb-512", only) {
            let tf = datasets[0].2.clone();
            datasets.push((
                "marschner-lobb-512".into(),
                synth::marschner_lobb(512)?.into(),
                tf,
            ));
        }
        if !as_json {
            outln!("\nGPU backend on {adapter}; frames per case: {frames} (median)")?;
        }
        let mut rows = Vec::new();
        rows.extend(pt_rows(&ctx, (quick, frames, only), sizes, as_json)?);
        if !as_json {
            outln!(
                "\n{:<20} {:>9} {:<22} {:>10} {:>12} {:>12} {:>10} {:>10}",
                "dataset",
                "size",
                "case",
                "ms/frame",
                "samples",
                "Msamples/s",
                "upload ms",
                "GPU MiB"
            )?;
        }
        for (name, volume, tf) in &datasets {
            let Volume::Grid(grid) = volume else { continue };
            let (mut renderer, upload_ms) = upload(&ctx, grid)?;
            for &(w, h) in sizes {
                for (label, integrator, shaded, mip) in CASES {
                    let scene = scene(volume, tf, (w, h), integrator, (shaded, mip))?;
                    let (ms, samples) = time(&mut renderer, &scene, frames)?;
                    let mib = renderer.device_bytes() as f64 / (1 << 20) as f64;
                    let rate = samples as f64 / ms * 1e3;
                    if !as_json {
                        outln!(
                            "{name:<20} {:>9} {label:<22} {ms:>10.1} {samples:>12} {:>12.1} \
                             {upload_ms:>10.1} {mib:>10.1}",
                            format!("{w}x{h}"),
                            rate / 1e6,
                        )?;
                    }
                    rows.push(json!({
                        "suite": "gpu", "adapter": adapter, "dataset": name, "width": w,
                        "height": h, "case": label, "ms": ms, "samples": samples,
                        "samples_per_s": rate, "upload_ms": upload_ms, "device_mib": mib,
                    }));
                }
            }
        }
        if let Some((name, volume, tf)) = datasets.first().filter(|d| d.0.starts_with("marschner"))
        {
            rows.extend(pool_rows(&ctx, (name, volume, tf), sizes, frames, as_json)?);
        }
        Ok(rows)
    }

    /// The Projected Tetrahedra rows: ψ colour, centroid order, each mesh at each size.
    fn pt_rows(
        ctx: &Arc<GpuContext>,
        (quick, frames, only): (bool, usize, Option<&str>),
        sizes: &[(usize, usize)],
        as_json: bool,
    ) -> Result<Vec<serde_json::Value>, CmdError> {
        let adapter = ctx.adapter().to_string();
        if !as_json {
            outln!(
                "{:<20} {:>9} {:<22} {:>10} {:>12} {:>12} {:>10}",
                "mesh",
                "size",
                "case",
                "ms/frame",
                "tets",
                "Mtets/s",
                "upload ms"
            )?;
        }
        let mut rows = Vec::new();
        for (name, volume) in meshes(quick)? {
            let Volume::Mesh(mesh) = &volume else {
                continue;
            };
            if !selected(&name, only) {
                continue;
            }
            let started = Instant::now();
            let mut renderer =
                GpuPtRenderer::new(ctx.clone(), mesh.clone()).map_err(RenderError::from)?;
            let upload_ms = started.elapsed().as_secs_f64() * 1e3;
            let tf = volume.preset_tf("auto")?;
            for &(w, h) in sizes {
                let mut scene = scene(
                    &volume,
                    &tf,
                    (w, h),
                    Integrator::Riemann { step: 0.5 },
                    (false, false),
                )?;
                scene.method = Method::ProjectedTetrahedra(PtSettings::default());
                scene.early_termination = None;
                let (ms, _) = time(&mut renderer, &scene, frames)?;
                let tets = mesh.tets().len();
                let rate = tets as f64 / ms * 1e3;
                if !as_json {
                    outln!(
                        "{name:<20} {:>9} {:<22} {ms:>10.1} {tets:>12} {:>12.1} {upload_ms:>10.1}",
                        format!("{w}x{h}"),
                        "pt psi",
                        rate / 1e6,
                    )?;
                }
                rows.push(json!({
                    "suite": "gpu", "adapter": adapter, "dataset": name, "width": w,
                    "height": h, "case": "pt psi", "ms": ms, "tets": tets,
                    "tets_per_s": rate, "upload_ms": upload_ms,
                }));
            }
        }
        Ok(rows)
    }

    /// The brick pool: the first grid, Riemann h=0.5, through a pool of a quarter of its
    /// bytes in bricks of 32 cells: ms/frame, dispatches and bricks uploaded per frame.
    fn pool_rows(
        ctx: &Arc<GpuContext>,
        (name, volume, tf): (&str, &Volume, &TransferFunction),
        sizes: &[(usize, usize)],
        frames: usize,
        as_json: bool,
    ) -> Result<Vec<serde_json::Value>, CmdError> {
        let Volume::Grid(grid) = volume else {
            return Ok(Vec::new());
        };
        let voxels: u64 = grid.dims().iter().map(|&n| n as u64).product();
        let options = PoolOptions {
            brick: 32,
            bytes: (voxels).max(8 * 33 * 33 * 33 * 4),
        };
        let source = PoolSource::Grid(grid.clone());
        let mut pool =
            GpuPoolRenderer::new(ctx.clone(), source, options).map_err(RenderError::from)?;
        if !as_json {
            outln!(
                "\n{:<20} {:>9} {:<22} {:>10} {:>8} {:>8} {:>8} {:>8}",
                "brick pool",
                "size",
                "case",
                "ms/frame",
                "slots",
                "bricks",
                "rounds",
                "uploads"
            )?;
        }
        let mut rows = Vec::new();
        for &(w, h) in sizes {
            let scene = scene(
                volume,
                tf,
                (w, h),
                Integrator::Riemann { step: 0.5 },
                (false, false),
            )?;
            let (ms, _) = time(&mut pool, &scene, frames)?;
            let st = pool.stats();
            if !as_json {
                outln!(
                    "{name:<20} {:>9} {:<22} {ms:>10.1} {:>8} {:>8} {:>8} {:>8}",
                    format!("{w}x{h}"),
                    "riemann h=0.5 pool",
                    st.capacity,
                    st.bricks,
                    st.rounds,
                    st.uploads
                )?;
            }
            rows.push(json!({
                "suite": "gpu", "dataset": name, "width": w, "height": h,
                "case": "riemann h=0.5 pool", "ms": ms, "slots": st.capacity,
                "bricks": st.bricks, "empty": st.empty, "rounds": st.rounds, "uploads": st.uploads,
            }));
        }
        Ok(rows)
    }

    /// The renderer of `grid` and the milliseconds its upload took.
    fn upload(ctx: &Arc<GpuContext>, grid: &Arc<Grid>) -> Result<(GpuGridRenderer, f64), CmdError> {
        let started = Instant::now();
        let r = GpuGridRenderer::new(ctx.clone(), grid.clone()).map_err(RenderError::from)?;
        Ok((r, started.elapsed().as_secs_f64() * 1e3))
    }

    fn scene(
        volume: &Volume,
        tf: &TransferFunction,
        (w, h): (usize, usize),
        integrator: Integrator,
        (shaded, mip): (bool, bool),
    ) -> Result<Scene, CmdError> {
        let spec = CameraSpec {
            azimuth: Some(30.0),
            elevation: Some(20.0),
            ..Default::default()
        };
        let mut scene = Scene::new(spec.resolve(&volume.bounds())?, w, h, tf.clone());
        scene.method = Method::GridRaycast(GridRaycast {
            integrator,
            ..GridRaycast::default()
        });
        scene.appearance.shade_volume = shaded;
        scene.appearance.mip = mip;
        Ok(scene)
    }

    /// The median ms of `frames` warm frames (after one that builds the tables and the
    /// gradient volume) and the samples of one.
    fn time(
        renderer: &mut dyn Renderer,
        scene: &Scene,
        frames: usize,
    ) -> Result<(f64, u64), CmdError> {
        frame(renderer, scene)?;
        let mut times = Vec::new();
        let mut samples = 0;
        for _ in 0..frames {
            let f = frame(renderer, scene)?;
            times.push(f.stats.ms);
            if let MethodStats::GridRaycast(s) = f.stats.method {
                samples = s.samples;
            }
        }
        Ok((median(&mut times), samples))
    }
}
