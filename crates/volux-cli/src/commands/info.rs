//! `volux info`.
use std::path::Path;

use serde_json::json;
use volux_core::histogram::Histogram;
use volux_core::{Grid, TetMesh};
use volux_io::{Dataset, Format};

use super::common::CmdError;
use crate::cli::LoadArgs;

pub fn run(path: &Path, as_json: bool, args: &LoadArgs, show: bool) -> Result<(), CmdError> {
    let (data, format) = super::common::load(path, args, show)?;
    let value = match &data {
        Dataset::Grid(g) => grid_json(g, format),
        Dataset::Mesh(m) => mesh_json(m, format),
        _ => return Err("unsupported dataset kind".into()),
    };
    if as_json {
        println!("{}", serde_json::to_string(&value)?);
    } else {
        print_text(path, &value);
    }
    Ok(())
}

fn grid_json(g: &Grid, format: Format) -> serde_json::Value {
    let h = Histogram::of_grid(g, 256);
    let b = g.bounds();
    json!({
        "kind": "grid",
        "format": format.name(),
        "dims": g.dims(),
        "spacing": g.spacing().to_array(),
        "origin": g.origin().to_array(),
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

fn print_text(path: &Path, v: &serde_json::Value) {
    println!("{}", path.display());
    let Some(obj) = v.as_object() else { return };
    for (k, val) in obj {
        match val {
            serde_json::Value::Array(a) if a.is_empty() => {}
            serde_json::Value::Array(a) if k == "notes" => {
                for n in a {
                    println!("  note: {}", n.as_str().unwrap_or_default());
                }
            }
            serde_json::Value::Object(o) => {
                let parts: Vec<String> =
                    o.iter().map(|(a, b)| format!("{a}={}", plain(b))).collect();
                println!("  {k:<15} {}", parts.join("  "));
            }
            _ => println!("  {k:<15} {}", plain(val)),
        }
    }
}

fn plain(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}
