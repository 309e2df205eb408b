//! The one tile driver of every renderer (pbrt-v4's `ImageTileIntegrator::Render`): the
//! image cut into square tiles, rendered in parallel with rayon, cancelled and reported the
//! same way everywhere, and stitched into one row-major buffer.
//!
//! A renderer only says how to render one tile ([`render_tiles`]'s closure); the driver
//! owns the split, the parallel loop, the cancellation check before each tile, the progress
//! report after each, and the stitch. Each tile is computed independently of the others
//! (and of the number of threads), so images are deterministic.
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use rayon::prelude::*;

use crate::error::RenderError;

/// Side of the square tiles of the ray casters, in pixels: neighbouring rays read the same
/// voxels or cells, so a tile keeps them on one core.
pub const TILE: usize = 16;

/// Called with (rows done, total rows) as a render progresses.
pub type ProgressFn = Arc<dyn Fn(usize, usize) + Send + Sync>;

/// How a render runs, apart from what it renders: a cancellation flag another thread may
/// set, and a progress callback.
#[derive(Clone, Default)]
pub struct Control {
    /// Set to true from another thread to stop the render with [`RenderError::Cancelled`].
    pub cancel: Option<Arc<AtomicBool>>,
    /// Called with (rows done, total rows) after each tile.
    pub progress: Option<ProgressFn>,
}

impl std::fmt::Debug for Control {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field("cancel", &self.cancel)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

impl Control {
    /// A control with a cancellation flag.
    pub fn with_cancel(cancel: Arc<AtomicBool>) -> Self {
        Self {
            cancel: Some(cancel),
            progress: None,
        }
    }

    /// Whether the render was asked to stop.
    pub fn is_cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// `Err(Cancelled)` once the render was asked to stop.
    pub fn check(&self) -> Result<(), RenderError> {
        if self.is_cancelled() {
            Err(RenderError::Cancelled)
        } else {
            Ok(())
        }
    }

    /// Reports `done` of `total` rows.
    pub fn report(&self, done: usize, total: usize) {
        if let Some(p) = &self.progress {
            p(done, total);
        }
    }
}

/// A pixel rectangle `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

impl Rect {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.y1 - self.y0
    }

    /// Pixels in the rectangle.
    pub fn area(&self) -> usize {
        self.width() * self.height()
    }
}

/// An image cut into square tiles of `side` pixels, row-major.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Tile side in pixels.
    pub side: usize,
    /// Tiles per row.
    pub cols: usize,
    /// Tile rows.
    pub rows: usize,
}

impl TileGrid {
    /// Tiles of `side` pixels covering a `width x height` image.
    pub fn new(width: usize, height: usize, side: usize) -> Self {
        let side = side.max(1);
        Self {
            width,
            height,
            side,
            cols: width.div_ceil(side),
            rows: height.div_ceil(side),
        }
    }

    /// Number of tiles.
    pub fn count(&self) -> usize {
        self.cols * self.rows
    }

    /// The pixels of tile `i`.
    pub fn rect(&self, i: usize) -> Rect {
        let (tx, ty) = (i % self.cols, i / self.cols);
        Rect {
            x0: tx * self.side,
            y0: ty * self.side,
            x1: ((tx + 1) * self.side).min(self.width),
            y1: ((ty + 1) * self.side).min(self.height),
        }
    }

    /// The tiles `[tx0, ty0, tx1, ty1]` (inclusive) that pixel centres inside the screen
    /// box `[min, max]` can fall in; `None` when it covers no pixel centre.
    #[inline]
    pub fn range(&self, min: [f32; 2], max: [f32; 2]) -> Option<[usize; 4]> {
        // Pixel x has centre x + 0.5: columns with min <= x + 0.5 <= max.
        let lo = |v: f32| (v - 0.5).ceil().max(0.0);
        let hi = |v: f32, n: usize| (v - 0.5).floor().min(n as f32 - 1.0);
        let (x0, x1) = (lo(min[0]), hi(max[0], self.width));
        let (y0, y1) = (lo(min[1]), hi(max[1], self.height));
        if !(x0 <= x1 && y0 <= y1) {
            return None;
        }
        Some([
            x0 as usize / self.side,
            y0 as usize / self.side,
            x1 as usize / self.side,
            y1 as usize / self.side,
        ])
    }
}

/// A rendered image's pixels (row-major) and the tiles' own results, in tile order.
pub struct Tiled<P, S> {
    /// `width * height` pixels, row-major.
    pub pixels: Vec<P>,
    /// What each tile returned besides its pixels (counters), in tile order.
    pub per_tile: Vec<S>,
}

/// Checks that a `width x height` image fits in the memory budget before it is rendered: the
/// tiles' pixels and the assembled ones (`P` each), and the RGBA `f32` image made of them.
pub fn check_image_memory<P>(width: usize, height: usize) -> Result<(), RenderError> {
    let per_pixel = 2 * std::mem::size_of::<P>() as u64 + 16;
    let pixels = volux_core::limits::count_of(&[width, height]);
    volux_core::limits::check_alloc("the image", pixels, per_pixel)?;
    Ok(())
}

/// Renders the tiles of `grid` in parallel: `tile(i, rect)` returns the pixels of tile `i`
/// (row-major within `rect`) and a value of its own (e.g. counters). Checks `control` for
/// cancellation before each tile and reports progress after each; returns
/// [`RenderError::Cancelled`] if asked to stop.
pub fn render_tiles<P, S, F>(
    grid: &TileGrid,
    control: &Control,
    tile: F,
) -> Result<Tiled<P, S>, RenderError>
where
    P: Copy + Default + Send,
    S: Send,
    F: Fn(usize, Rect) -> (Vec<P>, S) + Sync,
{
    check_image_memory::<P>(grid.width, grid.height)?;
    let done = AtomicUsize::new(0);
    let total = grid.count();
    let results: Vec<(Vec<P>, S)> = (0..total)
        .into_par_iter()
        .map(|i| {
            control.check()?;
            let out = tile(i, grid.rect(i));
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            control.report(n * grid.height / total.max(1), grid.height);
            Ok(out)
        })
        .collect::<Result<_, RenderError>>()?;
    let mut pixels = vec![P::default(); grid.width * grid.height];
    let mut per_tile = Vec::with_capacity(total);
    for (i, (px, s)) in results.into_iter().enumerate() {
        let r = grid.rect(i);
        debug_assert_eq!(px.len(), r.area());
        for (row, y) in (r.y0..r.y1).enumerate() {
            let dst = y * grid.width;
            pixels[dst + r.x0..dst + r.x1]
                .copy_from_slice(&px[row * r.width()..(row + 1) * r.width()]);
        }
        per_tile.push(s);
    }
    Ok(Tiled { pixels, per_tile })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once_and_stitch_in_place() {
        for (w, h, side) in [(37, 19, 16), (16, 16, 16), (1, 1, 32), (100, 70, 32)] {
            let grid = TileGrid::new(w, h, side);
            let out = render_tiles(&grid, &Control::default(), |i, r| {
                let px = (r.y0..r.y1)
                    .flat_map(|y| (r.x0..r.x1).map(move |x| (x, y)))
                    .collect::<Vec<_>>();
                (px, i)
            })
            .unwrap();
            assert_eq!(out.per_tile, (0..grid.count()).collect::<Vec<_>>());
            for (k, p) in out.pixels.iter().enumerate() {
                assert_eq!(*p, (k % w, k / w), "{w}x{h} tiles of {side}");
            }
        }
    }

    #[test]
    fn a_cancelled_render_stops_and_progress_reaches_the_end() {
        let grid = TileGrid::new(64, 48, 16);
        let cancel = Arc::new(AtomicBool::new(true));
        let r = render_tiles(&grid, &Control::with_cancel(cancel), |_, r| {
            (vec![0u8; r.area()], ())
        });
        assert!(matches!(r, Err(RenderError::Cancelled)));
        let last = Arc::new(AtomicUsize::new(0));
        let seen = last.clone();
        let control = Control {
            cancel: None,
            progress: Some(Arc::new(move |done, total| {
                assert_eq!(total, 48);
                seen.fetch_max(done, Ordering::Relaxed);
            })),
        };
        render_tiles(&grid, &control, |_, r| (vec![0u8; r.area()], ())).unwrap();
        assert_eq!(last.load(Ordering::Relaxed), 48);
    }

    #[test]
    fn screen_boxes_map_to_tile_ranges() {
        let tiles = TileGrid::new(100, 70, 32);
        assert_eq!((tiles.cols, tiles.rows), (4, 3));
        assert_eq!(tiles.range([0.6, 0.6], [0.7, 0.7]), None);
        assert_eq!(tiles.range([-5.0, -5.0], [-1.0, 3.0]), None);
        assert_eq!(tiles.range([0.0, 0.0], [40.0, 1.0]), Some([0, 0, 1, 0]));
        assert_eq!(
            tiles.range([90.0, 60.0], [500.0, 500.0]),
            Some([2, 1, 3, 2])
        );
        assert_eq!(tiles.rect(3).x1, 100);
    }
}
