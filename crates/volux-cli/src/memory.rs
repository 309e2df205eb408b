//! `--memory-budget SIZE`: parsing the size and applying it to the process.
//!
//! A size is a byte count with an optional binary unit (`4G`, `512M`, `1.5GiB`, `64KiB`,
//! `1000000`; `K`, `KB` and `KiB` all mean 1024 bytes, and so on up to `T`), or a percentage
//! of the memory available when the command starts (`50%`).

/// The units a size may carry (case-insensitive), with their bytes.
const UNITS: [(&str, f64); 13] = [
    ("", 1.0),
    ("b", 1.0),
    ("k", 1024.0),
    ("kb", 1024.0),
    ("kib", 1024.0),
    ("m", 1048576.0),
    ("mb", 1048576.0),
    ("mib", 1048576.0),
    ("g", 1073741824.0),
    ("gb", 1073741824.0),
    ("gib", 1073741824.0),
    ("t", 1099511627776.0),
    ("tib", 1099511627776.0),
];

/// The clap parser of `--memory-budget`: [`parse_size`] against the memory available now.
pub fn parse_budget(text: &str) -> Result<u64, String> {
    parse_size(text, volux_core::limits::available_memory())
}

/// Parses a memory size (see the module's doc); percentages are of `available` bytes.
/// Errors, in one line, on an empty, negative, zero, non-numeric or unknown-unit value, and
/// on a percentage outside (0, 100].
pub fn parse_size(text: &str, available: u64) -> Result<u64, String> {
    let t = text.trim();
    let expected = "expected a size such as 4G, 512M, 1.5GiB or 50%";
    if let Some(p) = t.strip_suffix('%') {
        let pct: f64 = p.trim().parse().map_err(|_| expected.to_string())?;
        if !(pct > 0.0 && pct <= 100.0) {
            return Err("a percentage of the available memory must be in (0, 100]".into());
        }
        return to_bytes(available as f64 * pct / 100.0);
    }
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number.parse().map_err(|_| expected.to_string())?;
    let unit = unit.trim().to_ascii_lowercase();
    let scale = UNITS
        .iter()
        .find(|(name, _)| *name == unit)
        .map(|(_, scale)| *scale)
        .ok_or_else(|| format!("unknown unit '{unit}': {expected}"))?;
    to_bytes(value * scale)
}

/// A positive, finite byte count that fits in `u64`, rounded down.
fn to_bytes(bytes: f64) -> Result<u64, String> {
    if !(bytes.is_finite() && bytes >= 1.0) {
        return Err("the memory budget must be at least 1 byte".into());
    }
    if bytes >= u64::MAX as f64 {
        return Err("the memory budget is too large".into());
    }
    Ok(bytes as u64)
}

/// Sets the process's memory budget when `--memory-budget` was given (before any work).
pub fn apply(budget: Option<u64>) -> Result<(), volux_core::Error> {
    match budget {
        Some(bytes) => volux_core::limits::set_memory_budget(bytes),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    const GIB: u64 = 1 << 30;

    #[test]
    fn sizes_with_units_and_percentages_parse() {
        assert_eq!(parse_size("4G", 0), Ok(4 * GIB));
        assert_eq!(parse_size("512M", 0), Ok(512 << 20));
        assert_eq!(parse_size("1.5GiB", 0), Ok(3 * GIB / 2));
        assert_eq!(parse_size(" 2 gb ", 0), Ok(2 * GIB));
        assert_eq!(parse_size("64KiB", 0), Ok(64 << 10));
        assert_eq!(parse_size("1000000", 0), Ok(1_000_000));
        assert_eq!(parse_size("1T", 0), Ok(1 << 40));
        assert_eq!(parse_size("50%", 8 * GIB), Ok(4 * GIB));
        assert_eq!(parse_size("100%", 8 * GIB), Ok(8 * GIB));
        assert_eq!(parse_size("12.5 %", 8 * GIB), Ok(GIB));
    }

    #[test]
    fn bad_sizes_are_one_line_errors() {
        for bad in [
            "",
            "G",
            "-1G",
            "0",
            "0%",
            "101%",
            "-5%",
            "abc",
            "4X",
            "4 GG",
            "1e3",
            "nan",
            "inf%",
            "1.2.3G",
            "0.1",
            "99999999999T",
            "%",
        ] {
            let e = parse_size(bad, 8 * GIB).expect_err(bad);
            assert!(!e.is_empty() && !e.contains('\n'), "{bad}: {e}");
        }
        assert!(parse_size("4X", 0)
            .unwrap_err()
            .starts_with("unknown unit 'x'"));
    }
}
