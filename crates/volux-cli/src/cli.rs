//! Command-line arguments.
use std::path::PathBuf;

pub use volux_app::Backend;

use clap::{ArgMatches, Args, FromArgMatches, Parser, Subcommand, ValueEnum};

/// Volux: accurate, fast volume visualization of regular grids and tetrahedral meshes.
#[derive(Debug, Parser)]
#[command(
    name = "volux",
    version,
    about,
    disable_help_subcommand = true,
    after_help = "Formats: `volux help tf` (transfer functions), `volux help camera`."
)]
pub struct Cli {
    /// Silence progress bars.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Memory the process may take for any one structure (grids, meshes, gradient volumes,
    /// acceleration structures, images): a size such as 4G, 512M or 1.5GiB, or a percentage
    /// of the available memory such as 50% [default: 75% of the available memory].
    #[arg(long, global = true, value_name = "SIZE", value_parser = crate::memory::parse_budget)]
    pub memory_budget: Option<u64>,
    /// The command.
    #[command(subcommand)]
    pub command: Command,
    /// The long names of the command's options given on the command line (filled after
    /// parsing), so that an option that would change nothing is refused rather than ignored.
    #[arg(skip)]
    pub given: Vec<String>,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe a file: format, dims or counts, spacing, type, value range, histogram, memory,
    /// mesh validation.
    Info {
        /// The file (or DICOM folder); none with --gpu.
        #[arg(required_unless_present = "gpu")]
        file: Option<PathBuf>,
        /// List the GPU adapters the GPU backend can render on, the one `--backend gpu`
        /// picks first (needs a build with the `gpu` feature).
        #[arg(long)]
        gpu: bool,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Convert between formats, chosen by OUT's extension: `.raw` (raw + JSON sidecar) or
    /// `.nrrd` for grids, `.vtet` (Volux binary tet mesh) for meshes and for grids split into
    /// tets, `.ome.zarr` (an OME-Zarr store, Zarr v3 + NGFF 0.5, zstd) for grids: written chunk
    /// by chunk with a pyramid of 2x averages (a memory-mapped raw or NRRD input larger than
    /// memory streams through).
    Convert {
        /// Input file.
        input: PathBuf,
        /// Output file (or `.ome.zarr` store folder).
        output: PathBuf,
        /// OME-Zarr output: samples per chunk side [default: 128].
        #[arg(long)]
        chunk: Option<usize>,
        /// OME-Zarr output: pyramid levels, a count or `auto` (halve until a level fits in
        /// one chunk) [default: auto].
        #[arg(long)]
        levels: Option<String>,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Generate a synthetic dataset: marschner-lobb, shepp-logan, sphere (grids, SIZE^3, or
    /// XxYxZ for a store), tets-smooth (about SIZE tets), torus (SIZE segments around the ring).
    Generate {
        /// What to generate.
        kind: Generator,
        /// Grid size per axis (or XxYxZ for an `.ome.zarr` store), tet count, or ring
        /// segments.
        #[arg(long, default_value = "128")]
        size: String,
        /// Output file (`.raw`, `.nrrd` or `.vtet`), or an `.ome.zarr` store for the grids,
        /// written chunk by chunk at any size (never the whole volume in memory).
        #[arg(long, short)]
        output: PathBuf,
        /// OME-Zarr output: samples per chunk side [default: 128].
        #[arg(long)]
        chunk: Option<usize>,
        /// OME-Zarr output: pyramid levels, a count or `auto` [default: auto].
        #[arg(long)]
        levels: Option<String>,
        /// OME-Zarr output: f32, or u16 (values in [0, 1] scaled to 0..65535) [default: f32].
        #[arg(long)]
        dtype: Option<String>,
    },
    /// Render a file to PNG.
    #[command(after_help = "JSON formats: `volux help tf`, `volux help camera`.")]
    Render(Box<RenderArgs>),
    /// Carve a grid (seed `004` sec. 4.4-4.5): erase discs and strokes through the whole
    /// depth and dig balls at the visible surface, in the order given, and write the sculpt
    /// mask as NRRD (u8: 1 kept, 0 removed; the grid's spacing, origin and direction).
    #[command(after_help = SCULPT_HELP)]
    Sculpt(Box<SculptArgs>),
    /// Measure on the visible surface (seed `004` sec. 6.2): pick points by pixel and print
    /// them (world coordinates) and the polyline's length in millimetres.
    #[command(after_help = PIXELS_HELP)]
    Measure(Box<MeasureArgs>),
    /// Label the visible voxels from seeds picked on the surface (seed `004` sec. 6.2): by
    /// default the voxels connected to each seed through visible voxels (`--rule
    /// connected`), or every visible voxel by its nearest seed (`--rule nearest`, world
    /// distance with the data's spacing); write the labels as NRRD (u8, 0: none).
    #[command(after_help = PIXELS_HELP)]
    Regions(Box<RegionsArgs>),
    /// Transfer functions: print a preset as JSON to start from.
    Tf {
        /// What to do.
        #[command(subcommand)]
        action: TfCommand,
    },
    /// Help on a command, or on a format: `tf` (transfer-function JSON), `camera` (camera
    /// JSON).
    Help {
        /// A command or a topic (tf, camera).
        topic: Option<String>,
    },
    /// Open the interactive viewer (volux-view) on a file, DICOM folder or session.
    View {
        /// What to open.
        path: Option<PathBuf>,
        /// Options passed on to volux-view (e.g. --screenshot OUT.png --size 800x600).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        rest: Vec<String>,
    },
    /// Render a built-in dataset (Marschner-Lobb, 128^3) to demo.png in the current folder.
    Demo {
        /// Output PNG.
        #[arg(long, short, default_value = "demo.png")]
        output: PathBuf,
    },
    /// Compare two PNG images: RMSE, largest and mean error per channel (in 0..1), and the
    /// percentage of pixels with a channel off by more than the threshold.
    Compare {
        /// First image.
        a: PathBuf,
        /// Second image.
        b: PathBuf,
        /// Per-channel error (0..1) above which a pixel counts as different.
        #[arg(long, default_value_t = 1.0 / 255.0)]
        threshold: f64,
        /// Write the largest channel difference of each pixel as a heat map PNG with a
        /// legend strip (black 0 to yellow at --diff-max, magenta above).
        #[arg(long)]
        diff: Option<PathBuf>,
        /// The difference at the top of the heat map's scale (0..1) [default: the largest
        /// difference in the images].
        #[arg(long)]
        diff_max: Option<f32>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Accuracy of Riemann sums and adaptive Simpson against the f64 reference (seed
    /// `001` tables B.1, B.2 and 5.5).
    Accuracy {
        /// The file (or DICOM folder); a generator name (marschner-lobb, shepp-logan,
        /// sphere) renders that synthetic volume at 64^3.
        file: PathBuf,
        /// Transfer function preset or JSON file.
        #[arg(long, default_value = "auto")]
        tf: String,
        /// Image size WxH.
        #[arg(long, default_value = "128x128")]
        size: String,
        /// Error threshold for the Riemann rows.
        #[arg(long, default_value_t = 0.01)]
        eps: f64,
        /// Largest step of the adaptive rows (voxels).
        #[arg(long, default_value_t = 0.5)]
        hmax: f64,
        /// Smallest step of the adaptive rows (voxels).
        #[arg(long, default_value_t = 0.001)]
        hmin: f64,
        /// Print a JSON list.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Speed: ms/frame and samples/s of the grid ray caster per integrator, tets/s of
    /// Projected Tetrahedra per colour mode, on synthetic and shared data.
    Bench {
        /// One frame per case and 512x512 only.
        #[arg(long)]
        quick: bool,
        /// Frames per case (the median is reported; `targets`: rounds, the fastest reported).
        #[arg(long, default_value_t = 3)]
        frames: usize,
        /// Synthetic volume size per axis.
        #[arg(long, default_value_t = 256)]
        grid_size: usize,
        /// Print a JSON list.
        #[arg(long)]
        json: bool,
        /// Which renderers: `grid` (ray casting), `pt` (Projected Tetrahedra), `tetray`
        /// (tetrahedral ray casting) or `all`; `targets` times the grid speed targets, the
        /// cases of a dataset in turn, `--frames` rounds, fastest frame per case.
        #[arg(long, value_enum, default_value_t = Suite::All)]
        suite: Suite,
        /// Grid suite: run only the cases whose "dataset integrator parameter" contains this
        /// text (e.g. `marschner riemann h=0.5`, matched word by word); targets and gpu
        /// suites: only the datasets (gpu: and meshes) whose name contains it (e.g. `shepp`).
        #[arg(long)]
        only: Option<String>,
        /// Time warm frames of this file (any format) instead of a suite: a turntable of
        /// --frames frames after a first one, with the `volux render` options given after
        /// `--` (e.g. `volux bench head.nrrd -- --tf ct-bone --size 800x600`).
        file: Option<PathBuf>,
        /// With FILE: `volux render` options (after `--`).
        #[arg(last = true)]
        render: Vec<String>,
    },
}

/// `volux tf` actions.
#[derive(Debug, Subcommand)]
pub enum TfCommand {
    /// Print a preset as JSON (stdout), to edit and pass back with --tf FILE.
    Show {
        /// The preset: auto, grayscale, ct-bone, ct-skin, ct-soft-tissue, mr-default,
        /// viridis, inferno, cool-warm; or a file (a ParaView preset or Slicer .vp prints as
        /// Volux JSON).
        preset: String,
        /// Fit the preset to this file (its value range, histogram and voxel size), as
        /// `volux render` does; `auto` needs it.
        #[arg(long)]
        data: Option<PathBuf>,
        #[command(flatten)]
        load: LoadArgs,
    },
}

/// Options that some readers need.
#[derive(Debug, Args, Clone, Default)]
pub struct LoadArgs {
    /// PLOT3D: q variable (density, momentum-x|y|z, energy, velocity-magnitude, or 0..4).
    #[arg(long)]
    pub q_variable: Option<String>,
    /// PLOT3D: q file (default: the xyz name with xyz replaced by q).
    #[arg(long)]
    pub q_file: Option<PathBuf>,
    /// DICOM: SeriesInstanceUID to load from a folder holding several series.
    #[arg(long)]
    pub series: Option<String>,
    /// VTK: name of the scalar array to use; OME-Zarr: path of the image inside the store
    /// (e.g. labels/cells).
    #[arg(long)]
    pub array: Option<String>,
    /// OME-Zarr: the pyramid level to load (0 = full resolution) [default: 0].
    #[arg(long)]
    pub level: Option<usize>,
    /// OME-Zarr, ImageJ hyperstacks and OME-TIFF: the channel index [default: 0].
    #[arg(long)]
    pub channel: Option<usize>,
    /// Files holding several volumes (4-D NIfTI, NRRD, MGH, DICOM series with several
    /// stacks, OME-Zarr, ImageJ hyperstacks, OME-TIFF): which one along time or the volume
    /// axis [default: 0]; `volux info` lists them.
    #[arg(long)]
    pub timepoint: Option<usize>,
    /// Vector and colour volumes: the component read as the scalar [default: the first
    /// component of a vector; a colour image keeps its colour].
    #[arg(long)]
    pub component: Option<usize>,
}

impl LoadArgs {
    /// The dataset at `path` read with these options: the one place where the reader
    /// options on the command line become the application layer's dataset reference.
    pub fn dataset(&self, path: &std::path::Path) -> volux_app::session::DatasetRef {
        volux_app::session::DatasetRef {
            path: path.to_path_buf(),
            q_variable: self.q_variable.clone(),
            q_file: self.q_file.clone(),
            series_uid: self.series.clone(),
            array: self.array.clone(),
            as_tets: false,
            channel: self.channel,
            timepoint: self.timepoint,
            component: self.component,
            level: self.level,
        }
    }
}

/// `volux render` options.
#[derive(Debug, Args, Clone)]
pub struct RenderArgs {
    /// The file (or DICOM folder) to render (none with --session: the session names it).
    #[arg(required_unless_present = "session")]
    pub file: Option<PathBuf>,
    /// Render a session saved by volux-view or `volux sculpt --session-out` (dataset,
    /// camera, TF, method, size, background, clip planes and sculpt steps, replayed, with
    /// its region labels and measurements): the viewer's picture, to the pixel; -o,
    /// --backend, and for a figure --size, --zoom, --background and --sixteen-bit go with
    /// it (each override said on stderr).
    #[arg(long, value_name = "S.json", conflicts_with = "file")]
    pub session: Option<PathBuf>,
    /// Output PNG [default: out.png, and it says so when it replaces a file].
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub view_args: ViewArgs,
    /// Integrator: riemann, trapezoid, simpson (fixed step), adaptive-simpson (error
    /// control), preintegrated (table over front/back values), reference (f64 ground
    /// truth, slow); for tetrahedral meshes with --method raycast: exact or psi.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Riemann)]
    pub integrator: IntegratorArg,
    /// Fixed-step integrators: step in voxel units.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.5)]
    pub step: f64,
    /// adaptive-simpson: absolute error tolerance per channel and ray.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.01)]
    pub tol: f64,
    /// adaptive-simpson: initial step (voxels).
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.5)]
    pub h0: f64,
    /// adaptive-simpson: smallest step (voxels), accepted whatever its error.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.001)]
    pub hmin: f64,
    /// adaptive-simpson: largest step (voxels).
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.5)]
    pub hmax: f64,
    /// adaptive-simpson: control the colour integral's step apart from the opacity's.
    #[arg(long)]
    pub decoupled: bool,
    /// adaptive-simpson (coupled): the step-size controller: the error-per-step controller
    /// (standard) or the seed's halving and doubling (seed, Algorithm 3).
    #[arg(long, value_enum, default_value_t = ControllerArg::Seed)]
    pub controller: ControllerArg,
    /// Reconstruction filter: trilinear, catmull-rom or b-spline (tricubic).
    #[arg(long, value_enum, default_value_t = ReconstructionArg::Trilinear)]
    pub reconstruction: ReconstructionArg,
    /// Blinn-Phong gradient shading.
    #[arg(long)]
    pub shade: bool,
    /// Shading: ambient coefficient.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.3)]
    pub ambient: f32,
    /// Shading: diffuse coefficient.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.7)]
    pub diffuse: f32,
    /// Shading: specular coefficient.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.3)]
    pub specular: f32,
    /// Shading: specular exponent.
    #[arg(long, allow_hyphen_values = true, default_value_t = 32.0)]
    pub shininess: f32,
    /// Shading: light direction X,Y,Z (towards the light), or `headlight`.
    #[arg(long, allow_hyphen_values = true, default_value = "headlight")]
    pub light: String,
    /// Maximum intensity projection.
    #[arg(long)]
    pub mip: bool,
    /// RGB volumes (colour DICOM, TIFF, NIfTI RGB24, NRRD RGB): colour from the transfer
    /// function, applied to their luminance, instead of their own colour (the default: the
    /// data's colour, the TF giving the opacity; `--component N` reads one channel).
    #[arg(long)]
    pub tf_colour: bool,
    /// Jitter each ray's first sample (fine noise instead of wood-grain rings).
    #[arg(long)]
    pub jitter: bool,
    /// Integrate every ray to its end (no early ray termination).
    #[arg(long)]
    pub no_early_termination: bool,
    /// Where to render: `cpu` (the reference engine), `gpu` (wgpu: grid ray casting with
    /// Riemann sums or MIP, clip planes and early termination; a build with the `gpu`
    /// feature), or
    /// `auto`: the GPU when the build has it, an adapter exists and it draws the scene, else
    /// the CPU.
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    /// Colour region labels: a label volume on the grid's voxels (integers 0 to 255, 0
    /// unlabelled; e.g. written by `volux regions`), each label in its palette colour, the
    /// opacity the transfer function's (grid ray casting, not MIP).
    #[arg(long, value_name = "LABELS.nrrd")]
    pub labels: Option<PathBuf>,
    /// Measure on the visible surface, as `volux measure` does, and draw it: pixel X,Y
    /// (at least two; a polyline in the order given) picked where the opacity along its ray
    /// reaches 0.5 after the clip planes and the mask; the points and the polyline are drawn
    /// on the picture and the length in world units (mm) is printed (grids).
    #[arg(long = "measure", value_name = "X,Y", allow_hyphen_values = true)]
    pub measure: Vec<String>,
    /// Write the per-pixel estimated integration error as a PNG (rays that missed the
    /// tolerance in magenta).
    #[arg(long)]
    pub error_map: Option<PathBuf>,
    /// Background colour as R,G,B in 0..1 (linear), or `none` for a transparent PNG.
    #[arg(long, allow_hyphen_values = true, default_value = "0,0,0")]
    pub background: String,
    /// Write 16 bits per channel.
    #[arg(long)]
    pub sixteen_bit: bool,
    /// Renderer: `auto` (grids: ray casting; meshes: Projected Tetrahedra), `pt` (cell
    /// projection of tetrahedral meshes), `raycast` (grids; meshes: exact cell-by-cell ray
    /// casting, colour from --integrator exact|psi or --color), `resample` (meshes resampled
    /// onto a grid, then ray cast).
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    pub method: MethodArg,
    /// PT: visibility order, `centroid` (radix sort, approximate) or `exact` (MPVO on convex
    /// meshes, per-pixel fragment sort otherwise).
    #[arg(long, value_enum, default_value_t = SortArg::Centroid)]
    pub sort: SortArg,
    /// PT: fragment colour, `average` (Shirley-Tuchman), `psi` (partial pre-integration) or
    /// `exact` (closed-form integral, the reference).
    #[arg(long, value_enum, default_value_t = ColorArg::Psi)]
    pub color: ColorArg,
    /// PT: render a grid by splitting every cell into five tetrahedra.
    #[arg(long)]
    pub as_tets: bool,
    /// Meshes: samples along the longest side of the resampling grid.
    #[arg(long, default_value_t = 256)]
    pub resample: usize,
    /// Print render statistics.
    #[arg(long)]
    pub stats: bool,
    /// With --stats on Projected Tetrahedra: also count the face pairs the centroid order
    /// draws out of the exact order (a diagnostic, timed apart; it adds about a third to the
    /// frame's wall time, so it is asked for, not part of --stats).
    #[arg(long)]
    pub sort_violations: bool,
    /// With --stats: print them as one JSON object (per frame with --orbit).
    #[arg(long)]
    pub json: bool,
    /// Render a turntable of N frames in one process (warm frames: the caches are built
    /// once): the camera turns about its up vector through its target by DEG degrees per
    /// frame (default 360/N); frames go to OUT_0000.png, OUT_0001.png, ... (OUT: -o without
    /// .png).
    #[arg(long, value_name = "N[:DEG]")]
    pub orbit: Option<String>,
    /// OME-Zarr: render out of core, chunk by chunk within the memory budget, at this
    /// pyramid level: `auto` (voxels about a pixel) or N (0 = full resolution). Without it a
    /// store is rendered out of core only when its full level is over the budget (`auto`).
    #[arg(long, value_name = "auto|N", conflicts_with = "level")]
    pub lod: Option<String>,
    /// With --orbit: write no images (figures only, with --stats).
    #[arg(long)]
    pub no_write: bool,
    /// OME-Zarr: render on the ranks of `mpirun -np N volux render STORE --distributed`
    /// (sort-last: each rank renders its k-d region of chunks, binary-swap compositing, rank 0
    /// writes the PNG) at --lod (default 0, full resolution); no early ray termination.
    /// Needs a volux built with `--features mpi`.
    #[arg(long, conflicts_with_all = ["orbit", "session"])]
    pub distributed: bool,
    /// Also write the image as raw linear premultiplied RGBA, little-endian f32, row by row
    /// (no background): for exact comparisons (`volux compare` reads quantized PNGs).
    #[arg(long, value_name = "F.f32")]
    pub raw_out: Option<PathBuf>,
    /// The frame of an --orbit being reported (set by the command, not typed).
    #[arg(skip)]
    pub frame_index: Option<usize>,
    #[command(flatten)]
    pub load: LoadArgs,
    /// The long names of the options given on the command line (filled after parsing), so
    /// that an option that would change nothing is refused rather than ignored.
    #[arg(skip)]
    pub given: Vec<String>,
}

/// The view options `volux render` and the sculpting commands share: the camera, the image
/// size, the transfer function and isosurfaces, the clip planes and a sculpt mask (so that
/// a pixel of `sculpt`, `measure` or `regions` is the pixel `render` draws with the same
/// options).
#[derive(Debug, Args, Clone)]
pub struct ViewArgs {
    /// Transfer function: a preset (auto, grayscale, ct-bone, ct-skin, ct-soft-tissue,
    /// mr-default, viridis, inferno, cool-warm) or a file: Volux JSON, a ParaView preset or a
    /// Slicer .vp (`volux help tf`); repeat it
    /// to layer several, each optionally weighted as NAME:WEIGHT (`--tf ct-bone --tf
    /// ct-skin:0.2`: bone under a faint skin) [default: auto].
    #[arg(long)]
    pub tf: Vec<String>,
    /// Multiply the extinction of the transfer function.
    #[arg(long, allow_hyphen_values = true, default_value_t = 1.0)]
    pub opacity_scale: f64,
    /// Camera JSON file (look-at or orbit form); overrides the angle options.
    #[arg(long)]
    pub camera: Option<PathBuf>,
    /// Orbit azimuth in degrees (default 0: looking along +y; thin slabs are seen along z).
    #[arg(long, allow_hyphen_values = true)]
    pub azimuth: Option<f64>,
    /// Orbit elevation in degrees (default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub elevation: Option<f64>,
    /// A named view, in the patient's terms (Slicer's convention: `left` puts the camera on
    /// the patient's left and shows that side): left, right, anterior (front), posterior
    /// (back) with superior up; superior (top), inferior (bottom) with anterior up, inferior
    /// being the radiological axial view. Axis views for any data: +x, -x, +y, -y, +z, -z
    /// (z up; y up for +-z). The world is LPS (+x left, +y posterior, +z superior), scans
    /// placed by their orientation. --up turns the image about the view direction;
    /// --azimuth and --elevation turn from the view.
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub view: Option<ViewArg>,
    /// Up direction X,Y,Z of the camera (default 0,0,1, or the named view's up; e.g. 0,0,-1
    /// for scans stored head down).
    #[arg(long, allow_hyphen_values = true)]
    pub up: Option<String>,
    /// What the camera frames: `visible` (what the transfer function and isosurfaces show,
    /// fitted to the image) or `all` (the whole bounding box, as a camera file sees it).
    #[arg(long, value_enum, default_value_t = FrameArg::Visible)]
    pub frame: FrameArg,
    /// Zoom factor.
    #[arg(long, allow_hyphen_values = true, default_value_t = 1.0)]
    pub zoom: f64,
    /// Use an orthographic projection.
    #[arg(long)]
    pub orthographic: bool,
    /// Image size WxH (for `sculpt`, `measure` and `regions`: the image the pixels refer
    /// to).
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// An isosurface VALUE:R,G,B,A (repeatable; grids: riemann integrator; PT: any colour).
    #[arg(long = "iso", allow_hyphen_values = true)]
    pub isos: Vec<String>,
    /// Keep the half-space A*x + B*y + C*z + D >= 0, world coordinates (millimetres for
    /// medical data); repeatable: the volume of interest is the data cut by every plane
    /// (grids).
    #[arg(
        long = "clip-plane",
        value_name = "A,B,C,D",
        allow_hyphen_values = true
    )]
    pub clip_planes: Vec<String>,
    /// A sculpt mask saved by `volux sculpt` (NRRD or any grid format, the grid's dims;
    /// non-zero voxels are kept, zero voxels removed): `render` applies it, `sculpt`,
    /// `measure` and `regions` start from it (grids).
    #[arg(long, value_name = "MASK.nrrd")]
    pub mask: Option<PathBuf>,
}

impl RenderArgs {
    /// Whether `--NAME` was given on the command line.
    pub fn given(&self, name: &str) -> bool {
        self.given.iter().any(|g| g == name)
    }

    /// The output path: `-o`, or `out.png`.
    pub fn output(&self) -> PathBuf {
        self.output
            .clone()
            .unwrap_or_else(|| PathBuf::from("out.png"))
    }
}

/// `volux render --view`: the patient's sides (LPS world: +x left, +y posterior, +z
/// superior, Slicer's convention) and the axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ViewArg {
    /// From the patient's left (camera on +x): shows the left side, superior up.
    #[value(alias = "l")]
    Left,
    /// From the patient's right (camera on -x): shows the right side, superior up.
    #[value(alias = "r")]
    Right,
    /// From the front (camera on -y): the face, superior up.
    #[value(alias = "front", alias = "a")]
    Anterior,
    /// From behind (camera on +y), superior up.
    #[value(alias = "back", alias = "p")]
    Posterior,
    /// From above the head (camera on +z), anterior up.
    #[value(alias = "top", alias = "s")]
    Superior,
    /// From the feet (camera on -z), anterior up: the radiological axial view (the
    /// patient's left on the image's right).
    #[value(alias = "bottom", alias = "i")]
    Inferior,
    /// Camera on +x, z up (axis views for data without a patient).
    #[value(name = "+x")]
    PlusX,
    /// Camera on -x, z up.
    #[value(name = "-x")]
    MinusX,
    /// Camera on +y, z up.
    #[value(name = "+y")]
    PlusY,
    /// Camera on -y, z up.
    #[value(name = "-y")]
    MinusY,
    /// Camera on +z, y up.
    #[value(name = "+z")]
    PlusZ,
    /// Camera on -z, y up.
    #[value(name = "-z")]
    MinusZ,
}

impl From<ViewArg> for volux_core::NamedView {
    fn from(v: ViewArg) -> Self {
        use volux_core::NamedView as N;
        match v {
            ViewArg::Left => N::Left,
            ViewArg::Right => N::Right,
            ViewArg::Anterior => N::Anterior,
            ViewArg::Posterior => N::Posterior,
            ViewArg::Superior => N::Superior,
            ViewArg::Inferior => N::Inferior,
            ViewArg::PlusX => N::PlusX,
            ViewArg::MinusX => N::MinusX,
            ViewArg::PlusY => N::PlusY,
            ViewArg::MinusY => N::MinusY,
            ViewArg::PlusZ => N::PlusZ,
            ViewArg::MinusZ => N::MinusZ,
        }
    }
}

/// `volux render --frame`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FrameArg {
    /// The region the transfer function and isosurfaces make visible, fitted to the image.
    Visible,
    /// The whole bounding box.
    All,
}

/// What `volux generate` makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Generator {
    /// The Marschner-Lobb test signal (grid).
    MarschnerLobb,
    /// The 3D Shepp-Logan phantom (grid).
    SheppLogan,
    /// A sphere's distance field (grid).
    Sphere,
    /// A cube of conforming tetrahedra with a smooth field (mesh).
    TetsSmooth,
    /// A tetrahedral torus (non-convex mesh).
    Torus,
}

/// `volux bench --suite`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Suite {
    /// Grid ray casting, PT and tet ray casting.
    All,
    /// Grid ray casting per integrator.
    Grid,
    /// Projected Tetrahedra per colour mode, and its accuracy.
    Pt,
    /// Tetrahedral ray casting.
    Tetray,
    /// The grid speed targets, cases in turn.
    Targets,
    /// The volume of interest (issue 18): plane cuts, and frames with clip planes.
    Voi,
    /// The GPU backend (issue 20; a build with `--features gpu`): ms/frame, samples/s,
    /// upload time and device memory of grid ray casting at 512x512 and 1920x1080.
    Gpu,
}

/// `volux render --method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Grids: ray casting; meshes: Projected Tetrahedra.
    Auto,
    /// Projected Tetrahedra (meshes; grids with --as-tets).
    Pt,
    /// Ray casting: grids sample by sample, meshes cell by cell.
    Raycast,
    /// Meshes resampled onto a grid, then ray cast.
    Resample,
    /// Grids: texture slicing on the GPU (seed 004 ch. 3), slices --step voxels apart;
    /// needs the GPU backend.
    Slicing,
}

/// `volux render --integrator`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Left Riemann sum, step-corrected opacity.
    Riemann,
    /// Fixed-step trapezoid rule.
    Trapezoid,
    /// Fixed-step Simpson rule.
    Simpson,
    /// Adaptive Simpson with error control (seed 001).
    #[value(alias = "adaptive")]
    AdaptiveSimpson,
    /// Pre-integrated classification.
    Preintegrated,
    /// The f64 ground truth (slow).
    Reference,
    /// Meshes (--method raycast): exact segment integral.
    Exact,
    /// Meshes (--method raycast): partial pre-integration.
    Psi,
}

impl IntegratorArg {
    /// The name as typed on the command line.
    pub fn name(self) -> String {
        self.to_possible_value()
            .map(|v| v.get_name().to_string())
            .unwrap_or_default()
    }
}

/// `volux render --controller`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ControllerArg {
    /// The error-per-step controller: `h 0.9 (tol / err)^(1/4)`, within `[0.2 h, 5 h]`.
    Standard,
    /// The seed's Algorithm 3: halve on failure, double after two successes.
    Seed,
}

/// `volux render --reconstruction`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReconstructionArg {
    /// Trilinear.
    Trilinear,
    /// Tricubic Catmull-Rom.
    CatmullRom,
    /// Tricubic B-spline.
    #[value(alias = "bspline")]
    BSpline,
}

/// `volux render --sort`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SortArg {
    /// Centroid radix sort (approximate).
    Centroid,
    /// MPVO on convex meshes, per-pixel fragment sort otherwise.
    Exact,
}

/// `volux render --color`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorArg {
    /// Shirley-Tuchman averages.
    Average,
    /// Partial pre-integration.
    Psi,
    /// Closed-form segment integral.
    Exact,
}

/// The name a value enum shows on the command line.
pub fn value_name(v: &impl ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// How the sculpting commands take pixels.
const PIXELS_HELP: &str = "Pixels are those of the PNG `volux render` writes with the same \
file, camera, size and transfer-function options: x to the right, y down from the top-left \
corner, continuous (pixel (i, j) spans i..i+1, j..j+1; its centre is i+0.5, j+0.5). A pixel \
is picked where the opacity along its ray reaches 0.5, after the clip planes and the mask.";

/// `volux sculpt`'s help after the options.
const SCULPT_HELP: &str = "The tools apply in the order given (--dig 200,180,12 --erase \
200,180,30 differs from the reverse). Pixels are those of the PNG `volux render` writes \
with the same file, camera, size and transfer-function options: x to the right, y down from \
the top-left corner, continuous (pixel (i, j)'s centre is i+0.5, j+0.5). Render the result \
with `volux render FILE --mask MASK.nrrd` and the same view options.";

/// The view that the sculpting commands pick in: the file, camera, image size, transfer
/// function, clip planes and a starting mask, defaulted as `volux render` defaults them.
#[derive(Debug, Args, Clone)]
pub struct ToolViewArgs {
    /// The grid file (or DICOM folder).
    pub file: PathBuf,
    #[command(flatten)]
    pub view_args: ViewArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

impl ToolViewArgs {
    /// The `volux render` arguments of this view (every other option at its default), so
    /// that the camera, size and transfer function are those `volux render` would use;
    /// `given`: the options typed.
    pub fn render_args(&self, given: &[String]) -> RenderArgs {
        let command = RenderArgs::augment_args(clap::Command::new("render"));
        let matches = command
            .try_get_matches_from(["render", "file"])
            .expect("the render defaults parse");
        let mut r = RenderArgs::from_arg_matches(&matches).expect("the render defaults parse");
        r.file = Some(self.file.clone());
        r.view_args = self.view_args.clone();
        r.load = self.load.clone();
        r.given = given
            .iter()
            .filter(|g| VIEW_OPTIONS.contains(&g.as_str()))
            .cloned()
            .collect();
        r
    }
}

/// The options of [`ToolViewArgs`] that `volux render` checks against each other.
const VIEW_OPTIONS: [&str; 12] = [
    "camera",
    "azimuth",
    "elevation",
    "view",
    "up",
    "frame",
    "zoom",
    "orthographic",
    "size",
    "tf",
    "opacity-scale",
    "iso",
];

/// `volux sculpt` options.
#[derive(Debug, Args, Clone)]
pub struct SculptArgs {
    #[command(flatten)]
    pub view: ToolViewArgs,
    /// Erase a disc: centre X,Y and radius R in pixels, through the whole depth
    /// (repeatable).
    #[arg(long, value_name = "X,Y,R", allow_hyphen_values = true)]
    pub erase: Vec<String>,
    /// Erase along a stroke: a disc of radius R pixels swept through the points
    /// (repeatable).
    #[arg(long, value_name = "X1,Y1,X2,Y2,...,R", allow_hyphen_values = true)]
    pub stroke: Vec<String>,
    /// Dig at pixel X,Y: remove a ball about the visible surface point there, R pixels in
    /// radius at its depth (repeatable; repeated digs go deeper).
    #[arg(long, value_name = "X,Y,R", allow_hyphen_values = true)]
    pub dig: Vec<String>,
    /// The mask written (NRRD, u8: 1 kept, 0 removed).
    #[arg(long, short, value_name = "MASK.nrrd")]
    pub output: PathBuf,
    /// Also save a session (for `volux render --session` and volux-view) holding the view
    /// and the sculpt steps.
    #[arg(long, value_name = "S.json")]
    pub session_out: Option<PathBuf>,
    /// The tools in command-line order (filled after parsing).
    #[arg(skip)]
    pub order: Vec<(ToolKind, usize)>,
}

/// A sculpting tool of `volux sculpt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ToolKind {
    /// `--erase`.
    Erase,
    /// `--stroke`.
    Stroke,
    /// `--dig`.
    Dig,
}

impl SculptArgs {
    /// Records the order of the `--erase`, `--stroke` and `--dig` options of `matches` (as
    /// `(tool, index among that tool's options)`): the tools apply in that order.
    pub fn fill_order(&mut self, matches: &ArgMatches) {
        let mut all = Vec::new();
        for (kind, id) in [
            (ToolKind::Erase, "erase"),
            (ToolKind::Stroke, "stroke"),
            (ToolKind::Dig, "dig"),
        ] {
            if let Some(at) = matches.indices_of(id) {
                all.extend(at.enumerate().map(|(n, at)| (at, kind, n)));
            }
        }
        all.sort_unstable();
        self.order = all.into_iter().map(|(_, kind, n)| (kind, n)).collect();
    }
}

/// `volux measure` options.
#[derive(Debug, Args, Clone)]
pub struct MeasureArgs {
    #[command(flatten)]
    pub view: ToolViewArgs,
    /// A pixel X,Y to pick (at least two; a polyline in the order given).
    #[arg(long = "point", value_name = "X,Y", allow_hyphen_values = true)]
    pub points: Vec<String>,
    /// Print `{"points": [[x,y,z], ...], "length_mm": L}`.
    #[arg(long)]
    pub json: bool,
}

/// `volux regions` options.
#[derive(Debug, Args, Clone)]
pub struct RegionsArgs {
    #[command(flatten)]
    pub view: ToolViewArgs,
    /// A seed: pixel X,Y picked on the visible surface, and its LABEL (1..255); repeatable.
    #[arg(long = "seed", value_name = "X,Y,LABEL", allow_hyphen_values = true)]
    pub seeds: Vec<String>,
    /// How the seeds claim voxels. `connected`: the visible voxels reachable from a seed
    /// through visible voxels (6-connected); where seeds' regions meet, a voxel goes to the
    /// seed reaching it in the fewest voxel steps (the earlier --seed at equal steps); what
    /// no seed touches stays 0. `nearest`: every visible voxel to the seed nearest in world
    /// distance, parts no seed touches included (the rule before issue 41).
    #[arg(long, value_enum, default_value_t = RuleArg::Connected)]
    pub rule: RuleArg,
    /// The label volume written (NRRD, u8, 0: no label).
    #[arg(long, short, value_name = "LABELS.nrrd")]
    pub output: PathBuf,
}

/// `volux regions --rule`: [`volux_core::sculpt::RegionRule`] on the command line.
///
/// `connected` is the default because a seed placed on a structure is expected to label
/// that structure, not the head rest beside it that touches nothing (issue 41). Saved
/// sessions do not follow this default: a label step saved without a rule replays as
/// `nearest`, what it meant when saved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RuleArg {
    /// The visible voxels connected to a seed (breadth-first from all seeds at once).
    Connected,
    /// Every visible voxel to its nearest seed in world distance.
    Nearest,
}

impl From<RuleArg> for volux_core::sculpt::RegionRule {
    fn from(rule: RuleArg) -> Self {
        match rule {
            RuleArg::Connected => Self::Connected,
            RuleArg::Nearest => Self::Nearest,
        }
    }
}

/// `--backend`: the application layer's backend names ([`Backend::NAMES`]), listed in the
/// help and completions.
fn backend_parser() -> impl clap::builder::TypedValueParser<Value = Backend> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(Backend::NAMES)
        .map(|s| s.parse::<Backend>().expect("a listed name"))
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::*;

    /// The option `id` of `command`.
    fn option<'a>(command: &'a clap::Command, id: &clap::Id) -> &'a clap::Arg {
        command
            .get_arguments()
            .find(|a| a.get_id() == id)
            .unwrap_or_else(|| panic!("{} has no {id}", command.get_name()))
    }

    /// `volux render` and the sculpting commands take the same view options: the same
    /// flags, help texts and defaults, from one struct.
    #[test]
    fn render_and_the_sculpting_commands_share_the_view_options() {
        let cli = Cli::command();
        let view = ViewArgs::augment_args(clap::Command::new("view"));
        let ids: Vec<_> = view.get_arguments().map(|a| a.get_id().clone()).collect();
        assert_eq!(ids.len(), 14, "{ids:?}");
        let render = cli.find_subcommand("render").unwrap();
        for name in ["sculpt", "measure", "regions"] {
            let tool = cli.find_subcommand(name).unwrap();
            for id in &ids {
                let (r, t) = (option(render, id), option(tool, id));
                assert_eq!(r.get_long(), t.get_long(), "{name} {id}");
                assert_eq!(r.get_help(), t.get_help(), "{name} {id}");
                assert_eq!(
                    r.get_default_values(),
                    t.get_default_values(),
                    "{name} {id}"
                );
            }
        }
        let size = option(render, &clap::Id::from("size"));
        assert_eq!(size.get_default_values(), ["512x512"]);
    }
}
