//! Guards against absurd allocations: sizes are checked before any memory is requested.
use crate::error::{Error, Result};

/// Bytes this process may reasonably allocate for one object: the machine's total memory
/// (from `/proc/meminfo`), or 16 GiB where that cannot be read.
pub fn memory_limit() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024)
        })
        .unwrap_or(16 << 30)
}

/// Checks that `count` elements of `elem_bytes` each fit in memory; returns the byte count.
pub fn check_alloc(what: &str, count: u64, elem_bytes: u64) -> Result<u64> {
    let limit = memory_limit();
    let bytes = count
        .checked_mul(elem_bytes)
        .ok_or_else(|| Error::TooLarge {
            what: what.to_string(),
            bytes: u64::MAX,
            limit,
        })?;
    if bytes > limit {
        return Err(Error::TooLarge {
            what: what.to_string(),
            bytes,
            limit,
        });
    }
    Ok(bytes)
}

/// Validates grid dimensions given as signed integers (as headers store them) and returns the
/// voxel count. Zero, negative and overflowing dimensions are errors.
pub fn checked_dims(dims: [i64; 3]) -> Result<([usize; 3], u64)> {
    if dims.iter().any(|&d| d <= 0) {
        return Err(Error::InvalidDims {
            dims,
            reason: "every dimension must be > 0".into(),
        });
    }
    let count = dims
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64))
        .filter(|&c| c <= (usize::MAX as u64) / 8)
        .ok_or_else(|| Error::InvalidDims {
            dims,
            reason: "the voxel count overflows".into(),
        })?;
    Ok((
        [dims[0] as usize, dims[1] as usize, dims[2] as usize],
        count,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn rejects_bad_dims() {
        assert!(checked_dims([0, 1, 1]).is_err());
        assert!(checked_dims([-3, 1, 1]).is_err());
        assert!(checked_dims([i64::MAX, i64::MAX, 2]).is_err());
        assert_eq!(checked_dims([2, 3, 4]).unwrap().1, 24);
    }
    #[test]
    fn rejects_absurd_alloc() {
        assert!(check_alloc("x", 1 << 62, 4).is_err());
        assert!(check_alloc("x", u64::MAX, 4).is_err());
        assert!(check_alloc("x", 1000, 4).is_ok());
    }
}
