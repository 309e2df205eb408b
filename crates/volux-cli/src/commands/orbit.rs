//! `volux render --orbit N[:DEG]`: a turntable of N frames in one process, one renderer
//! kept for all of them, so frames after the first are warm (what a viewer feels, and what
//! turntable animations need). The camera turns about its up vector through its target.
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use volux_core::image::PngOptions;
use volux_core::Camera;
use volux_render::engine::{create_renderer, Frame};
use volux_render::scene::{Scene, Volume};
use volux_render::tiles::Control;

use super::common::CmdError;
use super::report;
use crate::cli::RenderArgs;

/// Most frames an orbit renders.
pub const MAX_FRAMES: usize = 100_000;

/// Parses `N[:DEG]`: N frames (1..=[`MAX_FRAMES`]) turned by DEG degrees each (default
/// 360/N).
pub fn parse(spec: &str) -> Result<(usize, f64), CmdError> {
    let (n, deg) = match spec.split_once(':') {
        Some((n, d)) => (n, Some(d)),
        None => (spec, None),
    };
    let n: usize = n
        .trim()
        .parse()
        .ok()
        .filter(|n| (1..=MAX_FRAMES).contains(n))
        .ok_or_else(|| {
            format!("--orbit '{spec}': N is a whole number of frames from 1 to {MAX_FRAMES}")
        })?;
    let deg = match deg {
        None => 360.0 / n as f64,
        Some(d) => d
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|d| d.is_finite())
            .ok_or_else(|| format!("--orbit '{spec}': DEG is a number of degrees per frame"))?,
    };
    Ok((n, deg))
}

/// `camera` turned by `deg` degrees about its up vector through its target.
pub fn turned(camera: &Camera, deg: f64) -> Camera {
    let axis = camera.up.normalize_or(DVec3::Z);
    let turn = DMat3::from_axis_angle(axis, deg.to_radians());
    Camera {
        eye: camera.target + turn * (camera.eye - camera.target),
        up: turn * camera.up,
        ..*camera
    }
}

/// Frame `k`'s file: `out.png` -> `out_0007.png`.
pub fn frame_path(output: &Path, k: usize) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned());
    let name = format!("{}_{k:04}.png", stem.unwrap_or_else(|| "out".into()));
    output.with_file_name(name)
}

/// Renders the turntable of `scene` and reports each frame.
pub fn run(
    args: &RenderArgs,
    spec: &str,
    volume: &Volume,
    scene: &Scene,
    png: &PngOptions,
) -> Result<(), CmdError> {
    let (n, deg) = parse(spec)?;
    let output = args.output();
    frames(n, deg, volume, scene, |k, frame_scene, frame| {
        let path = frame_path(&output, k);
        if !args.no_write {
            frame
                .image
                .write_png(&path, png)
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        let mut frame_args = args.clone();
        frame_args.output = Some(path);
        frame_args.frame_index = Some(k);
        report::frame(&frame_args, frame, frame_scene, volume)?;
        Ok(())
    })?;
    if args.no_write {
        eprintln!("rendered {n} frames, {deg} degrees apart (no files: --no-write)");
    } else {
        eprintln!(
            "wrote {n} frames, {deg} degrees apart: {} .. {}",
            frame_path(&output, 0).display(),
            frame_path(&output, n - 1).display()
        );
    }
    Ok(())
}

/// Renders `n` frames of `scene` with one renderer, the camera turned by `deg` more each
/// time, handing each to `each` (frame number, its scene, the frame).
pub fn frames(
    n: usize,
    deg: f64,
    volume: &Volume,
    scene: &Scene,
    mut each: impl FnMut(usize, &Scene, &Frame) -> Result<(), CmdError>,
) -> Result<(), CmdError> {
    let mut renderer = create_renderer(volume, &scene.method)?;
    for k in 0..n {
        let mut frame_scene = scene.clone();
        frame_scene.view.camera = turned(&scene.view.camera, deg * k as f64);
        let frame = renderer.render(&frame_scene, &Control::default())?;
        each(k, &frame_scene, &frame)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::Projection;

    #[test]
    fn specs_frames_and_names() {
        assert_eq!(parse("36").unwrap(), (36, 10.0));
        assert_eq!(parse("4:-5").unwrap(), (4, -5.0));
        for bad in ["0", "x", "3:y", "3:inf", "-2"] {
            assert!(parse(bad).is_err(), "{bad}");
        }
        assert_eq!(
            frame_path(Path::new("a/t.png"), 7),
            Path::new("a/t_0007.png")
        );
    }

    /// A quarter turn about +z moves the eye from -y to +x (right-handed), keeping the
    /// distance, the target and the up.
    #[test]
    fn turns_about_up_through_the_target() {
        let c = Camera {
            eye: DVec3::new(1.0, -4.0, 2.0),
            target: DVec3::new(1.0, 0.0, 2.0),
            up: DVec3::Z,
            projection: Projection::Perspective { fov_y_deg: 30.0 },
        };
        let t = turned(&c, 90.0);
        assert!(
            (t.eye - DVec3::new(5.0, 0.0, 2.0)).length() < 1e-12,
            "{:?}",
            t.eye
        );
        assert_eq!((t.target, t.up), (c.target, c.up));
        assert!((turned(&c, 360.0).eye - c.eye).length() < 1e-12);
    }
}
