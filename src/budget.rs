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
/// index entries and results, and the moment's second copy of its shares while a round splits
/// the cells. `Solution::bytes` / samples measured 948 on the shipped room at the defaults
/// (`tests/breakdown.rs`).
pub const BYTES_PER_SAMPLE: usize = 3072;

/// What a solution holds, by part, in bytes (vectors' capacities): where the memory per sample
/// goes (`meshlight scale` prints it). The links and the tree live only while a round shoots;
/// their bytes are in [`ShootStats::bytes`](crate::solver::ShootStats::bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct Breakdown {
    /// The samples' own arrays: positions, normals, 2D positions, sides, radii, areas,
    /// centroids, rounds, reflectances.
    pub samples: usize,
    /// The area cells.
    pub cells: usize,
    /// The samples' shares of the cells, and where each sample's start.
    pub shares: usize,
    /// The per-side index for range queries.
    pub index: usize,
    /// Per-sample results: radiosity, irradiance, unshot radiosity, direct light, flags and
    /// row scales.
    pub results: usize,
    /// Light by way of specular surfaces.
    pub specular: usize,
    /// The surfaces' 2D triangles.
    pub maps: usize,
}

impl Breakdown {
    /// All of it.
    pub fn total(&self) -> usize {
        self.samples
            + self.cells
            + self.shares
            + self.index
            + self.results
            + self.specular
            + self.maps
    }
}

/// A size in bytes from its text: a number with an optional K, M or G suffix (binary units).
pub(crate) fn parse_bytes(text: &str) -> Result<usize, String> {
    let t = text.trim();
    let (number, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let scale: f64 = match unit {
        'B' => 1.0,
        'K' => 1024.0,
        'M' => 1024.0 * 1024.0,
        'G' => 1024.0 * 1024.0 * 1024.0,
        _ => return Err(format!("'{text}': the unit must be K, M or G")),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a size (e.g. 512M, 8G)"))?;
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < usize::MAX as f64) {
        return Err(format!("'{text}' is not a positive size"));
    }
    Ok(bytes as usize)
}

/// Bytes in binary units, for messages: "3.2 GiB".
pub(crate) fn human_bytes(bytes: f64) -> String {
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

/// A count for messages: digits grouped below a billion ("1,234,567"), three significant
/// figures in scientific notation above ("5.60e55"), so a mistaken input never prints a
/// number sixty digits long.
pub(crate) fn human_count(count: f64) -> String {
    if !count.is_finite() || count.abs() >= 1e9 {
        return format!("{count:.2e}");
    }
    let digits = format!("{:.0}", count.abs());
    let mut grouped = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            grouped.push(',');
        }
        grouped.push(c);
    }
    if count < -0.5 {
        grouped.insert(0, '-');
    }
    grouped
}

/// A number for messages: as Rust prints it between 0.001 and a million, in scientific notation
/// outside ("1e-12", "2.4e14").
pub(crate) fn human_number(x: f32) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Bytes an image's working arrays take per pixel at most while it is computed (the camera
/// hits, the radiance, the edge pixels' lists and their refined values), for the budget.
pub const BYTES_PER_PIXEL: usize = 96;

/// What this process can hold at most, where the system says: the machine's memory and swap,
/// and its own address-space limit (`ulimit -v`); `None` where it does not (not Linux).
fn machine_bytes() -> Option<f64> {
    let field = |text: &str, key: &str| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line.split_whitespace().nth(1)?.parse::<f64>().ok()
    };
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let memory = field(&meminfo, "MemTotal:")? * 1024.0 + field(&meminfo, "SwapTotal:")? * 1024.0;
    let address_space = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|limits| {
            let line = limits
                .lines()
                .find(|l| l.starts_with("Max address space"))?;
            line.split_whitespace().nth(3)?.parse::<f64>().ok()
        });
    Some(address_space.map_or(memory, |a| a.min(memory)))
}

/// The budget as this process can hold it: a budget raised past the machine (to `usize::MAX`,
/// say) counts as the machine, so that work too large for it is an error before anything is
/// allocated, not an abort when the allocation fails.
pub(crate) fn usable(budget: usize) -> usize {
    match machine_bytes() {
        Some(m) if m < budget as f64 => m as usize,
        _ => budget,
    }
}

/// Refuses an image of `width` × `height` pixels, at `per_pixel` bytes each, that the budget
/// (or the machine) cannot hold, before anything is allocated.
pub(crate) fn check_image(
    budget: usize,
    (width, height): (u32, u32),
    per_pixel: usize,
) -> crate::Result<()> {
    let bytes = f64::from(width) * f64::from(height) * per_pixel as f64;
    let usable = usable(budget);
    if bytes > usable as f64 {
        let what = if usable < budget {
            format!(
                "more than this machine holds ({})",
                human_bytes(usable as f64)
            )
        } else {
            "more than the budget".to_string()
        };
        return Err(exceeded(
            budget,
            format!(
                "a {width}×{height} image needs about {} ({per_pixel} bytes a pixel), {what}: \
                 make the camera smaller",
                human_bytes(bytes)
            ),
        ));
    }
    Ok(())
}

/// The error for work that would not fit: `what` needs `needed` bytes of `available`.
pub(crate) fn exceeded(budget: usize, problem: String) -> crate::Error {
    crate::Error::Budget { budget, problem }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sizes_parse_in_binary_units() {
        use super::parse_bytes;
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert_eq!(parse_bytes("512M"), Ok(512 << 20));
        assert_eq!(parse_bytes("8g"), Ok(8 << 30));
        assert_eq!(parse_bytes("1.5K"), Ok(1536));
        for bad in ["", "G", "-1G", "0", "4X", "lots"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
    }

    use super::*;

    #[test]
    fn sizes_read_in_binary_units() {
        assert_eq!(human_bytes(1000.0), "1000 bytes");
        assert_eq!(human_bytes(1536.0), "1.5 KiB");
        assert_eq!(human_bytes(8.0 * 1024.0 * 1024.0 * 1024.0), "8.0 GiB");
    }

    #[test]
    fn counts_are_grouped_or_short() {
        assert_eq!(human_count(0.0), "0");
        assert_eq!(human_count(999.0), "999");
        assert_eq!(human_count(1000.0), "1,000");
        assert_eq!(human_count(1_234_567.4), "1,234,567");
        assert_eq!(human_count(-4321.0), "-4,321");
        assert_eq!(human_count(5.6e55), "5.60e55");
    }
}
