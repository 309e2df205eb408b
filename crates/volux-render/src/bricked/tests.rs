//! Bricked rendering against in-core rendering of the same data: every integrator, odd sizes
//! not divisible by the chunk, anisotropic spacing, budgets of a few bricks that force
//! evictions within a frame, a brick face crossed at a grazing angle, and chunks that cannot
//! be read.
use std::sync::Arc;

use volux_core::bricked::{ChunkLayout, ChunkSource, GridChunks, Multiscale};
use volux_core::grid::{Buffer, Samples};
use volux_core::{CameraSpec, Grid, TransferFunction};

use super::fixtures::{grid, tf, CHUNK, DIMS};
use super::*;
use crate::integrate::{AdaptiveParams, Integrator, StepControl};
use crate::isosurface::{Isosurfaces, Isovalue};
use crate::raycast::cell_blocks::CellBlocks;
use crate::raycast::{render_field, render_grid, Placement, RenderOptions};
use crate::sampling::Trilinear;
use crate::shading::BlinnPhong;

fn volume(g: &Grid, budget: u64) -> BrickedVolume {
    let chunks = GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap();
    let ms = Multiscale::new("test", vec![Arc::new(chunks) as Arc<dyn ChunkSource>]).unwrap();
    BrickedVolume::open(ms, budget).unwrap()
}

/// `g` as level 0 and, as level 1, a grid of every other sample's place at twice the spacing
/// holding `value(i)` at sample `i`.
fn pyramid(g: &Grid, value: impl Fn(usize) -> f32) -> Vec<Arc<dyn ChunkSource>> {
    let full = GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap();
    let coarse_dims = DIMS.map(|d| d.div_ceil(2));
    let n: usize = coarse_dims.iter().product();
    let coarse = Grid::new(
        coarse_dims,
        [1.6, 2.2, 3.4],
        [-3.0, 2.0, 5.0],
        Samples::F32(Buffer::owned((0..n).map(value).collect())),
    )
    .unwrap();
    let coarse = GridChunks::new(Arc::new(coarse), CHUNK).unwrap();
    vec![Arc::new(full), Arc::new(coarse)]
}

fn options(g: &Grid, spec: &str) -> RenderOptions {
    let cam = CameraSpec::from_json(spec)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap();
    let mut o = RenderOptions::new(cam, tf());
    (o.width, o.height) = (40, 36);
    o
}

/// The largest difference of any channel of any pixel.
fn max_diff(a: &volux_core::Image, b: &volux_core::Image) -> f32 {
    let mut d = 0.0f32;
    for y in 0..a.height() {
        for x in 0..a.width() {
            for c in 0..4 {
                d = d.max((a.get(x, y)[c] - b.get(x, y)[c]).abs());
            }
        }
    }
    d
}

fn integrators() -> Vec<Integrator> {
    let adaptive = AdaptiveParams {
        tol: 1e-3,
        h0: 0.3,
        hmin: 0.02,
        hmax: 1.0,
        control: StepControl::Coupled,
        early_termination: None,
    };
    vec![
        Integrator::Riemann { step: 0.4 },
        Integrator::Trapezoid { step: 0.4 },
        Integrator::Simpson { step: 0.5 },
        Integrator::Preintegrated { step: 0.4 },
        Integrator::AdaptiveSimpson(adaptive),
        Integrator::AdaptiveSimpson(AdaptiveParams {
            control: StepControl::Decoupled,
            ..adaptive
        }),
        Integrator::Reference,
    ]
}

#[test]
fn every_integrator_equals_the_in_core_render_with_evictions_within_the_frame() {
    let g = grid();
    let Samples::F32(values) = g.samples() else {
        unreachable!()
    };
    let incore = Trilinear::new(values.as_slice(), DIMS);
    // Three bricks of 8x5x4 f32 (each one cell block of 9³): every frame evicts.
    let brick = 9 * 9 * 9 * 4;
    let small = volume(&g, 3 * brick);
    let roomy = volume(&g, 1 << 30);
    let mut cases: Vec<RenderOptions> = Vec::new();
    for integrator in integrators() {
        let mut o = options(&g, r#"{"azimuth": 33, "elevation": 21}"#);
        o.integrator = integrator;
        cases.push(o);
    }
    let mut mip = options(&g, r#"{"azimuth": -50, "elevation": 10}"#);
    mip.mip = true;
    cases.push(mip);
    let mut iso = options(&g, r#"{"azimuth": 120, "elevation": -30}"#);
    iso.isosurfaces = Isosurfaces::new(vec![Isovalue {
        value: 80.0,
        rgba: [1.0, 0.9, 0.7, 0.8],
    }])
    .unwrap();
    iso.iso_lighting = Some(BlinnPhong::default());
    cases.push(iso);
    let mut shaded = options(&g, r#"{"azimuth": 200, "elevation": 40}"#);
    shaded.shading = Some(BlinnPhong::default());
    cases.push(shaded);
    for o in &cases {
        let want = render_field(&incore, Placement::of(&g), g.range(), o).unwrap();
        for v in [&small, &roomy] {
            let got = render_level(v, 0, o).unwrap();
            let d = max_diff(&got.image, &want.image);
            assert!(
                d <= 1e-6,
                "{:?} mip {}: max difference {d}",
                o.integrator,
                o.mip
            );
        }
    }
    let stats = small.cache_stats(0).unwrap();
    assert!(stats.evictions > 0, "the small budget evicts: {stats:?}");
    assert!(stats.peak_bytes <= 3 * brick, "{stats:?}");
    assert_eq!(roomy.cache_stats(0).unwrap().evictions, 0);
    // The grid renderer (empty-space skipping, lanes) draws the same emission-only image.
    let o = &cases[0];
    let grid_image = render_grid(&g, o).unwrap().image;
    assert!(max_diff(&render_level(&roomy, 0, o).unwrap().image, &grid_image) <= 1e-6);
}

#[test]
fn a_ray_grazing_a_brick_face_samples_both_sides_exactly() {
    let g = grid();
    let Samples::F32(values) = g.samples() else {
        unreachable!()
    };
    let incore = Trilinear::new(values.as_slice(), DIMS);
    let v = volume(&g, 1 << 30);
    // The eye on the chunk face x = 8 (world -3 + 8 * 0.8), or a hair beside it, looking
    // along y: the middle column's rays run in (or along) the face, and every sample of
    // theirs gathers corners from both sides of it.
    for dx in [0.0, 1e-4, -1e-4] {
        let x = -3.0 + 8.0 * 0.8 + dx;
        let spec =
            format!(r#"{{"eye": [{x}, -40, 12], "target": [{x}, 10, 12.3], "up": [0, 0, 1]}}"#);
        let o = options(&g, &spec);
        let want = render_field(&incore, Placement::of(&g), g.range(), &o).unwrap();
        let got = render_level(&v, 0, &o).unwrap();
        let d = max_diff(&got.image, &want.image);
        assert!(d <= 1e-6, "dx {dx}: max difference {d}");
        assert!(want.stats.samples > 1000);
    }
}

/// A level whose chunk `bad` cannot be read (a corrupt or truncated chunk of a store) after
/// `reads_ok` good reads of it.
struct Broken {
    inner: GridChunks,
    bad: [usize; 3],
    reads_ok: std::sync::atomic::AtomicUsize,
}

impl ChunkSource for Broken {
    fn layout(&self) -> &ChunkLayout {
        self.inner.layout()
    }
    fn read_chunk(&self, c: [usize; 3]) -> volux_core::Result<Samples> {
        use std::sync::atomic::Ordering::Relaxed;
        let spent = |n: usize| n.checked_sub(1);
        if c == self.bad && self.reads_ok.fetch_update(Relaxed, Relaxed, spent).is_err() {
            return Err(volux_core::Error::Chunked(
                "truncated chunk (12 of 640 bytes)".into(),
            ));
        }
        self.inner.read_chunk(c)
    }
}

#[test]
fn a_chunk_that_cannot_be_read_is_one_error_naming_it_and_no_image() {
    let g = grid();
    let inner = GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap();
    let broken = Broken {
        inner,
        bad: [1, 1, 1],
        reads_ok: 0.into(),
    };
    let ms = Multiscale::new("broken", vec![Arc::new(broken) as Arc<dyn ChunkSource>]).unwrap();
    let o = options(&g, r#"{"azimuth": 10}"#);
    // Opening reads every chunk for the range: it fails, naming the chunk.
    let e = BrickedVolume::open(ms, 1 << 30).unwrap_err().to_string();
    assert!(e.contains("truncated chunk"), "{e}");
    // With the range known, the render reaches the chunk and stops with its name.
    let inner = GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap();
    let ranged = Ranged(
        // Read well once (the histogram's read), then truncated (the render's).
        Broken {
            inner,
            bad: [1, 1, 1],
            reads_ok: 1.into(),
        },
        g.range(),
    );
    let ms = Multiscale::new("broken", vec![Arc::new(ranged) as Arc<dyn ChunkSource>]).unwrap();
    let broken = BrickedVolume::open(ms, 1 << 30).unwrap();
    let e = render_level(&broken, 0, &o).unwrap_err().to_string();
    assert!(
        e.contains("chunk [1, 1, 1]") && e.contains("truncated"),
        "{e}"
    );
    // Levels that do not exist and voxel layers are refused with the reason.
    assert!(render_level(&volume(&g, 1 << 20), 3, &o).is_err());
    let mut masked = o.clone();
    masked.mask = Some(Arc::new(volux_core::sculpt::SculptMask::new(DIMS).unwrap()));
    let e = render_level(&volume(&g, 1 << 20), 0, &masked)
        .unwrap_err()
        .to_string();
    assert!(e.contains("sculpt mask"), "{e}");
}

/// A level that knows its range (as stores written by `volux convert` do).
struct Ranged(Broken, [f64; 2]);

impl ChunkSource for Ranged {
    fn layout(&self) -> &ChunkLayout {
        self.0.layout()
    }
    fn read_chunk(&self, c: [usize; 3]) -> volux_core::Result<Samples> {
        self.0.read_chunk(c)
    }
    fn value_range(&self) -> Option<[f64; 2]> {
        Some(self.1)
    }
}

#[test]
fn the_automatic_level_follows_the_pixel_size() {
    let g = grid();
    // A coarser level: every other sample, twice the spacing (its values do not matter here).
    let levels = pyramid(&g, |_| 50.0);
    let v = BrickedVolume::open(Multiscale::new("pyramid", levels).unwrap(), 1 << 30).unwrap();
    let v = Arc::new(v);
    let scene = |zoom: f64, size: usize| {
        let spec = CameraSpec {
            zoom: Some(zoom),
            ..Default::default()
        };
        let cam = spec.resolve(&g.bounds()).unwrap();
        crate::scene::Scene::new(cam, size, size, tf())
    };
    let auto = BrickedRenderer::new(v.clone(), Lod::Auto);
    // A small image of the whole volume: pixels are larger than the coarse voxels.
    assert_eq!(auto.level_for(&scene(1.0, 8)), 1);
    // A large, close view: pixels smaller than the full-resolution voxels.
    assert_eq!(auto.level_for(&scene(4.0, 2000)), 0);
    assert_eq!(
        BrickedRenderer::new(v.clone(), Lod::Level(7)).level_for(&scene(1.0, 8)),
        1
    );
    assert_eq!(
        BrickedRenderer::new(v, Lod::Level(0)).level_for(&scene(1.0, 8)),
        0
    );
}

#[test]
fn the_engine_renders_a_bricked_volume_as_the_grid_it_holds() {
    use crate::engine::render_once;
    use crate::scene::{Scene, Volume};
    let g = grid();
    let bricked = Volume::Bricked(Arc::new(volume(&g, 4 * 8 * 5 * 4 * 4)), Lod::Level(0));
    let incore = Volume::from(g.clone());
    assert_eq!(bricked.range(), incore.range());
    assert_eq!(bricked.bounds(), incore.bounds());
    // One level: the histogram is the grid's, so are the presets fitted on it.
    assert_eq!(
        bricked.preset_tf("auto").unwrap(),
        incore.preset_tf("auto").unwrap()
    );
    let cam = CameraSpec::from_json(r#"{"azimuth": 70, "elevation": 35}"#)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap();
    let scene = Scene::new(cam, 48, 40, tf());
    let control = crate::tiles::Control::default();
    let a = render_once(&bricked, &scene, &control).unwrap();
    let b = render_once(&incore, &scene, &control).unwrap();
    let d = max_diff(&a.image, &b.image);
    assert!(d <= 1e-6, "max difference {d}");
    assert!(bricked.to_tets().is_err());
}

#[test]
fn chunks_the_tf_makes_transparent_are_skipped_without_changing_a_pixel() {
    let g = grid();
    let Samples::F32(values) = g.samples() else {
        unreachable!()
    };
    let incore = Trilinear::new(values.as_slice(), DIMS);
    let v = volume(&g, 1 << 30);
    // Opaque only above 95: the chunks away from the sphere's centre are empty.
    let mut o = options(&g, r#"{"azimuth": 40, "elevation": 25}"#);
    o.tf = TransferFunction::from_json(
        r#"{"color": [[95,1,0.5,0.2],[120,1,1,1]], "extinction": [[95,0],[100,0.3],[120,0.6]]}"#,
    )
    .unwrap();
    let cells = v.chunk_cells(0).expect("the chunks' ranges are known");
    assert_eq!(cells.counts(), [3, 4, 4]);
    let table = crate::classify::ClassifyTable::new(&o.tf, v.range(), 4096);
    let empty = cells.empty_flags(&table, &[]);
    assert!(
        empty.iter().any(|e| *e) && !empty.iter().all(|e| *e),
        "{empty:?}"
    );
    for integrator in integrators() {
        o.integrator = integrator;
        let want = render_field(&incore, Placement::of(&g), g.range(), &o).unwrap();
        let got = render_level(&v, 0, &o).unwrap();
        let d = max_diff(&got.image, &want.image);
        assert!(d <= 1e-6, "{integrator:?}: max difference {d}");
        if matches!(
            integrator,
            Integrator::AdaptiveSimpson(_) | Integrator::Reference
        ) {
            continue; // not skipped (`render_level`), or no intervals taken
        }
        assert!(
            got.stats.samples < want.stats.samples,
            "{integrator:?}: {} samples skipping, {} without",
            got.stats.samples,
            want.stats.samples
        );
    }
}

#[test]
fn bricked_samples_equal_the_in_core_samples_bit_for_bit() {
    let g = grid();
    let Samples::F32(values) = g.samples() else {
        unreachable!()
    };
    let incore = Trilinear::new(values.as_slice(), DIMS);
    let failed = Arc::new(std::sync::atomic::AtomicBool::new(false));
    // Through the memo (a budget of three bricks), a table of the level (nothing resident
    // yet) and the level's whole copy (every brick resident).
    let small = volume(&g, 3 * 9 * 9 * 9 * 4);
    let memo = super::field::BrickedField::new(small.cache(0).unwrap(), 1 << 20, 1, failed.clone());
    let roomy = volume(&g, 1 << 30);
    let cache = roomy.cache(0).unwrap();
    let table = super::field::BrickedField::for_render(cache, failed.clone());
    let n = cache.layout().chunk_count();
    for i in 0..n {
        cache.get(cache.layout().chunk_coords(i)).unwrap();
    }
    let whole = super::field::BrickedField::for_render(cache, failed);
    assert_eq!(cache.stats().misses, n as u64, "each chunk read once");
    let fields = [(memo, "memo"), (table, "table"), (whole, "whole")];
    for (field, name) in &fields {
        assert_eq!(field.lookup_name(), *name);
        same_samples_as_in_core(field, &incore, name);
        field.forget();
    }
}

/// `field` samples as `incore` does, bit for bit, at 32,000 points over and a little beyond
/// the grid, on and off the chunk faces.
fn same_samples_as_in_core(
    field: &super::field::BrickedField,
    incore: &Trilinear<f32>,
    name: &str,
) {
    use crate::sampling::{Field, LANES};
    // Points over and a little beyond the grid, on and off the chunk faces.
    let mut state = 12345u64;
    let mut next = |hi: f32| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = (state >> 40) as f32 / (1u64 << 24) as f32;
        let x = -0.5 + u * (hi + 1.0);
        if state & 7 == 0 {
            x.round()
        } else {
            x
        }
    };
    for _ in 0..2000 {
        let p: [[f32; LANES]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|_| next(DIMS[a] as f32 - 1.0)));
        let got = field.sample_lanes(&p);
        let want = incore.sample_lanes(&p);
        for l in 0..LANES {
            let q = glam::Vec3::new(p[0][l], p[1][l], p[2][l]);
            assert_eq!(got[l].to_bits(), want[l].to_bits(), "{name}: lanes at {q}");
            assert_eq!(field.sample(q), incore.sample(q), "{name}: at {q}");
            assert_eq!(
                field.sample64(q.as_dvec3()),
                incore.sample64(q.as_dvec3()),
                "{name}: f64 at {q}"
            );
        }
        let p4: [[f32; 4]; 3] = std::array::from_fn(|a| std::array::from_fn(|l| p[a][l]));
        assert_eq!(
            field.sample4(&p4).map(f32::to_bits),
            incore.sample4(&p4).map(f32::to_bits),
            "{name}"
        );
    }
}

#[test]
fn the_levels_share_one_budget_and_the_coarse_bricks_go_first() {
    let g = grid();
    let levels = pyramid(&g, |i| (i % 97) as f32);
    // Room for the full level's 3 x 4 x 4 bricks of one cell block each, not for both.
    let brick = 9 * 9 * 9 * 4;
    let budget = 48 * brick;
    let v = BrickedVolume::open(Multiscale::new("pyramid", levels).unwrap(), budget).unwrap();
    let o = options(&g, r#"{"azimuth": 33, "elevation": 21}"#);
    // Twice: the warm coarse level becomes one copy (the pool's eviction handles both).
    render_level(&v, 1, &o).unwrap();
    render_level(&v, 1, &o).unwrap();
    let coarse = v.cache(1).unwrap();
    let coarse_bytes = coarse.resident_bytes();
    assert_eq!(coarse_bytes, CellBlocks::bytes_for(coarse.layout().dims));
    render_level(&v, 0, &o).unwrap();
    // The full level's bricks displaced the coarse ones: the pool stayed within the budget.
    assert!(
        v.resident_bytes() <= budget,
        "{} > {budget}",
        v.resident_bytes()
    );
    assert!(v.cache(1).unwrap().resident_bytes() < coarse_bytes);
    assert!(v.cache_stats(0).unwrap().peak_bytes <= budget);
}

#[test]
fn a_warm_level_becomes_one_copy_in_place_of_its_bricks() {
    let g = grid();
    let v = volume(&g, 1 << 30);
    let o = options(&g, r#"{"azimuth": 33, "elevation": 21}"#);
    let chunks = v.cache(0).unwrap().layout().chunk_count() as u64;
    // Cold: every chunk read once into a brick of its own.
    let cold = render_level(&v, 0, &o).unwrap();
    let reads = v.cache_stats(0).unwrap().misses;
    assert_eq!(reads, chunks);
    assert!(v.resident_bytes() >= chunks * 9 * 9 * 9 * 4);
    // Warm: the bricks give way to one copy of the level, read from them (no chunk read
    // again), and the frames are the same.
    for _ in 0..2 {
        let warm = render_level(&v, 0, &o).unwrap();
        assert_eq!(max_diff(&warm.image, &cold.image), 0.0);
        assert_eq!(v.resident_bytes(), CellBlocks::bytes_for(DIMS));
        assert_eq!(v.cache_stats(0).unwrap().misses, reads);
        assert!(v.cache(0).unwrap().is_resident([0, 0, 0]));
    }
}

#[test]
fn an_evicted_brick_no_reader_holds_is_filled_again_by_the_next_read() {
    let g = grid();
    let chunks = GridChunks::new(Arc::new(g.clone()), CHUNK).unwrap();
    let layout = chunks.layout().clone();
    // Room for one brick: each read evicts the previous one.
    let cache = super::cache::BrickCache::new(Arc::new(chunks), 9 * 9 * 9 * 4);
    let first = cache.get([0, 0, 0]).unwrap();
    let buffer = first.values.as_ptr();
    drop(first);
    // The second read evicts the first brick (no reader holds it: its buffer is kept), the
    // third takes that buffer and fills every sample of it.
    drop(cache.get([1, 0, 0]).unwrap());
    let third = cache.get([2, 1, 1]).unwrap();
    assert_eq!(third.values.as_ptr(), buffer, "the buffer was reused");
    let (lo, size) = layout.chunk_extent([2, 1, 1]);
    for k in lo[2]..lo[2] + size[2] {
        for j in lo[1]..lo[1] + size[1] {
            for i in lo[0]..lo[0] + size[0] {
                assert_eq!(third.at(i, j, k), g.value(i, j, k), "({i}, {j}, {k})");
            }
        }
    }
    // Beyond the chunk's samples (read by no cell of this chunk) the layout repeats the
    // last one, as a fresh brick does.
    let fresh = super::cache::BrickCache::new(
        Arc::new(GridChunks::new(Arc::new(g), CHUNK).unwrap()),
        1 << 20,
    );
    assert_eq!(fresh.get([2, 1, 1]).unwrap().values, third.values);
}

#[test]
fn a_chunk_is_read_once_however_many_readers_miss_it_at_once() {
    let g = grid();
    let source = Arc::new(GridChunks::new(Arc::new(g), CHUNK).unwrap());
    let cache = super::cache::BrickCache::new(source, 1 << 20);
    // Eight threads miss the same chunk together: one reads it, the others wait for it.
    let barrier = std::sync::Barrier::new(8);
    std::thread::scope(|s| {
        for _ in 0..8 {
            s.spawn(|| {
                barrier.wait();
                cache.get([1, 2, 1]).unwrap()
            });
        }
    });
    let stats = cache.stats();
    assert_eq!((stats.misses, stats.hits), (1, 7), "{stats:?}");
    // The prefetcher skips what is resident and reads the rest once.
    assert_eq!(cache.prefetch([1, 2, 1]), Ok(false));
    assert_eq!(cache.prefetch([0, 0, 0]), Ok(true));
    assert_eq!(cache.prefetch([0, 0, 0]), Ok(false));
    assert_eq!(cache.stats().misses, 2);
}

/// A budget of one brick thrashes between two chunks: each read after the first two is a
/// re-read after an eviction, which the figures say (the rays' hit rate would not).
#[test]
fn chunks_read_again_after_an_eviction_are_counted() {
    let g = grid();
    let source = Arc::new(GridChunks::new(Arc::new(g), CHUNK).unwrap());
    let cache = super::cache::BrickCache::new(source, 1);
    for c in [[0, 0, 0], [1, 0, 0], [0, 0, 0], [1, 0, 0], [1, 0, 0]] {
        cache.get(c).unwrap();
    }
    let stats = cache.stats();
    assert_eq!(
        (stats.misses, stats.rereads, stats.hits),
        (4, 2, 1),
        "{stats:?}"
    );
    assert!(stats.evictions >= 3, "{stats:?}");
}
