//! RGB grids drawn in their own colour (VTK's dependent components): the colour of a pixel is
//! the data's, its opacity the transfer function's on the luminance. Checked against the
//! emission-absorption integral of a constant medium (colour / opacity is the voxels' colour
//! in linear light, whatever the opacity) and against the same picture drawn by the TF's
//! colours on a scalar grid (the lane paths and the ray-by-ray path compute the same sums).
use glam::DVec3;
use volux_core::color::Rgb;
use volux_core::image::srgb_to_linear;
use volux_core::{Buffer, Camera, Grid, Projection, Samples, TransferFunction};
use volux_render::engine::create_renderer;
use volux_render::scene::{Method, Scene, Volume};
use volux_render::tiles::Control;

const N: usize = 12;

/// An `N`^3 RGB grid whose voxels left of the middle are `left` and the others `right`.
fn rgb_grid(left: [u8; 3], right: [u8; 3]) -> Grid {
    let channel = |c: usize| {
        let v: Vec<u8> = (0..N * N * N)
            .map(|i| if i % N < N / 2 { left[c] } else { right[c] })
            .collect();
        Samples::U8(Buffer::owned(v))
    };
    let rgb = Rgb::new([channel(0), channel(1), channel(2)]).unwrap();
    Grid::from_rgb([N, N, N], [1.0; 3], [0.0; 3], rgb).unwrap()
}

/// A TF of colour `rgb` (linear) and extinction `tau` per voxel over every value.
fn tf(rgb: [f32; 3], tau: f64) -> TransferFunction {
    TransferFunction::from_json(&format!(
        r#"{{"color": [[0, {r}, {g}, {b}], [255, {r}, {g}, {b}]],
            "extinction": [[0, {tau}], [255, {tau}]]}}"#,
        r = rgb[0],
        g = rgb[1],
        b = rgb[2]
    ))
    .unwrap()
}

/// Looks down -z through the whole grid, orthographic, the image covering it.
fn scene(tf: TransferFunction) -> Scene {
    let c = (N - 1) as f64 / 2.0;
    let camera = Camera {
        eye: DVec3::new(c, c, 40.0),
        target: DVec3::new(c, c, c),
        up: DVec3::Y,
        projection: Projection::Orthographic {
            height: N as f64 + 2.0,
        },
    };
    Scene::new(camera, 32, 32, tf)
}

fn render(grid: Grid, scene: &Scene) -> volux_core::Image {
    let volume = Volume::from(grid);
    let mut r = create_renderer(&volume, &Method::Auto).unwrap();
    r.render(scene, &Control::default()).unwrap().image
}

fn linear(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| srgb_to_linear(f32::from(v) / 255.0))
}

#[test]
fn a_pixel_has_the_voxels_colour_and_the_tfs_opacity() {
    let (red, blue) = ([200, 30, 30], [30, 60, 220]);
    let image = render(rgb_grid(red, blue), &scene(tf([1.0, 1.0, 1.0], 0.1)));
    // The optical depth is 0.1 per voxel over the 11 voxels between the faces.
    let alpha = 1.0 - (-0.1f32 * (N - 1) as f32).exp();
    for (x, want) in [(9, linear(red)), (22, linear(blue))] {
        let p = image.get(x, 16);
        assert!(
            (p[3] - alpha).abs() < 2e-3,
            "alpha {} instead of {alpha}",
            p[3]
        );
        for c in 0..3 {
            let colour = p[c] / p[3];
            assert!(
                (colour - want[c]).abs() < 1e-5,
                "pixel {x}: channel {c} is {colour}, the voxels' is {}",
                want[c]
            );
        }
    }
}

#[test]
fn the_tfs_colour_when_data_colour_is_off() {
    let mut s = scene(tf([0.25, 0.5, 1.0], 0.1));
    s.appearance.data_colour = false;
    let p = render(rgb_grid([200, 30, 30], [200, 30, 30]), &s).get(16, 16);
    for (c, want) in [0.25f32, 0.5, 1.0].iter().enumerate() {
        assert!((p[c] / p[3] - want).abs() < 1e-5, "{p:?}");
    }
}

#[test]
fn data_colour_is_the_picture_of_the_same_colour_given_by_the_tf() {
    let colour = [90u8, 160, 40];
    let rgb = rgb_grid(colour, colour);
    let scalar = Grid::new(rgb.dims(), [1.0; 3], [0.0; 3], rgb.samples().clone()).unwrap();
    let by_data = render(rgb, &scene(tf([1.0, 1.0, 1.0], 0.05)));
    let by_tf = render(scalar, &scene(tf(linear(colour), 0.05)));
    let worst = by_data
        .pixels()
        .iter()
        .zip(by_tf.pixels())
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "largest difference {worst}");
}
