//! `volux help [TOPIC|COMMAND]`: the commands' help, and the JSON formats a user writes by
//! hand (transfer functions, cameras), with examples.
use clap::CommandFactory;

use super::common::CmdError;
use crate::cli::Cli;

/// The topics besides the commands.
pub const TOPICS: [(&str, &str); 2] = [("tf", TF_HELP), ("camera", CAMERA_HELP)];

/// Prints the help of `topic`: a format, a command, or the overview.
pub fn run(topic: Option<&str>) -> Result<(), CmdError> {
    let mut cli = Cli::command();
    let Some(topic) = topic else {
        cli.print_long_help()?;
        return Ok(());
    };
    if let Some((_, text)) = TOPICS.iter().find(|(name, _)| *name == topic) {
        out!("{text}")?;
        return Ok(());
    }
    match cli.find_subcommand_mut(topic) {
        Some(sub) => {
            let mut sub = sub.clone().bin_name(format!("volux {topic}"));
            sub.print_long_help()?;
            Ok(())
        }
        None => Err(format!(
            "no help on '{topic}': the topics are tf, camera and the commands ({})",
            Cli::command()
                .get_subcommands()
                .map(|c| c.get_name().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
        .into()),
    }
}

/// `volux help tf`.
const TF_HELP: &str = r#"Transfer functions (--tf PRESET|FILE, repeatable)

A transfer function gives each data value a colour and an extinction (absorption per unit
length); both are piecewise linear between control points.

  {
    "space": "value",
    "color": [[-600, 0.6, 0.35, 0.25], [300, 1.0, 0.9, 0.8]],
    "extinction": [[-600, 0.0], [-300, 0.15], [1500, 1.0]],
    "opacity_scale": 1.0,
    "unit_length": 1.0
  }

Fields (only "color" is required):
  space          "value" (default): positions are data values (Hounsfield units for CT);
                 "normalized": positions are 0..1 over the data's range.
  color          [[position, r, g, b], ...]: linear RGB in 0..1, sorted by position.
  extinction     [[position, tau], ...]: tau >= 0 per unit_length of distance.
  opacity        [[position, alpha], ...]: instead of "extinction", the opacity of a slab
                 opacity_step thick (alpha in 0..1); converted as tau = -ln(1 - alpha) / step.
  opacity_step   thickness that "opacity" refers to, in unit_length (default 1).
  opacity_scale  multiplies the extinction (default 1); --opacity-scale multiplies it again.
  unit_length    world length that tau refers to (default 1 world unit, e.g. 1 mm). Presets
                 use the volume's unit: a grid's smallest voxel spacing, a mesh's bounding-box
                 diagonal / 256, so a preset looks alike at any resolution.
Outside the first and last points, the end values hold.

Presets: auto (fitted to the histogram), grayscale, ct-bone, ct-skin, ct-soft-tissue (CT, in
Hounsfield units), mr-default, viridis, inferno, cool-warm (normalized). Start from one:
  volux tf show ct-skin > skin.json                 # edit, then --tf skin.json
  volux tf show auto --data head.nrrd > mine.json   # fitted to this file's values and voxels

Files from other programs are read too (told apart by extension and content):
  ParaView presets (.json with "RGBPoints", "Points"; ColorSpace RGB, HSV, Lab/CIELAB,
  Diverging or Step; Lab/CIEDE2000 is refused) and 3D Slicer volume properties (.vp).
  Opacity is per 1 world unit (neither file stores a unit distance), VTK's colour-space and
  midpoint/sharpness curves are followed within 1e-4; gradient opacity and shading are not
  applied (a warning says so). Examples: docs/examples/paraview-preset.json,
  docs/examples/paraview-cool-to-warm.json (ParaView's default map, Diverging) and
  docs/examples/slicer-volume-property.vp; `volux tf show FILE` prints one as Volux JSON.

Layers: repeat --tf to add transfer functions; NAME:WEIGHT multiplies a layer's extinction.
Extinctions add, colours mix weighted by extinction:
  volux render ct.nii.gz --tf ct-bone --tf ct-skin:0.2 --shade     # bone under faint skin
"#;

/// `volux help camera`.
const CAMERA_HELP: &str = r#"Cameras (--camera FILE.json, or the orbit options of `volux render`)

Orbit form: angles around the centre of what is framed.
  {"projection": "perspective", "fov_y_deg": 30, "azimuth": 30, "elevation": 15, "zoom": 1.2}
Look-at form: positions in world units (the data's coordinates, e.g. mm). The world is
LPS, as DICOM and ITK (+x the patient's left, +y posterior, +z superior); scans that carry
an orientation (NIfTI, DICOM, NRRD, MetaImage, VTI) are placed in it by their direction
matrix, so a camera means the same view whichever way the slices were stored.
  {"projection": "orthographic", "eye": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1]}

Fields (all optional):
  projection   "perspective" (default) or "orthographic".
  fov_y_deg    vertical field of view in degrees (default 30).
  eye          [x, y, z]: camera position (look-at form).
  target       [x, y, z]: the point looked at (default: the centre of the framed box).
  up           [x, y, z]: up direction (default [0, 0, 1]; [0, 0, -1] for scans stored head
               down).
  azimuth      degrees around the up axis (default 0: the camera on -y looking along +y).
  elevation    degrees above the horizontal plane (default 0).
  distance     from the target (default: the framed box's bounding sphere fits the view).
  zoom         magnification (default 1; 2 shows the data twice as large).
A file with only a few slices in z (a thin slab) and no angles is seen along z.

Without --camera, `volux render` builds the orbit camera from --view, --azimuth,
--elevation (degrees, turning from the view), --up X,Y,Z (turns the image about the view's
direction), --zoom and --orthographic, and
fits the framed box to the image. --frame visible (default) frames what the transfer
function and isosurfaces show; --frame all the whole bounding box. A camera file is used as
written: its missing fields fit the framed box.

Named views speak of the patient, as 3D Slicer does: the view from the LEFT puts the camera
on the patient's left and shows the patient's left side. The world is LPS millimetres (+x
the patient's left, +y posterior, +z superior) and scans are placed by their orientation
(NIfTI sform/qform, DICOM ImageOrientationPatient, NRRD space directions).
  left, right            the camera on +x, -x; superior up.
  anterior (front)       the camera on -y, facing the face; superior up.
  posterior (back)       the camera on +y; superior up.
  superior (top)         the camera above the head (+z); anterior up.
  inferior (bottom)      the camera at the feet (-z); anterior up: the radiological axial
                         view, the patient's left on the image's right.
  +x -x +y -y +z -z      axis views for data without a patient: z up (y up for +z, -z).
                         Write --view=-x (a value starting with '-').
"#;
