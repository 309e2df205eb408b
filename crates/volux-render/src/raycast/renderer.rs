//! The grid ray caster with its per-volume caches.
use std::ops::Deref;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use volux_core::grid::Scalar;
use volux_core::Grid;

use super::cell_blocks::{BlockedTrilinear, CellBlocks};
use super::context::{Classification, Derived};
use super::options::{Placement, RenderOptions, Rendered};
use super::traverse::render_with;
use crate::data_colour::DataColour;
use crate::error::RenderError;
use crate::frame::{Frame, MethodStats, Rebuilt};
use crate::integrate::integrator::Integrator;
use crate::integrate::preintegrated::PreintegrationTable;
use crate::macrocell::MacrocellGrid;
use crate::renderer::{frame, wrong_method, Renderer};
use crate::sampling::{Reconstruction, Tricubic, Trilinear};
use crate::scene::{GridRaycast, Method, Scene};
use crate::shading::gradient::GradientVolume;
use crate::tiles::Control;

/// Renders a grid with the integrator of `opts` (no caching: see [`GridRenderer`]).
pub fn render_grid(grid: &Grid, opts: &RenderOptions) -> Result<Rendered, RenderError> {
    GridRenderer::new(grid).render_with(opts)
}

/// A grid ray caster that keeps what it derives between renders, keyed on what it was
/// derived from: the macrocell min/max grid, the gradient volume and the bricked copy of the
/// samples that the trilinear paths read (data, built once), the
/// classification table with the macrocells' empty flags and the pre-integration table
/// (rebuilt when the TF, the isovalues or the step change). An interactive session pays for
/// each once.
///
/// Both data structures are optional, and checked against the memory budget
/// ([`GridRenderer::with_memory_budget`], by default the process's) before they are built:
/// over it, gradients are taken on the fly and empty space is not skipped, and the image is
/// the same.
pub struct GridRenderer<G: Deref<Target = Grid> = Arc<Grid>> {
    grid: G,
    macrocells: OnceLock<Option<MacrocellGrid>>,
    classification: Mutex<Option<Arc<Classification>>>,
    preintegration: Mutex<Option<Arc<PreintegrationTable>>>,
    gradients: OnceLock<Option<GradientVolume>>,
    /// The grid's own colour, for RGB grids.
    data_colour: OnceLock<Option<Arc<DataColour>>>,
    /// The bricked samples.
    blocks: OnceLock<Option<CellBlocks>>,
    /// Bytes the derived structures may take each.
    memory_budget: u64,
    /// Whether tiles may take the lane paths; tests turn it off to compare them with the
    /// ray-by-ray paths, which compute the same sums.
    pub(super) lanes: bool,
}

impl<G: Deref<Target = Grid>> GridRenderer<G> {
    /// A renderer for `grid` (borrowed, `&Grid`, or shared, `Arc<Grid>`).
    pub fn new(grid: G) -> Self {
        Self {
            grid,
            macrocells: OnceLock::new(),
            classification: Mutex::new(None),
            preintegration: Mutex::new(None),
            gradients: OnceLock::new(),
            data_colour: OnceLock::new(),
            blocks: OnceLock::new(),
            memory_budget: volux_core::limits::memory_budget(),
            lanes: true,
        }
    }

    /// This renderer with a memory budget of `bytes` for each structure it derives (the
    /// gradient volume, the macrocells) instead of the process's.
    pub fn with_memory_budget(mut self, bytes: u64) -> Self {
        self.memory_budget = bytes;
        self
    }

    /// The macrocell min/max grid, built on first use (`None` if it does not fit in the
    /// memory budget: empty space is then not skipped).
    pub fn macrocells(&self) -> Option<&MacrocellGrid> {
        self.macrocells
            .get_or_init(|| {
                let dims = self.grid.dims();
                MacrocellGrid::check_within(self.memory_budget, dims).ok()?;
                Some(volux_core::with_samples!(self.grid.samples(), |s| {
                    MacrocellGrid::build(s, dims)
                }))
            })
            .as_ref()
    }

    /// The pre-integration table for `opts` (`None` for the other integrators), rebuilt only
    /// when the TF or the step changed; and whether it was rebuilt.
    pub fn preintegration(
        &self,
        opts: &RenderOptions,
    ) -> Result<(Option<Arc<PreintegrationTable>>, bool), RenderError> {
        let Integrator::Preintegrated { step } = opts.integrator else {
            return Ok((None, false));
        };
        let d = step * self.grid.spacing().min_element();
        let range = self.grid.range();
        let mut cache = self
            .preintegration
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if let Some(t) = cache
            .as_ref()
            .filter(|t| t.is_valid_for(&opts.tf, range, d))
        {
            return Ok((Some(t.clone()), false));
        }
        let table = Arc::new(PreintegrationTable::new(&opts.tf, range, d)?);
        *cache = Some(table.clone());
        Ok((Some(table), true))
    }

    /// The precomputed gradient volume, built on the first shaded render (`None` if it does
    /// not fit in the memory budget: gradients are then computed on the fly).
    pub fn gradients(&self) -> Option<&GradientVolume> {
        self.gradients
            .get_or_init(|| {
                let g = &*self.grid;
                volux_core::with_samples!(g.samples(), |s| GradientVolume::build_within(
                    self.memory_budget,
                    &Trilinear::new(s, g.dims()),
                    g.spacing().as_vec3(),
                    0
                )
                .ok())
            })
            .as_ref()
    }

    /// The grid's own colour when it is an RGB grid ([`crate::data_colour`]).
    pub fn data_colour(&self) -> Option<&Arc<DataColour>> {
        self.data_colour
            .get_or_init(|| DataColour::of(&self.grid).map(Arc::new))
            .as_ref()
    }

    /// The bricked copy of the samples `s` (the grid's), built on first use (`None` if it
    /// does not fit in the memory budget: the row-major samples are read, with the same
    /// values).
    fn blocks<T: Scalar>(&self, s: &[T]) -> Option<&CellBlocks> {
        self.blocks
            .get_or_init(|| {
                CellBlocks::build(s, self.grid.dims(), brick_budget(s, self.memory_budget))
            })
            .as_ref()
    }

    /// Renders the samples `s` (the grid's) with trilinear reconstruction, through their
    /// bricked copy when there is one.
    fn render_trilinear<T: Scalar>(
        &self,
        s: &[T],
        place: Placement,
        range: [f64; 2],
        opts: &RenderOptions,
        derived: Derived<'_>,
    ) -> Result<Rendered, RenderError> {
        let linear = Trilinear::new(s, self.grid.dims());
        match self.blocks(s) {
            Some(blocks) => render_with(
                &BlockedTrilinear { blocks, linear },
                place,
                range,
                opts,
                derived,
            ),
            None => render_with(&linear, place, range, opts, derived),
        }
    }

    /// The classification for `opts`, rebuilt only when the TF or the isovalues changed
    /// (`cells`: with the empty flags of these macrocells); and whether it was rebuilt.
    fn classification(
        &self,
        opts: &RenderOptions,
        cells: Option<&MacrocellGrid>,
    ) -> (Arc<Classification>, bool) {
        let range = self.grid.range();
        let mut cache = self
            .classification
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if let Some(c) = cache.as_ref().filter(|c| c.is_for(opts, range, cells)) {
            return (c.clone(), false);
        }
        let c = Arc::new(Classification::new(opts, range, cells));
        *cache = Some(c.clone());
        (c, true)
    }

    /// Renders with `opts`.
    pub fn render_with(&self, opts: &RenderOptions) -> Result<Rendered, RenderError> {
        opts.validate()?;
        let g = &*self.grid;
        let cubic = matches!(
            opts.reconstruction,
            Reconstruction::CatmullRom | Reconstruction::BSpline
        );
        let built_data = (!cubic && self.blocks.get().is_none())
            || (opts.empty_space_skipping && self.macrocells.get().is_none())
            || (opts.shading.is_some() && self.gradients.get().is_none());
        let cells = opts
            .empty_space_skipping
            .then(|| self.macrocells())
            .flatten();
        let (classification, classified) = self.classification(opts, cells);
        let (pre, pre_built) = self.preintegration(opts)?;
        let gradients = opts.shading.as_ref().and_then(|_| self.gradients());
        let derived = Derived {
            macrocells: cells,
            classification: Some(&classification),
            intervals: None,
            preintegration: pre.as_deref(),
            gradients,
            lanes: self.lanes,
        };
        let (place, range) = (Placement::of(g), g.range());
        let mut out = match opts.reconstruction {
            Reconstruction::CatmullRom | Reconstruction::BSpline => {
                // Cubic filters reach one voxel further than a macrocell's samples (and
                // Catmull-Rom overshoots), so empty-space skipping is off for them.
                let derived = Derived {
                    macrocells: None,
                    ..derived
                };
                let bspline = opts.reconstruction == Reconstruction::BSpline;
                volux_core::with_samples!(g.samples(), |s| render_with(
                    &Tricubic::new(s, g.dims(), bspline),
                    place,
                    range,
                    opts,
                    derived
                ))
            }
            _ => volux_core::with_samples!(g.samples(), |s| self
                .render_trilinear(s, place, range, opts, derived)),
        }?;
        out.stats.rebuilt = Rebuilt {
            data: built_data,
            classification: classified || pre_built,
            view: true,
        };
        Ok(out)
    }
}

impl<G: Deref<Target = Grid> + Send> Renderer for GridRenderer<G> {
    fn name(&self) -> &'static str {
        "raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let settings = grid_settings(scene)?;
        let mut opts = RenderOptions::from_scene(scene, &settings, control);
        if scene.appearance.data_colour && !scene.appearance.mip {
            opts.data_colour = self.data_colour().cloned();
        }
        let r = self.render_with(&opts)?;
        Ok(grid_frame(r, &settings, started))
    }
}

/// The grid ray casting settings of `scene` (its method resolved for a grid), the scene
/// checked: what every grid renderer (in core and bricked) starts a frame with.
pub(crate) fn grid_settings(scene: &Scene) -> Result<GridRaycast, RenderError> {
    let settings = match scene.method {
        Method::Auto => GridRaycast::default(),
        Method::GridRaycast(s) => s,
        other => return Err(wrong_method("raycast", &other)),
    };
    scene.validate()?;
    Ok(settings)
}

/// The frame of a grid render: the error map where the integrator estimates it.
pub(crate) fn grid_frame(r: Rendered, settings: &GridRaycast, started: Instant) -> Frame {
    let estimates = matches!(settings.integrator, Integrator::AdaptiveSimpson(_));
    let rebuilt = r.stats.rebuilt;
    frame(
        r.image,
        estimates.then_some(r.error_map),
        started,
        rebuilt,
        MethodStats::GridRaycast(r.stats),
    )
}

/// A bricked copy of any size takes at most this many bytes.
const BRICKS_ANY_GRID: u64 = 256 << 20;

/// The bytes the bricked copy of the samples `s` may take: within `budget`, and at most twice
/// the samples' own bytes (an f32 grid's copy takes 1.42x) or [`BRICKS_ANY_GRID`]. The copy
/// stores f32, 2.8x an `i16` grid and 5.7x a `u8` one, and it measured at most 1.2x faster
/// on such grids (the heads of `../shared/bench/`), which fit the cache anyway: a large 8- or
/// 16-bit volume is read row-major rather than taking several times its size again.
fn brick_budget<T: Scalar>(s: &[T], budget: u64) -> u64 {
    let own = std::mem::size_of_val(s) as u64;
    budget.min(own.saturating_mul(2).max(BRICKS_ANY_GRID))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_blocks_of_large_narrow_grids_are_not_built() {
        let gib = 1u64 << 30;
        // Small grids: up to the fixed allowance, whatever their type.
        assert_eq!(brick_budget(&[0u8; 1000], 8 * gib), BRICKS_ANY_GRID);
        // A large u8 grid (its copy would be 5.7x) gets twice its bytes: too little.
        let big = vec![0u8; 300 << 20];
        assert_eq!(brick_budget(&big, 8 * gib), 600 << 20);
        assert!(CellBlocks::bytes_for([1024, 1024, 300]) > 600 << 20);
        // The memory budget bounds it in any case.
        assert_eq!(brick_budget(&big, 100 << 20), 100 << 20);
    }
}
