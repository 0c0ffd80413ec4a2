//! EnergyPlus weather files (EPW): the site in the LOCATION header and, for every hour of a
//! year, the sky's diffuse horizontal and the sun's direct normal light (scene-format v4, "A
//! year of weather").
//!
//! The reader keeps what daylight needs and checks it: 8,760 (or, in a leap year, 8,784) data
//! rows, each with its date and hour, the irradiances (fields 14-16, W/m²) and the
//! illuminances (fields 17-19, lx). Real files carry missing-value codes (9999 for an
//! irradiance, 999999 for an illuminance), comment lines, and trailing commas; some converters
//! write 0 for every illuminance they did not have: such an hour takes its illuminance from
//! its irradiance (Perez's luminous efficacy, when the sun's position is known: see
//! [`WeatherHour::illuminance`]).

use std::path::Path;

use crate::error::{Error, Result};

/// The site an EPW's LOCATION line gives.
#[derive(Clone, Debug, PartialEq)]
pub struct WeatherSite {
    /// The place's name (city, region, country as the file gives them).
    pub name: String,
    /// Degrees, north positive.
    pub latitude: f64,
    /// Degrees, east positive.
    pub longitude: f64,
    /// Hours east of UTC of the local standard time.
    pub timezone: f64,
}

/// One hour of weather: the daylight fields of one data row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeatherHour {
    /// The year the row names.
    pub year: i32,
    /// 1-12.
    pub month: u32,
    /// 1-31.
    pub day: u32,
    /// 1-24: the hour ending at `hour`:00 local standard time.
    pub hour: u32,
    /// Direct normal illuminance (lx), if the file gives it.
    pub direct_normal_lx: Option<f64>,
    /// Diffuse horizontal illuminance (lx), if the file gives it.
    pub diffuse_horizontal_lx: Option<f64>,
    /// Direct normal irradiance (W/m²), if the file gives it.
    pub direct_normal_w: Option<f64>,
    /// Diffuse horizontal irradiance (W/m²), if the file gives it.
    pub diffuse_horizontal_w: Option<f64>,
}

/// A year of weather.
#[derive(Clone, Debug, PartialEq)]
pub struct Weather {
    /// From the LOCATION line.
    pub site: WeatherSite,
    /// Every data row, in file order.
    pub hours: Vec<WeatherHour>,
}

/// The irradiance fields' missing-value code (and anything above it).
const MISSING_IRRADIANCE: f64 = 9999.0;
/// The illuminance fields' missing-value code.
const MISSING_ILLUMINANCE: f64 = 999_900.0;
/// Header records before the data.
const HEADERS: [&str; 8] = [
    "LOCATION",
    "DESIGN CONDITIONS",
    "TYPICAL/EXTREME PERIODS",
    "GROUND TEMPERATURES",
    "HOLIDAYS/DAYLIGHT SAVINGS",
    "COMMENTS 1",
    "COMMENTS 2",
    "DATA PERIODS",
];

impl WeatherHour {
    /// (direct normal, diffuse horizontal) illuminance in lx: the file's illuminances, or where
    /// it has none, its irradiances through Perez's 1990 luminous efficacy at the sun's zenith
    /// angle (degrees) on `day_of_year`; `None` where neither is given.
    pub fn illuminance(&self, zenith: f64, day_of_year: u32) -> Option<(f64, f64)> {
        if let (Some(dn), Some(dh)) = (self.direct_normal_lx, self.diffuse_horizontal_lx) {
            return Some((dn, dh));
        }
        let (dn, dh) = (self.direct_normal_w?, self.diffuse_horizontal_w?);
        Some(super::sky::illuminance_of_irradiance(
            dn,
            dh,
            zenith,
            day_of_year,
        ))
    }
}

/// Reads an EPW file.
pub fn read(path: &Path) -> Result<Weather> {
    let bytes = std::fs::read(path).map_err(|cause| Error::Read {
        path: path.to_path_buf(),
        cause,
    })?;
    // Some files carry Latin-1 place names: the numbers are ASCII either way.
    let text = String::from_utf8_lossy(&bytes);
    parse(&text, path)
}

/// Parses an EPW's text; errors name `path` and the line.
pub fn parse(text: &str, path: &Path) -> Result<Weather> {
    let fail = |line: usize, problem: String| Error::scene(path, Some(line), problem);
    let mut site = None;
    let mut hours = Vec::with_capacity(8784);
    let mut last_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last_line = line;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('!') || trimmed.starts_with('#') {
            continue;
        }
        let upper = trimmed.to_ascii_uppercase();
        if let Some(header) = HEADERS.iter().find(|h| upper.starts_with(*h)) {
            if *header == "LOCATION" {
                site = Some(location(trimmed).map_err(|p| fail(line, p))?);
            }
            continue;
        }
        if site.is_none() {
            return Err(fail(
                line,
                "no LOCATION line before the data: is this an EnergyPlus weather file (EPW)?"
                    .into(),
            ));
        }
        hours.push(row(trimmed).map_err(|p| fail(line, p))?);
    }
    let Some(site) = site else {
        return Err(fail(
            last_line.max(1),
            "no LOCATION line: is this an EnergyPlus weather file (EPW)?".into(),
        ));
    };
    if hours.len() != 8760 && hours.len() != 8784 {
        return Err(fail(
            last_line.max(1),
            format!(
                "{} hourly rows: a year of weather has 8760 (8784 in a leap year)",
                hours.len()
            ),
        ));
    }
    Ok(Weather { site, hours })
}

/// The fields of a line, trimmed, without the empty ones a trailing comma leaves.
fn fields(line: &str) -> Vec<&str> {
    let mut f: Vec<&str> = line.split(',').map(str::trim).collect();
    while f.last().is_some_and(|s| s.is_empty()) {
        f.pop();
    }
    f
}

/// `LOCATION,city,state,country,source,WMO,latitude,longitude,timezone,elevation`.
fn location(line: &str) -> std::result::Result<WeatherSite, String> {
    let f = fields(line);
    if f.len() < 9 {
        return Err(format!(
            "LOCATION has {} fields: it needs city, region, country, source, station, \
             latitude, longitude and time zone",
            f.len().saturating_sub(1)
        ));
    }
    let number = |i: usize, name: &str, range: std::ops::RangeInclusive<f64>| {
        let v: f64 = f[i]
            .parse()
            .map_err(|_| format!("LOCATION {name} '{}' is not a number", f[i]))?;
        if range.contains(&v) {
            Ok(v)
        } else {
            Err(format!(
                "LOCATION {name} {v} is outside {} to {}",
                range.start(),
                range.end()
            ))
        }
    };
    Ok(WeatherSite {
        name: [f[1], f[2], f[3]]
            .iter()
            .filter(|s| !s.is_empty() && **s != "-")
            .copied()
            .collect::<Vec<_>>()
            .join(", "),
        latitude: number(6, "latitude", -90.0..=90.0)?,
        longitude: number(7, "longitude", -180.0..=180.0)?,
        timezone: number(8, "time zone", -14.0..=14.0)?,
    })
}

/// One data row.
fn row(line: &str) -> std::result::Result<WeatherHour, String> {
    let f = fields(line);
    if f.len() < 19 {
        return Err(format!(
            "a data row has {} fields: the daylight fields are 14 to 19 (of 35)",
            f.len()
        ));
    }
    let int = |i: usize, name: &str| {
        f[i].parse::<i64>()
            .map_err(|_| format!("field {} ({name}) '{}' is not a whole number", i + 1, f[i]))
    };
    let year = int(0, "year")?;
    let (month, day, hour) = (int(1, "month")?, int(2, "day")?, int(3, "hour")?);
    if !(1..=12).contains(&month) {
        return Err(format!("month {month} is not 1 to 12"));
    }
    let days = super::days_in_month(year as i32, month as u32);
    if !(1..=i64::from(days)).contains(&day) {
        return Err(format!("day {day} is not 1 to {days} of month {month}"));
    }
    if !(1..=24).contains(&hour) {
        return Err(format!("hour {hour} is not 1 to 24"));
    }
    // A value, or None for the missing-value code.
    let value = |i: usize, name: &str, missing: f64| -> std::result::Result<Option<f64>, String> {
        let v: f64 = f[i]
            .parse()
            .map_err(|_| format!("field {} ({name}) '{}' is not a number", i + 1, f[i]))?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!("field {} ({name}) {v} is not a value ≥ 0", i + 1));
        }
        Ok((v < missing).then_some(v))
    };
    let direct_normal_w = value(14, "direct normal radiation", MISSING_IRRADIANCE)?;
    let diffuse_horizontal_w = value(15, "diffuse horizontal radiation", MISSING_IRRADIANCE)?;
    let global_lx = value(16, "global horizontal illuminance", MISSING_ILLUMINANCE)?;
    let mut direct_normal_lx = value(17, "direct normal illuminance", MISSING_ILLUMINANCE)?;
    let mut diffuse_horizontal_lx =
        value(18, "diffuse horizontal illuminance", MISSING_ILLUMINANCE)?;
    // Illuminances all 0 while the irradiances say there is light: the file has none.
    let lit = direct_normal_w.unwrap_or(0.0) > 0.0 || diffuse_horizontal_w.unwrap_or(0.0) > 0.0;
    let unlit = [global_lx, direct_normal_lx, diffuse_horizontal_lx]
        .iter()
        .all(|v| v.unwrap_or(0.0) == 0.0);
    if lit && unlit {
        direct_normal_lx = None;
        diffuse_horizontal_lx = None;
    }
    Ok(WeatherHour {
        year: year as i32,
        month: month as u32,
        day: day as u32,
        hour: hour as u32,
        direct_normal_lx,
        diffuse_horizontal_lx,
        direct_normal_w,
        diffuse_horizontal_w,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "LOCATION,Testville,XX,Nowhere,synthetic,000000,52.37,4.90,1.0,0.0\n\
        DESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\n\
        HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,made by hand\nCOMMENTS 2,\n\
        DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31\n";

    fn year(leap: bool, row: impl Fn(u32, u32, u32) -> String) -> String {
        let mut text = HEADER.to_string();
        let y = if leap { 2024 } else { 2023 };
        for month in 1..=12 {
            for day in 1..=crate::daylight::days_in_month(y, month) {
                for hour in 1..=24 {
                    text += &row(month, day, hour);
                    text.push('\n');
                }
            }
        }
        text
    }

    fn plain(month: u32, day: u32, hour: u32) -> String {
        format!(
            "2023,{month},{day},{hour},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,\
             10.0,5.0,70,101325,0,0,300,200,500,100,40000,50000,12000,2000,180,3.0,5,5,20.0,\
             77777,9,999999999,10,0.1,0,88,0.2,0.0,0.0,"
        )
    }

    #[test]
    fn a_year_reads_with_its_site_and_daylight_fields() {
        let w = parse(&year(false, plain), Path::new("t.epw")).unwrap();
        assert_eq!(w.hours.len(), 8760);
        assert_eq!(w.site.latitude, 52.37);
        assert_eq!(w.site.longitude, 4.90);
        assert_eq!(w.site.timezone, 1.0);
        assert_eq!(w.site.name, "Testville, XX, Nowhere");
        let h = w.hours[8759];
        assert_eq!((h.month, h.day, h.hour), (12, 31, 24));
        assert_eq!(h.direct_normal_lx, Some(50_000.0));
        assert_eq!(h.diffuse_horizontal_lx, Some(12_000.0));
        assert_eq!(h.illuminance(30.0, 1), Some((50_000.0, 12_000.0)));
    }

    #[test]
    fn a_leap_year_and_missing_codes_are_read() {
        let text = year(true, |m, d, h| {
            plain(m, d, h).replacen("2023,", "2024,", 1).replace(
                "40000,50000,12000",
                if h == 12 {
                    "999999,999999,999999"
                } else {
                    "0,0,0"
                },
            )
        });
        let w = parse(&text, Path::new("t.epw")).unwrap();
        assert_eq!(w.hours.len(), 8784);
        // Missing illuminance: the irradiance through the efficacy (about 100-130 lm/W).
        let h = w.hours[11];
        assert_eq!(h.direct_normal_lx, None);
        let (dn, dh) = h.illuminance(40.0, 1).unwrap();
        assert!((50_000.0..65_000.0).contains(&dn), "{dn}");
        assert!((10_000.0..14_000.0).contains(&dh), "{dh}");
        // Zero illuminance beside positive irradiance: taken as missing too.
        assert_eq!(w.hours[0].direct_normal_lx, None);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let good = year(false, plain);
        let cases: Vec<(String, usize, &str)> = vec![
            (
                good.replacen("2023,1,1,5,", "2023,1,1,25,", 1),
                13,
                "hour 25",
            ),
            (
                good.replacen("2023,2,28,1,", "2023,2,29,1,", 1),
                8 + 58 * 24 + 1,
                "day 29",
            ),
            (
                good.replacen(",500,100,40000", ",500,-3,40000", 1),
                9,
                "diffuse horizontal radiation",
            ),
            (
                good.replacen("2023,1,1,2,60,", "2023,1,1,2,60\n", 1),
                10,
                "fields",
            ),
            (good.replace("LOCATION,", "PLACE,"), 1, "LOCATION"),
            (
                good.replace("52.37,4.90", "north,4.90"),
                1,
                "latitude 'north'",
            ),
        ];
        for (text, line, words) in cases {
            let e = parse(&text, Path::new("w.epw")).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("w.epw:{line}:")) && e.contains(words),
                "{e} (expected line {line}, '{words}')"
            );
        }
        // A short year names the last line.
        let short: String = good.lines().take(100).map(|l| format!("{l}\n")).collect();
        let e = parse(&short, Path::new("w.epw")).unwrap_err().to_string();
        assert!(e.contains("92 hourly rows"), "{e}");
    }
}
