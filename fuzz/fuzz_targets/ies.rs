//! IES LM-63 parsing under arbitrary bytes: a distribution or an error, never a panic, an
//! abort or a huge allocation; what parses gives finite, non-negative intensities.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use meshlight::ies::Photometry;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(p) = Photometry::parse(Path::new("fuzz.ies"), &text) {
        for (c, g) in [(0.0, 0.0), (45.0, 30.0), (200.0, 95.0), (359.9, 180.0), (-10.0, 60.0)] {
            let i = p.intensity(c, g);
            assert!(i.is_finite() && i >= 0.0, "{i} at C {c}, γ {g}");
        }
    }
});
