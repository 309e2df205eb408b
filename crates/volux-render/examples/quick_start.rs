//! Renders a volume file (any format `volux-io` reads) or, without an argument, the built-in
//! Marschner-Lobb signal, with the automatic transfer function, to `quick_start.png`:
//!
//! ```sh
//! cargo run --release -p volux-render --example quick_start [FILE]
//! ```
use std::error::Error;
use std::path::Path;

use volux_core::image::PngOptions;
use volux_core::{synth, CameraSpec};
use volux_io::{Dataset, LoadOptions};
use volux_render::engine::create_renderer;
use volux_render::scene::{Scene, Volume};
use volux_render::tiles::Control;

fn main() -> Result<(), Box<dyn Error>> {
    // 1. The volume: a file, or a generated one.
    let volume = match std::env::args().nth(1) {
        Some(path) => match volux_io::load(Path::new(&path), &LoadOptions::default())?.0 {
            Dataset::Grid(g) => Volume::from(g),
            Dataset::Mesh(m) => Volume::from(m),
            _ => return Err("unsupported dataset kind".into()),
        },
        None => Volume::from(synth::marschner_lobb(128)?),
    };
    // 2. The scene: a camera framing the volume, the automatic transfer function; the
    //    method is chosen by the library (grids: ray casting; meshes: Projected Tetrahedra).
    let camera = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    }
    .resolve(&volume.bounds())?;
    let scene = Scene::new(camera, 512, 512, volume.preset_tf("auto")?);
    // 3. One call renders a frame.
    let mut renderer = create_renderer(&volume, &scene.method)?;
    let frame = renderer.render(&scene, &Control::default())?;
    // 4. The PNG.
    frame
        .image
        .write_png(Path::new("quick_start.png"), &PngOptions::default())?;
    println!(
        "{} rendered by '{}' in {:.0} ms: quick_start.png",
        volume.kind(),
        renderer.name(),
        frame.stats.ms
    );
    Ok(())
}
