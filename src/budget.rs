//! The memory budget every large structure counts against ([`Options::memory_budget`]): what
//! a sample is budgeted at before it is placed, the default, and how sizes are written in
//! messages.
//!
//! [`Options::memory_budget`]: crate::solver::Options::memory_budget

/// The default [`Options::memory_budget`](crate::solver::Options::memory_budget): 8 GiB, a
/// third of this project's 24 GiB test machine: half of it holds about 1.4 million samples at
/// [`BYTES_PER_SAMPLE`].
pub const DEFAULT_MEMORY_BUDGET: usize = 8 << 30;

/// Bytes a sample is budgeted at before it is placed: its arrays, area cells and shares,
/// index entries and results. `Solution::bytes` / samples measured 1,420–1,950 on the shipped
/// scenes at the defaults (vectors grown by doubling hold up to twice what they use).
pub const BYTES_PER_SAMPLE: usize = 3072;

/// Bytes in binary units, for messages: "3.2 GiB".
pub fn human_bytes(bytes: f64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} bytes")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// The error for work that would not fit: `what` needs `needed` bytes of `available`.
pub(crate) fn exceeded(budget: usize, problem: String) -> crate::Error {
    crate::Error::Budget { budget, problem }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_in_binary_units() {
        assert_eq!(human_bytes(1000.0), "1000 bytes");
        assert_eq!(human_bytes(1536.0), "1.5 KiB");
        assert_eq!(human_bytes(8.0 * 1024.0 * 1024.0 * 1024.0), "8.0 GiB");
    }
}
