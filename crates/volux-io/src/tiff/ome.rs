//! OME-TIFF metadata: the OME-XML document (OME Data Model, schema 2016-06) in the first
//! page's `ImageDescription`.
//!
//! From the first `<Image>`'s `<Pixels>`: `SizeX/Y/Z/C/T`, `Type` (`int8`, `uint8`, `int16`,
//! `uint16`, `int32`, `uint32`, `float`, `double`), `DimensionOrder` (`XYZCT`, `XYCZT`, ...: the three letters after `XY`
//! run from fastest to slowest, so for `XYZCT` plane (z, c, t) is `z + Z * (c + C * t)`),
//! `PhysicalSizeX/Y/Z` with `PhysicalSizeXUnit`... (default `µm`; converted to micrometres).
//! `<TiffData IFD= FirstZ= FirstC= FirstT= PlaneCount=>` elements map planes to pages
//! (without any, plane i is page i; `PlaneCount` defaults to 1 when `IFD` is given, else to
//! all planes). RGB pages hold 3 of the `SizeC` samples each (`<Channel SamplesPerPixel="3">`):
//! their planes are counted with `SizeC / 3` channels. `TimeIncrement` (with its unit, default
//! seconds) gives the time axis its step. Only single-file OME-TIFF is read: a `<UUID FileName=>` naming another file is
//! refused.
use std::collections::HashMap;
use std::path::Path;

use volux_core::volume_axes::{AxisKind, ExtraAxis};

use crate::error::{ErrorKind, ReadError, Result};
use crate::vtk_xml::tree::{self, Elem};

use super::layout::{choose, micrometres_per, positive, Layout};
use super::pages::{PageInfo, Photometric, Stored};

/// Whether `desc` is OME-XML (it starts with an XML declaration or `<OME`, and names `<OME`).
pub fn is_ome(desc: &str) -> bool {
    let d = desc.trim_start();
    (d.starts_with("<?xml") || d.starts_with("<OME")) && d.contains("<OME")
}

/// The element name without its namespace prefix.
fn local(name: &str) -> &str {
    name.rsplit(':').next().unwrap_or(name)
}

/// The first descendant of `e` named `name` (depth first).
fn find<'a>(e: &'a Elem, name: &str) -> Option<&'a Elem> {
    e.children.iter().find_map(|c| {
        (local(&c.name) == name)
            .then_some(c)
            .or_else(|| find(c, name))
    })
}

/// The `<Pixels>` of an OME-XML document, as Volux uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct Pixels {
    /// SizeX, SizeY, SizeZ, SizeC, SizeT.
    pub size: [usize; 5],
    /// `Type`.
    pub ty: String,
    /// `DimensionOrder`.
    pub order: String,
    /// `PhysicalSizeX/Y/Z` and their units (default `µm`).
    pub physical: [Option<(f64, String)>; 3],
    /// TiffData: (IFD, FirstZ, FirstC, FirstT, PlaneCount); `None` where absent.
    pub tiff_data: Vec<[Option<usize>; 5]>,
    /// How many `<Image>`s the document holds.
    pub images: usize,
    /// `TimeIncrement` and `TimeIncrementUnit` (default `s`).
    pub time_increment: Option<(f64, String)>,
}

/// Parses the OME-XML `desc` of `path`.
pub fn parse(path: &Path, desc: &str) -> Result<Pixels> {
    let err = |m: String| ReadError::new(path, ErrorKind::Header(format!("OME-XML: {m}")));
    let root = tree::parse(desc.as_bytes()).map_err(err)?;
    let ome = find(&root, "OME").ok_or_else(|| err("no <OME> element".into()))?;
    let images = ome
        .children
        .iter()
        .filter(|c| local(&c.name) == "Image")
        .count();
    let px = find(ome, "Pixels").ok_or_else(|| err("no <Pixels> element".into()))?;
    let attr = |k: &str| px.attrs.iter().find(|(n, _)| local(n) == k).map(|(_, v)| v);
    let size = |k: &str, required: bool| -> Result<usize> {
        match attr(k) {
            Some(v) => v
                .trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| err(format!("{k}=\"{v}\" is not a positive count"))),
            None if required => Err(err(format!("<Pixels> has no {k}"))),
            None => Ok(1),
        }
    };
    let size = [
        size("SizeX", true)?,
        size("SizeY", true)?,
        size("SizeZ", false)?,
        size("SizeC", false)?,
        size("SizeT", false)?,
    ];
    let order = attr("DimensionOrder")
        .cloned()
        .unwrap_or_else(|| "XYZCT".into());
    let o = order.to_ascii_uppercase();
    let valid =
        o.len() == 5 && o.starts_with("XY") && ['Z', 'C', 'T'].iter().all(|c| o[2..].contains(*c));
    if !valid {
        return Err(err(format!(
            "DimensionOrder=\"{order}\" is not XY followed by Z, C and T in some order"
        )));
    }
    let physical = ["X", "Y", "Z"].map(|a| {
        let v = attr(&format!("PhysicalSize{a}"))?
            .trim()
            .parse::<f64>()
            .ok()?;
        let unit = attr(&format!("PhysicalSize{a}Unit")).map_or("µm".to_string(), Clone::clone);
        Some((v, unit))
    });
    let mut tiff_data = Vec::new();
    for td in px.children.iter().filter(|c| local(&c.name) == "TiffData") {
        if let Some(uuid) = td.children.iter().find(|c| local(&c.name) == "UUID") {
            let named = uuid.attr("FileName").unwrap_or("");
            let here = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            if !named.is_empty() && named != here {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!(
                        "multi-file OME-TIFF (planes in '{named}'); Volux reads single-file \
                         OME-TIFF"
                    )),
                ));
            }
        }
        let num = |k: &str| -> Result<Option<usize>> {
            td.attr(k)
                .map(|v| {
                    v.trim()
                        .parse::<usize>()
                        .map_err(|_| err(format!("TiffData {k}=\"{v}\" is not a count")))
                })
                .transpose()
        };
        tiff_data.push([
            num("IFD")?,
            num("FirstZ")?,
            num("FirstC")?,
            num("FirstT")?,
            num("PlaneCount")?,
        ]);
    }
    let time_increment = attr("TimeIncrement")
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(|v| {
            let unit = attr("TimeIncrementUnit").map_or("s".to_string(), Clone::clone);
            (v, unit)
        });
    Ok(Pixels {
        size,
        ty: attr("Type").cloned().unwrap_or_default(),
        order: o,
        physical,
        tiff_data,
        images,
        time_increment,
    })
}

impl Pixels {
    /// The plane index of (z, c, t) in `DimensionOrder`, with `sc` channel planes.
    fn plane(&self, zct: [usize; 3], sc: usize) -> usize {
        let (mut index, mut stride) = (0, 1);
        for letter in self.order[2..].chars() {
            let (i, n) = match letter {
                'Z' => (zct[0], self.size[2]),
                'C' => (zct[1], sc),
                _ => (zct[2], self.size[4]),
            };
            index = i.saturating_mul(stride).saturating_add(index);
            stride = stride.saturating_mul(n);
        }
        index
    }

    /// The page of every plane, from the `TiffData` elements (plane i on page i without
    /// them). The caller has checked that the planes are at most the pages.
    fn pages(&self, planes: usize, sc: usize) -> HashMap<usize, usize> {
        if self.tiff_data.is_empty() {
            return (0..planes).map(|p| (p, p)).collect();
        }
        let mut map = HashMap::new();
        for &[ifd, z, c, t, count] in &self.tiff_data {
            let first = self.plane([z.unwrap_or(0), c.unwrap_or(0), t.unwrap_or(0)], sc);
            let count = count.unwrap_or(if ifd.is_some() { 1 } else { planes });
            let ifd = ifd.unwrap_or(0);
            for k in 0..count.min(planes.saturating_sub(first)) {
                map.insert(first + k, ifd.saturating_add(k));
            }
        }
        map
    }

    /// The pages of channel `channel` and timepoint `timepoint`, and the spacing, for a file
    /// of `pages` pages whose first page is `first`.
    pub fn layout(
        &self,
        path: &Path,
        pages: usize,
        first: &PageInfo,
        channel: usize,
        timepoint: usize,
    ) -> Result<Layout> {
        let invalid =
            |m: String| ReadError::new(path, ErrorKind::Invalid(format!("OME-TIFF: {m}")));
        let [sx, sy, sz, size_c, st] = self.size;
        let (width, height) = (first.width, first.height);
        if (sx, sy) != (width, height) {
            return Err(invalid(format!(
                "OME-XML says {sx}x{sy} pixels, the first page is {width}x{height}"
            )));
        }
        let expected = match self.ty.to_ascii_lowercase().as_str() {
            "int8" => Some(Stored::I8),
            "uint8" => Some(Stored::U8),
            "int16" => Some(Stored::I16),
            "uint16" => Some(Stored::U16),
            "int32" => Some(Stored::I32),
            "uint32" => Some(Stored::U32),
            "float" => Some(Stored::F32),
            "double" => Some(Stored::F64),
            _ => None,
        };
        if expected.is_some_and(|e| e != first.stored) {
            return Err(invalid(format!(
                "OME-XML says Type=\"{}\", the pages hold {}",
                self.ty,
                first.stored.name()
            )));
        }
        // An RGB page holds 3 of the SizeC samples.
        let per_page = if matches!(first.photometric, Photometric::Rgb | Photometric::YCbCr) {
            3
        } else {
            1
        };
        if size_c % per_page != 0 {
            return Err(invalid(format!(
                "OME-XML says SizeC=\"{size_c}\", but the pages hold {per_page} samples each"
            )));
        }
        let sc = size_c / per_page;
        let channel = choose(path, "channel", channel, sc)?;
        let timepoint = choose(path, "timepoint", timepoint, st)?;
        let planes = sz.saturating_mul(sc).saturating_mul(st);
        if planes > pages {
            return Err(invalid(format!(
                "OME-XML declares {sz} z x {sc} c x {st} t = {planes} planes, but the file has \
                 {pages} pages"
            )));
        }
        let map = self.pages(planes, sc);
        let ifds = (0..sz)
            .map(|z| {
                map.get(&self.plane([z, channel, timepoint], sc))
                    .copied()
                    .ok_or_else(|| {
                        invalid(format!(
                            "no TiffData gives the page of z {z}, channel {channel}, timepoint \
                             {timepoint}"
                        ))
                    })
            })
            .collect::<Result<Vec<_>>>()?;
        let mut notes = Vec::new();
        if sc > 1 || st > 1 {
            notes.push(format!(
                "OME-TIFF of {sc} channel(s), {sz} z, {st} timepoint(s) ({}): channel \
                 {channel}, timepoint {timepoint} read",
                self.order
            ));
        }
        if self.images > 1 {
            notes.push(format!(
                "the OME-XML describes {} images; the first is read",
                self.images
            ));
        }
        let mut axes = Vec::new();
        if sc > 1 {
            axes.push(ExtraAxis::new(AxisKind::Channel, sc, Some(channel)));
        }
        if st > 1 {
            let mut time = ExtraAxis::new(AxisKind::Time, st, Some(timepoint));
            if let Some((v, unit)) = &self.time_increment {
                time = time.with_meaning(format!("step {v} {unit}"));
            }
            axes.push(time);
        }
        let (spacing, spacing_note) = self.spacing(path)?;
        Ok(Layout {
            ifds,
            spacing,
            spacing_note,
            flavour: "OME",
            notes,
            axes,
        })
    }

    /// Spacing from `PhysicalSizeX/Y/Z`, in micrometres when every unit given converts.
    fn spacing(&self, path: &Path) -> Result<([f64; 3], String)> {
        if self.physical.iter().all(Option::is_none) {
            return Ok((
                [1.0; 3],
                "no spacing information (OME-XML without PhysicalSize): spacing 1".into(),
            ));
        }
        let mut out = [1.0; 3];
        let mut units = Vec::new();
        let mut converted = true;
        for (a, p) in self.physical.iter().enumerate() {
            if let Some((v, unit)) = p {
                let v = positive(path, &format!("OME PhysicalSize{}", ["X", "Y", "Z"][a]), *v)?;
                match micrometres_per(unit) {
                    Some(f) => out[a] = v * f,
                    None => {
                        out[a] = v;
                        converted = false;
                    }
                }
                if !units.contains(unit) {
                    units.push(unit.clone());
                }
            }
        }
        let missing: Vec<&str> = ["x", "y", "z"]
            .iter()
            .zip(&self.physical)
            .filter(|(_, p)| p.is_none())
            .map(|(a, _)| *a)
            .collect();
        let missing = if missing.is_empty() {
            String::new()
        } else {
            format!(" ({} not given: 1)", missing.join(", "))
        };
        let units = units.join(", ");
        let note = if converted {
            format!("spacing in micrometres, from OME PhysicalSize ({units}){missing}")
        } else {
            format!("spacing from OME PhysicalSize in its units ({units}), not converted{missing}")
        };
        Ok((out, note))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const XML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<OME xmlns="http://www.openmicroscopy.org/Schemas/OME/2016-06"><Image ID="Image:0"><Pixels ID="Pixels:0" DimensionOrder="XYCZT" Type="uint16" SizeX="4" SizeY="3" SizeZ="5" SizeC="2" SizeT="1" PhysicalSizeX="0.2" PhysicalSizeY="0.2" PhysicalSizeZ="1.5" PhysicalSizeZUnit="nm"><Channel ID="Channel:0:0"/><TiffData IFD="0" PlaneCount="10"/></Pixels></Image></OME>"#;

    /// A 4 x 3 page of `stored` samples, grayscale or RGB.
    fn page(stored: Stored, rgb: bool) -> PageInfo {
        PageInfo {
            width: 4,
            height: 3,
            stored,
            photometric: if rgb {
                Photometric::Rgb
            } else {
                Photometric::MinIsBlack
            },
            decoded_samples: if rgb { 3 } else { 1 },
            extra: 0,
            planar: false,
            compression: 1,
            colormap: None,
        }
    }

    #[test]
    fn dimension_order_picks_the_pages() {
        let p = Path::new("a.ome.tif");
        assert!(is_ome(XML));
        let px = parse(p, XML).unwrap();
        assert_eq!(px.size, [4, 3, 5, 2, 1]);
        let gray = page(Stored::U16, false);
        let l = px.layout(p, 10, &gray, 1, 0).unwrap();
        assert_eq!(l.ifds, vec![1, 3, 5, 7, 9]);
        assert!((l.spacing[2] - 0.0015).abs() < 1e-12);
        assert_eq!(l.axes, vec![ExtraAxis::new(AxisKind::Channel, 2, Some(1))]);
        let e = px.layout(p, 10, &gray, 0, 1).unwrap_err();
        assert!(e.to_string().contains("timepoint 1 does not exist"), "{e}");
        let e = px.layout(p, 9, &gray, 0, 0).unwrap_err();
        assert!(e.to_string().contains("9 pages"), "{e}");
        let e = px
            .layout(p, 10, &page(Stored::F32, false), 0, 0)
            .unwrap_err();
        assert!(e.to_string().contains("float32"), "{e}");
    }

    #[test]
    fn rgb_pages_hold_three_of_size_c() {
        let p = Path::new("a.ome.tif");
        let xml = XML
            .replace(
                "DimensionOrder=\"XYCZT\"",
                "DimensionOrder=\"XYCZT\" TimeIncrement=\"2.5\"",
            )
            .replace("SizeC=\"2\" SizeT=\"1\"", "SizeC=\"3\" SizeT=\"2\"");
        let px = parse(p, &xml).unwrap();
        let l = px.layout(p, 10, &page(Stored::U16, true), 0, 1).unwrap();
        assert_eq!(l.ifds, vec![5, 6, 7, 8, 9]);
        assert_eq!(l.axes.len(), 1);
        assert_eq!(
            l.axes[0].describe(),
            "time: 2 volumes (timepoint 1 read), step 2.5 s"
        );
        let e = px
            .layout(p, 10, &page(Stored::U16, true), 1, 0)
            .unwrap_err();
        assert!(e.to_string().contains("channel 1 does not exist"), "{e}");
    }

    #[test]
    fn other_files_are_refused() {
        let xml = XML.replace(
            r#"<TiffData IFD="0" PlaneCount="10"/>"#,
            r#"<TiffData IFD="0" PlaneCount="10"><UUID FileName="b.ome.tif">urn:uuid:1</UUID></TiffData>"#,
        );
        let e = parse(Path::new("a.ome.tif"), &xml).unwrap_err();
        assert!(e.to_string().contains("multi-file"), "{e}");
    }
}
