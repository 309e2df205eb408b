//! `volux bench --suite tetray`: the tetrahedral ray caster on the PT suite's meshes:
//! ms/frame at 512x512 for exact and ψ colour, automatic TF, early termination at 0.999, and
//! the bytes per tet of its acceleration structures (boundary BVH, face planes, adjacency).
use serde_json::json;
use volux_core::CameraSpec;
use volux_render::engine::{create_renderer, MethodStats};
use volux_render::integrate::SegmentRule;
use volux_render::scene::{Method, Scene};
use volux_render::tetray::TetRayStats;

use super::common::{frame, median, meshes, EARLY_TERMINATION};
use crate::commands::common::CmdError;

/// Runs the tet ray casting benchmark; returns the JSON rows.
pub fn run(quick: bool, frames: usize, as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let frames = if quick { 1 } else { frames.max(1) };
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    if !as_json {
        outln!("\nTet ray casting, 512x512, automatic TF; threads: {threads}; frames per case: {frames} (median)")?;
        outln!(
            "{:<14} {:>9} {:<8} {:>9} {:>9} {:>11} {:>10} {:>10} {:>9}",
            "mesh",
            "tets",
            "colour",
            "ms/frame",
            "M tets/s",
            "segments",
            "reentries",
            "abandoned",
            "bytes/tet"
        )?;
    }
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    for (name, volume) in meshes(quick)? {
        let tf = volume.preset_tf("auto")?;
        let mut renderer = create_renderer(&volume, &Method::TetRaycast(SegmentRule::Exact))?;
        for (label, rule) in [("exact", SegmentRule::Exact), ("psi", SegmentRule::Psi)] {
            let mut scene = Scene::new(spec.resolve(&volume.bounds())?, 512, 512, tf.clone());
            scene.method = Method::TetRaycast(rule);
            scene.early_termination = Some(EARLY_TERMINATION);
            let mut times = Vec::new();
            let mut stats = TetRayStats::default();
            for _ in 0..frames {
                let r = frame(renderer.as_mut(), &scene)?;
                times.push(r.stats.ms / 1e3);
                if let MethodStats::TetRaycast(s) = r.stats.method {
                    stats = s;
                }
            }
            let s = median(&mut times);
            let tets = stats.tets;
            if !as_json {
                outln!(
                    "{:<14} {:>9} {:<8} {:>9.1} {:>9.2} {:>11} {:>10} {:>10} {:>9.1}",
                    name,
                    tets,
                    label,
                    s * 1e3,
                    tets as f64 / s / 1e6,
                    stats.segments,
                    stats.reentries,
                    stats.abandoned,
                    stats.bytes_per_tet
                )?;
            }
            rows.push(json!({
                "suite": "tetray", "dataset": name, "width": 512, "height": 512, "color": label,
                "tets": tets, "ms": s * 1e3, "tets_per_s": tets as f64 / s,
                "segments": stats.segments, "reentries": stats.reentries,
                "abandoned": stats.abandoned, "bytes_per_tet": stats.bytes_per_tet,
            }));
        }
    }
    Ok(rows)
}
