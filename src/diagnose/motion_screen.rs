//! The motion screen (issue 32, item 4): where some setup leaves the sled's motion after
//! the stroke out, the sled-motion candidate's delay and return speed are searched from the
//! data before its fit.
//!
//! Why a screen of its own: a moving sled changes the landing points so much that the
//! baseline, fitted without it, has already bent k_elastic, μ and k_drag towards it; from
//! the baseline's optimum any motion looks worse, and with a moving sled the shared
//! parameters have several basins (a compass search from the baseline's point lands in
//! the wrong one; docs/diagnosis-report.md). So:
//!
//! 1. **Grid.** At every point of a grid over the unstated delay and return speed
//!    ([`MOTION_GRID`]), and over both return directions where some setup leaves
//!    `motion_direction` out ([`Space::with_motion_direction`]; the direction is a choice, not
//!    a fitted parameter, so the screen's pick is the candidate's), held fixed
//!    ([`Space::pin`]), the shared parameters are searched over
//!    their whole box: one differential evolution per grid point, all in lockstep (one engine
//!    call per generation), at the screen's particle count, every population starting from
//!    the same points (the baseline's and a Halton set), so that the grid points are
//!    compared from equal starts; then each grid point is polished ([`SCREEN_POLISH`]
//!    Levenberg–Marquardt steps at the same count) from the better of its evolution's best
//!    and the baseline's point, since a short evolution can miss the valley of the shared
//!    parameters at the right motion.
//! 2. **Ranking at the full budget.** Each grid point's best member is simulated again at
//!    the full particle count and the points are ranked by their *loss-adjusted* SSE (the
//!    fit's own objective, `Target::sse`, the gap the diagnosis ranks models on). Both halves
//!    matter. At the screen's 2000 particles a DE's minimum is partly a lucky draw of the
//!    particle streams: on campaign uB, with the true motion stated, the screen's best
//!    point scored 24.1 %² and 39.1 %² on the full budget's streams. And on raw SSEs a
//!    motion that loses grains in flight mimics the 0-4 % each run spills in handling: on
//!    uB the true motion fitted to 27.2 %² raw and a slow return at once to 26.4 %², but
//!    once the spill is allowed for, 4.4 %² against 15.6 %² on fresh streams; on uC 19.0
//!    against 15.7 raw, 3.8 against 8.4 adjusted. Ranked on raw SSEs, the slow return won.
//! 3. **Polish.** The best `POLISHED` grid points are polished at the full budget (the
//!    diagnosis's compass search, `--polish` iterations, the motion still held), and the
//!    best of them by the loss-adjusted SSE is the sled-motion fit's start, where the
//!    motion is free again. The
//!    fit polishes from it and from the baseline's point (so that the candidate is never
//!    worse than no motion), without a differential evolution of its own: the screen was
//!    its global search, and a DE over all five parameters at the screen's particle count
//!    never improved on the screen's point (campaigns uA-uC) while its lucky minima could
//!    pull the polish into the slow-return basin. The polish matters: on uB the true
//!    motion's grid point led a slow return at once by 25.7 against 26.9 %² before it and
//!    18.0 against 24.9 after (shared parameters from a short DE are not yet converged).
//!    And it needs its iterations: a polish of 3 left uA's grid point (0 s, 0.25 m/s) at
//!    38.4 %² raw where a full fit at that held motion reaches 28.4, and the free fit from
//!    there stopped at 0.2 m/s for the true 0.3 (17.0 %² left on fresh streams); with the
//!    diagnosis's 12 the point scores 30.6, the fit finds 0.35 m/s and leaves 3.6 %²
//!    (uB 2.2 → 1.0, uC 7.0 → 8.5; docs/diagnosis-report.md).
//!
//! Costs nothing when every setup states its motion.

use super::baseline::Baseline;
use super::run::Run;
use crate::calibrate::{Fit, Model, Search, Simulator, Solver, Space, Target};
use crate::model::effects::{EffectKind, MotionDirection};

/// The grid of unstated sled motions: delays (s) "at once" and well into the flights (a
/// longer delay outlasts them: the baseline's own start), and return speeds (m/s) doubling
/// over the search box (the POC profile's 0.05 m/s to a fast return). At a few tenths of a
/// m/s the sled returns its stroke (10 mm on the practice rig) in tens of milliseconds,
/// while grains fly, and the outcome is steep in the speed: at a step of 2.7 (0.3 to
/// 0.8 m/s) a 0.05 s, 0.5 m/s motion fell between two points that each screened worse than
/// no motion at all (docs/diagnosis-report.md). The fit moves the motion from the chosen
/// point onward. A third delay, 0.1 s, was tried: it let the screen start a 0.1 s return
/// from its own point (the motion sweep's m20), but it also let a 0.1 s, 1 m/s return
/// "explain" a DEM campaign whose sled rests (`diagnose_dem_candidate`, 95 % of the gap):
/// a false cause is worse than a miss, so the grid keeps two (docs/diagnosis-report.md).
pub const MOTION_GRID: ([f64; 2], [f64; 6]) = ([0.0, 0.05], [0.03, 0.06, 0.12, 0.25, 0.5, 1.0]);
/// The differential evolution over the shared parameters at each grid point: population
/// (about three per parameter, the baseline's point among them) and the generations every
/// grid point gets.
const POP: usize = 10;
const GENERATIONS: usize = 8;
/// Levenberg–Marquardt iterations per grid point at the screen's particle count after its
/// evolution (it stops sooner once a step gains less than the solver's minimum).
const SCREEN_POLISH: usize = 6;
/// Grid points polished at the full budget (the best by the loss-adjusted SSE of their
/// screened point), each with the diagnosis's compass iterations.
const POLISHED: usize = 3;

/// The motion screen's answer: the sled-motion fit's start (the space's parameter order)
/// and the simulations of the condition set it took.
#[derive(Clone, Debug)]
pub struct MotionStart {
    pub x: Vec<f64>,
    /// The return direction the screen chose where some setup leaves it out (None where
    /// every setup states it).
    pub direction: Option<MotionDirection>,
    pub evaluations: u64,
    /// Every grid point as the screen left it, best first: what the report's ridge reads.
    pub points: Vec<ScreenedMotion>,
}

/// One grid point of the screen as it ended: the held motion and its loss-adjusted SSE at
/// the full budget on the fit's streams (%²), polished for the best [`POLISHED`].
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenedMotion {
    pub direction: Option<MotionDirection>,
    /// The grid's values of the motion's unstated parameters (`delay_s`, `return_speed_m_s`).
    pub motion: Vec<(&'static str, f64)>,
    pub sse: f64,
    pub polished: bool,
}

/// The grid points that fit about as well as the best: an SSE within `floor` (%², the
/// data's noise floor) of the best one's. More than one is a ridge: motions that move the
/// sled about as far during the flights (a later return against a faster one) and that these
/// data do not tell apart, so the fitted motion is one of them, not *the* motion
/// (docs/diagnosis-report.md). `points` best first, as [`MotionStart::points`].
pub fn about_as_well(points: &[ScreenedMotion], floor: f64) -> Vec<&ScreenedMotion> {
    let Some(best) = points.iter().map(|p| p.sse).min_by(f64::total_cmp) else { return Vec::new() };
    points.iter().filter(|p| p.sse <= best + floor.max(0.0)).collect()
}

/// Every combination of the grid's values for the free parameters `names` (the motion's,
/// in the space's order): `delay_s` takes the grid's delays, `return_speed_m_s` its speeds.
pub fn grid(names: &[&'static str]) -> Vec<Vec<(&'static str, f64)>> {
    let mut grid: Vec<Vec<(&'static str, f64)>> = vec![Vec::new()];
    for name in names {
        let values: &[f64] = if *name == "delay_s" { &MOTION_GRID.0 } else { &MOTION_GRID.1 };
        grid = grid.iter().flat_map(|g| values.iter().map(move |v| [g.clone(), vec![(*name, *v)]].concat())).collect();
    }
    grid
}

/// One point of the screen: the return direction assumed where a setup states none (None:
/// every setup states it) and the held motion values.
type GridPoint = (Option<MotionDirection>, Vec<(&'static str, f64)>);

/// `n` points of the box `bounds` that every grid point's population starts from: `first`,
/// then a Halton sequence (bases 2, 3, 5, 7), the same for every grid point.
pub fn common_starts(first: &[f64], bounds: &[(f64, f64)], n: usize) -> Vec<Vec<f64>> {
    std::iter::once(first.to_vec()).chain((1..n).map(|i| halton_point(i, bounds))).collect()
}

/// The i-th point of a Halton sequence (bases 2, 3, 5, 7, repeating) scaled into `bounds`.
pub(crate) fn halton_point(i: usize, bounds: &[(f64, f64)]) -> Vec<f64> {
    bounds.iter().enumerate().map(|(k, (lo, hi))| lo + halton(i, [2, 3, 5, 7][k % 4]) * (hi - lo)).collect()
}

/// The motion-screen stage of a diagnosis: where the sled-motion candidate is tried and
/// some setup leaves the motion out, the start of its fit ([`motion_start`]); None where
/// it is not tried or every setup states the motion.
pub fn screen_motion(
    run: &Run,
    baseline: &Baseline,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Option<MotionStart>> {
    if !run.effects.contains(&EffectKind::SledMotion) {
        return Ok(None);
    }
    let space = Space::new(run.shared.clone(), &[EffectKind::SledMotion], run.conditions());
    motion_start(&run.solver, &run.sim, &space, &run.targets, &baseline.fit.x, log)
}

/// The start for the sled-motion candidate's fit in `space` when some setup leaves the
/// motion out (None when every setup states it), from the baseline's optimum `base` (the
/// baseline's parameters, the shared ones first). `solver` is the diagnosis's: the screen
/// runs at its screen particle count, the ranking and polish at its full one.
pub fn motion_start(
    solver: &Solver,
    sim: &Simulator,
    space: &Space,
    targets: &[Target],
    base: &[f64],
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Option<MotionStart>> {
    let names = space.names();
    let motion: Vec<&'static str> = space
        .free
        .iter()
        .filter(|(k, _)| space.effects[*k] == EffectKind::SledMotion)
        .map(|(k, i)| space.effects[*k].param_names()[*i])
        .collect();
    // a direction some setup leaves out is a third axis of the grid: the two directions move
    // the landing points differently (a return along the launch direction after 0.1 s at
    // 0.1 m/s read `unexplained` when only the slope was screened; docs/diagnosis-report.md)
    let directions: Vec<Option<MotionDirection>> = if Space::direction_unstated(sim.conditions) {
        vec![Some(MotionDirection::Slope), Some(MotionDirection::Launch)]
    } else {
        vec![None]
    };
    if (motion.is_empty() && directions.len() == 1) || base.len() < space.shared.len() {
        return Ok(None);
    }
    let started = std::time::Instant::now();
    let grid: Vec<GridPoint> =
        directions.iter().flat_map(|d| grid(&motion).into_iter().map(move |g| (*d, g))).collect();
    let spaces: Vec<Space> = grid
        .iter()
        .map(|(d, g)| {
            let directed = d.map_or_else(|| space.clone(), |d| space.with_motion_direction(d));
            g.iter().try_fold(directed, |s, (n, v)| s.pin(n, *v)).expect("the motion's parameters are free")
        })
        .collect();
    log(format!(
        "diagnose: sled-motion: the setups leave the motion out; screening {} grid points{} ({} members × {} generations each at {} particles)",
        grid.len(),
        if directions.len() > 1 { " in both return directions" } else { "" },
        POP,
        GENERATIONS,
        solver.screen_particles
    ));
    // every pinned space has the shared parameters and any other free ones the same way
    let fixed = &spaces[0];
    let first = fixed.start_from(&names[..space.shared.len()], &base[..space.shared.len()]);
    let Some(first) = first.filter(|_| fixed.dim() == space.shared.len()) else {
        return Ok(None);
    };
    let starts = common_starts(&first, &fixed.bounds(), POP);
    let models: Vec<Model> = spaces
        .iter()
        .enumerate()
        .map(|(g, s)| Model { space: s, targets, starts: starts.clone(), search: Search::Global { stream: g as u64 } })
        .collect();
    // 1. every grid point's DE
    let screen = Solver { pop: POP, generations: GENERATIONS, ..*solver };
    let screened = screen.screen(sim, &models, &mut |_| {})?;
    let mut evaluations: u64 = screened.iter().map(|s| s.evaluations).sum();
    // 1b. and polished from the better of its best member and the baseline's point (the
    // diagnosis's Levenberg–Marquardt steps, at the screen's count): a short evolution from
    // random starts can miss the shared parameters' valley at the right motion. A return
    // at 0.058 m/s right after the launch screened 53.1 %² at the grid's (0 s, 0.06 m/s)
    // with k_elastic 0.43 for the true 0.7, ranked sixth, and the candidate lost to
    // quadratic drag (the planted benchmark, docs/diagnosis-report.md)
    let lm = Solver { polish_iterations: SCREEN_POLISH, particles: solver.screen_particles, ..*solver };
    let valley: Vec<Model> = spaces
        .iter()
        .zip(&screened)
        .map(|(s, sc)| Model {
            space: s,
            targets,
            starts: vec![sc.members[0].0.clone(), first.clone()],
            search: Search::FromStarts,
        })
        .collect();
    let screened: Vec<Fit> = lm.polish(sim, &valley, &mut |_| {})?;
    evaluations += screened.iter().map(|f| f.evaluations).sum::<u64>();

    // 2. each grid point's best again at the full budget, ranked by the loss-adjusted SSE
    let full = Solver { polish_iterations: 0, ..*solver };
    let best: Vec<Model> = spaces
        .iter()
        .zip(&screened)
        .map(|(s, sc)| Model { space: s, targets, starts: vec![sc.x.clone()], search: Search::FromStarts })
        .collect();
    let ranked = full.polish(sim, &best, &mut |_| {})?;
    evaluations += ranked.len() as u64;
    // a fit's value is its loss-adjusted SSE summed over the conditions: the diagnosis's
    // objective allows each condition's handling loss (`Target::sse`)
    let mut order: Vec<(usize, f64)> = ranked.iter().map(|f| f.value).enumerate().collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let describe = |g: usize, x: &[f64]| {
        let (direction, point) = &grid[g];
        let motion: Vec<String> = direction
            .map(|d| format!("direction {}", d.name()))
            .into_iter()
            .chain(point.iter().map(|(n, v)| format!("{n} {v}")))
            .collect();
        let shared: Vec<String> = spaces[g].names().iter().zip(x).map(|(n, v)| format!("{n} {v:.3}")).collect();
        format!("{}: {}", motion.join(", "), shared.join(", "))
    };
    let shown: Vec<String> = order
        .iter()
        .map(|(g, a)| {
            let f = &screened[*g];
            format!("{} (screen {:.1}, full, loss-adjusted {a:.1})", describe(*g, &f.x), f.value)
        })
        .collect();
    log(format!(
        "diagnose: sled-motion: grid points at {} particles, best first (SSE %²): {} ({:.1} s elapsed)",
        solver.particles,
        shown.join("; "),
        started.elapsed().as_secs_f64()
    ));

    // 3. the best few polished at the full budget, the motion still held
    let chosen: Vec<usize> = order.iter().take(POLISHED).map(|(g, _)| *g).collect();
    let polish = Solver { polish_iterations: solver.polish_iterations, ..*solver };
    let models: Vec<Model> = chosen
        .iter()
        .map(|g| Model { space: &spaces[*g], targets, starts: vec![ranked[*g].x.clone()], search: Search::FromStarts })
        .collect();
    let polished = polish.polish(sim, &models, &mut |_| {})?;
    evaluations += polished.iter().map(|f| f.evaluations).sum::<u64>();
    let scored: Vec<(usize, f64, &Fit)> = chosen.iter().zip(&polished).map(|(g, f)| (*g, f.value, f)).collect();
    let shown: Vec<String> =
        scored.iter().map(|(g, a, f)| format!("{} (full, loss-adjusted {a:.1})", describe(*g, &f.x))).collect();
    log(format!("diagnose: sled-motion: polished at the full budget, the motion held: {}", shown.join("; ")));
    let (g, _, f) = scored.iter().min_by(|a, b| a.1.total_cmp(&b.1)).expect("at least one grid point");

    // back to the candidate's own parameters: the fit's shared values, the grid's motion
    let fitted = spaces[*g].names();
    let x: Vec<f64> = names
        .iter()
        .map(|n| match fitted.iter().position(|m| m == n) {
            Some(p) => f.x[p],
            None => grid[*g].1.iter().find(|(m, _)| m == n).map(|(_, v)| *v).expect("a pinned motion parameter"),
        })
        .collect();
    log(format!(
        "diagnose: sled-motion: the fit starts from {} (the screen took {:.1} s, {evaluations} simulations of the conditions)",
        describe(*g, &f.x),
        started.elapsed().as_secs_f64()
    ));
    let mut points: Vec<ScreenedMotion> = grid
        .iter()
        .zip(&ranked)
        .map(|((direction, motion), r)| ScreenedMotion {
            direction: *direction,
            motion: motion.clone(),
            sse: r.value,
            polished: false,
        })
        .collect();
    for (g, value, _) in &scored {
        points[*g].sse = *value;
        points[*g].polished = true;
    }
    points.sort_by(|a, b| a.sse.total_cmp(&b.sse));
    Ok(Some(MotionStart { x, direction: grid[*g].0, evaluations, points }))
}

/// The i-th point of the van der Corput sequence in `base`.
fn halton(mut i: usize, base: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_crosses_every_delay_with_every_speed_in_the_spaces_order() {
        let g = grid(&["delay_s", "return_speed_m_s"]);
        assert_eq!(g.len(), MOTION_GRID.0.len() * MOTION_GRID.1.len());
        assert_eq!(g[0], [("delay_s", 0.0), ("return_speed_m_s", 0.03)]);
        assert_eq!(g[7], [("delay_s", 0.05), ("return_speed_m_s", 0.06)]);
        // a setup that states the delay leaves only the speed to scan
        let speeds = grid(&["return_speed_m_s"]);
        assert_eq!(speeds.iter().map(|p| p[0].1).collect::<Vec<_>>(), MOTION_GRID.1);
        assert_eq!(grid(&[]), [Vec::<(&str, f64)>::new()]);
    }

    #[test]
    fn the_ridge_is_every_grid_point_within_the_noise_floor_of_the_best() {
        let point = |delay: f64, speed: f64, sse: f64| ScreenedMotion {
            direction: Some(MotionDirection::Slope),
            motion: vec![("delay_s", delay), ("return_speed_m_s", speed)],
            sse,
            polished: false,
        };
        let points = [point(0.0, 0.12, 4.0), point(0.05, 0.25, 5.5), point(0.1, 0.5, 6.1), point(0.0, 1.0, 90.0)];
        let near = |floor| about_as_well(&points, floor).iter().map(|p| p.sse).collect::<Vec<_>>();
        assert_eq!(near(2.0), [4.0, 5.5], "within 2 %² of the best's 4.0");
        assert_eq!(near(0.0), [4.0], "a zero floor keeps the best alone");
        assert_eq!(near(-1.0), [4.0], "a floor is never negative");
        assert_eq!(near(100.0).len(), 4);
        assert!(about_as_well(&[], 1.0).is_empty());
    }

    #[test]
    fn common_starts_are_the_first_point_then_a_halton_set_inside_the_box() {
        let bounds = [(0.0, 1.0), (10.0, 20.0), (-1.0, 1.0)];
        let s = common_starts(&[0.5, 15.0, 0.0], &bounds, 4);
        assert_eq!(s.len(), 4);
        assert_eq!(s[0], [0.5, 15.0, 0.0]);
        // van der Corput in bases 2, 3, 5: 1/2, 1/3, 1/5, then 1/4, 2/3, 2/5, then 3/4, 1/9, 3/5
        let near = |a: &[f64], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(near(&s[1], [0.5, 10.0 + 10.0 / 3.0, -1.0 + 2.0 / 5.0]), "{:?}", s[1]);
        assert!(near(&s[2], [0.25, 10.0 + 20.0 / 3.0, -1.0 + 4.0 / 5.0]), "{:?}", s[2]);
        assert!(near(&s[3], [0.75, 10.0 + 10.0 / 9.0, -1.0 + 6.0 / 5.0]), "{:?}", s[3]);
        assert!(s.iter().all(|p| p.iter().zip(&bounds).all(|(v, (lo, hi))| (lo..=hi).contains(&v))));
    }
}
