//! Heat-map images of per-pixel values (errors, costs, sample counts) with a legend.
//!
//! Values from 0 to `max` go through the inferno colour scale ([`crate::transfer::INFERNO`]:
//! near black at 0, pale yellow at `max`); values above `max` are magenta, NaN is mid grey,
//! negative values count as 0. Below the image [`heat_map`] appends a legend strip of
//! [`LEGEND_HEIGHT`] pixels: the colour bar from 0 to `max` across the width, a magenta block
//! at its right end, and the labels `0`, `max` and `over` in a tiny pixel font.
use crate::error::{Error, Result};
use crate::image::{srgb_to_linear, Image};
use crate::transfer::{colormap_at, INFERNO};

/// Colour of values above `max`.
pub const OVER_COLOR: [f32; 3] = [1.0, 0.0, 1.0];

/// Height in pixels of the legend strip [`heat_map`] appends below the image.
pub const LEGEND_HEIGHT: usize = BAR_TOP + BAR_HEIGHT + GAP + GLYPH_ROWS * SCALE + GAP;

/// Black rows between the image and the colour bar.
const BAR_TOP: usize = 2;
/// Height of the colour bar.
const BAR_HEIGHT: usize = 12;
/// Width of the magenta "over" block at the right end of the bar.
const OVER_WIDTH: usize = 4;
/// Gap below the bar and below the labels.
const GAP: usize = 2;
/// Glyph size of the pixel font, before scaling.
const GLYPH_COLS: usize = 3;
/// Glyph rows of the pixel font, before scaling.
const GLYPH_ROWS: usize = 5;
/// Scale of the pixel font.
const SCALE: usize = 2;
/// Horizontal advance of one character, scaled.
const ADVANCE: usize = (GLYPH_COLS + 1) * SCALE;

/// A `width` x `height` heat map of `values` (row-major, top row first) scaled 0..`max`, with
/// the legend strip below it: the result is `width` x (`height` + [`LEGEND_HEIGHT`]), opaque.
///
/// Errors: a zero width or height, a value count other than `width * height`, a `max` that
/// is not finite and > 0, or an image too large for memory.
pub fn heat_map(values: &[f32], width: usize, height: usize, max: f32) -> Result<Image> {
    let total = check_inputs(values, width, height, max)?;
    crate::limits::check_alloc("heat map", total as u64, 16)?;
    let mut pixels: Vec<[f32; 4]> = values.iter().map(|&v| opaque(heat_color(v, max))).collect();
    pixels.resize(total, [0.0, 0.0, 0.0, 1.0]);
    let mut img = Image::from_pixels(width, height + LEGEND_HEIGHT, pixels)?;
    draw_legend(&mut img, height, max);
    Ok(img)
}

/// The line a command prints to explain the colours of [`heat_map`], e.g.
/// `colour scale: black 0 to yellow 0.01, magenta above (grey: NaN)`.
pub fn heat_map_legend_text(max: f32) -> String {
    format!(
        "colour scale: black 0 to yellow {}, magenta above (grey: NaN)",
        short_number(max)
    )
}

/// The linear RGB colour of `value` on the scale 0..`max`.
pub fn heat_color(value: f32, max: f32) -> [f32; 3] {
    if value.is_nan() {
        return [srgb_to_linear(0.5); 3];
    }
    if value > max {
        return OVER_COLOR;
    }
    let t = f64::from(value.max(0.0)) / f64::from(max);
    colormap_at(&INFERNO, t).map(|c| c as f32)
}

/// `max` formatted briefly: plain (`0.05`, `250`) unless scientific (`1e-3`, `2.5e6`) is
/// shorter; three significant digits at most.
pub fn short_number(max: f32) -> String {
    if !max.is_finite() {
        return max.to_string();
    }
    let sci = format!("{max:.2e}");
    let (mantissa, exponent) = sci.split_once('e').unwrap_or((&sci, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    let sci = format!("{mantissa}e{exponent}");
    let plain = sci.parse::<f32>().map_or(sci.clone(), |v| v.to_string());
    if plain.len() <= sci.len() || plain.len() <= 4 {
        plain
    } else {
        sci
    }
}

/// Checks the arguments of [`heat_map`]; returns the pixel count with the legend.
fn check_inputs(values: &[f32], width: usize, height: usize, max: f32) -> Result<usize> {
    let dims_err = |reason: &str| Error::InvalidDims {
        dims: [width, height, 1].map(|d| i64::try_from(d).unwrap_or(i64::MAX)),
        reason: reason.into(),
    };
    if width == 0 || height == 0 {
        return Err(dims_err("a heat map needs a width and height > 0"));
    }
    let total = height
        .checked_add(LEGEND_HEIGHT)
        .and_then(|h| h.checked_mul(width))
        .ok_or_else(|| dims_err("the heat map's pixel count overflows"))?;
    // Cannot overflow: smaller than `total`.
    let expected = width * height;
    if values.len() != expected {
        return Err(Error::SizeMismatch {
            expected: expected as u64,
            actual: values.len() as u64,
        });
    }
    if !(max.is_finite() && max > 0.0) {
        return Err(Error::InvalidHeatMap(format!(
            "the scale maximum {max} must be finite and > 0"
        )));
    }
    Ok(total)
}

/// An opaque pixel of colour `c`.
fn opaque(c: [f32; 3]) -> [f32; 4] {
    [c[0], c[1], c[2], 1.0]
}

/// Draws the colour bar, the "over" block and the labels below row `top` (the legend area,
/// already black).
fn draw_legend(img: &mut Image, top: usize, max: f32) {
    let width = img.width();
    let over = if width >= 2 * OVER_WIDTH {
        OVER_WIDTH
    } else {
        0
    };
    let bar = width - over;
    for x in 0..width {
        let color = if x < bar {
            let t = x as f32 / (bar.max(2) - 1) as f32;
            heat_color(t * max, max)
        } else {
            OVER_COLOR
        };
        for y in top + BAR_TOP..top + BAR_TOP + BAR_HEIGHT {
            put(img, x, y, opaque(color));
        }
    }
    let text_y = top + BAR_TOP + BAR_HEIGHT + GAP;
    draw_labels(img, text_y, bar, over > 0, &short_number(max));
}

/// Draws `0` at the left, the maximum right-aligned at the end of the bar (left of `over`
/// when the "over" block is shown), and `over` at the right; labels that would overlap are
/// left out.
fn draw_labels(img: &mut Image, y: usize, bar: usize, with_over: bool, max_label: &str) {
    let width = img.width();
    let zero_end = text_width("0");
    draw_text(img, 0, y, "0");
    let mut right = width;
    if with_over && text_width("over") + zero_end + SCALE <= width {
        right = width - text_width("over");
        draw_text(img, right, y, "over");
        right = right.saturating_sub(ADVANCE);
    }
    let end = right.min(bar);
    let w = text_width(max_label);
    if end >= w && end - w >= zero_end + ADVANCE {
        draw_text(img, end - w, y, max_label);
    }
}

/// Width in pixels of `text` in the scaled pixel font.
fn text_width(text: &str) -> usize {
    (text.chars().count() * ADVANCE).saturating_sub(SCALE)
}

/// Draws `text` in white with its top-left corner at (`x`, `y`), clipped to the image.
fn draw_text(img: &mut Image, x: usize, y: usize, text: &str) {
    for (i, ch) in text.chars().enumerate() {
        let rows = glyph(ch);
        for (gy, row) in rows.iter().enumerate() {
            for gx in 0..GLYPH_COLS {
                if row >> (GLYPH_COLS - 1 - gx) & 1 == 1 {
                    let px = x + i * ADVANCE + gx * SCALE;
                    fill(img, px, y + gy * SCALE, SCALE, [1.0; 4]);
                }
            }
        }
    }
}

/// Fills a `size` x `size` square at (`x`, `y`), clipped to the image.
fn fill(img: &mut Image, x: usize, y: usize, size: usize, color: [f32; 4]) {
    for dy in 0..size {
        for dx in 0..size {
            put(img, x + dx, y + dy, color);
        }
    }
}

/// Sets pixel (`x`, `y`) when it lies inside the image.
fn put(img: &mut Image, x: usize, y: usize, color: [f32; 4]) {
    let (w, h) = (img.width(), img.height());
    if x < w && y < h {
        img.pixels_mut()[y * w + x] = color;
    }
}

/// The 3x5 glyph of `ch`, one row per entry, most significant of the 3 bits at the left;
/// characters outside the font are blank.
fn glyph(ch: char) -> [u8; GLYPH_ROWS] {
    match ch {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b001, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        'e' => [0b000, 0b011, 0b111, 0b100, 0b011],
        'o' => [0b000, 0b111, 0b101, 0b101, 0b111],
        'v' => [0b000, 0b101, 0b101, 0b101, 0b010],
        'r' => [0b000, 0b011, 0b100, 0b100, 0b100],
        _ => [0; GLYPH_ROWS],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgb(p: [f32; 4]) -> [f32; 3] {
        [p[0], p[1], p[2]]
    }

    fn start() -> [f32; 3] {
        colormap_at(&INFERNO, 0.0).map(|c| c as f32)
    }

    fn end() -> [f32; 3] {
        colormap_at(&INFERNO, 1.0).map(|c| c as f32)
    }

    #[test]
    fn values_map_onto_the_scale() {
        let values = [0.0, 0.05, 0.07, f32::NAN, -1.0, f32::INFINITY];
        let img = heat_map(&values, 3, 2, 0.05).unwrap();
        assert_eq!(rgb(img.get(0, 0)), start());
        assert_eq!(rgb(img.get(1, 0)), end());
        assert_eq!(rgb(img.get(2, 0)), OVER_COLOR);
        assert_eq!(rgb(img.get(0, 1)), [srgb_to_linear(0.5); 3]);
        assert_eq!(rgb(img.get(1, 1)), start());
        assert_eq!(rgb(img.get(2, 1)), OVER_COLOR);
        assert!(img.pixels().iter().all(|p| p[3] == 1.0));
        // Start is near black, end is bright yellow.
        assert!(start().iter().all(|&c| c < 0.01));
        let e = end();
        assert!(e[0] > 0.9 && e[1] > 0.9 && e[2] < 0.5, "{e:?}");
    }

    #[test]
    fn legend_is_appended_below() {
        let (w, h) = (64, 10);
        let img = heat_map(&vec![0.5; w * h], w, h, 1.0).unwrap();
        assert_eq!((img.width(), img.height()), (w, h + LEGEND_HEIGHT));
        let bar_y = h + BAR_TOP + BAR_HEIGHT / 2;
        assert_eq!(rgb(img.get(0, bar_y)), start());
        assert_eq!(rgb(img.get(w - OVER_WIDTH - 1, bar_y)), end());
        assert_eq!(rgb(img.get(w - 1, bar_y)), OVER_COLOR);
        assert_eq!(rgb(img.get(w - OVER_WIDTH, bar_y)), OVER_COLOR);
        // The gap above the bar is black, and the label row holds some white pixels.
        assert_eq!(img.get(5, h), [0.0, 0.0, 0.0, 1.0]);
        let text_y = h + BAR_TOP + BAR_HEIGHT + GAP;
        let white = |x0: usize, x1: usize| {
            (x0..x1).any(|x| (text_y..text_y + 10).any(|y| img.get(x, y) == [1.0; 4]))
        };
        assert!(white(0, 6), "0 label");
        assert!(white(w - text_width("over"), w), "over label");
        assert!(white(20, w - text_width("over") - 2), "max label");
    }

    #[test]
    fn narrow_images_clip_the_legend() {
        for w in 1..20 {
            let img = heat_map(&vec![1.0; w], w, 1, 2.0).unwrap();
            assert_eq!(img.height(), 1 + LEGEND_HEIGHT);
        }
    }

    #[test]
    fn bad_sizes_and_scales_error() {
        assert!(matches!(
            heat_map(&[], 0, 3, 1.0),
            Err(Error::InvalidDims { .. })
        ));
        assert!(matches!(
            heat_map(&[], 3, 0, 1.0),
            Err(Error::InvalidDims { .. })
        ));
        assert!(matches!(
            heat_map(&[0.0; 5], 2, 2, 1.0),
            Err(Error::SizeMismatch {
                expected: 4,
                actual: 5
            })
        ));
        assert!(heat_map(&[0.0], usize::MAX, 2, 1.0).is_err());
        for max in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                heat_map(&[0.0], 1, 1, max),
                Err(Error::InvalidHeatMap(_))
            ));
        }
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(short_number(0.05), "0.05");
        assert_eq!(short_number(0.01), "0.01");
        assert_eq!(short_number(0.001), "1e-3");
        assert_eq!(short_number(0.000_123_4), "1.23e-4");
        assert_eq!(short_number(250.0), "250");
        assert_eq!(short_number(1000.0), "1000");
        assert_eq!(short_number(2_500_000.0), "2.5e6");
        assert_eq!(short_number(1.0), "1");
    }

    #[test]
    fn legend_text_names_the_scale() {
        assert_eq!(
            heat_map_legend_text(0.01),
            "colour scale: black 0 to yellow 0.01, magenta above (grey: NaN)"
        );
    }

    #[test]
    fn font_covers_the_labels() {
        for ch in "0123456789.-eover".chars() {
            assert!(glyph(ch).iter().any(|&r| r != 0), "{ch}");
        }
        assert_eq!(glyph('x'), [0; GLYPH_ROWS]);
        assert_eq!(text_width("0"), 6);
        assert_eq!(text_width("over"), 30);
    }
}
