//! Guards against absurd allocations: sizes are checked before any memory is requested,
//! against one process-wide **memory budget**.
//!
//! The budget defaults to [`DEFAULT_BUDGET_FRACTION`] of the memory available when it is
//! first read (`MemAvailable` in `/proc/meminfo`, else `MemTotal`, else 16 GiB); a front end
//! may set it once, before any work, with [`set_memory_budget`] (the CLI's
//! `--memory-budget`). Every large structure (grids read from files, meshes made from grids,
//! gradient volumes, acceleration structures, images) is checked with [`check_alloc`] before
//! it is allocated, so a hostile file ends in one error naming the structure rather than in
//! the allocator aborting the process. [`check_alloc_within`] takes the budget as a
//! parameter, for callers (and tests) that carry their own.
use std::sync::OnceLock;

use crate::error::{Error, Result};

/// The fraction of the available memory the budget defaults to: three quarters.
pub const DEFAULT_BUDGET_FRACTION: (u64, u64) = (3, 4);

/// The memory assumed available where `/proc/meminfo` cannot be read: 16 GiB.
const FALLBACK_MEMORY: u64 = 16 << 30;

/// The process's budget, fixed on first read or by [`set_memory_budget`].
static BUDGET: OnceLock<u64> = OnceLock::new();

/// The value in bytes of field `key` (e.g. `MemAvailable`) of `/proc/meminfo` text.
fn meminfo_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.split(':').next() == Some(key))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// The memory available in `/proc/meminfo` text: `MemAvailable`, else `MemTotal`.
fn available_in(meminfo: Option<&str>) -> u64 {
    meminfo
        .and_then(|t| meminfo_field(t, "MemAvailable").or_else(|| meminfo_field(t, "MemTotal")))
        .filter(|&b| b > 0)
        .unwrap_or(FALLBACK_MEMORY)
}

/// Bytes of memory available to this process now: `MemAvailable` from `/proc/meminfo`,
/// falling back to `MemTotal`, then to 16 GiB; and no more than the address space left
/// under the process's own limit (`ulimit -v`, `prlimit --as`), where one is set, so that
/// the budget refuses what the limit would turn into an abort.
pub fn available_memory() -> u64 {
    let machine = available_in(std::fs::read_to_string("/proc/meminfo").ok().as_deref());
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let status = std::fs::read_to_string("/proc/self/status").ok();
    match address_space_left(limits.as_deref(), status.as_deref()) {
        Some(left) => machine.min(left),
        None => machine,
    }
}

/// The address space left under the soft `Max address space` limit of `/proc/self/limits`
/// (`None` when unlimited or unreadable), given the `VmSize` of `/proc/self/status`.
fn address_space_left(limits: Option<&str>, status: Option<&str>) -> Option<u64> {
    let line = limits?
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line
        .trim_start_matches("Max address space")
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let used_kb: u64 = status
        .and_then(|s| s.lines().find(|l| l.starts_with("VmSize:")))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    Some(soft.saturating_sub(used_kb.saturating_mul(1024)))
}

/// The budget [`memory_budget`] defaults to: [`DEFAULT_BUDGET_FRACTION`] of
/// [`available_memory`].
pub fn default_memory_budget() -> u64 {
    let (num, den) = DEFAULT_BUDGET_FRACTION;
    (available_memory() / den).saturating_mul(num).max(1)
}

/// Sets the process's memory budget, in bytes. It can be set once, before anything reads it;
/// zero, a second call, or a call after the first check are errors.
pub fn set_memory_budget(bytes: u64) -> Result<()> {
    if bytes == 0 {
        return Err(Error::MemoryBudget("it must be more than 0 bytes".into()));
    }
    BUDGET.set(bytes).map_err(|_| {
        Error::MemoryBudget(format!(
            "it is already {} and can be set only once, before any work",
            crate::units::format_bytes(memory_budget())
        ))
    })
}

/// The process's memory budget in bytes: what [`set_memory_budget`] set, else
/// [`default_memory_budget`] (read once, then fixed).
pub fn memory_budget() -> u64 {
    *BUDGET.get_or_init(default_memory_budget)
}

/// The memory budget, under the name readers have used for it.
pub fn memory_limit() -> u64 {
    memory_budget()
}

/// Checks that `count` elements of `elem_bytes` each fit in the process's memory budget;
/// returns the byte count. `what` names the structure in the error ("the gradient volume").
pub fn check_alloc(what: &str, count: u64, elem_bytes: u64) -> Result<u64> {
    check_alloc_within(memory_budget(), what, count, elem_bytes)
}

/// Checks that `count` elements of `elem_bytes` each fit in `budget` bytes; returns the byte
/// count, or [`Error::OverBudget`] naming `what` (with `u64::MAX` bytes when the size
/// overflows).
pub fn check_alloc_within(budget: u64, what: &str, count: u64, elem_bytes: u64) -> Result<u64> {
    match count.checked_mul(elem_bytes) {
        Some(bytes) if bytes <= budget => Ok(bytes),
        over => Err(Error::OverBudget {
            what: what.to_string(),
            bytes: over.unwrap_or(u64::MAX),
            budget,
        }),
    }
}

/// The product of `dims` as a `u64`, `u64::MAX` when it overflows (which any budget
/// refuses).
pub fn count_of(dims: &[usize]) -> u64 {
    dims.iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64))
        .unwrap_or(u64::MAX)
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
    fn budget_checks_name_the_structure_and_sizes() {
        assert_eq!(check_alloc_within(1000, "x", 250, 4).unwrap(), 1000);
        let e = check_alloc_within(6 << 29, "the gradient volume", 1 << 30, 8).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the gradient volume needs 8.0 GiB, over the memory budget of 3.0 GiB"
        );
        let e = check_alloc_within(1 << 20, "tets", u64::MAX, 16).unwrap_err();
        assert!(
            matches!(
                e,
                Error::OverBudget {
                    bytes: u64::MAX,
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(count_of(&[2, 3, 4]), 24);
        assert_eq!(count_of(&[usize::MAX, 3]), u64::MAX);
    }
    #[test]
    fn available_memory_reads_meminfo_with_fallbacks() {
        let both = "MemTotal:       16000 kB\nMemFree: 1 kB\nMemAvailable:    8000 kB\n";
        assert_eq!(available_in(Some(both)), 8000 * 1024);
        assert_eq!(available_in(Some("MemTotal: 4 kB\n")), 4096);
        assert_eq!(available_in(Some("garbage")), FALLBACK_MEMORY);
        assert_eq!(available_in(None), FALLBACK_MEMORY);
        assert!(default_memory_budget() > 0);
    }
    #[test]
    fn an_address_space_limit_caps_what_is_available() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         2147483648           unlimited            bytes\n";
        let status = "Name: volux\nVmSize:\t  524288 kB\n";
        assert_eq!(
            address_space_left(Some(limits), Some(status)),
            Some(2147483648 - 524288 * 1024)
        );
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_left(Some(unlimited), Some(status)), None);
        assert_eq!(address_space_left(None, None), None);
    }
    #[test]
    fn zero_budget_is_refused() {
        assert!(set_memory_budget(0).is_err());
    }
    #[test]
    fn rejects_absurd_alloc() {
        assert!(check_alloc("x", 1 << 62, 4).is_err());
        assert!(check_alloc("x", u64::MAX, 4).is_err());
        assert!(check_alloc("x", 1000, 4).is_ok());
    }
}
