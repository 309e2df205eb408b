//! The words of options that every front end reads the same way: memory sizes and budgets,
//! pyramid levels and image sizes (backends: [`crate::backend::Backend::parse`]). Each parser returns a [`WordError`] that names
//! the word and what was expected; the front end adds its option's name (`--memory-budget`
//! on the command line, the budget field in the viewer).
//!
//! A memory size is a byte count with an optional binary unit (`4G`, `512M`, `1.5GiB`,
//! `64KiB`, `1000000`; `K`, `KB` and `KiB` all mean 1024 bytes, and so on up to `T`), or a
//! percentage of the memory available when it is read (`50%`).
use volux_render::bricked::Lod;

/// Largest image side a front end accepts (`WxH`).
pub const MAX_IMAGE_SIDE: usize = 16384;

/// A word that does not parse, and what was expected.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum WordError {
    /// Not a memory size.
    #[error("'{given}': expected a size such as 4G, 512M, 1.5GiB or 50%")]
    NotASize {
        /// The word.
        given: String,
    },
    /// A memory size with a unit that is not a byte unit.
    #[error("'{given}': unknown unit '{unit}' (B, K, M, G or T, with or without B or iB)")]
    UnknownUnit {
        /// The word.
        given: String,
        /// Its unit, lower case.
        unit: String,
    },
    /// A percentage outside (0, 100].
    #[error("'{given}': a percentage of the available memory must be in (0, 100]")]
    PercentOutOfRange {
        /// The word.
        given: String,
    },
    /// A size under one byte or over 2^64.
    #[error("'{given}': a memory size must be at least 1 byte and under 16 EiB")]
    BytesOutOfRange {
        /// The word.
        given: String,
    },
    /// Not `auto` nor a level number.
    #[error("'{given}': expected auto or a level number (0 = full resolution)")]
    NotALevel {
        /// The word.
        given: String,
    },
    /// Not `WxH` with sides from 1 to [`MAX_IMAGE_SIDE`].
    #[error("'{given}': expected WxH, e.g. 800x600, each side from 1 to {MAX_IMAGE_SIDE}")]
    NotAnImageSize {
        /// The word.
        given: String,
    },
    /// Not a backend's name.
    #[error("'{given}': expected auto, cpu or gpu")]
    NotABackend {
        /// The word.
        given: String,
    },
}

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

/// A memory budget: [`memory_size`] against the memory available now.
pub fn memory_budget(text: &str) -> Result<u64, WordError> {
    memory_size(text, volux_core::limits::available_memory())
}

/// A memory size (see the module's doc); percentages are of `available` bytes. Refuses an
/// empty, negative, zero, non-numeric or unknown-unit word, and a percentage outside
/// (0, 100].
pub fn memory_size(text: &str, available: u64) -> Result<u64, WordError> {
    let given = || text.to_string();
    let t = text.trim();
    if let Some(p) = t.strip_suffix('%') {
        let pct: f64 = plain_number(p.trim()).ok_or(WordError::NotASize { given: given() })?;
        if !(pct > 0.0 && pct <= 100.0) {
            return Err(WordError::PercentOutOfRange { given: given() });
        }
        return to_bytes(available as f64 * pct / 100.0, text);
    }
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value = plain_number(number).ok_or(WordError::NotASize { given: given() })?;
    let unit = unit.trim().to_ascii_lowercase();
    let scale = UNITS
        .iter()
        .find(|(name, _)| *name == unit)
        .map(|(_, scale)| *scale)
        .ok_or_else(|| WordError::UnknownUnit {
            given: given(),
            unit,
        })?;
    to_bytes(value * scale, text)
}

/// A number of digits with at most one decimal point (no sign, exponent, `inf` or `nan`).
fn plain_number(s: &str) -> Option<f64> {
    let plain = !s.is_empty()
        && s.chars().all(|c| c.is_ascii_digit() || c == '.')
        && s.chars().filter(|&c| c == '.').count() <= 1;
    plain.then(|| s.parse().ok()).flatten()
}

/// A positive, finite byte count that fits in `u64`, rounded down.
fn to_bytes(bytes: f64, text: &str) -> Result<u64, WordError> {
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(WordError::BytesOutOfRange {
            given: text.to_string(),
        });
    }
    Ok(bytes as u64)
}

/// A pyramid level: `auto` or a level number (0: full resolution).
pub fn level(text: &str) -> Result<Lod, WordError> {
    let t = text.trim();
    if t == "auto" {
        return Ok(Lod::Auto);
    }
    t.parse::<usize>()
        .map(Lod::Level)
        .map_err(|_| WordError::NotALevel {
            given: text.to_string(),
        })
}

/// The word of a level ([`level`] reads it back): `auto` or its number.
pub fn level_word(lod: Lod) -> String {
    match lod {
        Lod::Auto => "auto".to_string(),
        Lod::Level(n) => n.to_string(),
    }
}

/// An image size `WxH` (or `WXH`), each side from 1 to [`MAX_IMAGE_SIDE`].
pub fn image_size(text: &str) -> Result<(usize, usize), WordError> {
    let bad = || WordError::NotAnImageSize {
        given: text.to_string(),
    };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |v: &str| {
        v.trim()
            .parse::<usize>()
            .ok()
            .filter(|n| (1..=MAX_IMAGE_SIDE).contains(n))
            .ok_or_else(bad)
    };
    Ok((side(w)?, side(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    const GIB: u64 = 1 << 30;

    #[test]
    fn sizes_with_units_and_percentages_parse() {
        assert_eq!(memory_size("4G", 0), Ok(4 * GIB));
        assert_eq!(memory_size("512M", 0), Ok(512 << 20));
        assert_eq!(memory_size("1.5GiB", 0), Ok(3 * GIB / 2));
        assert_eq!(memory_size(" 2 gb ", 0), Ok(2 * GIB));
        assert_eq!(memory_size("64KiB", 0), Ok(64 << 10));
        assert_eq!(memory_size("1.5kb", 0), Ok(1536));
        assert_eq!(memory_size("1000000", 0), Ok(1_000_000));
        assert_eq!(memory_size("1T", 0), Ok(1 << 40));
        assert_eq!(memory_size("50%", 8 * GIB), Ok(4 * GIB));
        assert_eq!(memory_size("150%", 8 * GIB).ok(), None);
        assert_eq!(memory_size("100%", 8 * GIB), Ok(8 * GIB));
        assert_eq!(memory_size("12.5 %", 8 * GIB), Ok(GIB));
        assert!(memory_budget("50%").is_ok_and(|b| b > 0));
    }

    #[test]
    fn bad_sizes_say_which_word_and_why() {
        for bad in [
            "",
            "G",
            "-1G",
            "0",
            "0%",
            "101%",
            "150%",
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
            let e = memory_size(bad, 8 * GIB).expect_err(bad).to_string();
            assert!(e.contains(&format!("'{bad}'")), "{bad}: {e}");
            assert!(!e.contains('\n') && !e.contains("--"), "{bad}: {e}");
        }
        assert_eq!(
            memory_size("4X", 0),
            Err(WordError::UnknownUnit {
                given: "4X".into(),
                unit: "x".into()
            })
        );
        assert_eq!(
            memory_size("101%", 0),
            Err(WordError::PercentOutOfRange {
                given: "101%".into()
            })
        );
    }

    #[test]
    fn levels_and_image_sizes() {
        assert_eq!(level("auto"), Ok(Lod::Auto));
        assert_eq!(level("2"), Ok(Lod::Level(2)));
        assert!(matches!(level("fine"), Err(WordError::NotALevel { .. })));
        assert_eq!(image_size("800x600"), Ok((800, 600)));
        assert_eq!(image_size("16X9"), Ok((16, 9)));
        for bad in ["800", "0x5", "5x16385", "ax5", "5x"] {
            assert!(
                matches!(image_size(bad), Err(WordError::NotAnImageSize { .. })),
                "{bad}"
            );
        }
    }
}
