//! Byte counts in human units ("8.0 GiB"), for messages about memory.

/// The binary units, from the largest down.
const UNITS: [(&str, u64); 6] = [
    ("EiB", 1 << 60),
    ("PiB", 1 << 50),
    ("TiB", 1 << 40),
    ("GiB", 1 << 30),
    ("MiB", 1 << 20),
    ("KiB", 1 << 10),
];

/// `bytes` in the largest binary unit it reaches, with one decimal (`8.0 GiB`, `1.5 MiB`);
/// below 1 KiB, a plain count (`512 B`).
pub fn format_bytes(bytes: u64) -> String {
    match UNITS.iter().find(|(_, size)| bytes >= *size) {
        Some((name, size)) => format!("{:.1} {name}", bytes as f64 / *size as f64),
        None => format!("{bytes} B"),
    }
}

/// `a` and `b` in the unit of [`format_bytes`], with as many decimals (one to three) as it
/// takes for two different counts to read differently (`1.46 GiB` over `1.45 GiB`, not
/// `1.5 GiB` over `1.5 GiB`).
pub fn format_bytes_apart(a: u64, b: u64) -> (String, String) {
    let with = |bytes: u64, decimals: usize| match UNITS.iter().find(|(_, size)| bytes >= *size) {
        Some((name, size)) => format!("{:.decimals$} {name}", bytes as f64 / *size as f64),
        None => format!("{bytes} B"),
    };
    (1..=3)
        .map(|d| (with(a, d), with(b, d)))
        .find(|(x, y)| x != y || a == b)
        .unwrap_or_else(|| (with(a, 3), with(b, 3)))
}

/// The symbol of a length unit as files name it (`micrometer`, `micron`, `um`, `µm`,
/// `millimeter`, `mm`, ...: OME-NGFF, ImageJ, NRRD `space units`), `None` when it is not a
/// length unit Volux knows.
pub fn length_symbol(name: &str) -> Option<&'static str> {
    let n = name.trim().trim_matches('"').to_ascii_lowercase();
    Some(match n.as_str() {
        "nm" | "nanometer" | "nanometre" => "nm",
        "um" | "µm" | "μm" | "\\u00b5m" | "micrometer" | "micrometre" | "micron" | "microns" => {
            "µm"
        }
        "mm" | "millimeter" | "millimetre" => "mm",
        "cm" | "centimeter" | "centimetre" => "cm",
        "m" | "meter" | "metre" => "m",
        _ => return None,
    })
}

/// The OME-NGFF name of a length symbol (`µm` -> `micrometer`).
pub fn length_name(symbol: &str) -> Option<&'static str> {
    Some(match symbol {
        "nm" => "nanometer",
        "µm" => "micrometer",
        "mm" => "millimeter",
        "cm" => "centimeter",
        "m" => "meter",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::{format_bytes, format_bytes_apart};

    #[test]
    fn bytes_read_in_the_largest_unit() {
        assert_eq!(format_bytes(0), "0 B");
        assert_eq!(format_bytes(1023), "1023 B");
        assert_eq!(format_bytes(1024), "1.0 KiB");
        assert_eq!(format_bytes(3 << 19), "1.5 MiB");
        assert_eq!(format_bytes(8 << 30), "8.0 GiB");
        assert_eq!(format_bytes(u64::MAX), "16.0 EiB");
    }

    #[test]
    fn close_counts_read_differently() {
        let (a, b) = format_bytes_apart(1_570_000_000, 1_560_000_000);
        assert_ne!(a, b);
        assert_eq!(
            format_bytes_apart(8 << 30, 1 << 30),
            ("8.0 GiB".into(), "1.0 GiB".into())
        );
        assert_eq!(
            format_bytes_apart(100, 100),
            ("100 B".into(), "100 B".into())
        );
    }
}
