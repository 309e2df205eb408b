//! The viewer benchmark: the window's render thread and caches driven by a script, without
//! a window, so the figures are what a user feels minus the screen's own delay (one
//! display refresh). A scripted orbit (input at 60 Hz for a few seconds), then the last
//! input and the wait for the full-resolution frame, then a scripted TF drag (a control
//! point moved at 60 Hz). Reports input-to-preview latency (p50, p95), preview frames per
//! second, the time from the last input to the full frame, and the TF-edit latency. Before
//! that, the opening: the time to open the dataset, to its first picture (for an OME-Zarr
//! store, the coarsest level: [`crate::progressive`]) and to the fully refined frame.
use std::path::Path;
use std::time::{Duration, Instant};

use serde::Serialize;
use volux_app::session::DatasetRef;
use volux_render::bricked::Lod;
use volux_render::scene::{Method, Scene};

use crate::dataset;
use crate::navigation;
use crate::render_service::{Event, FinishedFrame, RenderService, VolumeRef};
use crate::tf_editor::in_value_space;

/// Interval between scripted inputs (60 Hz).
pub const INPUT_INTERVAL: Duration = Duration::from_micros(16_667);

/// The figures of one dataset.
#[derive(Clone, Debug, Serialize)]
pub struct ViewerBench {
    /// The file.
    pub dataset: String,
    /// The method's name.
    pub method: String,
    /// View size.
    pub size: [usize; 2],
    /// From the start to the dataset opened (read in full, or a store's metadata and
    /// histogram), ms.
    pub open_ms: f64,
    /// From the start to the first picture (a store's coarsest level), ms.
    pub first_picture_ms: f64,
    /// The level of that picture (stores only).
    pub first_level: Option<usize>,
    /// From the start to the fully refined frame, ms.
    pub refined_ms: f64,
    /// The level refinement ended at (stores only).
    pub refined_level: Option<usize>,
    /// Input-to-preview latency during the orbit, median (ms).
    pub orbit_latency_p50_ms: f64,
    /// ... 95th percentile (ms).
    pub orbit_latency_p95_ms: f64,
    /// Preview frames per second during the orbit.
    pub preview_fps: f64,
    /// Mean preview divisor during the orbit.
    pub mean_divisor: f64,
    /// From the last input to the full-resolution frame (ms).
    pub full_after_input_ms: f64,
    /// TF-edit-to-preview latency, median (ms).
    pub tf_latency_p50_ms: f64,
    /// ... 95th percentile (ms).
    pub tf_latency_p95_ms: f64,
}

/// Runs the benchmark on `path` at `size` with a `seconds`-long orbit (and TF drag); a
/// store refines to the level `lod` picks.
pub fn run(
    path: &Path,
    size: (usize, usize),
    seconds: f64,
    lod: Lod,
) -> Result<ViewerBench, String> {
    let source = DatasetRef {
        path: path.to_path_buf(),
        ..Default::default()
    };
    let start = Instant::now();
    let loaded = dataset::load(&source)?;
    let open_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut volume = loaded.volume.clone();
    volume.volume = crate::store::with_lod(&volume.volume, lod);
    let range = volume.volume.range();
    let tf = in_value_space(
        &volume.volume.preset_tf("auto").map_err(|e| e.to_string())?,
        range,
    );
    let aspect = size.0 as f64 / size.1 as f64;
    let mut scene = Scene::new(
        navigation::home(&volume.volume.bounds(), aspect),
        size.0,
        size.1,
        tf,
    );
    scene.method = Method::Auto
        .resolve(&volume.volume)
        .map_err(|e| e.to_string())?;
    let mut service = RenderService::start(|| {});
    // Warm up: the first frame builds the caches (as opening a file does).
    service.submit(&volume, &scene, false);
    let first = wait_frame(&service, Duration::from_secs(600))?;
    let first_picture_ms = start.elapsed().as_secs_f64() * 1e3;
    let refined = if first.full {
        first.clone()
    } else {
        wait_full(&service, Duration::from_secs(600))?
    };
    let refined_ms = start.elapsed().as_secs_f64() * 1e3;
    let degrees_per_input =
        360.0 / (seconds / INPUT_INTERVAL.as_secs_f64()) / navigation::ORBIT_DEG_PER_PIXEL;
    let orbit = drive(&mut service, &volume, &mut scene, seconds, |s, _| {
        s.view.camera = navigation::orbit(&s.view.camera, degrees_per_input, 0.0);
    })?;
    let last_input = Instant::now();
    service.submit(&volume, &scene, false);
    wait_full(&service, Duration::from_secs(600))?;
    let full_after = last_input.elapsed().as_secs_f64() * 1e3;
    let tf_drag = drive(
        &mut service,
        &volume,
        &mut scene,
        seconds.min(2.0),
        |s, k| {
            let tf = &mut s.appearance.tf;
            let pts = if tf.extinction.is_empty() {
                &mut tf.opacity
            } else {
                &mut tf.extinction
            };
            let i = pts.len() / 2;
            pts[i][1] *= if (k / 30) % 2 == 0 { 1.01 } else { 1.0 / 1.01 };
        },
    )?;
    let latencies = |frames: &[FinishedFrame]| {
        let mut v: Vec<f64> = frames
            .iter()
            .map(|f| f.latency.as_secs_f64() * 1e3)
            .collect();
        v.sort_by(f64::total_cmp);
        (percentile(&v, 0.5), percentile(&v, 0.95))
    };
    let (o50, o95) = latencies(&orbit);
    let (t50, t95) = latencies(&tf_drag);
    Ok(ViewerBench {
        dataset: path.display().to_string(),
        method: scene.method.name().into(),
        size: [size.0, size.1],
        open_ms,
        first_picture_ms,
        first_level: first.level.map(|l| l.level),
        refined_ms,
        refined_level: refined.level.map(|l| l.level),
        orbit_latency_p50_ms: o50,
        orbit_latency_p95_ms: o95,
        preview_fps: orbit.len() as f64 / seconds,
        mean_divisor: orbit.iter().map(|f| f.divisor as f64).sum::<f64>()
            / orbit.len().max(1) as f64,
        full_after_input_ms: full_after,
        tf_latency_p50_ms: t50,
        tf_latency_p95_ms: t95,
    })
}

/// Submits an input every [`INPUT_INTERVAL`] for `seconds` (`step` changes the scene), and
/// collects the previews that come back.
fn drive(
    service: &mut RenderService,
    volume: &VolumeRef,
    scene: &mut Scene,
    seconds: f64,
    mut step: impl FnMut(&mut Scene, usize),
) -> Result<Vec<FinishedFrame>, String> {
    let start = Instant::now();
    let mut frames = Vec::new();
    let mut k = 0;
    while start.elapsed().as_secs_f64() < seconds {
        step(scene, k);
        service.submit(volume, scene, true);
        let next = start + INPUT_INTERVAL * (k as u32 + 1);
        k += 1;
        while let Some(left) = next.checked_duration_since(Instant::now()) {
            match service.wait(left) {
                Some(Event::Frame(f)) => frames.push(*f),
                Some(Event::Failed { message, .. }) => return Err(message),
                None => break,
            }
        }
    }
    Ok(frames)
}

fn wait_frame(service: &RenderService, timeout: Duration) -> Result<FinishedFrame, String> {
    match service.wait(timeout) {
        Some(Event::Frame(f)) => Ok(*f),
        Some(Event::Failed { message, .. }) => Err(message),
        None => Err("no frame in time".into()),
    }
}

fn wait_full(service: &RenderService, timeout: Duration) -> Result<FinishedFrame, String> {
    let end = Instant::now() + timeout;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match service.wait(left) {
            Some(Event::Frame(f)) if f.full && f.generation == service.generation() => {
                return Ok(*f)
            }
            Some(Event::Frame(_)) => {}
            Some(Event::Failed { message, .. }) => return Err(message),
            None => return Err("no full frame in time".into()),
        }
    }
}

/// The `q` quantile of sorted values (nearest rank; NaN when empty).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[i]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.5), 50.0);
        assert_eq!(percentile(&v, 0.95), 95.0);
        assert!(percentile(&[], 0.5).is_nan());
    }
}
