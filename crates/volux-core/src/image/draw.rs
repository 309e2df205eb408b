//! Anti-aliased marks drawn over an image: round-capped segments and discs (annotations
//! such as `volux render --measure`'s polyline). Coordinates are continuous pixels (x right,
//! y down, pixel (i, j)'s centre at i + 0.5, j + 0.5); a pixel is covered by the share of a
//! one-pixel box filter that falls inside the shape, estimated from the distance of its
//! centre to the shape's edge.
use super::Image;
use crate::segment;

/// Coverage of a pixel whose centre lies `distance` from a capsule's axis, `half` its
/// half-width: 1 well inside, 0 well outside, linear across a one-pixel band.
fn coverage(distance: f64, half: f64) -> f32 {
    (half + 0.5 - distance).clamp(0.0, 1.0) as f32
}

/// [`segment::segment_distance`] of pixel coordinates.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    segment::segment_distance(p.into(), a.into(), b.into())
}

impl Image {
    /// Draws the segment `a`-`b`, `width` pixels wide with round caps, in the opaque linear
    /// colour `rgb` over what is there (anti-aliased edges). Non-finite input or a
    /// non-positive width draws nothing; parts outside the image are cut.
    pub fn draw_segment(&mut self, a: [f64; 2], b: [f64; 2], width: f64, rgb: [f32; 3]) {
        let finite = a.iter().chain(&b).all(|v| v.is_finite());
        if !finite || !width.is_finite() || width <= 0.0 {
            return;
        }
        let half = width / 2.0;
        let reach = half + 1.0;
        let span = |lo: f64, hi: f64, n: usize| {
            let first = (lo - reach).floor().max(0.0) as usize;
            let last = ((hi + reach).ceil().max(0.0) as usize).min(n);
            first..last
        };
        for y in span(a[1].min(b[1]), a[1].max(b[1]), self.height) {
            for x in span(a[0].min(b[0]), a[0].max(b[0]), self.width) {
                let centre = [x as f64 + 0.5, y as f64 + 0.5];
                let c = coverage(segment_distance(centre, a, b), half);
                if c > 0.0 {
                    self.blend(x, y, rgb, c);
                }
            }
        }
    }

    /// Draws a filled disc of `radius` pixels about `centre` in the opaque linear colour
    /// `rgb` (anti-aliased edge).
    pub fn draw_disc(&mut self, centre: [f64; 2], radius: f64, rgb: [f32; 3]) {
        self.draw_segment(centre, centre, 2.0 * radius, rgb);
    }

    /// Draws the polyline through `points` and a disc at each point, in `rgb` over a dark
    /// outline one and a half pixels wide, so that it reads on bright and dark pictures
    /// alike: `width` is the line's, `radius` the discs'.
    pub fn draw_marked_polyline(
        &mut self,
        points: &[[f64; 2]],
        width: f64,
        radius: f64,
        rgb: [f32; 3],
    ) {
        const OUTLINE: [f32; 3] = [0.0; 3];
        for (colour, grow) in [(OUTLINE, 3.0), (rgb, 0.0)] {
            for pair in points.windows(2) {
                self.draw_segment(pair[0], pair[1], width + grow, colour);
            }
            for &p in points {
                self.draw_disc(p, radius + grow / 2.0, colour);
            }
        }
    }

    /// Puts the opaque colour `rgb` over pixel (x, y) with coverage `c` (premultiplied).
    fn blend(&mut self, x: usize, y: usize, rgb: [f32; 3], c: f32) {
        let p = &mut self.pixels[y * self.width + x];
        for (v, s) in p.iter_mut().zip(rgb) {
            *v = s * c + *v * (1.0 - c);
        }
        p[3] = c + p[3] * (1.0 - c);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pixels (x, y) that a drawing changed.
    fn touched(img: &Image) -> Vec<(usize, usize)> {
        let w = img.width();
        img.pixels()
            .iter()
            .enumerate()
            .filter(|(_, p)| p[3] > 0.0)
            .map(|(i, _)| (i % w, i / w))
            .collect()
    }

    #[test]
    fn a_segments_pixels_lie_on_the_segment() {
        let mut img = Image::new(40, 30);
        let (a, b) = ([3.2, 4.7], [35.5, 22.1]);
        img.draw_segment(a, b, 2.0, [1.0, 0.5, 0.0]);
        let hit = touched(&img);
        assert!(
            hit.len() > 60,
            "a 37-pixel line 2 px wide: {} pixels",
            hit.len()
        );
        for &(x, y) in &hit {
            let d = segment_distance([x as f64 + 0.5, y as f64 + 0.5], a, b);
            assert!(d < 1.0 + 0.5, "pixel ({x}, {y}) is {d} px from the segment");
        }
        // Pixels whose centre is on the axis are fully covered, in the colour.
        for t in [0.1, 0.5, 0.9] {
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let (x, y) = (p[0] as usize, p[1] as usize);
            let d = segment_distance([x as f64 + 0.5, y as f64 + 0.5], a, b);
            if d <= 0.5 {
                assert_eq!(img.get(x, y), [1.0, 0.5, 0.0, 1.0]);
            }
        }
        // Nothing beyond the caps.
        assert!(hit.iter().all(|&(x, _)| (2..=37).contains(&x)));
    }

    #[test]
    fn a_disc_covers_its_radius_and_no_more() {
        let mut img = Image::new(20, 20);
        img.draw_disc([10.0, 10.0], 4.0, [0.0, 1.0, 0.0]);
        assert_eq!(img.get(10, 10), [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(img.get(11, 11), [0.0, 1.0, 0.0, 1.0]);
        for (x, y) in touched(&img) {
            let d = segment_distance([x as f64 + 0.5, y as f64 + 0.5], [10.0; 2], [10.0; 2]);
            assert!(d < 4.5, "({x}, {y}) at {d}");
        }
        let area = touched(&img).len() as f64;
        assert!((area - std::f64::consts::PI * 16.0).abs() < 20.0, "{area}");
    }

    #[test]
    fn marks_outside_or_invalid_change_nothing() {
        let mut img = Image::new(8, 8);
        img.draw_segment([-50.0, -50.0], [-20.0, -30.0], 3.0, [1.0; 3]);
        img.draw_segment([1.0, 1.0], [f64::NAN, 2.0], 3.0, [1.0; 3]);
        img.draw_segment([1.0, 1.0], [6.0, 6.0], 0.0, [1.0; 3]);
        img.draw_disc([100.0, 4.0], 3.0, [1.0; 3]);
        assert_eq!(img, Image::new(8, 8));
    }

    #[test]
    fn a_marked_polyline_is_bright_inside_a_dark_outline() {
        let mut img = Image::from_pixels(30, 10, vec![[1.0; 4]; 300]).unwrap();
        img.draw_marked_polyline(&[[5.0, 5.0], [25.0, 5.0]], 2.0, 3.0, [1.0, 1.0, 0.0]);
        assert_eq!(img.get(15, 4), [1.0, 1.0, 0.0, 1.0]);
        assert_eq!(img.get(15, 3), [0.0, 0.0, 0.0, 1.0], "the outline is dark");
        assert_eq!(img.get(15, 0), [1.0; 4]);
    }
}
