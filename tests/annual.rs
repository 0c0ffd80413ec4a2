//! A year of daylight (scene-format v4, "A year of weather"): the weather reader on a real
//! typical year, the metrics of a synthetic year whose every hour is known by hand, and the
//! side-lit office's year against one-moment solves of its hours' skies on both backends.

mod common;

use std::path::Path;

use common::{camera, material, Builder};
use glam::Vec3;
use meshlight::annual::{annual, AnnualOptions, Year};
use meshlight::daylight::epw::{self, Weather};
use meshlight::daylight::spa::{delta_t, sun_position, LocalTime, Observer};
use meshlight::daylight::{AnnualSettings, Site};
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::scene::{luminance, Grid};
use meshlight::{Backend, Control, Options, Scene};

fn office_weather() -> Weather {
    epw::read(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/office/greensboro.epw"
    )))
    .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_typical_year_reads_as_its_tmy3_source_says() {
    let w = office_weather();
    assert_eq!(w.hours.len(), 8760);
    assert_eq!(
        (w.site.latitude, w.site.longitude, w.site.timezone),
        (36.1, -79.95, -5.0)
    );
    // NREL's TMY3 row "06/16/1989,14:00": DNI 1 W/m², DHI 292 W/m², DN illuminance 1 and DH
    // 354 in its units of 100 lx.
    let h = w
        .hours
        .iter()
        .find(|h| (h.month, h.day, h.hour) == (6, 16, 14))
        .unwrap();
    assert_eq!(h.year, 1989);
    assert_eq!(
        (h.direct_normal_w, h.diffuse_horizontal_w),
        (Some(1.0), Some(292.0))
    );
    assert_eq!(
        (h.direct_normal_lx, h.diffuse_horizontal_lx),
        (Some(100.0), Some(35_400.0))
    );
    // Irradiance through the efficacy lands near the measured illuminance (an overcast
    // hour's diffuse light: about 120 lm/W).
    let converted = meshlight::daylight::epw::WeatherHour {
        direct_normal_lx: None,
        diffuse_horizontal_lx: None,
        ..*h
    };
    let (_, dh) = converted.illuminance(30.0, 167).unwrap();
    assert!((dh / 35_400.0 - 1.0).abs() < 0.1, "{dh}");
}

/// An EPW year at (0°, 0°, UTC) whose hour `h` of day `d` (1-based day of the year) has the
/// light `light(d, h)` = (direct normal, diffuse horizontal).
fn synthetic_year(light: impl Fn(u32, u32) -> (f64, f64)) -> Weather {
    let mut text = String::from(
        "LOCATION,Null Island,-,-,synthetic,000000,0.0,0.0,0.0,0.0\nDATA PERIODS,1,1,Data,Sunday,1/1,12/31\n",
    );
    let mut day = 0;
    for month in 1..=12 {
        for d in 1..=meshlight::daylight::days_in_month(2023, month) {
            day += 1;
            for hour in 1..=24 {
                let (dn, dh) = light(day, hour);
                text += &format!(
                    "2023,{month},{d},{hour},60,_,20,10,50,101325,0,0,0,0,0,0,0,{dn},{dh},0\n"
                );
            }
        }
    }
    epw::parse(&text, Path::new("synthetic.epw")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_synthetic_year_gives_the_metrics_counted_by_hand() {
    // Points 1 m over a black floor see the whole sky and nothing else: each hour's
    // illuminance is the sky's diffuse horizontal, plus the sun's direct normal × cos z.
    // At (0°, 0°) in UTC the sun is up from about 6:00 to 18:00 all year, so every occupied
    // hour (8-18) is lit; the other hours have no light in the file and are left out.
    // Days cycle through 50, 200, 1000 and 5000 lx of sky; every tenth day has a sun of
    // 100,000 lx at 12:00-13:00.
    let sky = [50.0, 200.0, 1000.0, 5000.0];
    let light = |d: u32, h: u32| {
        if !(9..=18).contains(&h) {
            return (0.0, 0.0);
        }
        let dn = if d % 10 == 0 && h == 13 {
            100_000.0
        } else {
            0.0
        };
        (dn, sky[(d % 4) as usize])
    };
    let weather = synthetic_year(light);
    // A black floor: no light comes back from it.
    let scene = open_floor(0.0, false);
    // By hand: which hours reach 300 lx, which are useful, which have sun.
    let (mut above, mut useful, mut sun, mut exposure) = (0u32, 0u32, 0u32, 0.0f64);
    let observer = Observer {
        latitude: 0.0,
        longitude: 0.0,
        elevation: 0.0,
        pressure: 1010.0,
        temperature: 10.0,
    };
    for (i, h) in weather.hours.iter().enumerate() {
        let (day, hour) = (i as u32 / 24 + 1, h.hour);
        let (dn, dh) = light(day, hour);
        if dh == 0.0 {
            continue;
        }
        let direct = if dn > 0.0 {
            let time = LocalTime {
                year: 2023,
                month: h.month,
                day: h.day,
                hour: hour - 1,
                minute: 30,
                second: 0.0,
                timezone: 0.0,
            };
            let z = sun_position(&time, &observer, delta_t(2023.5)).zenith;
            dn * z.to_radians().cos()
        } else {
            0.0
        };
        let e = dh + direct;
        above += u32::from(e >= 300.0);
        useful += u32::from((100.0..=3000.0).contains(&e));
        sun += u32::from(direct >= 1000.0);
        exposure += e;
    }
    assert_eq!(sun, 36);
    for backend in Backend::available() {
        let vis = backend.build(&scene).unwrap();
        let options = AnnualOptions::default();
        let year = annual(&scene, &weather, vis.as_ref(), &options, &mut |_| {
            Control::Continue
        })
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(!year.stopped);
        assert_eq!(year.sun_hours.len(), 3650, "{}", backend.name());
        let g = &year.grids[0];
        assert_eq!(g.summary.occupied_hours, 3650);
        assert_eq!(g.summary.daylight_hours, 3650);
        for m in g.metrics.iter().map(|m| m.unwrap()) {
            assert_eq!(
                m.da,
                100.0 * f64::from(above) / 3650.0,
                "{}",
                backend.name()
            );
            assert_eq!(
                m.udi,
                100.0 * f64::from(useful) / 3650.0,
                "{}",
                backend.name()
            );
            assert_eq!(m.sun_hours, sun, "{}", backend.name());
            assert!(
                (m.exposure / exposure - 1.0).abs() < 0.005,
                "{}: exposure {} against {exposure} by hand",
                backend.name(),
                m.exposure
            );
        }
        // Every point alike: DA (60%) ≥ 50% everywhere, no point past 250 sun hours, and
        // 300 lx on every point in the hours that reach it.
        assert_eq!((g.summary.sda, g.summary.ase), (100.0, 0.0));
        assert_eq!(
            g.summary.en17037_hours,
            100.0 * f64::from(above) / 3650.0,
            "{}",
            backend.name()
        );
    }
}

/// An open floor of reflectance `kd` with one grid 1 m over it and `[annual]`; with `wall`, a
/// wall beside the grid (shadows and inter-reflection, not open sky alone).
fn open_floor(kd: f32, wall: bool) -> Scene {
    let mut b = Builder::default();
    let floor = b.material(material("floor", kd, 0.0));
    b.quad(
        [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ],
        floor,
    );
    if wall {
        let m = b.material(material("wall", 0.7, 0.0));
        b.quad(
            [
                Vec3::new(1.0, 0.0, -2.0),
                Vec3::new(1.0, 0.0, 2.0),
                Vec3::new(1.0, 3.0, 2.0),
                Vec3::new(1.0, 3.0, -2.0),
            ],
            m,
        );
    }
    let mut scene = b.scene(camera(Vec3::new(0.0, 2.0, -4.0), Vec3::ZERO, 16));
    let grid = Grid::new(
        "open",
        Vec3::new(-0.5, 1.0, -0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Some(Vec3::Y),
        Some(0.5),
    )
    .unwrap();
    scene.add_grid(grid).unwrap();
    scene.set_annual(Some(AnnualSettings {
        weather: "synthetic.epw".into(),
        hours: (8, 18),
        sky_subdivision: 1,
        site: Site::default(),
    }));
    scene
}

#[test]
fn a_stopped_year_counts_the_hours_done_and_a_year_without_its_parts_is_an_error() {
    let weather = synthetic_year(|_, h| {
        if (9..=18).contains(&h) {
            (0.0, 1000.0)
        } else {
            (0.0, 0.0)
        }
    });
    let scene = open_floor(0.5, false);
    let vis = Backend::default_backend().build(&scene).unwrap();
    let options = AnnualOptions::default();
    // Stopped among the hours: the metrics of those done, counted consistently.
    let year = annual(&scene, &weather, vis.as_ref(), &options, &mut |p| {
        if p.phase == meshlight::Phase::Hours && p.fraction > 0.3 {
            Control::Stop
        } else {
            Control::Continue
        }
    })
    .unwrap();
    assert!(year.stopped);
    let done = year.sun_hours.len();
    assert!(done > 0 && done < 3650, "{done}");
    let g = &year.grids[0];
    assert_eq!(g.summary.daylight_hours as usize, done);
    assert!(g.summary.occupied_hours as usize >= done);
    // Stopped while the coefficients are shot: no hours.
    let year = annual(&scene, &weather, vis.as_ref(), &options, &mut |p| {
        if p.phase == meshlight::Phase::Coefficients && p.fraction > 0.1 {
            Control::Stop
        } else {
            Control::Continue
        }
    })
    .unwrap();
    assert!(year.stopped && year.sun_hours.is_empty());
    // Without [annual], or without grids: an error naming what is missing.
    let mut bare = scene.clone();
    bare.set_annual(None);
    let e = annual(&bare, &weather, vis.as_ref(), &options, &mut |_| {
        Control::Continue
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("has no [annual]"), "{e}");
    // A budget too small for the coefficients is refused before they are held.
    let tight = AnnualOptions {
        solver: Options {
            // About 280 samples: the solve fits, its sky rays' 5 KiB a sample do not.
            epsilon: Some(0.5),
            memory_budget: 7 << 18,
            ..Options::default()
        },
        ..AnnualOptions::default()
    };
    match annual(&scene, &weather, vis.as_ref(), &tight, &mut |_| {
        Control::Continue
    }) {
        Err(e @ meshlight::Error::Budget { .. }) => {
            assert!(e.to_string().contains("a year of daylight needs"), "{e}")
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a year beyond its budget ran"),
    }
}

#[test]
fn one_and_two_threads_give_the_same_year() {
    // Sun every tenth day at noon, so the sun lattice and the shadow rays are in it too.
    let weather = synthetic_year(|d, h| match h {
        13 if d % 10 == 0 => (80_000.0, 12_000.0),
        9..=18 => (0.0, 8_000.0),
        _ => (0.0, 0.0),
    });
    let scene = open_floor(0.5, true);
    let years: Vec<Year> = [1, 2]
        .iter()
        .map(|&threads| {
            let options = AnnualOptions {
                solver: Options {
                    threads,
                    epsilon: Some(0.5),
                    ..Options::default()
                },
                lux: LuxOptions {
                    threads,
                    ..LuxOptions::default()
                },
                hourly: true,
            };
            let vis = Backend::default_backend().build(&scene).unwrap();
            annual(&scene, &weather, vis.as_ref(), &options, &mut |_| {
                Control::Continue
            })
            .unwrap()
        })
        .collect();
    assert_eq!(years[0].grids[0].hourly, years[1].grids[0].hourly);
    assert_eq!(years[0].grids[0].metrics, years[1].grids[0].metrics);
}

/// The office's scene file with `[annual]` replaced by one moment's Perez sky.
fn office_at(weather: &Weather, h: &meshlight::daylight::epw::WeatherHour) -> Scene {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/office"));
    let text = std::fs::read_to_string(dir.join("annual.toml")).unwrap();
    let (head, tail) = text.split_once("[annual]").unwrap();
    let grids = &tail[tail.find("[[grid]]").unwrap()..];
    let (dn, dh) = (
        h.direct_normal_lx.unwrap(),
        h.diffuse_horizontal_lx.unwrap(),
    );
    let head = head.replace(
        "[site]",
        &format!(
            "[site]\nlatitude = {}\nlongitude = {}\ntimezone = {}",
            weather.site.latitude, weather.site.longitude, weather.site.timezone
        ),
    );
    let sky = format!(
        "[sky]\nmodel = \"perez\"\ntime = \"{:04}-{:02}-{:02}T{:02}:30\"\ndirect_normal = {dn}\n\
         diffuse_horizontal = {dh}\n\n",
        h.year,
        h.month,
        h.day,
        h.hour - 1
    );
    let obj = dir.join("office.obj");
    let text = format!("{head}{sky}{grids}").replace(
        "obj = \"office.obj\"",
        &format!("obj = \"{}\"", obj.display()),
    );
    let path = std::env::temp_dir().join(format!("meshlight-annual-{}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_file(&path).ok();
    scene
}

#[test]
#[ignore = "full tier: a large or repeated solve (cargo test -- --include-ignored)"]
fn the_office_year_matches_one_moment_solves_hour_by_hour() {
    let weather = office_weather();
    let scene = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/office/annual.toml"
    ))
    .unwrap();
    // At the defaults: at ε 0.3 (a third of the samples) low winter suns put a point up to
    // 6.3% off (docs/performance.md), the sun's patch falling between coarser samples.
    let solver = Options::default();
    let lux = LuxOptions {
        light_samples: 16,
        ..LuxOptions::default()
    };
    let options = AnnualOptions {
        solver: solver.clone(),
        lux,
        hourly: true,
    };
    for backend in Backend::available() {
        let vis = backend.build(&scene).unwrap();
        let year: Year = annual(&scene, &weather, vis.as_ref(), &options, &mut |_| {
            Control::Continue
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let n = year.grids[0].points.len();
        // Ten hours spread over the year: every 440th hour with the sun up.
        let (mut clear, mut overcast, mut sun_in) = (0, 0, 0);
        let mut worst: (f64, f64) = (0.0, 0.0);
        for k in (0..10).map(|i| 100 + 440 * i) {
            let stamp = year.sun_hours[k];
            let h = weather
                .hours
                .iter()
                .find(|h| (h.month, h.day, h.hour) == (stamp.month, stamp.day, stamp.hour))
                .unwrap();
            let moment = office_at(&weather, h);
            let vis1 = backend.build(&moment).unwrap();
            let solution =
                meshlight::solve(&moment, vis1.as_ref(), &solver, &mut |_| Control::Continue)
                    .unwrap();
            let e = illuminance(
                &moment,
                &solution,
                vis1.as_ref(),
                &moment.grids()[0],
                &lux,
                &mut |_| Control::Continue,
            )
            .unwrap();
            let one: Vec<f64> = e
                .values
                .iter()
                .map(|v| f64::from(luminance(v.as_vec3())))
                .collect();
            let ours: Vec<f64> = year.grids[0].hourly[k * n..(k + 1) * n]
                .iter()
                .map(|&v| f64::from(v))
                .collect();
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let off_mean = (mean(&ours) / mean(&one) - 1.0).abs();
            let off_point = ours
                .iter()
                .zip(&one)
                .map(|(a, b)| (a / b - 1.0).abs())
                .fold(0.0, f64::max);
            assert!(
                off_mean < 0.02 && off_point < 0.05,
                "{} {:?}: mean {:.0} lx against {:.0} one-moment, worst point {:.2}%",
                backend.name(),
                stamp,
                mean(&ours),
                mean(&one),
                100.0 * off_point
            );
            worst = (worst.0.max(off_mean), worst.1.max(off_point));
            let dn = h.direct_normal_lx.unwrap();
            let is_clear = dn > 20_000.0;
            clear += usize::from(is_clear);
            overcast += usize::from(dn < 1_000.0);
            // The sun's patch on the work plane: a clear hour with some point lit above 15% of
            // the direct normal illuminance (a sun above 11° through a pane passing 80%
            // gives more; in the clear hours taken without it, the brightest point gets 9.5%
            // and 12.9% of it from the sky through the window).
            let brightest = one.iter().copied().fold(0.0, f64::max);
            sun_in += usize::from(is_clear && brightest > 0.15 * dn);
        }
        // The hours span clear and overcast skies, and clear hours with the sun on the work
        // plane (a low winter sun through the south window) and without (a high summer one).
        assert!(
            clear >= 3 && overcast >= 2 && sun_in >= 1 && sun_in < clear,
            "clear {clear}, overcast {overcast}, the sun on the plane {sun_in}"
        );
        eprintln!(
            "{}: worst mean {:.2}%, worst point {:.2}% over 10 hours",
            backend.name(),
            100.0 * worst.0,
            100.0 * worst.1
        );
    }
}
