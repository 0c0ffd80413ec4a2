//! One progress contract for every long call: each of solve, render, lux, the path tracer and
//! the patch solver hears its phases through the same callback, honours a Stop in any phase,
//! remembers it, and returns a partial result a host can use.

mod common;

use common::shipped;
use meshlight::lux::{illuminance, LuxOptions};
use meshlight::progress::{Control, Phase, Progress};
use meshlight::reference::{patch_radiosity, path_trace, PatchOptions, PathOptions};
use meshlight::solver::{Options, StopReason};
use meshlight::{Backend, RenderOptions, Scene};

/// The room at a small size (its light panel, boxes and coloured walls).
fn room() -> Scene {
    let mut scene = Scene::load(shipped("room")).unwrap();
    let camera = meshlight::scene::Camera {
        width: 48,
        height: 48,
        ..*scene.camera()
    };
    scene.set_camera(camera).unwrap();
    scene
}

/// A callback that answers Stop from the first report of `phase` on (and Continue before),
/// and remembers every report.
fn stop_at(phase: Phase, heard: &mut Vec<Progress>) -> impl FnMut(&Progress) -> Control + '_ {
    let mut stopping = false;
    move |p: &Progress| {
        heard.push(*p);
        stopping |= p.phase == phase;
        if stopping {
            Control::Stop
        } else {
            Control::Continue
        }
    }
}

#[test]
fn a_solve_stopped_in_any_phase_returns_an_estimate_that_renders() {
    let scene = room();
    let vis = Backend::Bvh.build(&scene).unwrap();
    let options = Options {
        rounds: 1,
        ..Options::default()
    };
    let full =
        meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap();
    let phases = [
        Phase::Sampling,
        Phase::Areas,
        Phase::DirectLight,
        Phase::Links,
        Phase::Shooting,
        Phase::Adaptive,
    ];
    for phase in phases {
        let mut heard = Vec::new();
        let s = meshlight::solve(
            &scene,
            vis.as_ref(),
            &options,
            &mut stop_at(phase, &mut heard),
        )
        .unwrap();
        assert!(
            heard.iter().any(|p| p.phase == phase),
            "{phase:?} never heard"
        );
        // Usable: the invariants hold and it renders to a finite image.
        assert_eq!(s.validate(), Ok(()), "{phase:?}");
        let (image, _) = meshlight::render(
            &scene,
            &s,
            vis.as_ref(),
            &RenderOptions::default(),
            &mut |_| Control::Continue,
        )
        .unwrap();
        assert!(image.pixels.iter().all(|p| p.is_finite()), "{phase:?}");
        // Remembered: once stopped, no sweep was shot and no round was added.
        let first_stop = heard.iter().position(|p| p.phase == phase).unwrap();
        assert!(
            heard[first_stop..]
                .iter()
                .all(|p| p.round == heard[first_stop].round && p.shots <= 1),
            "{phase:?}: work went on after the stop: {:?}",
            &heard[first_stop..]
        );
        // Reported as stopped whatever the phase: the docs' contract (once an adaptive
        // phase's Stop said Converged).
        assert_eq!(s.stop(), StopReason::Stopped, "{phase:?}");
        if phase == Phase::Adaptive {
            // The first round was complete: its estimate is kept whole.
            assert_eq!(s.rounds().len(), 1);
            assert_eq!(s.samples().len(), full.rounds()[0].samples);
        } else {
            assert!(s.samples().len() <= full.samples().len());
        }
    }
}

#[test]
fn a_render_stopped_part_way_keeps_the_pixels_it_traced() {
    let scene = room();
    let vis = Backend::Bvh.build(&scene).unwrap();
    let s = meshlight::solve(&scene, vis.as_ref(), &Options::default(), &mut |_| {
        Control::Continue
    })
    .unwrap();
    let mut heard = Vec::new();
    let (image, stats) = meshlight::render(
        &scene,
        &s,
        vis.as_ref(),
        &RenderOptions::default(),
        &mut |p| {
            heard.push(*p);
            if p.fraction >= 0.2 {
                Control::Stop
            } else {
                Control::Continue
            }
        },
    )
    .unwrap();
    assert!(stats.stopped);
    assert!(heard.iter().all(|p| p.phase == Phase::Rendering));
    // Rows are traced top down: the top is lit, the bottom black.
    let w = image.width as usize;
    let row = |y: usize| {
        image.pixels[y * w..(y + 1) * w]
            .iter()
            .map(|p| p.x)
            .sum::<f32>()
    };
    assert!(row(0) > 0.0 && row(image.height as usize - 1) == 0.0);
    // Stopped after about a fifth: fewer rays than the whole picture's.
    assert!(stats.camera_rays <= u64::from(image.width * image.height));
}

#[test]
fn a_grid_stopped_while_gathering_says_how_many_points_it_measured() {
    // The gallery's geometry is generated: made here if missing.
    let path = meshlight_gallery::ensure().expect("generate the gallery");
    let scene = Scene::load(path.with_file_name("design.toml")).unwrap();
    let vis = Backend::Bvh.build(&scene).unwrap();
    let options = Options {
        rounds: 0,
        epsilon: Some(0.6),
        ..Options::default()
    };
    let s = meshlight::solve(&scene, vis.as_ref(), &options, &mut |_| Control::Continue).unwrap();
    let grid = &scene.grids()[0];
    let lux = LuxOptions::default();
    let go = |stop: Option<Phase>| {
        let mut heard = Vec::new();
        let e = match stop {
            Some(phase) => illuminance(&scene, &s, vis.as_ref(), grid, &lux, &mut |p| {
                heard.push(*p);
                if p.phase == phase && p.fraction > 0.3 {
                    Control::Stop
                } else {
                    Control::Continue
                }
            }),
            None => illuminance(&scene, &s, vis.as_ref(), grid, &lux, &mut |p| {
                heard.push(*p);
                Control::Continue
            }),
        };
        (e.unwrap(), heard)
    };
    let (whole, heard) = go(None);
    assert_eq!(whole.measured, whole.values.len());
    assert!(heard.iter().any(|p| p.phase == Phase::DirectLight));
    assert!(heard.iter().any(|p| p.phase == Phase::Gathering));
    let (part, _) = go(Some(Phase::Gathering));
    assert!(
        part.measured > 0 && part.measured < part.values.len(),
        "{}",
        part.measured
    );
    // The measured points are the whole call's, bit for bit.
    assert_eq!(part.values[..part.measured], whole.values[..part.measured]);
    let (none, _) = go(Some(Phase::DirectLight));
    assert_eq!(none.measured, 0);
}

#[test]
fn the_path_tracer_stops_after_a_pass_and_the_patch_solver_renders_its_estimate() {
    let scene = room();
    let vis = Backend::Bvh.build(&scene).unwrap();
    let options = PathOptions {
        spp: 64,
        ..PathOptions::default()
    };
    let mut heard = Vec::new();
    let traced = path_trace(
        &scene,
        vis.as_ref(),
        &options,
        &mut stop_at(Phase::Tracing, &mut heard),
    )
    .unwrap();
    assert!(traced.stopped);
    // The first pass ran (both half-images need samples), and no more than it.
    assert!(traced.spp >= 2 && traced.spp < 64, "{}", traced.spp);
    assert!(traced.image.mean() > 0.0 && traced.image.mean().is_finite());

    let mut heard = Vec::new();
    let patches = patch_radiosity(
        &scene,
        vis.as_ref(),
        &PatchOptions {
            patch_size: 0.5,
            ..PatchOptions::default()
        },
        &mut stop_at(Phase::Shooting, &mut heard),
    )
    .unwrap();
    assert!(patches.stopped);
    assert_eq!(patches.shots, 0, "stopped at the first shooting report");
    assert!(heard.iter().any(|p| p.phase == Phase::Meshing));
    assert!(heard.iter().any(|p| p.phase == Phase::Rendering));
    // Nothing shot yet: what shows is the emitters' own light and the point lights' direct
    // light — finite, and the panel lit.
    assert!(patches.image.pixels.iter().all(|p| p.is_finite()));
    assert!(patches.image.mean() > 0.0);
}

/// A backend that takes `delay` over every call once `slow` is set, as a host's remote or
/// instrumented ray caster may (fast before, so a test reaches every phase in good time).
struct Slow {
    inner: Box<dyn meshlight::Visibility>,
    delay: std::time::Duration,
    slow: std::sync::atomic::AtomicBool,
}

impl Slow {
    fn wait(&self) {
        if self.slow.load(std::sync::atomic::Ordering::Relaxed) {
            std::thread::sleep(self.delay);
        }
    }
}

impl meshlight::Visibility for Slow {
    fn name(&self) -> &'static str {
        "slow"
    }
    fn occluded(
        &self,
        segments: &[meshlight::visibility::Segment],
        out: &mut [bool],
    ) -> meshlight::Result<()> {
        self.wait();
        self.inner.occluded(segments, out)
    }
    fn intersect(
        &self,
        rays: &[meshlight::visibility::Ray],
        out: &mut [Option<meshlight::visibility::Hit>],
    ) -> meshlight::Result<()> {
        self.wait();
        self.inner.intersect(rays, out)
    }
}

#[test]
fn a_stop_is_honoured_within_a_second_with_a_slow_backend() {
    // From the Stop on, the backend takes 20 ms a call: the room's solve would take minutes
    // that way. A Stop answered at the first report of any phase, or later within it, must end
    // the call within 1 s plus one call of the backend.
    let scene = room();
    let options = Options {
        rounds: 2,
        ..Options::default()
    };
    let phases = [
        Phase::Sampling,
        Phase::Areas,
        Phase::DirectLight,
        Phase::Links,
        Phase::Shooting,
        Phase::Adaptive,
    ];
    for phase in phases {
        for nth in [1, 3] {
            let slow = Slow {
                inner: Backend::Bvh.build(&scene).unwrap(),
                delay: std::time::Duration::from_millis(20),
                slow: false.into(),
            };
            let mut stopped_at = None;
            let mut heard = 0;
            let s = meshlight::solve(&scene, &slow, &options, &mut |p: &Progress| {
                heard += usize::from(p.phase == phase);
                if heard >= nth && stopped_at.is_none() {
                    stopped_at = Some(std::time::Instant::now());
                    slow.slow.store(true, std::sync::atomic::Ordering::Relaxed);
                }
                if stopped_at.is_some() {
                    Control::Stop
                } else {
                    Control::Continue
                }
            })
            .unwrap();
            let Some(at) = stopped_at else {
                // The phase ended before its nth report: nothing to time.
                continue;
            };
            let after = at.elapsed();
            println!("stopped at report {nth} of {phase:?}: returned {after:?} later");
            assert!(
                after.as_secs_f64() < 1.02,
                "{phase:?} #{nth}: {after:?} after the Stop"
            );
            assert_eq!(s.validate(), Ok(()));
        }
    }
}

#[test]
fn a_stop_is_heard_within_half_a_second_in_every_phase_of_a_slow_caster() {
    // From the first report of a phase on, every call to the caster takes 20 ms. The host
    // wants to stop 0.6 s into the phase; the library must report often enough to hear it
    // (no gap between reports over 0.5 s) and return within 0.5 s of the Stop.
    let scene = room();
    let phases = [
        Phase::Sampling,
        Phase::Areas,
        Phase::DirectLight,
        Phase::Links,
        Phase::Shooting,
        Phase::Adaptive,
    ];
    let mut late = Vec::new();
    for (threads, phase) in [1, 2].into_iter().flat_map(|t| phases.map(|p| (t, p))) {
        let options = Options {
            rounds: 2,
            threads,
            ..Options::default()
        };
        let slow = Slow {
            inner: Backend::Bvh.build(&scene).unwrap(),
            delay: std::time::Duration::from_millis(20),
            slow: false.into(),
        };
        let mut times: Vec<std::time::Instant> = Vec::new();
        let mut stopped_at = None;
        meshlight::solve(&scene, &slow, &options, &mut |p: &Progress| {
            let now = std::time::Instant::now();
            if p.phase == phase || !times.is_empty() {
                slow.slow.store(true, std::sync::atomic::Ordering::Relaxed);
                times.push(now);
            }
            if stopped_at.is_none()
                && times
                    .first()
                    .is_some_and(|t| now.duration_since(*t).as_secs_f64() > 0.6)
            {
                stopped_at = Some(now);
            }
            if stopped_at.is_some() {
                Control::Stop
            } else {
                Control::Continue
            }
        })
        .unwrap();
        let end = std::time::Instant::now();
        assert!(!times.is_empty(), "{phase:?} never heard");
        let last = stopped_at.unwrap_or(end);
        let gap = times
            .windows(2)
            .filter(|w| w[1] <= last)
            .map(|w| w[1].duration_since(w[0]).as_secs_f64())
            .fold(0.0, f64::max);
        let after = stopped_at.map(|t| end.duration_since(t).as_secs_f64());
        println!("{threads} threads, {phase:?}: longest gap {gap:.3} s, returned {after:?} s after the Stop");
        if gap >= 0.5 {
            late.push(format!(
                "{threads} threads, {phase:?}: {gap:.3} s between reports"
            ));
        }
        if let Some(after) = after.filter(|&a| a >= 0.5) {
            late.push(format!(
                "{threads} threads, {phase:?}: returned {after:.3} s after the Stop"
            ));
        }
    }
    assert!(late.is_empty(), "{late:#?}");
}
