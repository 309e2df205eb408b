//! What to render: the [`Volume`], the [`View`] (camera and image size), the [`Appearance`]
//! (transfer function, lighting, isosurfaces, MIP) and the [`Method`] (which renderer, with
//! its settings), gathered in a [`Scene`]. A front end builds a scene and hands it to a
//! [`Renderer`](crate::renderer::Renderer) made for the volume
//! ([`create_renderer`](crate::engine::create_renderer)); it never reaches into a renderer.
//!
//! # Units, stated once
//!
//! Every length a [`Method`] holds (a grid integrator's step, adaptive Simpson's `h0`,
//! `hmin`, `hmax`) is in the volume's **unit length**, [`Volume::unit_length`]:
//!
//! - a grid's smallest sample spacing (the seed `001`'s "voxel units");
//! - a tetrahedral mesh's bounding-box diagonal divided by [`MESH_UNITS_PER_DIAGONAL`] (256):
//!   meshes have no voxel, so this is a length of the same order for a mesh the size of a
//!   256-voxel grid.
//!
//! The renderers convert to world units. Transfer-function presets take the same unit
//! ([`Volume::preset_tf`]), so a preset looks alike on a grid and on its tetrahedral split.
//!
//! # One set of defaults
//!
//! [`Scene::new`] gives every method the same defaults: early termination at opacity
//! [`DEFAULT_EARLY_TERMINATION`], the default [`BlinnPhong`] lighting for isosurfaces (and for
//! the volume when [`Appearance::shade_volume`] is set), ψ colour for the tetrahedral
//! renderers ([`SegmentRule::Psi`]), Riemann steps of half a unit for grids.
use std::sync::Arc;

use volux_core::histogram::Histogram;
use volux_core::sculpt::SculptMask;
use volux_core::tetrahedralize::grid_to_tets;
use volux_core::voi::ClipPlane;
use volux_core::{Aabb, Camera, Grid, TetMesh, TransferFunction};

use crate::bricked::volume::{BrickedVolume, Lod};
use crate::error::{Refusal, Remedy, RenderError, Setting, SettingError};
use crate::integrate::integrator::Integrator;
use crate::integrate::segment::SegmentRule;
use crate::isosurface::Isosurfaces;
use crate::sampling::Reconstruction;
use crate::sculpt::labels::LabelVolume;
use crate::shading::BlinnPhong;

/// A mesh's unit length is its bounding-box diagonal divided by this ([`Volume::unit_length`]).
pub const MESH_UNITS_PER_DIAGONAL: f64 = 256.0;

/// The opacity at which every method stops a ray or pixel by default.
pub const DEFAULT_EARLY_TERMINATION: f32 = 0.99;

/// Bins of the histogram presets are fitted on.
pub const HISTOGRAM_BINS: usize = 256;

/// The data a renderer draws, shared (`Arc`) so that a viewer can keep rendering it on
/// another thread.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum Volume {
    /// A regular grid of scalars.
    Grid(Arc<Grid>),
    /// A tetrahedral mesh with one scalar per vertex.
    Mesh(Arc<TetMesh>),
    /// A grid stored in chunks, rendered out of core ([`crate::bricked`]), with the way its
    /// pyramid level is chosen.
    Bricked(Arc<BrickedVolume>, Lod),
}

impl From<Grid> for Volume {
    fn from(g: Grid) -> Self {
        Self::Grid(Arc::new(g))
    }
}

impl From<TetMesh> for Volume {
    fn from(m: TetMesh) -> Self {
        Self::Mesh(Arc::new(m))
    }
}

impl Volume {
    /// What kind of volume this is, in words.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Grid(_) => "grid",
            Self::Mesh(_) => "tetrahedral mesh",
            Self::Bricked(..) => "bricked grid",
        }
    }

    /// The world-space bounding box.
    pub fn bounds(&self) -> Aabb {
        match self {
            Self::Grid(g) => g.bounds(),
            Self::Mesh(m) => m.bounds(),
            Self::Bricked(b, _) => b.bounds(),
        }
    }

    /// The scalar range `[min, max]`.
    pub fn range(&self) -> [f64; 2] {
        match self {
            Self::Grid(g) => g.range(),
            Self::Mesh(m) => m.range(),
            Self::Bricked(b, _) => b.range(),
        }
    }

    /// The unit of every length in a [`Method`] (see the module documentation): a grid's
    /// smallest spacing, a mesh's diagonal / [`MESH_UNITS_PER_DIAGONAL`].
    pub fn unit_length(&self) -> f64 {
        match self {
            Self::Grid(g) => g.spacing().min_element(),
            Self::Mesh(m) => m.bounds().diagonal() / MESH_UNITS_PER_DIAGONAL,
            Self::Bricked(b, _) => b.unit_length(),
        }
    }

    /// A histogram of the scalars with `bins` bins over [`Volume::range`].
    pub fn histogram(&self, bins: usize) -> Histogram {
        match self {
            Self::Grid(g) => Histogram::of_grid(g, bins),
            Self::Mesh(m) => Histogram::from_values(m.scalars(), m.range(), bins),
            Self::Bricked(b, _) => b.histogram(bins),
        }
    }

    /// Whether the volume looks like a CT in Hounsfield units: a grid of signed 16-bit values
    /// whose minimum is air or the scanner's padding (-4000 to -900 HU) and whose maximum
    /// reaches bone (at least 300 HU). Integer magnitudes of MR, PET or microscopy are not
    /// negative; a float simulation field is not 16-bit.
    pub fn looks_like_ct(&self) -> bool {
        let [lo, hi] = self.range();
        let signed16 = match self {
            Self::Grid(g) => g.scalar_type() == volux_core::ScalarType::I16,
            _ => false,
        };
        signed16 && (-4000.0..=-900.0).contains(&lo) && hi >= 300.0
    }

    /// The first picture's transfer function and whether to shade the volume, for a front
    /// end that opens data without being told how to show it: a CT ([`Self::looks_like_ct`])
    /// gets bone under a faint skin (`ct-bone` + `ct-skin` at 0.15), lit; other grids the
    /// `auto` preset, lit (a grid unlit is a flat blob); meshes `auto`, unlit (PT draws no
    /// gradient light).
    pub fn first_look(&self) -> Result<(TransferFunction, bool), RenderError> {
        let grid = matches!(self, Self::Grid(_));
        if self.looks_like_ct() {
            let range = self.range();
            let hist = self.histogram(HISTOGRAM_BINS);
            let preset = |name| -> Result<TransferFunction, RenderError> {
                Ok(TransferFunction::preset(name, &hist)?
                    .with_unit_length(self.unit_length())
                    .resolved(range))
            };
            let layers = [(preset("ct-bone")?, 1.0), (preset("ct-skin")?, 0.15)];
            return Ok((TransferFunction::layered(&layers)?, true));
        }
        Ok((self.preset_tf("auto")?, grid))
    }

    /// A transfer-function preset (`auto`, `ct-bone`, ...) fitted to this volume's histogram,
    /// its extinction per [`Volume::unit_length`].
    pub fn preset_tf(&self, name: &str) -> Result<TransferFunction, RenderError> {
        let hist = self.histogram(HISTOGRAM_BINS);
        Ok(TransferFunction::preset(name, &hist)?.with_unit_length(self.unit_length()))
    }

    /// A grid split into tetrahedra (five per cell, conforming), so that the tetrahedral
    /// renderers can draw it; a mesh is returned as it is.
    pub fn to_tets(&self) -> Result<Volume, RenderError> {
        match self {
            Self::Grid(g) => Ok(grid_to_tets(g)?.into()),
            Self::Mesh(_) => Ok(self.clone()),
            Self::Bricked(..) => Err(Refusal::new(
                "a bricked grid",
                "is not split into tetrahedra: it is ray cast out of core",
                None,
            )
            .into()),
        }
    }
}

/// Where the volume is seen from, and the image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The camera.
    pub camera: Camera,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

impl View {
    /// The same view at `1 / divisor` of the resolution (rounded up; `divisor` 0 or 1 is the
    /// view itself): progressive refinement renders such a preview first.
    pub fn reduced(&self, divisor: usize) -> Self {
        let k = divisor.max(1);
        Self {
            width: self.width.div_ceil(k),
            height: self.height.div_ceil(k),
            ..*self
        }
    }
}

/// How the data looks: classification, lighting, isosurfaces, projection mode.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Appearance {
    /// The transfer function (colour and extinction per unit length of its own).
    pub tf: TransferFunction,
    /// Multiplies the transfer function's extinction (on top of its own `opacity_scale`).
    pub opacity_scale: f64,
    /// Blinn-Phong lighting of the isosurfaces, and of the volume when
    /// [`Appearance::shade_volume`] is set.
    pub lighting: BlinnPhong,
    /// Gradient shading of the volume samples (grid ray casting; the mesh renderers light
    /// their isosurfaces only and ignore it).
    pub shade_volume: bool,
    /// Isosurfaces drawn with the volume.
    pub isosurfaces: Isosurfaces,
    /// Maximum intensity projection: each pixel shows the TF colour of the largest value
    /// along its ray, opaque (the ray casters; Projected Tetrahedra composites cells and
    /// ignores it).
    pub mip: bool,
    /// An RGB grid is drawn in its own colour, the transfer function giving the opacity of
    /// its luminance ([`crate::data_colour`]); `false`: in the TF's colours, as any grid.
    /// No effect on grids without colour, nor on MIP.
    #[serde(default = "yes", skip_serializing_if = "is_yes")]
    pub data_colour: bool,
}

fn yes() -> bool {
    true
}

fn is_yes(b: &bool) -> bool {
    *b
}

impl Appearance {
    /// `tf` as it is, default lighting, no isosurfaces, compositing.
    pub fn new(tf: TransferFunction) -> Self {
        Self {
            tf,
            opacity_scale: 1.0,
            lighting: BlinnPhong::default(),
            shade_volume: false,
            isosurfaces: Isosurfaces::default(),
            mip: false,
            data_colour: true,
        }
    }

    /// The transfer function the renderers use: [`Appearance::tf`] with its extinction
    /// multiplied by [`Appearance::opacity_scale`].
    pub fn effective_tf(&self) -> TransferFunction {
        let scale = self.tf.opacity_scale * self.opacity_scale;
        self.tf.clone().with_opacity_scale(scale)
    }
}

/// Grid ray casting settings (steps in the volume's unit length: voxels).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridRaycast {
    /// How each ray is integrated.
    pub integrator: Integrator,
    /// Reconstruction filter.
    pub reconstruction: Reconstruction,
    /// Offset each ray's first sample by a per-pixel pseudo-random fraction of the step.
    pub jitter: bool,
}

impl Default for GridRaycast {
    /// Riemann sum with a step of half a voxel, trilinear, no jitter.
    fn default() -> Self {
        Self {
            integrator: Integrator::Riemann { step: 0.5 },
            reconstruction: Reconstruction::Trilinear,
            jitter: false,
        }
    }
}

/// Visibility order of Projected Tetrahedra ([`crate::pt::sort`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SortMode {
    /// Centroid depth, radix sorted (the seeds' order; approximate).
    #[default]
    Centroid,
    /// Exact: MPVO for convex meshes, per-pixel fragment sorting otherwise.
    Exact,
}

/// Projected Tetrahedra settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PtSettings {
    /// Visibility order.
    pub sort: SortMode,
    /// Fragment colour (average, ψ or exact).
    pub color: SegmentRule,
    /// Count the face pairs the centroid order gets wrong against the exact order (costs an
    /// exact sort; for statistics).
    pub count_violations: bool,
}

/// Texture slicing settings (seed `004` ch. 3): view-aligned slices `step` apart, in the
/// volume's unit length (voxels). A GPU method: only `volux-gpu` draws it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlicingSettings {
    /// The distance between slices (voxels of the smallest spacing).
    pub step: f64,
}

impl Default for SlicingSettings {
    /// Slices half a voxel apart, as the ray caster's default step.
    fn default() -> Self {
        Self { step: 0.5 }
    }
}

/// Which renderer draws the volume, with its settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "name", content = "settings", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Method {
    /// The library's choice: grids are ray cast, meshes drawn with Projected Tetrahedra, each
    /// with its default settings.
    #[default]
    Auto,
    /// Image-order ray casting of a grid (seed `001`).
    GridRaycast(GridRaycast),
    /// Projected Tetrahedra of a mesh (seeds `000`, `002`).
    ProjectedTetrahedra(PtSettings),
    /// Cell-to-cell ray casting of a mesh, each segment or the whole ray coloured by the
    /// rule (adaptive steps in the volume's unit length).
    TetRaycast(SegmentRule),
    /// The brute-force per-pixel reference of meshes: every ray clipped against every cell
    /// on its pixel, segments sorted and integrated exactly, no early termination (slow;
    /// tests and accuracy figures).
    MeshReference,
    /// A mesh resampled onto a grid whose longest side has `samples` samples, then ray cast
    /// (steps in voxels of that grid).
    Resample {
        /// Samples along the longest side.
        samples: usize,
        /// The grid ray casting of the resampled grid.
        raycast: GridRaycast,
    },
    /// Texture slicing of a grid on the GPU (seed `004` ch. 3): view-aligned slices of the
    /// volume of interest composited back to front. The CPU engine refuses it
    /// ([`create_renderer`](crate::engine::create_renderer)).
    Slicing(SlicingSettings),
}

impl Method {
    /// A short name: `auto`, `raycast`, `pt`, `tet-raycast`, `mesh-reference`, `resample`,
    /// `slicing`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::GridRaycast(_) => "raycast",
            Self::ProjectedTetrahedra(_) => "pt",
            Self::TetRaycast(_) => "tet-raycast",
            Self::MeshReference => "mesh-reference",
            Self::Resample { .. } => "resample",
            Self::Slicing(_) => "slicing",
        }
    }

    /// Whether only the GPU backend draws this method (texture slicing): `auto` then takes
    /// any adapter, a software one included.
    pub fn gpu_only(&self) -> bool {
        matches!(self, Self::Slicing(_))
    }

    /// Ray casting of `volume`: the grid ray caster with `grid` for grids, the tet ray caster
    /// with `mesh` for meshes.
    pub fn raycast(volume: &Volume, grid: GridRaycast, mesh: SegmentRule) -> Self {
        match volume {
            Volume::Grid(_) | Volume::Bricked(..) => Self::GridRaycast(grid),
            Volume::Mesh(_) => Self::TetRaycast(mesh),
        }
    }

    /// The concrete method for `volume`: [`Method::Auto`] resolved, and an error when the
    /// method does not apply to the volume (PT or tet ray casting of a grid: split it first
    /// with [`Volume::to_tets`]; grid ray casting of a mesh: resample it).
    pub fn resolve(&self, volume: &Volume) -> Result<Method, RenderError> {
        let wrong = |why: &str, remedy: Option<Remedy>| {
            Err(Refusal::new(
                format!("the {} method", self.name()),
                format!("does not draw a {}: {why}", volume.kind()),
                remedy,
            )
            .into())
        };
        match (self, volume) {
            (Self::Auto, Volume::Grid(_) | Volume::Bricked(..)) => {
                Ok(Self::GridRaycast(GridRaycast::default()))
            }
            (Self::Auto, Volume::Mesh(_)) => Ok(Self::ProjectedTetrahedra(PtSettings::default())),
            (Self::GridRaycast(_), Volume::Grid(_) | Volume::Bricked(..)) => Ok(*self),
            (Self::GridRaycast(_), _) => wrong(
                "a mesh is ray cast cell by cell, or resampled onto a grid",
                Some(Remedy::Method("tet-raycast")),
            ),
            (
                Self::ProjectedTetrahedra(_) | Self::TetRaycast(_) | Self::MeshReference,
                Volume::Mesh(_),
            ) => Ok(*self),
            (Self::ProjectedTetrahedra(_) | Self::TetRaycast(_) | Self::MeshReference, _) => {
                wrong("it draws tetrahedra", Some(Remedy::SplitIntoTets))
            }
            (Self::Resample { .. }, Volume::Mesh(_)) => Ok(*self),
            (Self::Resample { .. }, _) => wrong("it is a grid already", None),
            (Self::Slicing(_), Volume::Grid(_)) => Ok(*self),
            (Self::Slicing(_), _) => wrong("it slices grids held in memory", None),
        }
    }
}

impl Method {
    /// Whether the method draws tetrahedra (Projected Tetrahedra, tet ray casting, the mesh
    /// reference): a grid must be split first ([`Volume::to_tets`]).
    pub fn draws_tets(&self) -> bool {
        matches!(
            self,
            Self::ProjectedTetrahedra(_) | Self::TetRaycast(_) | Self::MeshReference
        )
    }

    /// Whether this (resolved) method draws everything `appearance` asks for: Projected
    /// Tetrahedra composites cells and has no maximum intensity projection, and the mesh
    /// renderers light their isosurfaces but not the volume. A front end calls this so that
    /// an option is never silently ignored.
    pub fn check_appearance(&self, appearance: &Appearance) -> Result<(), RenderError> {
        let who = match self {
            Self::ProjectedTetrahedra(_) => "Projected Tetrahedra",
            Self::TetRaycast(_) => "mesh ray casting",
            Self::MeshReference => "the mesh reference",
            _ => self.name(),
        };
        let refuse =
            |what: &str, instead: Remedy| Err(Refusal::new(who, what, Some(instead)).into());
        let mesh = self.draws_tets();
        if appearance.mip && matches!(self, Self::ProjectedTetrahedra(_) | Self::MeshReference) {
            return refuse(
                "composites cells and has no maximum intensity projection",
                Remedy::Method("raycast"),
            );
        }
        if appearance.mip && (appearance.shade_volume || !appearance.isosurfaces.is_empty()) {
            return refuse(
                "with maximum intensity projection shows the colour of each ray's largest \
                 value, unlit and without isosurfaces",
                Remedy::DropMip,
            );
        }
        if appearance.shade_volume && mesh {
            return refuse(
                "lights isosurfaces but does not shade the volume",
                Remedy::Method("resample"),
            );
        }
        Ok(())
    }
}

/// Everything that decides a frame besides the volume: what a front end changes between
/// frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Camera and image size.
    pub view: View,
    /// Classification, lighting, isosurfaces, MIP.
    pub appearance: Appearance,
    /// The renderer and its settings.
    pub method: Method,
    /// Stop a ray (or a pixel's fragments) once its opacity reaches this; `None` integrates
    /// to the end (references).
    pub early_termination: Option<f32>,
    /// World-space clipping planes, each keeping `normal . x + offset >= 0`: the volume of
    /// interest is the data box cut by all of them (seed `004`, ch. 4). Every renderer draws
    /// them exactly: grid ray casting (every integrator: rays clipped to the planes) and
    /// resampling (through it), tet ray casting and the mesh reference (segments trimmed to
    /// each ray's window), PT (fragments trimmed to each pixel's window, cells wholly outside
    /// a plane culled).
    pub clip_planes: Vec<ClipPlane>,
    /// The sculpt mask of a grid (seed `004` sec. 4.4-4.5): samples where the interpolated
    /// mask is under 0.5 are not drawn. Grid ray casting draws it (every integrator); the
    /// mesh renderers refuse a scene with a mask. Shared, so that cloning a scene is cheap.
    pub mask: Option<Arc<SculptMask>>,
    /// Region labels of a grid (seed `004` sec. 6.2), drawn by grid ray casting in their
    /// colours in place of the TF's (maximum intensity projection keeps the TF's colours).
    pub labels: Option<Arc<LabelVolume>>,
}

impl Scene {
    /// A scene with the defaults of every method (see the module documentation).
    pub fn new(camera: Camera, width: usize, height: usize, tf: TransferFunction) -> Self {
        Self {
            view: View {
                camera,
                width,
                height,
            },
            appearance: Appearance::new(tf),
            method: Method::Auto,
            early_termination: Some(DEFAULT_EARLY_TERMINATION),
            clip_planes: Vec::new(),
            mask: None,
            labels: None,
        }
    }

    /// Why this scene cannot draw region labels ([`Scene::labels`]), when it cannot: MIP
    /// shows the transfer function's colours, and the mesh renderers draw no labels. Every
    /// front end says this rather than dropping the labels without a word.
    pub fn labels_not_drawn(&self) -> Option<&'static str> {
        if self.appearance.mip {
            Some("labels colour the composited rendering; MIP shows the TF's colours")
        } else if self.method.draws_tets() {
            Some("labels colour grid ray casting, not the tetrahedra")
        } else {
            None
        }
    }

    /// Checks what does not depend on the volume: image size, camera, transfer function,
    /// lighting, early termination.
    pub fn validate(&self) -> Result<(), RenderError> {
        crate::error::check_image_size(self.view.width, self.view.height)?;
        self.view.camera.validate()?;
        self.appearance.tf.validate()?;
        let s = self.appearance.opacity_scale;
        if !(s.is_finite() && s >= 0.0) {
            return Err(SettingError::new(Setting::OpacityScale, s, "finite and >= 0").into());
        }
        self.appearance.lighting.validate()?;
        check_early_termination(self.early_termination)?;
        for p in &self.clip_planes {
            // Planes read from a session file are checked as the CLI's are.
            p.check()?;
        }
        Ok(())
    }
}

/// Checks an early ray termination opacity: `None`, or positive and finite.
pub(crate) fn check_early_termination(opacity: Option<f32>) -> Result<(), SettingError> {
    match opacity {
        Some(e) if !(e > 0.0 && e.is_finite()) => Err(SettingError::new(
            Setting::EarlyTermination,
            e,
            "a positive opacity",
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::synth;

    fn grid() -> Volume {
        synth::marschner_lobb(9).unwrap().into()
    }

    /// A CT-like int16 grid: air at `air` HU, a cube of bone (1200 HU) in soft tissue (40).
    fn ct(air: i16) -> Volume {
        let n = 16;
        let values: Vec<i16> = (0..n * n * n)
            .map(|i| {
                let c = [i % n, (i / n) % n, i / (n * n)];
                if c.iter().all(|&v| (6..10).contains(&v)) {
                    1200
                } else if c.iter().all(|&v| (2..14).contains(&v)) {
                    40
                } else {
                    air
                }
            })
            .collect();
        let samples = volux_core::Samples::I16(volux_core::Buffer::owned(values));
        Grid::new([n; 3], [1.0; 3], [0.0; 3], samples)
            .unwrap()
            .into()
    }

    /// A CT opens as bone under faint skin, lit; other grids as `auto`, lit; a field with
    /// negative values that is not 16-bit, or an int16 volume without air, is not a CT.
    #[test]
    fn a_ct_first_looks_like_bone_and_other_data_like_auto() {
        for air in [-1024, -1000, -3024] {
            let v = ct(air);
            assert!(v.looks_like_ct(), "air {air}");
            let (tf, shade) = v.first_look().unwrap();
            assert!(shade);
            let tf = tf.resolved(v.range());
            assert_eq!(tf.tau_per_world(f64::from(air)), 0.0, "air is clear");
            assert!(tf.tau_per_world(1200.0) > 0.0, "bone shows");
        }
        assert!(!ct(0).looks_like_ct(), "no air");
        let g = grid();
        assert!(!g.looks_like_ct());
        let (tf, shade) = g.first_look().unwrap();
        assert!(shade);
        assert_eq!(tf, g.preset_tf("auto").unwrap());
        let m = g.to_tets().unwrap();
        assert!(!m.first_look().unwrap().1, "PT draws no gradient light");
    }

    #[test]
    fn auto_picks_the_renderer_of_each_kind_and_wrong_pairs_are_refused() {
        let g = grid();
        let m = g.to_tets().unwrap();
        assert_eq!(m.kind(), "tetrahedral mesh");
        assert!(matches!(
            Method::Auto.resolve(&g),
            Ok(Method::GridRaycast(_))
        ));
        assert!(matches!(
            Method::Auto.resolve(&m),
            Ok(Method::ProjectedTetrahedra(_))
        ));
        let pt = Method::ProjectedTetrahedra(PtSettings::default());
        let e = pt.resolve(&g).unwrap_err();
        assert_eq!(e.remedy(), Some(crate::error::Remedy::SplitIntoTets), "{e}");
        assert!(e.to_string().contains("Volume::to_tets"), "{e}");
        assert!(Method::GridRaycast(GridRaycast::default())
            .resolve(&m)
            .is_err());
        assert!(matches!(
            Method::raycast(&m, GridRaycast::default(), SegmentRule::Exact),
            Method::TetRaycast(SegmentRule::Exact)
        ));
    }

    #[test]
    fn slicing_is_named_kept_for_grids_and_refused_by_the_cpu_engine() {
        let g = grid();
        let slicing = Method::Slicing(SlicingSettings::default());
        assert_eq!(slicing.name(), "slicing");
        assert_eq!(slicing.resolve(&g).unwrap(), slicing);
        assert!(slicing.resolve(&g.to_tets().unwrap()).is_err());
        let json = serde_json::to_string(&slicing).unwrap();
        assert_eq!(json, r#"{"name":"slicing","settings":{"step":0.5}}"#);
        let e = crate::engine::create_renderer(&g, &slicing).err().unwrap();
        assert_eq!(e.remedy(), Some(crate::error::Remedy::GpuBackend), "{e}");
        assert!(e.to_string().contains("GPU method"), "{e}");
    }

    #[test]
    fn appearance_a_method_cannot_draw_is_refused() {
        let g = grid();
        let tf = g.preset_tf("grayscale").unwrap();
        let mip = Appearance {
            mip: true,
            ..Appearance::new(tf.clone())
        };
        let shaded = Appearance {
            shade_volume: true,
            ..Appearance::new(tf.clone())
        };
        let pt = Method::ProjectedTetrahedra(PtSettings::default());
        let tet = Method::TetRaycast(SegmentRule::Psi);
        let grid = Method::GridRaycast(GridRaycast::default());
        let e = pt.check_appearance(&mip).unwrap_err().to_string();
        assert!(e.contains("maximum intensity"), "{e}");
        assert!(tet.check_appearance(&mip).is_ok());
        let e = tet.check_appearance(&shaded).unwrap_err().to_string();
        assert!(e.contains("does not shade the volume"), "{e}");
        assert!(grid.check_appearance(&mip).is_ok());
        assert!(grid.check_appearance(&shaded).is_ok());
        let lit_mip = Appearance {
            shade_volume: true,
            ..mip.clone()
        };
        let e = grid.check_appearance(&lit_mip).unwrap_err().to_string();
        assert!(e.contains("unlit and without isosurfaces"), "{e}");
        assert!(pt.check_appearance(&Appearance::new(tf)).is_ok());
    }

    #[test]
    fn units_are_the_smallest_spacing_and_the_mesh_diagonal_share() {
        let g = grid();
        let Volume::Grid(grid) = &g else {
            unreachable!()
        };
        assert_eq!(g.unit_length(), grid.spacing().min_element());
        let m = g.to_tets().unwrap();
        assert!((m.unit_length() - g.bounds().diagonal() / 256.0).abs() < 1e-12);
        let tf = m.preset_tf("auto").unwrap();
        assert_eq!(tf.unit_length, m.unit_length());
    }

    #[test]
    fn opacity_scales_multiply_and_bad_scenes_are_refused() {
        let g = grid();
        let mut tf = g.preset_tf("grayscale").unwrap();
        tf.opacity_scale = 2.0;
        let camera = volux_core::CameraSpec::default()
            .resolve(&g.bounds())
            .unwrap();
        let mut scene = Scene::new(camera, 8, 8, tf);
        scene.appearance.opacity_scale = 1.5;
        assert_eq!(scene.appearance.effective_tf().opacity_scale, 3.0);
        assert!(scene.validate().is_ok());
        assert_eq!(scene.view.reduced(3).width, 3);
        let mut bad = scene.clone();
        bad.view.width = 0;
        assert!(bad.validate().is_err());
        let mut bad = scene.clone();
        bad.early_termination = Some(f32::NAN);
        assert!(bad.validate().is_err());
        let mut bad = scene.clone();
        bad.clip_planes = vec![ClipPlane {
            normal: glam::DVec3::new(0.0, 3.0, 0.0),
            offset: 0.0,
        }];
        assert!(bad.validate().is_err());
        let mut bad = scene;
        bad.appearance.opacity_scale = -1.0;
        assert!(bad.validate().is_err());
    }
}
