//! `--memory-budget SIZE`: the size read by the application layer
//! ([`volux_app::words::memory_budget`]: `4G`, `512M`, `1.5GiB`, `50%` of the memory
//! available now) and applied to the process.

/// The clap parser of `--memory-budget`.
pub fn parse_budget(text: &str) -> Result<u64, String> {
    volux_app::words::memory_budget(text).map_err(|e| e.to_string())
}

/// Sets the process's memory budget when `--memory-budget` was given (before any work).
pub fn apply(budget: Option<u64>) -> Result<(), volux_core::Error> {
    match budget {
        Some(bytes) => volux_core::limits::set_memory_budget(bytes),
        None => Ok(()),
    }
}
