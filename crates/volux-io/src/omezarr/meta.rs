//! OME-NGFF `multiscales` metadata: version 0.4 (in `.zattrs` of a Zarr v2 group) and 0.5
//! (under `attributes.ome` of a Zarr v3 `zarr.json`), parsed into [`MultiscaleMeta`], and the
//! spacing and origin each level gets from its coordinate transformations.
use std::path::Path;

use serde_json::{Map, Value};

use crate::error::{ErrorKind, ReadError, Result};

/// Metadata files larger than this are refused (chunk ranges of a million chunks fit).
const METADATA_LIMIT: u64 = 256 << 20;

/// One axis of an NGFF image.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Its name (`x`, `y`, `z`, `c`, `t`).
    pub name: String,
    /// Its type (`space`, `time`, `channel`), when given.
    pub kind: Option<String>,
    /// Its unit (`micrometer`, `millimeter`), when given.
    pub unit: Option<String>,
}

impl Axis {
    /// Whether the axis is spatial: typed `space`, or untyped and named `x`, `y` or `z`.
    pub fn is_space(&self) -> bool {
        match &self.kind {
            Some(k) => k == "space",
            None => matches!(self.name.as_str(), "x" | "y" | "z"),
        }
    }
}

/// One level (dataset) of a multiscale image: its array path and its transform.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetMeta {
    /// The array's path relative to the group.
    pub path: String,
    /// Scale per array axis (the dataset's, times the multiscale's).
    pub scale: Vec<f64>,
    /// Translation per array axis (the dataset's scaled by the multiscale's scale, plus the
    /// multiscale's translation).
    pub translation: Vec<f64>,
}

/// One entry of `multiscales`.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiscaleMeta {
    /// Its name, when given.
    pub name: Option<String>,
    /// The NGFF version (`0.4`, `0.5`), when given.
    pub version: Option<String>,
    /// The axes, slowest first (as the arrays are indexed).
    pub axes: Vec<Axis>,
    /// The levels, full resolution first.
    pub datasets: Vec<DatasetMeta>,
}

/// A group's metadata: the Zarr format (2 or 3) and its attributes.
#[derive(Clone, Debug)]
pub struct GroupAttributes {
    /// 2 or 3.
    pub zarr_format: u8,
    /// The group's attributes (`.zattrs`, or `attributes` of `zarr.json`).
    pub attributes: Map<String, Value>,
    /// Whether the node is an array rather than a group.
    pub is_array: bool,
}

fn header(path: &Path, msg: impl Into<String>) -> ReadError {
    ReadError::new(path, ErrorKind::Header(msg.into()))
}

/// Reads and parses a JSON metadata file, bounded in size.
pub fn read_json(path: &Path) -> Result<Value> {
    let bytes = crate::util::read_regular(path, METADATA_LIMIT)?;
    serde_json::from_slice(&bytes).map_err(|e| header(path, format!("invalid JSON: {e}")))
}

/// Reads the node metadata of the Zarr group or array at `dir` (v3 `zarr.json` first, then
/// v2 `.zgroup`/`.zarray` with `.zattrs`); `None` when `dir` holds neither.
pub fn read_node(dir: &Path) -> Result<Option<GroupAttributes>> {
    let v3 = dir.join("zarr.json");
    if v3.is_file() {
        let json = read_json(&v3)?;
        let node = json.get("node_type").and_then(Value::as_str).unwrap_or("");
        if json.get("zarr_format").and_then(Value::as_u64) != Some(3) {
            return Err(header(&v3, "zarr.json without \"zarr_format\": 3"));
        }
        let attributes = match json.get("attributes") {
            Some(Value::Object(m)) => m.clone(),
            None | Some(Value::Null) => Map::new(),
            Some(_) => return Err(header(&v3, "\"attributes\" is not an object")),
        };
        return Ok(Some(GroupAttributes {
            zarr_format: 3,
            attributes,
            is_array: node == "array",
        }));
    }
    let (zattrs, zarray, zgroup) = (
        dir.join(".zattrs"),
        dir.join(".zarray"),
        dir.join(".zgroup"),
    );
    if !(zattrs.is_file() || zarray.is_file() || zgroup.is_file()) {
        return Ok(None);
    }
    let attributes = if zattrs.is_file() {
        match read_json(&zattrs)? {
            Value::Object(m) => m,
            _ => return Err(header(&zattrs, "not a JSON object")),
        }
    } else {
        Map::new()
    };
    Ok(Some(GroupAttributes {
        zarr_format: 2,
        attributes,
        is_array: zarray.is_file(),
    }))
}

/// The `multiscales` list of a group's attributes: under `ome` (NGFF 0.5) or at the top
/// (0.4 and earlier); `None` when absent.
pub fn multiscales_value(attrs: &Map<String, Value>) -> Option<(&Vec<Value>, Option<&str>)> {
    if let Some(ome) = attrs.get("ome").and_then(Value::as_object) {
        if let Some(list) = ome.get("multiscales").and_then(Value::as_array) {
            return Some((list, ome.get("version").and_then(Value::as_str)));
        }
    }
    attrs
        .get("multiscales")
        .and_then(Value::as_array)
        .map(|l| (l, None))
}

/// Scale and translation of a `coordinateTransformations` list (identity when absent), for
/// `n` axes.
fn transforms(path: &Path, v: Option<&Value>, n: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut scale = vec![1.0; n];
    let mut translation = vec![0.0; n];
    let Some(v) = v else {
        return Ok((scale, translation));
    };
    let list = v
        .as_array()
        .ok_or_else(|| header(path, "coordinateTransformations is not a list"))?;
    for t in list {
        let kind = t.get("type").and_then(Value::as_str).unwrap_or("");
        let numbers = |key: &str| -> Result<Vec<f64>> {
            if t.get("path").is_some() {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!(
                        "a {kind} transform stored in a file (\"path\")"
                    )),
                ));
            }
            let vals: Option<Vec<f64>> = t
                .get(key)
                .and_then(Value::as_array)
                .map(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
                .unwrap_or(None);
            match vals {
                Some(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
                _ => Err(header(
                    path,
                    format!("a {kind} transform needs {n} finite numbers under \"{key}\""),
                )),
            }
        };
        match kind {
            "scale" => {
                let s = numbers("scale")?;
                for a in 0..n {
                    scale[a] *= s[a];
                    translation[a] *= s[a];
                }
            }
            "translation" => {
                let t = numbers("translation")?;
                for a in 0..n {
                    translation[a] += t[a];
                }
            }
            "identity" => {}
            other => {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!("coordinate transformation \"{other}\"")),
                ))
            }
        }
    }
    Ok((scale, translation))
}

/// Parses one `multiscales` entry; `ndim` is the dimensionality of its first array when the
/// entry has no `axes` (NGFF before 0.4), `path` names the metadata file in errors.
pub fn parse_multiscale(
    path: &Path,
    v: &Value,
    version: Option<&str>,
    ndim_hint: impl Fn(&str) -> Result<usize>,
) -> Result<MultiscaleMeta> {
    let datasets_v = v
        .get("datasets")
        .and_then(Value::as_array)
        .filter(|d| !d.is_empty())
        .ok_or_else(|| header(path, "multiscales entry without datasets"))?;
    let first_path = datasets_v[0]
        .get("path")
        .and_then(Value::as_str)
        .ok_or_else(|| header(path, "dataset without a \"path\""))?;
    let axes: Vec<Axis> = match v.get("axes").and_then(Value::as_array) {
        Some(list) => list
            .iter()
            .map(|a| match a {
                Value::String(s) => Ok(Axis {
                    name: s.clone(),
                    kind: None,
                    unit: None,
                }),
                Value::Object(o) => Ok(Axis {
                    name: o
                        .get("name")
                        .and_then(Value::as_str)
                        .ok_or_else(|| header(path, "an axis without a name"))?
                        .to_string(),
                    kind: o.get("type").and_then(Value::as_str).map(str::to_string),
                    unit: o.get("unit").and_then(Value::as_str).map(str::to_string),
                }),
                _ => Err(header(path, "an axis is neither a name nor an object")),
            })
            .collect::<Result<_>>()?,
        None => {
            let n = ndim_hint(first_path)?;
            let names = ["t", "c", "z", "y", "x"];
            names[5usize.saturating_sub(n)..]
                .iter()
                .map(|s| Axis {
                    name: s.to_string(),
                    kind: None,
                    unit: None,
                })
                .collect()
        }
    };
    let n = axes.len();
    let (ms_scale, ms_translation) = transforms(path, v.get("coordinateTransformations"), n)?;
    let datasets = datasets_v
        .iter()
        .map(|d| {
            let p = d
                .get("path")
                .and_then(Value::as_str)
                .ok_or_else(|| header(path, "dataset without a \"path\""))?;
            let (s, t) = transforms(path, d.get("coordinateTransformations"), n)?;
            Ok(DatasetMeta {
                path: p.to_string(),
                scale: (0..n).map(|a| s[a] * ms_scale[a]).collect(),
                translation: (0..n)
                    .map(|a| t[a] * ms_scale[a] + ms_translation[a])
                    .collect(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(MultiscaleMeta {
        name: v.get("name").and_then(Value::as_str).map(str::to_string),
        version: v
            .get("version")
            .and_then(Value::as_str)
            .or(version)
            .map(str::to_string),
        axes,
        datasets,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_and_multiscale_transforms_compose() {
        let v: Value = serde_json::json!({
            "axes": [{"name": "z", "type": "space", "unit": "micrometer"},
                     {"name": "y", "type": "space"}, {"name": "x", "type": "space"}],
            "datasets": [{"path": "0", "coordinateTransformations": [
                {"type": "scale", "scale": [2.0, 1.0, 0.5]},
                {"type": "translation", "translation": [1.0, 2.0, 3.0]}]}],
            "coordinateTransformations": [{"type": "scale", "scale": [10.0, 1.0, 1.0]},
                {"type": "translation", "translation": [0.0, 0.0, -1.0]}]
        });
        let m = parse_multiscale(Path::new("t"), &v, Some("0.5"), |_| Ok(3)).unwrap();
        assert_eq!(m.datasets[0].scale, vec![20.0, 1.0, 0.5]);
        assert_eq!(m.datasets[0].translation, vec![10.0, 2.0, 2.0]);
        assert_eq!(m.axes[0].unit.as_deref(), Some("micrometer"));
        assert_eq!(m.version.as_deref(), Some("0.5"));
    }
}
