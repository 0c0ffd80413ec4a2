//! The hierarchical solver, the paper's future work: samples grouped in a cluster tree, linked
//! cluster to cluster where an error bound allows and sample to sample elsewhere, and shot
//! along those links, every sample's unshot power at once, sweep after sweep.
//!
//! A round: build the tree (`tree`), mark which nodes may stand for their members
//! (`coherence`), cut the tree into receiver groups and build each group's links (`links`) in
//! the pipeline, take every receiver's row sum from the links (one sweep with unit radiosity;
//! see `normalise`), then sweep (`sweep`) until the unshot power is below the tolerance. The
//! links and their visibility are built once per round and kept for all its sweeps; every
//! structure grows with the number of links, which grows about linearly with the samples.
//!
//! Each receiver group is one job: its links, its sweeps' arithmetic and its samples' results
//! depend on nothing else, and the coordinator applies the groups' results in order, so the
//! answer is bit-identical for any number of workers. Spread over ranks (`distributed`), each
//! rank links and gathers its own groups only, and the groups' results are all-gathered before
//! the coordinator applies them, in the same order: bit-identical for any number of ranks too.

pub(crate) mod coherence;
pub(crate) mod links;
pub(crate) mod sweep;
pub(crate) mod tree;
mod wire;

use std::ops::ControlFlow;
use std::sync::RwLock;

use glam::DVec3;

use self::coherence::Context;
use self::links::{Linker, Links};
use self::sweep::{shooters, Shooter, Sources};
use self::tree::{Ref, Tree};
use super::normalise::row_scale;
use super::pipeline::{with_pool, Pool};
use super::shooting::{nothing_to_shoot, unshot_power, Settings, State, Tick};
use super::stats::{ShootStats, StopReason};
use super::warm::{self, Regather};
use crate::distributed::{gather_one, owners, sum_over, Ranks};
use crate::error::Result;
use crate::progress::Control;
use crate::visibility::Visibility;

/// Shooters darker than this fraction of the mean radiosity are weighed as this bright in the
/// error bound: their light may grow in later sweeps (a room lit through a doorway).
const DARK_WEIGHT: f64 = 0.2;

/// A round whose warm start left less than the tolerance unshot links its samples to gather
/// its new samples' light (`warm::Regather`) only if they are at least this share of all.
const REGATHER_SHARE: f64 = 0.01;

/// Sweeps at most, unless `max_shots` says otherwise.
pub(crate) const MAX_SWEEPS: u64 = 10_000;

/// Samples per receiver group: enough groups to share among the workers, whatever their
/// number (the groups must not depend on it, for determinism).
fn group_size(n: usize) -> usize {
    (n / 256).max(1024)
}

/// What a sweep reads (see `sweep::Sources`); no scales: unscaled.
#[derive(Default)]
struct Inputs {
    unshot: Vec<DVec3>,
    shooters: Vec<Shooter>,
    scales: Vec<f32>,
}

/// One receiver group: its links (as the jobs that found them handed them over), and what
/// they delivered to its members in the last sweep.
struct Group {
    root: Ref,
    /// The rank that holds its links and gathers it (0 in one process).
    owner: usize,
    /// Whether that is this rank.
    owned: bool,
    links: Vec<Links>,
    delivered: Vec<DVec3>,
}

/// Shoots until converged, out of sweeps, or told to stop; `report` hears every group linked
/// and every sweep.
pub(crate) fn shoot(
    state: &mut State,
    vis: &dyn Visibility,
    settings: &Settings,
    cx: &Context,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<ShootStats> {
    if let Some(stats) = nothing_to_shoot(state) {
        return Ok(stats);
    }
    let samples = state.samples;
    let n = samples.len();
    let emitted = state.ledger.emitted.element_sum();
    let mut stats = ShootStats::new();

    // Nothing to do where the warm start left less than the tolerance unshot.
    let unshot: f64 = (0..n)
        .map(|k| unshot_power(state.unshot[k], samples.area[k]))
        .sum();
    stats.initial_unshot_fraction = unshot / emitted;
    stats.unshot_fraction = stats.initial_unshot_fraction;
    // A round that adds only a handful of samples is not worth linking everything for their
    // gather: where nothing else needs the links, they keep their interpolated light.
    let regathers = state
        .regather
        .is_some_and(|r| (n - r.first) as f64 >= REGATHER_SHARE * n as f64);
    if stats.unshot_fraction < settings.tolerance && !regathers {
        return Ok(stats);
    }

    let (tree, groups, flow) = tree_and_links(state, vis, settings, cx, &mut stats, report)?;
    let ranks = settings.exec.ranks;
    // Each rank gives 3 values a sample of its groups to every sweep's exchange.
    let mut counts = vec![0usize; ranks.size().max(1)];
    for g in &groups {
        counts[g.owner] += 3 * members_of(&tree, g.root);
    }
    let all = || groups.iter().flat_map(|g| &g.links);
    stats.held_links = all().map(|l| (l.leaf.len() + l.cluster.len()) as u64).sum();
    stats.leaf_links = all().map(|l| l.leaf.len() as u64).sum();
    stats.links = stats.held_links;
    stats.most_held_links = stats.held_links;
    if ranks.size() > 1 {
        // Counts below 2⁵³ are exact in f64.
        let held = gather_one(ranks, stats.held_links as f64)?;
        stats.links = held.iter().sum::<f64>() as u64;
        stats.most_held_links = held.iter().fold(0.0f64, |a, &b| a.max(b)) as u64;
        stats.leaf_links = sum_over(ranks, stats.leaf_links)?;
        stats.queries = sum_over(ranks, stats.queries)?;
    }
    let link_bytes: usize = all().map(Links::bytes).sum();
    if crate::distributed::any(ranks, flow.is_break())? {
        stats.stop = StopReason::Stopped;
        stats.bytes = link_bytes as u64;
        return Ok(stats);
    }
    let mut linked = Linked::new(tree, groups, counts);
    sweep(state, &mut linked, settings, &mut stats, report)?;
    let delivered: usize = linked
        .groups
        .iter()
        .map(|g| g.delivered.capacity() * std::mem::size_of::<DVec3>())
        .sum();
    let nodes = linked.tree.nodes.len();
    stats.bytes = (link_bytes
        + delivered
        + nodes * (std::mem::size_of::<tree::Node>() + std::mem::size_of::<Shooter>()))
        as u64;
    Ok(stats)
}

/// The tree, weighing each shooter by its radiosity, and every receiver group's links; whether
/// the host let the linking finish.
fn tree_and_links(
    state: &State,
    vis: &dyn Visibility,
    settings: &Settings,
    cx: &Context,
    stats: &mut ShootStats,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<(Tree, Vec<Group>, ControlFlow<()>)> {
    let samples = state.samples;
    let (weight, reference) = shooter_weights(state);
    let rho: Vec<f32> = state
        .reflectance
        .iter()
        .map(|r| r.max_element() as f32)
        .collect();
    let tree = Tree::build(samples, &rho, &weight, cx);
    debug_assert_eq!(tree.validate(samples), Ok(()));
    let roots = tree.cut(group_size(samples.len()));
    let linker = Linker {
        tree: &tree,
        samples,
        maps: state.maps,
        vis,
        lift: settings.lift,
        tolerance: settings.threshold * reference,
        faint_links: !settings.exact_visibility,
        seed: settings.exec.seed,
        halt: &std::sync::atomic::AtomicBool::new(false),
    };
    let room = link_room(settings.memory_bytes, tree.nodes.len());
    let (groups, flow) = link_groups(&linker, &roots, settings, room, stats, report)?;
    Ok((tree, groups, flow))
}

/// One tree and its links with their row sums, kept to shoot many lightings of the same
/// samples (`solver::basis`): sweeps only, no linking, for each. A single solve sweeps one too.
pub(crate) struct Linked {
    tree: Tree,
    groups: Vec<Group>,
    counts: Vec<usize>,
    /// Each receiver's normalised row sum, for the sweeps' balance (empty: none needed).
    rows: Vec<f64>,
    links: u64,
    leaf_links: u64,
}

impl Linked {
    /// The tree and its groups of links, `counts` what each rank gives to a sweep's exchange;
    /// no row sums yet.
    fn new(tree: Tree, groups: Vec<Group>, counts: Vec<usize>) -> Linked {
        Linked {
            tree,
            groups,
            counts,
            rows: Vec::new(),
            links: 0,
            leaf_links: 0,
        }
    }
}

/// Builds the tree and links for `state`'s samples, its shooters weighed by
/// `state.radiosity`, and their row sums and scales (into `state.row_scale`); `None` if the
/// host stopped. One process only.
pub(crate) fn link(
    state: &mut State,
    vis: &dyn Visibility,
    settings: &Settings,
    cx: &Context,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<Option<Linked>> {
    let n = state.samples.len();
    let mut stats = ShootStats::new();
    let (tree, groups, flow) = tree_and_links(state, vis, settings, cx, &mut stats, report)?;
    if flow.is_break() {
        return Ok(None);
    }
    let all = || groups.iter().flat_map(|g| &g.links);
    stats.links = all().map(|l| (l.leaf.len() + l.cluster.len()) as u64).sum();
    stats.leaf_links = all().map(|l| l.leaf.len() as u64).sum();
    let counts = vec![3 * n];
    // The row sums alone: a sweep budget of none.
    let rows_only = Settings {
        normalise: true,
        max_shots: 0,
        ..*settings
    };
    let mut linked = Linked::new(tree, groups, counts);
    sweep(state, &mut linked, &rows_only, &mut stats, report)?;
    linked.links = stats.links;
    linked.leaf_links = stats.leaf_links;
    Ok(Some(linked))
}

/// Shoots `state` along `linked`'s links until converged (the row scales in `state` are those
/// the linking found).
pub(crate) fn shoot_along(
    state: &mut State,
    linked: &mut Linked,
    settings: &Settings,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<ShootStats> {
    if let Some(stats) = nothing_to_shoot(state) {
        return Ok(stats);
    }
    let mut stats = ShootStats::new();
    stats.links = linked.links;
    stats.leaf_links = linked.leaf_links;
    let settings = Settings {
        normalise: false,
        ..*settings
    };
    sweep(state, linked, &settings, &mut stats, report)?;
    Ok(stats)
}

/// What the cluster threshold means: each shooter's weight in the links' error bound (its
/// radiosity, but no darker than [`DARK_WEIGHT`] × the reference), and the reference radiosity
/// the threshold is a fraction of (the area-weighted mean radiosity). A link is accepted when
/// the radiosity error it can make is below threshold × reference.
fn shooter_weights(state: &State) -> (Vec<f64>, f64) {
    let samples = state.samples;
    let brightness: Vec<f64> = state.radiosity.iter().map(|b| b.max_element()).collect();
    let area: f64 = samples.area.iter().sum();
    let reference = if area > 0.0 {
        brightness
            .iter()
            .zip(&samples.area)
            .map(|(b, a)| b * a)
            .sum::<f64>()
            / area
    } else {
        0.0
    };
    let weight = brightness
        .iter()
        .map(|&b| b.max(DARK_WEIGHT * reference))
        .collect();
    (weight, reference)
}

/// What the links may hold of `memory_bytes` (what the samples leave of the budget): less the
/// tree's nodes and their shooters, and a quarter of the rest kept for what is not counted
/// (the jobs in flight, whose lists grow by doubling, the scene and its visibility structure,
/// the allocator's slack). Without that quarter, the atrium at `--epsilon 0.3` under a 250 MiB
/// budget stopped with a peak of 292 MiB; with it, 222 MiB (`/usr/bin/time -f %M`).
fn link_room(memory_bytes: usize, nodes: usize) -> usize {
    let tree = nodes * (std::mem::size_of::<tree::Node>() + std::mem::size_of::<Shooter>());
    memory_bytes.saturating_sub(tree) / 4 * 3
}

/// Every receiver group's links: every pair of groups (each group with itself too) is a job of
/// the pipeline, whose links go to its two groups; then each group's parts, in job order. The
/// links count against what the samples and the tree leave of the memory budget (`link_room`)
/// as they come in. Whether the host let the linking finish.
///
/// A group's parts are kept as they came, not joined into one list: the sweeps read them in
/// job order all the same, and joining held every link twice for a moment, which the
/// allocator kept as the run's peak (the atrium: 740 MiB against 428 MiB).
///
/// Over several ranks, rank r runs every size-th job (pairs near each other in the tree, the
/// costly ones, are thus spread evenly); the groups then go to the ranks in contiguous runs of
/// about equal links (the links a group gets say what it costs to hold and to sweep, which its
/// samples do not: a group in a large open room gets several times the links of one in a
/// corridor), and each part of a link list is sent to its group's rank (see `wire`).
fn link_groups(
    linker: &Linker,
    roots: &[Ref],
    settings: &Settings,
    room: usize,
    stats: &mut ShootStats,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<(Vec<Group>, ControlFlow<()>)> {
    let threads = settings.exec.threads;
    let ranks = settings.exec.ranks;
    let (me, size) = (ranks.rank(), ranks.size().max(1));
    let pairs: Vec<(usize, usize)> = (0..roots.len())
        .flat_map(|x| (x..roots.len()).map(move |y| (x, y)))
        .collect();
    let jobs: Vec<usize> = (0..pairs.len())
        .filter(|&j| crate::distributed::deals(ranks, j))
        .collect();
    let link = |job: usize| {
        let (x, y) = pairs[job];
        linker.links_between(roots[x], roots[y])
    };
    let total = jobs.len();
    // Per group, the parts found here, with their jobs.
    let mut parts: Vec<Vec<(u32, Links)>> = vec![Vec::new(); roots.len()];
    // The pipeline holds at most its capacity of jobs' links beyond those counted.
    let mut held = 0usize;
    let done = std::cell::Cell::new(0.0);
    let halt = |flow: ControlFlow<()>| {
        if flow.is_break() {
            linker
                .halt
                .store(true, std::sync::atomic::Ordering::Relaxed);
        }
        flow
    };
    let report = std::cell::RefCell::new(report);
    let flow = with_pool(threads, settings.capacity, &link, |pool| {
        let apply = |i: usize, (first, second): (Links, Links)| {
            let job = jobs[i];
            let (x, y) = pairs[job];
            stats.queries += first.queries + second.queries;
            held += first.bytes() + second.bytes();
            if held > room {
                // The pairs' links are uneven (neighbours cost the most), so this is a guide.
                let rate = held as f64 / (i + 1) as f64;
                return Err(crate::budget::exceeded(
                    settings.budget,
                    format!(
                        "the cluster links outgrew what the samples and the tree leave of the \
                         budget ({} after {} of {} groups' pairs; at that rate all of them \
                         would need about {}): raise the budget or choose a larger ε",
                        crate::budget::human_bytes(room as f64),
                        i + 1,
                        total,
                        crate::budget::human_bytes(rate * total as f64),
                    ),
                ));
            }
            for (group, links) in [(x, first), (y, second)] {
                if !(links.leaf.is_empty() && links.cluster.is_empty()) {
                    parts[group].push((job as u32, links));
                }
            }
            done.set((i + 1) as f64 / total.max(1) as f64);
            let mut report = report.borrow_mut();
            Ok(halt(flow(report(Tick::linking(done.get())))))
        };
        // A slow backend's pair can take seconds: the host still hears the phase meanwhile.
        let tick = || halt(flow((report.borrow_mut())(Tick::linking(done.get()))));
        pool.run_ticking(jobs.iter().copied(), apply, tick)
    })?;
    let owner = if size > 1 {
        let owner = share_groups(ranks, &parts)?;
        let mut to = vec![Vec::new(); size];
        for (g, group_parts) in parts.iter_mut().enumerate() {
            if owner[g] != me {
                for (job, links) in group_parts.drain(..) {
                    wire::put(&mut to[owner[g]], job, g, &links);
                }
                *group_parts = Vec::new();
            }
        }
        for words in ranks.exchange(&to)? {
            wire::take(&words, &mut parts)?;
        }
        owner
    } else {
        vec![0; roots.len()]
    };
    let groups: Vec<Group> = roots
        .iter()
        .zip(owner)
        .zip(parts)
        .map(|((&root, owner), mut parts)| {
            // Job order, as one process finds them: the sums in the sweeps go in that order.
            parts.sort_by_key(|(job, _)| *job);
            Group {
                root,
                owned: owner == me,
                owner,
                links: parts.into_iter().map(|(_, links)| links).collect(),
                delivered: Vec::new(),
            }
        })
        .collect();
    Ok((groups, flow))
}

/// The rank of each group: contiguous runs of about equal links, from every rank's counts.
fn share_groups(ranks: &dyn Ranks, parts: &[Vec<(u32, Links)>]) -> Result<Vec<usize>> {
    let size = ranks.size().max(1);
    let n = parts.len();
    let here: Vec<f64> = parts
        .iter()
        .map(|p| {
            p.iter()
                .map(|(_, l)| (l.leaf.len() + l.cluster.len()) as f64)
                .sum()
        })
        .collect();
    let mut all = vec![0.0; n * size];
    ranks.all_gather(&here, &vec![n; size], &mut all)?;
    // A group's weight: its links, plus one so that groups without links still spread.
    let weight: Vec<usize> = (0..n)
        .map(|g| (0..size).map(|r| all[r * n + g]).sum::<f64>() as usize + 1)
        .collect();
    Ok(owners(&weight, size))
}

/// The row sums (one sweep with unit radiosity, when the settings ask: into `linked.rows`),
/// then sweeps along `linked`'s groups until the unshot power is below the tolerance, the
/// sweeps run out, or the host stops. Row sums found before (for the balance) stay in
/// `linked.rows` where the sweeps do not find them.
fn sweep(
    state: &mut State,
    linked: &mut Linked,
    settings: &Settings,
    stats: &mut ShootStats,
    report: &mut dyn FnMut(Tick) -> Control,
) -> Result<()> {
    let (tree, counts) = (&linked.tree, linked.counts.as_slice());
    let mut groups = std::mem::take(&mut linked.groups);
    let given = std::mem::take(&mut linked.rows);
    let samples = state.samples;
    let n = samples.len();
    let emitted = state.ledger.emitted.element_sum();
    // What every group's sweep reads: written by the coordinator between sweeps, read by the
    // workers during them.
    let inputs = RwLock::new(Inputs::default());
    let ranks = settings.exec.ranks;
    let work = |group: Group| -> Result<Group> {
        let inputs = inputs.read().unwrap_or_else(|e| e.into_inner());
        Ok(gather_group(group, tree, samples, &inputs))
    };
    let set = |unshot: &[DVec3], scales: &[f32]| {
        let mut inputs = inputs.write().unwrap_or_else(|e| e.into_inner());
        inputs.unshot.clear();
        inputs.unshot.extend_from_slice(unshot);
        // The old shooters go first: a node's shooter is 96 bytes, and there are about as
        // many nodes as samples.
        drop(std::mem::take(&mut inputs.shooters));
        inputs.shooters = shooters(tree, samples, unshot);
        inputs.scales.clear();
        inputs.scales.extend_from_slice(scales);
    };
    let rows = with_pool(settings.exec.threads, settings.capacity, &work, |pool| {
        let mut sweeps = Sweeps {
            pool,
            tree,
            ranks,
            counts,
        };
        // Row sums: one sweep with unit radiosity everywhere, unscaled. Each sample's
        // normalised row sum is by reciprocity also the share of what it shoots that the
        // links should deliver (see `balance`).
        let mut rows = given;
        if settings.normalise {
            if let Some(sums) = row_sums(&mut sweeps, &mut groups, state, stats, &set)? {
                rows = sums;
            }
        }
        if let Some(regather) = state.regather {
            stats.exchanged_bytes +=
                regather_once(&mut sweeps, &mut groups, state, regather, &set)?;
        }
        let max_sweeps = if settings.max_shots == u64::MAX {
            MAX_SWEEPS
        } else {
            settings.max_shots
        };
        let mut first = true;
        let mut last_shot = None;
        loop {
            let total: f64 = (0..n)
                .map(|k| unshot_power(state.unshot[k], samples.area[k]))
                .sum();
            stats.unshot_fraction = total / emitted;
            if first {
                stats.initial_unshot_fraction = stats.unshot_fraction;
                first = false;
            }
            if let Some(stop) = settled(stats, settings, total, max_sweeps) {
                stats.stop = stop;
                break;
            }
            let stop = report(Tick::shooting(
                stats.shots,
                stats.unshot_fraction,
                stats.initial_unshot_fraction,
                settings.tolerance,
            )) == Control::Stop;
            if crate::distributed::any(ranks, stop)? {
                stats.stop = StopReason::Stopped;
                break;
            }
            let shot = shoot_once(&mut sweeps, &mut groups, state, &rows, &set, &inputs, stats)?;
            stats.shots += 1;
            last_shot = Some(shot);
        }
        if stats.stop == StopReason::Converged {
            if let Some(shot) = last_shot {
                tail(state, shot);
            }
        }
        Ok(rows)
    })?;
    linked.groups = groups;
    linked.rows = rows;
    Ok(())
}

/// One group's sweep: what its links deliver to its members from the shooters' unshot
/// radiosity, each member's share scaled by its row scale (where the sweep has them). Another
/// rank's group is left as it is: its deliveries come in the exchange.
fn gather_group(
    mut group: Group,
    tree: &Tree,
    samples: &crate::sampling::Samples,
    inputs: &Inputs,
) -> Group {
    if !group.owned {
        return group;
    }
    let sources = Sources {
        tree,
        samples,
        unshot: &inputs.unshot,
        shooters: &inputs.shooters,
    };
    sources.gather(group.root, &group.links, &mut group.delivered);
    if !inputs.scales.is_empty() {
        let first = first_member(tree, group.root);
        for (p, h) in group.delivered.iter_mut().enumerate() {
            *h *= f64::from(inputs.scales[tree.order[first + p] as usize]);
        }
    }
    group
}

/// The groups' sweeps on the pipeline's workers, and their deliveries swapped between ranks.
struct Sweeps<'p, 'w, 'a> {
    pool: &'p mut Pool<'w, Group, Group>,
    tree: &'a Tree,
    ranks: &'a dyn Ranks,
    /// What each rank gives to an exchange.
    counts: &'a [usize],
}

impl Sweeps<'_, '_, '_> {
    /// One sweep of every group (each gathers what its links deliver), in order; the bytes the
    /// exchange moved.
    fn run(&mut self, groups: &mut Vec<Group>) -> Result<u64> {
        let mut kept = Vec::with_capacity(groups.len());
        self.pool.run_all(groups.drain(..), |_, group| {
            kept.push(group);
            Ok(())
        })?;
        *groups = kept;
        exchange(groups, self.tree, self.ranks, self.counts)
    }
}

/// The row sums: one sweep with unit radiosity everywhere, unscaled, which sets each
/// receiver's row scale (`normalise`); the normalised sums where cluster links need them for
/// the balance (with sample-to-sample links alone, threshold 0, the transport is the flat
/// solver's, and stays so).
fn row_sums(
    sweeps: &mut Sweeps,
    groups: &mut Vec<Group>,
    state: &mut State,
    stats: &mut ShootStats,
    set: &dyn Fn(&[DVec3], &[f32]),
) -> Result<Option<Vec<f64>>> {
    let (tree, n) = (sweeps.tree, state.samples.len());
    set(&vec![DVec3::ONE; n], &[]);
    let mut sums = vec![0.0f64; n];
    stats.exchanged_bytes += sweeps.run(groups)?;
    for group in groups.iter() {
        let first = first_member(tree, group.root);
        for (p, h) in group.delivered.iter().enumerate() {
            sums[tree.order[first + p] as usize] = h.x;
        }
    }
    for (i, scale) in state.row_scale.iter_mut().enumerate() {
        *scale = row_scale(sums[i], state.closed[i], state.dark_emitters[i]);
    }
    Ok((stats.links > stats.leaf_links).then(|| {
        sums.iter()
            .zip(state.row_scale.iter())
            .map(|(&sum, &scale)| sum * f64::from(scale))
            .collect()
    }))
}

/// One sweep of the light every sample has shot so far (`warm::shot`), row-scaled as the
/// shots are, and by way of specular surfaces: each new sample's own inter-reflected light,
/// in place of the one its warm start interpolated (`warm::Regather`). The bytes exchanged.
fn regather_once(
    sweeps: &mut Sweeps,
    groups: &mut Vec<Group>,
    state: &mut State,
    regather: Regather,
    set: &dyn Fn(&[DVec3], &[f32]),
) -> Result<u64> {
    let tree = sweeps.tree;
    let shot = warm::shot(state.irradiance, state.unshot, state.reflectance);
    set(&shot, state.row_scale);
    let bytes = sweeps.run(groups)?;
    for group in groups.iter() {
        let first = first_member(tree, group.root);
        for (p, &h) in group.delivered.iter().enumerate() {
            let k = tree.order[first + p] as usize;
            if k >= regather.first {
                let through = state
                    .specular
                    .map_or(DVec3::ZERO, |g| g.row_times(k, &shot));
                regather.apply(
                    state.irradiance,
                    state.unshot,
                    state.reflectance,
                    k,
                    h + through,
                );
            }
        }
    }
    Ok(bytes)
}

/// Why the sweeps end before the next, if they do: diverged, converged (the unshot power
/// `total` below the tolerance), or out of sweeps.
fn settled(
    stats: &ShootStats,
    settings: &Settings,
    total: f64,
    max_sweeps: u64,
) -> Option<StopReason> {
    if stats.unshot_fraction.is_nan() || stats.unshot_fraction >= 1e6 {
        Some(StopReason::Diverged)
    } else if stats.unshot_fraction < settings.tolerance || total == 0.0 {
        Some(StopReason::Converged)
    } else if stats.shots >= max_sweeps {
        Some(StopReason::ShotLimit)
    } else {
        None
    }
}

/// One sweep: every sample shoots its unshot radiosity along the links (and by way of specular
/// surfaces), each receiver's delivery balanced against what its shooters owe (`rows`, where
/// given); the power shot.
fn shoot_once(
    sweeps: &mut Sweeps,
    groups: &mut Vec<Group>,
    state: &mut State,
    rows: &[f64],
    set: &dyn Fn(&[DVec3], &[f32]),
    inputs: &RwLock<Inputs>,
    stats: &mut ShootStats,
) -> Result<DVec3> {
    let (tree, samples) = (sweeps.tree, state.samples);
    let n = samples.len();
    set(state.unshot, state.row_scale);
    let shot: DVec3 = (0..n).map(|k| state.unshot[k] * samples.area[k]).sum();
    let owed: DVec3 = if rows.is_empty() {
        DVec3::ZERO
    } else {
        (0..n)
            .map(|k| state.unshot[k] * (samples.area[k] * rows[k]))
            .sum()
    };
    let mut delivered = DVec3::ZERO;
    stats.exchanged_bytes += sweeps.run(groups)?;
    for group in groups.iter() {
        let first = first_member(tree, group.root);
        for (p, &h) in group.delivered.iter().enumerate() {
            delivered += h * samples.area[tree.order[first + p] as usize];
        }
    }
    let factor = if rows.is_empty() {
        DVec3::ONE
    } else {
        balance(owed, delivered)
    };
    delivered *= factor;
    let (irradiance, unshot) = (&mut *state.irradiance, &mut *state.unshot);
    let reflectance = state.reflectance;
    for group in groups.iter() {
        let first = first_member(tree, group.root);
        for (p, &h) in group.delivered.iter().enumerate() {
            let k = tree.order[first + p] as usize;
            let h = h * factor;
            irradiance[k] += h;
            unshot[k] = reflectance[k] * h;
        }
    }
    // And by way of specular surfaces: G applied to what was shot.
    if let Some(g) = state.specular {
        let inputs = inputs.read().unwrap_or_else(|e| e.into_inner());
        for k in 0..n {
            let h = g.row_times(k, &inputs.unshot);
            irradiance[k] += h;
            unshot[k] += reflectance[k] * h;
            delivered += h * samples.area[k];
        }
    }
    state.ledger.escaped += shot - delivered;
    Ok(shot)
}

/// Reflections beyond this share per sweep are not extrapolated (the tail's factor r/(1 − r)
/// would be 99 or more, on a ratio measured from one sweep).
const TAIL_LIMIT: f64 = 0.99;

/// The tail is left out when the unshot power's magnitude exceeds its sum by more than this
/// share (light of both signs: see [`tail`]).
const TAIL_MIXED: f64 = 1e-3;

/// The light still unshot when the sweeps stop, carried on to its end: sweeps shoot every
/// sample at once, so their unshot power settles into one shape that shrinks by a ratio r per
/// sweep (the iteration's dominant eigenvector), and what the remaining sweeps would add to
/// sample k's irradiance is its last increment h_k times r + r² + … = r/(1 − r), with h_k =
/// ΔB_k / ρ_k. At the default tolerance a thousandth of the emitted power is left, which at
/// albedo 0.95 would have been reflected about 20 more times (−0.1% of the image on a
/// Cornell-like room at Kd 0.95). Unshot power is then spent: a later round's warm start must
/// not shoot it again. The ledger books the tail's shots (U/(1 − r)) less what they deliver as
/// escaped, so that it still adds up.
fn tail(state: &mut State, shot: DVec3) {
    let samples = state.samples;
    let n = samples.len();
    let left: DVec3 = (0..n).map(|k| state.unshot[k] * samples.area[k]).sum();
    let magnitude: DVec3 = (0..n)
        .map(|k| state.unshot[k].abs() * samples.area[k])
        .sum();
    // Only light of one sign settles into a steady shape that shrinks by one ratio: after a
    // warm start the unshot power is corrections of both signs, which cancel as they spread
    // rather than shrink in place, and extrapolating each sample's own share of them left a
    // blotch (`room`: p99 over 4 × 4 blocks 3.27%, 1.46% without it).
    let ratio = |u: f64, s: f64, m: f64| {
        let r = u / s;
        if u > 0.0 && s > 0.0 && r < TAIL_LIMIT && m <= u * (1.0 + TAIL_MIXED) {
            r
        } else {
            0.0
        }
    };
    let r = DVec3::new(
        ratio(left.x, shot.x, magnitude.x),
        ratio(left.y, shot.y, magnitude.y),
        ratio(left.z, shot.z, magnitude.z),
    );
    if r == DVec3::ZERO {
        return;
    }
    let factor = r / (DVec3::ONE - r);
    let mut delivered = DVec3::ZERO;
    for k in 0..n {
        let rho = state.reflectance[k];
        let unshot = state.unshot[k];
        let h = DVec3::new(
            if rho.x > 0.0 { unshot.x / rho.x } else { 0.0 },
            if rho.y > 0.0 { unshot.y / rho.y } else { 0.0 },
            if rho.z > 0.0 { unshot.z / rho.z } else { 0.0 },
        ) * factor;
        state.irradiance[k] += h;
        delivered += h * samples.area[k];
        // Spent where extrapolated; a channel without a tail keeps its unshot power.
        state.unshot[k] = DVec3::select(r.cmpgt(DVec3::ZERO), DVec3::ZERO, unshot);
    }
    let spent = DVec3::select(r.cmpgt(DVec3::ZERO), left, DVec3::ZERO);
    state.ledger.escaped += spent * (DVec3::ONE + factor) - delivered;
}

/// Corrections larger than this are not the cluster formula's error but something the rows
/// do not see (a sweep of mixed-sign warm-start power nearly cancelling, say): left alone.
const BALANCE_LIMIT: f64 = 0.1;

/// The factor (per channel) that makes up what a sweep's links fail to deliver of what its
/// shooters owe: each sample's share of its own shot is its normalised row sum (reciprocity:
/// A_k Σⱼ F_kj = Σⱼ A_j F_jk), so `owed` = Σ ΔB_k A_k row_k. Cluster links lose light the
/// exact form factors would deliver (faint partly visible links carry their probes' share, and
/// the far-field formula errs at second order near the admissible distance), and at high albedo
/// the loss compounds sweep after sweep: on a Cornell-like room at Kd 0.95 the links delivered
/// 0.46% less than the flat solver's and the image was 0.5% darker, evenly. Scaling the whole
/// sweep, rather than each shooter's links by a factor fixed in advance, holds for whatever
/// unshot power the sweep carries (fixed column factors, measured with unit radiosity,
/// created energy from concentrated power).
///
/// Never below 1: a sweep that delivers more than its rows owe is not scaled down. The rows
/// are not exact either (the flat solver's point-to-disc factors deliver 0.1% more than its
/// rows on that room, and that image is the closer to the path tracer), and on the gallery,
/// where the hierarchy delivers 0.3% more than its rows, scaling down took the image from
/// −0.1% to −0.5% against the path tracer.
fn balance(owed: DVec3, delivered: DVec3) -> DVec3 {
    let one = |o: f64, d: f64| {
        let f = o / d;
        if o > 0.0 && d > 0.0 && (1.0..=1.0 + BALANCE_LIMIT).contains(&f) {
            f
        } else {
            1.0
        }
    };
    DVec3::new(
        one(owed.x, delivered.x),
        one(owed.y, delivered.y),
        one(owed.z, delivered.z),
    )
}

/// Every rank's groups' deliveries to every rank (one all-gather of 3 values a sample, in tree
/// order: each rank's groups are one run of it); bytes received.
fn exchange(groups: &mut [Group], tree: &Tree, ranks: &dyn Ranks, counts: &[usize]) -> Result<u64> {
    if ranks.size() <= 1 {
        return Ok(0);
    }
    let mine: Vec<f64> = groups
        .iter()
        .filter(|g| g.owned)
        .flat_map(|g| g.delivered.iter().flat_map(|h| [h.x, h.y, h.z]))
        .collect();
    let mut all = vec![0.0; counts.iter().sum()];
    ranks.all_gather(&mine, counts, &mut all)?;
    for group in groups.iter_mut().filter(|g| !g.owned) {
        let first = 3 * first_member(tree, group.root);
        let values = &all[first..first + 3 * members_of(tree, group.root)];
        group.delivered.clear();
        group
            .delivered
            .extend(values.chunks_exact(3).map(|v| DVec3::new(v[0], v[1], v[2])));
    }
    Ok(((all.len() - mine.len()) * std::mem::size_of::<f64>()) as u64)
}

/// How many samples `r` stands for.
fn members_of(tree: &Tree, r: Ref) -> usize {
    if r.is_leaf() {
        1
    } else {
        tree.nodes[r.index()].count as usize
    }
}

fn first_member(tree: &Tree, r: Ref) -> usize {
    if r.is_leaf() {
        tree.place[r.index()] as usize
    } else {
        tree.nodes[r.index()].first as usize
    }
}

fn flow(control: Control) -> ControlFlow<()> {
    match control {
        Control::Continue => ControlFlow::Continue(()),
        Control::Stop => ControlFlow::Break(()),
    }
}
