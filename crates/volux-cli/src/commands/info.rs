//! `volux info`.
use std::path::Path;

use serde_json::json;
use volux_core::histogram::Histogram;
use volux_core::{Grid, TetMesh};
use volux_io::{Dataset, Format};

use super::common::CmdError;
use crate::cli::LoadArgs;
use crate::messages::sanitize;
use crate::numbers::human;
use volux_core::units::format_bytes;

/// Describes the file at `path`.
pub fn run(path: &Path, as_json: bool, args: &LoadArgs, show: bool) -> Result<(), CmdError> {
    let (data, format) = super::common::load(path, args, show)?;
    let value = match &data {
        Dataset::Grid(g) => grid_json(g, format),
        Dataset::Mesh(m) => mesh_json(m, format),
        _ => return Err("unsupported dataset kind".into()),
    };
    if as_json {
        outln!("{}", serde_json::to_string(&value)?)?;
    } else {
        print_text(path, &value)?;
    }
    Ok(())
}

fn grid_json(g: &Grid, format: Format) -> serde_json::Value {
    let h = Histogram::of_grid(g, 256);
    let b = g.bounds();
    let d = g.direction();
    json!({
        "kind": "grid",
        "format": format.name(),
        "dims": g.dims(),
        "spacing": g.spacing().to_array(),
        "origin": g.origin().to_array(),
        // The unit of spacing, origin and bounds (mm unless the file says otherwise).
        "units": g.unit(),
        // LPS world (DICOM/ITK); the letters each index axis points towards, and the
        // direction matrix's columns (the world directions of i, j, k).
        "orientation": g.orientation_code(),
        "direction": [d.x_axis.to_array(), d.y_axis.to_array(), d.z_axis.to_array()],
        "bounds": [b.min.to_array(), b.max.to_array()],
        "dtype": g.scalar_type().name(),
        "range": g.range(),
        "histogram": {
            "p1": h.quantile(0.01), "p50": h.quantile(0.5), "p99": h.quantile(0.99),
            "mode": h.mode(), "sparkline": sparkline(&h, 32),
        },
        "memory_bytes": g.memory_bytes(),
        "memory_mapped": g.samples().is_mapped(),
        "notes": g.notes(),
        // Axes beyond x, y, z (time, b-values, components, colour): what the file holds
        // besides the volume read, and which option chooses among them.
        "volumes": g.extra_axes().iter().map(|a| json!({
            "kind": a.kind, "len": a.len, "chosen": a.chosen, "option": a.kind.option(),
            "values": a.values, "meaning": a.meaning, "text": a.describe(),
        })).collect::<Vec<_>>(),
    })
}

fn mesh_json(m: &TetMesh, format: Format) -> serde_json::Value {
    let b = m.bounds();
    json!({
        "kind": "mesh",
        "format": format.name(),
        "vertices": m.positions().len(),
        "tets": m.tets().len(),
        "range": m.range(),
        "bounds": [b.min.to_array(), b.max.to_array()],
        "boundary_faces": m.boundary_faces().len(),
        "validation": m.report(),
        "bytes_per_tet": m.bytes_per_tet(),
        "notes": m.notes(),
    })
}

/// A one-line histogram made of block characters (log-scaled counts).
fn sparkline(h: &Histogram, width: usize) -> String {
    const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];
    let per = h.counts.len().div_ceil(width);
    let sums: Vec<f64> = h
        .counts
        .chunks(per)
        .map(|c| (c.iter().sum::<u64>() as f64 + 1.0).ln())
        .collect();
    let max = sums.iter().cloned().fold(0.0, f64::max).max(1e-9);
    sums.iter()
        .map(|s| BARS[((s / max) * 7.0).round() as usize])
        .collect()
}

/// The order people read a description in: what the file is first, then its shape, values
/// and memory (keys not listed follow alphabetically).
const ORDER: [&str; 24] = [
    "format",
    "kind",
    "dims",
    "levels",
    "chunk",
    "codec",
    "vertices",
    "tets",
    "dtype",
    "spacing",
    "origin",
    "units",
    "orientation",
    "direction",
    "bounds",
    "range",
    "volumes",
    "axes",
    "histogram",
    "boundary_faces",
    "validation",
    "memory_bytes",
    "memory_mapped",
    "bytes_per_tet",
];

/// Prints a description for people, keys in [`ORDER`].
pub(super) fn print_text(path: &Path, v: &serde_json::Value) -> std::io::Result<()> {
    outln!("{}", path.display())?;
    let Some(obj) = v.as_object() else {
        return Ok(());
    };
    let rank = |k: &str| ORDER.iter().position(|o| *o == k).unwrap_or(ORDER.len());
    let mut keys: Vec<&String> = obj.keys().collect();
    keys.sort_by_key(|k| (rank(k), k.as_str()));
    for k in keys {
        let val = &obj[k.as_str()];
        match val {
            serde_json::Value::Array(a) if k == "levels" => {
                outln!("  {k:<15} {}", a.len())?;
                for l in a {
                    outln!("    {}", sanitize(l.as_str().unwrap_or_default()))?;
                }
            }
            serde_json::Value::Array(a) if k == "volumes" => {
                for axis in a {
                    outln!(
                        "  {:<15} {}",
                        "volumes",
                        sanitize(axis["text"].as_str().unwrap_or_default())
                    )?;
                }
            }
            serde_json::Value::Array(a) if k == "notes" => {
                for n in a {
                    outln!("  note: {}", sanitize(n.as_str().unwrap_or_default()))?;
                }
            }
            _ if k == "memory_bytes" => {
                outln!("  {k:<15} {}", format_bytes(val.as_u64().unwrap_or(0)))?
            }
            _ => outln!("  {k:<15} {}", sanitize(&plain(val)))?,
        }
    }
    Ok(())
}

/// A value for people: numbers rounded to five significant digits, lists and objects on
/// one line (full precision stays in `--json`).
fn plain(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => n.as_f64().map_or_else(|| n.to_string(), human),
        serde_json::Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(plain).collect();
            format!("[{}]", parts.join(", "))
        }
        serde_json::Value::Object(o) => {
            let parts: Vec<String> = o.iter().map(|(k, v)| format!("{k}={}", plain(v))).collect();
            parts.join("  ")
        }
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numbers::human;

    #[test]
    fn numbers_are_rounded_for_people() {
        assert_eq!(human(-1000.50390625), "-1000.5");
        assert_eq!(human(0.19259999692440033), "0.1926");
        assert_eq!(human(244.042956), "244.04");
        assert_eq!(human(-1024.0), "-1024");
        assert_eq!(human(0.0009570312), "0.00095703");
        let v = serde_json::json!({"mode": -1000.50390625, "p1": 15.3359375});
        assert_eq!(plain(&v), "mode=-1000.5  p1=15.336");
    }
}
