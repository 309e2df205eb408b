//! The type stubs (`python/volux/_volux.pyi`) declare every class, method and function the
//! extension module defines: each `#[pyclass(name = "...")]`, each function of a
//! `#[pymethods]` block and each `#[pyfunction]` of `src/` has its `class` or `def` in the
//! stubs. (`tests/test_stubs.py` checks the same against the imported module.)
use std::path::Path;

/// The name of the `fn` on the first line after `start` that declares one.
fn next_fn(lines: &[&str], start: usize) -> Option<String> {
    lines[start..].iter().find_map(|l| {
        let l = l.trim_start();
        let rest = l
            .strip_prefix("pub fn ")
            .or_else(|| l.strip_prefix("fn "))?;
        Some(rest.split(['(', '<']).next()?.to_string())
    })
}

#[test]
fn every_python_name_of_the_module_is_in_the_stubs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let stubs = std::fs::read_to_string(root.join("python/volux/_volux.pyi")).unwrap();
    let mut missing = Vec::new();
    let mut seen = 0;
    for entry in std::fs::read_dir(root.join("src")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut in_methods = false;
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim_start();
            if t.starts_with("#[pyclass(") {
                if let Some(name) = t
                    .split("name = \"")
                    .nth(1)
                    .and_then(|r| r.split('"').next())
                {
                    seen += 1;
                    if !stubs.contains(&format!("class {name}")) {
                        missing.push(format!("class {name} ({})", path.display()));
                    }
                }
            }
            if t.starts_with("#[pymethods]") {
                in_methods = true;
            }
            if in_methods && *line == "}" {
                in_methods = false;
            }
            let is_fn = t.starts_with("#[pyfunction]")
                || (in_methods && (t.starts_with("fn ") || t.starts_with("pub fn ")));
            if is_fn {
                let start = if t.starts_with("#[pyfunction]") {
                    i + 1
                } else {
                    i
                };
                let Some(name) = next_fn(&lines, start) else {
                    continue;
                };
                // `#[new]` (among the attributes above the `fn`) is `__init__` in the stubs.
                let attributes = lines[..start]
                    .iter()
                    .rev()
                    .take_while(|l| !l.trim().is_empty() && !l.trim().ends_with('}'));
                let name = if attributes.into_iter().any(|l| l.contains("#[new]")) {
                    "__init__".to_string()
                } else {
                    name
                };
                seen += 1;
                if !stubs.contains(&format!("def {name}(")) {
                    missing.push(format!("def {name} ({})", path.display()));
                }
            }
        }
    }
    assert!(
        seen > 40,
        "only {seen} Python names found: the scan is broken"
    );
    assert!(missing.is_empty(), "not in _volux.pyi: {missing:?}");
}
