//! The process's peak memory (resident set), as Linux reports it: the figure the summaries print
//! and `meshlight scale` measures per run.

/// Peak resident memory of this process so far, bytes (`None` where the system does not say).
pub fn peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Starts a new peak from the current resident memory (Linux ≥ 4.0); whether it could.
pub fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}
