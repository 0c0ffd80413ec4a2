//! What the command line prints: scene info, solve and render summaries, the visibility
//! benchmark's tables.

use std::fmt::Write;

use glam::{DVec3, Vec3};
use meshlight::render::RenderStats;
use meshlight::solver::{EpsilonSource, Options, StopReason};
use meshlight::{Image, Scene, Solution};

use super::bench::{BenchReport, Rate};

/// How many of each kind of light `info` lists.
const LISTED: usize = 10;

fn v3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn rgb(v: DVec3) -> String {
    format!("{:.4} {:.4} {:.4}", v.x, v.y, v.z)
}

/// One material: its name, kind and parameters.
fn material_line(m: &meshlight::scene::Material) -> String {
    use meshlight::scene::Kind;
    let mut line = format!("'{}': {}, Kd {}", m.name, m.kind.name(), v3(m.kd));
    match m.kind {
        Kind::Diffuse => {}
        Kind::Specular { ks, roughness } => {
            line += &format!(", Ks {}, roughness {roughness}", v3(ks));
        }
        Kind::Glass { ior, transmit, .. } => {
            line = format!(
                "'{}': {}, index {ior}, transmission {}",
                m.name,
                m.kind.name(),
                v3(transmit)
            );
        }
    }
    if m.is_emitter() {
        line += &format!(", Ke {}", v3(m.ke));
    }
    if m.two_sided {
        line += ", two-sided";
    }
    line
}

/// `meshlight info`.
pub fn info(scene: &Scene) -> String {
    let mut s = String::new();
    info_geometry(&mut s, scene);
    info_lights(&mut s, scene);
    info_camera_and_sky(&mut s, scene);
    match scene.solver_defaults().epsilon {
        Some(e) => {
            let _ = writeln!(s, "solver        epsilon {e} (scene file)");
        }
        None => {
            let _ = writeln!(s, "solver        no defaults in the scene file");
        }
    }
    s
}

/// `info`'s geometry: triangles, surfaces, materials, area, bounds.
fn info_geometry(s: &mut String, scene: &Scene) {
    let b = &scene.bounds();
    let _ = writeln!(s, "scene         {}", scene.path().display());
    let _ = writeln!(s, "triangles     {}", scene.triangles().len());
    let _ = writeln!(s, "surfaces      {}", scene.surfaces().len());
    let _ = writeln!(s, "materials     {}", scene.materials().len());
    for m in scene.materials() {
        let _ = writeln!(s, "  {}", material_line(m));
    }
    let _ = writeln!(s, "total area    {:.6}", scene.total_area());
    let _ = writeln!(
        s,
        "two-sided     {}",
        if scene.two_sided() { "yes" } else { "no" }
    );
    let _ = writeln!(
        s,
        "bounds        {} to {} (diagonal {:.6})",
        v3(b.min),
        v3(b.max),
        b.diagonal()
    );
}

/// `info`'s lights: area lights (the first few listed), point lights, luminaires, and the power
/// they emit.
fn info_lights(s: &mut String, scene: &Scene) {
    let emitters: Vec<_> = scene.emitters().collect();
    let area: f64 = 0.0
        + emitters
            .iter()
            .map(|&(i, _)| scene.surfaces()[i as usize].area)
            .sum::<f64>();
    let power: DVec3 = emitters.iter().map(|&(_, p)| p).sum();
    let lights = scene.area_light_count();
    let grouped = if lights == emitters.len() {
        String::new()
    } else {
        format!(" in {lights} light(s)")
    };
    let _ = writeln!(
        s,
        "area lights   {} surface(s){grouped}, area {:.6}, power {} W",
        emitters.len(),
        area,
        rgb(power)
    );
    for &(i, p) in emitters.iter().take(LISTED) {
        let surface = &scene.surfaces()[i as usize];
        let _ = writeln!(
            s,
            "  surface {i} '{}': area {:.6}, normal {}, power {} W",
            scene.materials()[surface.material as usize].name,
            surface.area,
            v3(surface.normal),
            rgb(p)
        );
    }
    if emitters.len() > LISTED {
        let _ = writeln!(s, "  ... and {} more", emitters.len() - LISTED);
    }
    let u = scene.units();
    let _ = writeln!(s, "point lights  {}", scene.point_lights().len());
    for l in scene.point_lights().iter().take(LISTED) {
        let _ = writeln!(
            s,
            "  at {}: intensity {} {}, power {} {}",
            v3(l.position),
            v3(l.intensity),
            u.intensity(),
            rgb(l.power()),
            u.flux()
        );
    }
    if scene.point_lights().len() > LISTED {
        let _ = writeln!(s, "  ... and {} more", scene.point_lights().len() - LISTED);
    }
    let _ = writeln!(s, "luminaires    {}", scene.luminaires().len());
    for l in scene.luminaires().iter().take(LISTED) {
        let flux = l.flux();
        let _ = writeln!(
            s,
            "  at {}: aim {}, flux {:.1} {} (RGB {} {})",
            v3(l.position),
            v3(l.aim),
            meshlight::scene::luminance(flux.as_vec3()),
            u.flux(),
            rgb(flux),
            u.flux()
        );
    }
    if scene.luminaires().len() > LISTED {
        let _ = writeln!(s, "  ... and {} more", scene.luminaires().len() - LISTED);
    }
    let _ = writeln!(
        s,
        "emitted power {} {}",
        rgb(scene.emitted_power()),
        u.flux()
    );
}

/// `info`'s camera, specular surfaces, sky and year.
fn info_camera_and_sky(s: &mut String, scene: &Scene) {
    let c = &scene.camera();
    let _ = writeln!(
        s,
        "camera        at {} looking at {}, up {}, fov_y {}°, {}x{}",
        v3(c.position),
        v3(c.look_at),
        v3(c.up),
        c.fov_y,
        c.width,
        c.height
    );
    let sp = meshlight::solver::specular_summary(scene, meshlight::solver::DEFAULT_SPECULAR_DEPTH);
    if sp.flat_reflectors + sp.curved_facets + sp.refracting_faces + sp.glossy_surfaces > 0 {
        let _ =
            writeln!(
            s,
            "specular      {} flat reflector(s), {} curved facet(s), {} refracting glass face(s), \
             {} glossy surface(s); images through {} chain(s){}; photons {}",
            sp.flat_reflectors,
            sp.curved_facets,
            sp.refracting_faces,
            sp.glossy_surfaces,
            sp.chains,
            if sp.chains_complete { "" } else { " (the rest by photons)" },
            if sp.photons { "yes" } else { "no" }
        );
    }
    if let Some(d) = scene.daylight() {
        let model = match d.sky().model() {
            meshlight::daylight::SkyModel::Uniform => "uniform".to_string(),
            meshlight::daylight::SkyModel::CieOvercast => "CIE overcast".to_string(),
            meshlight::daylight::SkyModel::Cie(t) => format!("CIE general sky type {t}"),
            meshlight::daylight::SkyModel::Perez {
                clearness,
                brightness,
            } => format!("Perez (clearness {clearness:.3}, brightness {brightness:.3})"),
        };
        let _ = writeln!(
            s,
            "sky           {model}, {} lx on the unobstructed horizontal; ground luminance {:.0}",
            d.diffuse_horizontal(),
            d.ground_luminance()
        );
        if let Some((zenith, azimuth)) = d.sun() {
            let _ = writeln!(
                s,
                "sun:          altitude {:.2}°, azimuth {:.2}° (clockwise from north)",
                90.0 - zenith,
                azimuth
            );
        }
    }
    if let Some(a) = scene.annual() {
        let _ = writeln!(
            s,
            "annual        weather {}, occupied hours {}-{}, sky in {} patches (`meshlight \
             annual`)",
            a.weather.display(),
            a.hours.0,
            a.hours.1,
            meshlight::daylight::patches::Patches::new(a.sky_subdivision).len()
        );
    }
}

fn mega(rates: &[Rate], threads: usize) -> Option<f64> {
    rates
        .iter()
        .find(|r| r.threads == threads)
        .map(|r| r.per_second / 1e6)
}

fn cells(rates: &[Rate], threads: &[usize]) -> String {
    threads
        .iter()
        .map(|&t| mega(rates, t).map_or_else(|| format!("{:>9}", "-"), |m| format!("{m:>9.2}")))
        .collect::<Vec<_>>()
        .join(" ")
}

/// `meshlight bench-vis`.
pub fn bench_report(scene: &Scene, r: &BenchReport) -> String {
    let mut s = String::new();
    let threads: Vec<usize> = r
        .backends
        .first()
        .map(|b| b.occlusion.iter().map(|x| x.threads).collect())
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "scene {}: {} triangles; {} occlusion segments (facing surface points), {} camera rays",
        scene.path().display(),
        scene.triangles().len(),
        r.segments,
        r.rays
    );
    if let Some(h) = r.embree_headers {
        let _ = writeln!(s, "embree shim compiled against {h}");
    }
    let heads = |what: &str| heads(threads.as_ref(), what);
    let _ = writeln!(
        s,
        "\nMillion queries per second (best of runs), through the Visibility trait:"
    );
    let _ = writeln!(
        s,
        "{:<28} {:>10} {} {}",
        "backend",
        "build ms",
        heads("occl"),
        heads("hit")
    );
    for b in &r.backends {
        let _ = writeln!(
            s,
            "{:<28} {:>10.2} {} {}",
            b.detail,
            b.build.as_secs_f64() * 1e3,
            cells(&b.occlusion, &threads),
            cells(&b.intersect, &threads)
        );
    }
    if !r.embree_raw.is_empty() {
        bench_raw(&mut s, r, &threads);
    }
    bench_ratios(&mut s, r, &threads);
    if let Some(a) = r.agreement {
        let _ = writeln!(
            s,
            "\nagreement embree vs bvh: {} of {} occlusion answers differ ({:.2e}); {} of {} rays differ in hit/miss, {} in distance (>1e-4 relative)",
            a.occlusion,
            r.segments,
            a.occlusion as f64 / r.segments.max(1) as f64,
            a.hit_or_miss,
            r.rays,
            a.distance
        );
    }
    s
}

/// A column heading per thread count: "occl 2T".
fn heads(threads: &[usize], what: &str) -> String {
    threads
        .iter()
        .map(|t| format!("{:>9}", format!("{what} {t}T")))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The Embree shim's raw rates, and the trait's share of the best raw path.
fn bench_raw(s: &mut String, r: &BenchReport, threads: &[usize]) {
    let heads = |what: &str| heads(threads, what);
    let _ = writeln!(s, "\nEmbree raw shim, whole share per call (Mq/s):");
    let _ = writeln!(
        s,
        "{:<28} {:>10} {} {}",
        "mode",
        "",
        heads("occl"),
        heads("hit")
    );
    for raw in &r.embree_raw {
        let _ = writeln!(
            s,
            "{:<28} {:>10} {} {}",
            raw.mode,
            "",
            cells(&raw.occlusion, threads),
            cells(&raw.intersect, threads)
        );
    }
    if let Some(embree) = r
        .backends
        .iter()
        .find(|b| b.backend == meshlight::Backend::Embree)
    {
        for &t in threads {
            let best = r
                .embree_raw
                .iter()
                .filter_map(|raw| mega(&raw.occlusion, t))
                .fold(0.0, f64::max);
            if let (Some(through), true) = (mega(&embree.occlusion, t), best > 0.0) {
                let _ = writeln!(
                    s,
                    "trait / best raw path, {t} thread(s): {:.1}%",
                    100.0 * through / best
                );
            }
        }
    }
}

/// Embree's rates over each other backend's, thread count by thread count.
fn bench_ratios(s: &mut String, r: &BenchReport, threads: &[usize]) {
    let embree = r
        .backends
        .iter()
        .find(|b| b.backend == meshlight::Backend::Embree);
    if let Some(e) = embree {
        for b in r
            .backends
            .iter()
            .filter(|b| b.backend != meshlight::Backend::Embree)
        {
            for &t in threads {
                if let (Some(x), Some(y)) = (mega(&e.occlusion, t), mega(&b.occlusion, t)) {
                    let hx = mega(&e.intersect, t).unwrap_or(0.0);
                    let hy = mega(&b.intersect, t).unwrap_or(f64::NAN);
                    let _ = writeln!(
                        s,
                        "embree / {}, {t} thread(s): occlusion {:.2}x, closest hit {:.2}x",
                        b.detail,
                        x / y,
                        hx / hy
                    );
                }
            }
        }
    }
}

/// The solve's summary: samples per round, shots, queries, unshot fraction, time per phase.
pub fn solve_summary(scene: &Scene, s: &Solution, o: &Options, backend: &str) -> String {
    let mut out = String::new();
    summary_settings(&mut out, scene, s, o, backend);
    summary_rounds(&mut out, s);
    if s.stop() == StopReason::Diverged {
        let _ = writeln!(
            out,
            "warning: the solve diverged: its unshot power grew; the image is not to be trusted"
        );
    }
    summary_memory(&mut out, s, o);
    summary_energy(&mut out, scene, s);
    if s.stop() == StopReason::ShotLimit {
        let _ = writeln!(
            out,
            "warning: the last solve stopped at its shot limit with {:.2e} of the emitted power unshot",
            s.rounds().last().map_or(0.0, |r| r.shooting.unshot_fraction)
        );
    }
    out
}

/// The summary's first line: the scene, the backend and the settings that matter most.
fn summary_settings(out: &mut String, scene: &Scene, s: &Solution, o: &Options, backend: &str) {
    let source = match s.epsilon_source() {
        EpsilonSource::Options => "command line",
        EpsilonSource::SceneFile => "scene file",
        EpsilonSource::Automatic => "automatic",
        EpsilonSource::LightLength => "the scene's light length",
        _ => "",
    };
    let scaled = match s.epsilon_source() {
        EpsilonSource::SceneFile | EpsilonSource::Automatic | EpsilonSource::LightLength
            if o.epsilon_scale != 1.0 =>
        {
            format!(" × {}", o.epsilon_scale)
        }
        _ => String::new(),
    };
    let _ = writeln!(
        out,
        "scene {}: {} triangles, {} surfaces; backend {}, {} thread(s); ε {} ({source}{scaled}), α {}, ζ {}, {} light samples",
        scene.path().display(),
        scene.triangles().len(),
        scene.surfaces().len(),
        backend,
        o.threads,
        // Six significant figures: a scaled ε (0.1 × 0.6) prints as 0.06, not 0.060000002.
        format!("{:.6}", s.epsilon())
            .trim_end_matches('0')
            .trim_end_matches('.'),
        o.alpha,
        o.zeta,
        o.light_samples
    );
}

/// The summary's table: a row per round.
fn summary_rounds(out: &mut String, s: &Solution) {
    let _ = writeln!(
        out,
        "{:>5} {:>8} {:>7} {:>7} {:>8} {:>10} {:>11} {:>9} {:>17} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "round",
        "samples",
        "added",
        "refined",
        "shots",
        "links",
        "vis queries",
        "shadow q",
        "unshot start→end",
        "stop",
        "place s",
        "areas s",
        "direct s",
        "links s",
        "shoot s"
    );
    for r in s.rounds() {
        let stop = match r.shooting.stop {
            StopReason::Converged => "converged",
            StopReason::ShotLimit => "shot limit",
            StopReason::Stopped => "stopped",
            StopReason::NoLight => "no light",
            StopReason::Diverged => "DIVERGED",
            _ => "?",
        };
        let _ = writeln!(
            out,
            "{:>5} {:>8} {:>7} {:>7} {:>8} {:>10} {:>11} {:>9} {:>17} {:>10} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3}{}",
            r.round,
            r.samples,
            r.added,
            r.refined,
            r.shooting.shots,
            r.shooting.links,
            r.shooting.queries,
            r.direct_queries,
            format!("{:.2e}→{:.2e}", r.shooting.initial_unshot_fraction, r.shooting.unshot_fraction),
            stop,
            r.seconds.sampling,
            r.seconds.areas,
            r.seconds.direct,
            r.seconds.links,
            r.seconds.shooting,
            if r.capped { "  (sample budget reached)" } else { "" }
        );
    }
}

/// What the samples and the links held against the budget, and over ranks what each held.
fn summary_memory(out: &mut String, s: &Solution, o: &Options) {
    let bytes: u64 = s
        .rounds()
        .iter()
        .map(|r| r.shooting.bytes)
        .max()
        .unwrap_or(0);
    let samples_bytes: u64 = s
        .rounds()
        .iter()
        .map(|r| r.solution_bytes)
        .max()
        .unwrap_or(0);
    let _ = writeln!(
        out,
        "solver: {}; samples held at most {}, links and caches {}, of a {} budget",
        if o.flat() {
            "flat (every sample to every sample)".into()
        } else {
            format!("cluster hierarchy, threshold {}", o.cluster_threshold)
        },
        crate::units::bytes(samples_bytes as f64),
        crate::units::bytes(bytes as f64),
        crate::units::bytes(o.memory_budget as f64),
    );
    let size = crate::ranks::ranks().size();
    if size > 1 {
        // The round with the most links is what bounds a rank's memory.
        if let Some(r) = s.rounds().iter().max_by_key(|r| r.shooting.links) {
            let sh = &r.shooting;
            // Each sweep and the row sums' sweep exchange once.
            let exchanges = (sh.shots + 1).max(1);
            let _ = writeln!(
                out,
                "ranks: {size}; links held per rank at most {} of {} ({:.2}x), round {}; each \
                 sweep all-gathers {} (24 bytes a sample), of which rank 0 received {}",
                sh.most_held_links,
                sh.links,
                sh.most_held_links as f64 / sh.links.max(1) as f64,
                r.round,
                crate::units::bytes(24.0 * r.samples as f64),
                crate::units::bytes(sh.exchanged_bytes as f64 / exchanges as f64),
            );
        }
    }
}

/// Where the emitted light went, where the account adds up (a single solve, no specular
/// surfaces).
fn summary_energy(out: &mut String, scene: &Scene, s: &Solution) {
    let emitted = s.ledger().emitted.element_sum();
    // Adaptive rounds start new samples from interpolated light, which the ledger does not
    // follow: only a single solve's account adds up. Specular surfaces have no samples: what
    // they absorb is not counted, so the account is left out where a scene has them.
    let specular = scene.materials().iter().any(|m| m.is_specular());
    if emitted > 0.0 && s.rounds().len() == 1 && !specular {
        // Where the light went: a closed scene's "left" is what the lights that reflect
        // nothing took, plus what the transfer lost; an open one's adds its openings.
        let share = |p: f64| 100.0 * p / emitted;
        let _ = writeln!(
            out,
            "energy: of the emitted power, {:.2}% absorbed by the surfaces, {:.2}% left them \
             (openings, lights that reflect nothing, transfer losses), {:.2}% unshot",
            share(s.absorbed(scene).element_sum()),
            share(s.ledger().escaped.element_sum()),
            share(s.unshot_power().element_sum())
        );
    }
}

/// The render's summary.
pub fn render_summary(image: &Image, stats: &RenderStats, seconds: f64) -> String {
    format!(
        "render {}x{}: {} camera rays ({} edge pixels supersampled), {} interpolation queries, {} shadow rays, {:.3} s; mean radiance {:.5}\n",
        image.width, image.height, stats.camera_rays, stats.supersampled_pixels, stats.interpolation_queries, stats.shadow_rays, seconds, image.mean()
    )
}

/// Writes `image` as a false-colour PNG of its luminance, with a legend in `units`.
pub fn false_colour_render(
    image: &Image,
    path: &std::path::Path,
    kind: super::FalseColor,
    range: Option<(f64, f64)>,
    log: bool,
    units: meshlight::scene::Units,
) -> anyhow::Result<()> {
    let values: Vec<f64> = image
        .pixels
        .iter()
        .map(|p| f64::from(meshlight::scene::luminance(*p)))
        .collect();
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_unstable_by(f64::total_cmp);
    let percentile = |v: &[f64], q: usize| v.get(v.len() * q / 100).copied().unwrap_or(0.0);
    let (low, high) = match range {
        Some(r) => r,
        None if log => {
            let positive: Vec<f64> = sorted.iter().copied().filter(|&v| v > 0.0).collect();
            (percentile(&positive, 1), percentile(&positive, 99))
        }
        None => (0.0, percentile(&sorted, 99)),
    };
    if log && low <= 0.0 {
        anyhow::bail!("--log needs a range above 0 (the image has no lit pixel, or MIN ≤ 0)");
    }
    let high = if high > low { high } else { low + 1.0 };
    let (unit, name) = match kind {
        super::FalseColor::Luminance => (units.radiance(), "luminance"),
        super::FalseColor::Illuminance => (units.irradiance(), "illuminance"),
    };
    super::plot::sequential_png(
        path,
        (image.width, image.height),
        &values,
        (low, high, log),
        unit,
        &format!("{name} ({unit})"),
    )
}
