//! Sizes as the command prints them.

/// Bytes in binary units, one decimal above a KiB: "3.2 GiB".
pub fn bytes(n: f64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if n < 1024.0 {
        return format!("{n:.0} bytes");
    }
    // The largest unit the size reaches, TiB at most.
    let power = (1..=UNITS.len())
        .take_while(|&p| n >= 1024f64.powi(p as i32))
        .last()
        .unwrap_or(1);
    format!("{:.1} {}", n / 1024f64.powi(power as i32), UNITS[power - 1])
}

#[cfg(test)]
mod tests {
    #[test]
    fn sizes_take_the_largest_unit_they_reach() {
        assert_eq!(super::bytes(0.0), "0 bytes");
        assert_eq!(super::bytes(1023.0), "1023 bytes");
        assert_eq!(super::bytes(1024.0), "1.0 KiB");
        assert_eq!(super::bytes(1.5 * 1024.0 * 1024.0), "1.5 MiB");
        assert_eq!(super::bytes(3.0 * 1024f64.powi(5)), "3072.0 TiB");
    }
}
