//! Steady conveying (issue 42): the sled's whole cycle run K times on a conveyor whose every
//! tooth carries a fill, as the performance model assumes (5.3, D.7: ṁ = m_regolith
//! (d_avg / l_conv) f counts every tooth's fill), and the mass conveyed per stroke once it is
//! steady.
//!
//! The conveyor is **periodic**: `period_teeth` teeth of the model's profile, the last
//! tooth's base joining the first tooth's ramp across the box's periodic boundary, so a grain
//! that passes the end lands on the start (an endless conveyor of full teeth; LIGGGHTS meshes
//! interact across periodic boundaries). The case runs in the **sled's frame** in conveyor
//! coordinates (x along the conveyor, up the slope; y normal to it; z the slab's periodic
//! depth): the mesh never moves, gravity is tilted, g (−sin α, −cos α), and the sled's motion
//! becomes what a translating frame adds to every grain:
//! - the stroke, the sled accelerating at a along the launch direction l (α + offset + δ,
//!   listing lines 35/167) for v0/a: a force −m a l on every grain (a second `fix gravity`);
//! - the sled's stop: every grain's velocity relative to the sled grows by v0 l
//!   (`velocity ... sum yes`), so those in the pocket leave it at v0 as the model's do;
//! - the return after the grains rest (5.3.1, Eq. 5.13: at the downstroke speed v_d over the
//!   stroke v0²/(2a)): +v_d down the slope... as relative velocity, +v_d along x at its start
//!   and −v_d at its end, instantaneous as the single stroke's mesh motion is;
//! - Stokes drag acts on the velocity relative to the air, which is at rest in the lab: in
//!   the sled's frame `fix viscous` sees the relative velocity, and a force −γ v_sled
//!   (`fix addforce`, per size class) adds what the sled's own velocity contributes.
//!
//! After settling and after every cycle the grains' unwrapped positions are dumped; a
//! stroke's advance is the mass-weighted mean of their displacement along the conveyor. The
//! cycles after the first are the steady state when their advances show no trend (the
//! report gives the first and the second half of them).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::case::{drag_commands, stop_when_every_grain_is_gone, Case, ALL_LOST, DUMP, GRAINS, MESH, SCRIPT};
use super::contact::{property_commands, CONTACT_MODEL};
use super::grains::{Grain, Placement};
use super::losses::{classify_on_conveyor, read_sightings, LeftBy, TRACK};
use super::stl::{extrude, facet_line, profile_polyline, stl_text};
use crate::io::atomic::write_atomic;
use crate::model::geometry::Profile;
use crate::model::Scenario;

/// The dump after settling (cycle 0) and after cycle k: `cycle-NNN.dump`.
pub fn cycle_dump(k: u32) -> String {
    format!("cycle-{k:03}.dump")
}

/// Simulated time per rest check, s (as the single stroke's).
const CHUNK_S: f64 = 0.02;
/// Longest settling before the first stroke, s.
const MAX_SETTLE_S: f64 = 1.0;

/// A periodic conveyor of `period_teeth` full teeth, run for `strokes` cycles.
#[derive(Clone, Debug, Serialize)]
pub struct Conveyor {
    /// The single-stroke case of tooth 0 the conveyor is built from (its contact, grain size
    /// and motion; its mesh and box are not used).
    pub tooth: Case,
    pub period_teeth: u32,
    pub strokes: u32,
    /// Every tooth's grains, conveyor frame (x along the conveyor from tooth 0's p1, y
    /// normal to it), class by class.
    pub grains: Vec<Grain>,
    /// The classes' grain counts over all teeth (the case's classes × `period_teeth`).
    pub class_counts: Vec<u32>,
    /// Box [lo, hi] in x (periodic: one period), y, z (periodic: the slab), m.
    pub bounds: [[f64; 2]; 3],
    /// Launch direction l in conveyor coordinates (unit vector).
    pub launch: [f64; 2],
    /// The return's speed (`[performance] downstroke_speed`), m/s.
    pub return_speed_m_s: f64,
}

/// Global frame (x horizontal, y up) to conveyor frame (x up the slope, y normal).
fn to_conveyor(p: [f64; 2], alpha: f64) -> [f64; 2] {
    let (s, c) = alpha.sin_cos();
    [p[0] * c + p[1] * s, -p[0] * s + p[1] * c]
}

impl Conveyor {
    /// The conveyor of `period_teeth` teeth (at least 2) like `tooth`'s, each filled as
    /// `tooth`'s fill is (the placement of seed `tooth.seed + k` for tooth k), run `strokes`
    /// cycles. Refuses a stated sled return (the cycle's own return is the thesis's).
    pub fn build(scenario: &Scenario, tooth: Case, period_teeth: u32, strokes: u32) -> Result<Conveyor, String> {
        if !(2..=64).contains(&period_teeth) {
            return Err(format!("[dem] period_teeth must lie in [2, 64], got {period_teeth}"));
        }
        if !(1..=200).contains(&strokes) {
            return Err(format!("--strokes must lie in [1, 200], got {strokes}"));
        }
        if tooth.motion.ret.is_some() {
            return Err("a stated sled return (the sled-motion effect, or a setup's motion_delay_s) is not carried into steady conveying: each cycle returns the sled at [performance] downstroke_speed once the grains rest (5.3.1)".into());
        }
        let alpha = scenario.environment.alpha_deg.to_radians();
        let pitch = tooth.design.l_c;
        let mut placements: Vec<Placement> = Vec::with_capacity(period_teeth as usize);
        for k in 0..period_teeth {
            let case = if k == 0 {
                tooth.clone()
            } else {
                Case::build(scenario, &tooth.design, &tooth.settings, tooth.seed + k as u64, None)?
            };
            placements.push(case.placement);
        }
        let period = period_teeth as f64 * pitch;
        let classes = tooth.placement.classes.len();
        let mut grains = Vec::new();
        let mut class_counts = vec![0u32; classes];
        for (class, count) in class_counts.iter_mut().enumerate() {
            for (k, p) in placements.iter().enumerate() {
                for g in p.grains.iter().filter(|g| g.class == class) {
                    let q = to_conveyor([g.pos[0], g.pos[1]], alpha);
                    let x = (q[0] + k as f64 * pitch).rem_euclid(period);
                    grains.push(Grain { pos: [x, q[1], g.pos[2]], ..*g });
                    *count += 1;
                }
            }
        }
        let launch_local = tooth.launch_angle_rad - alpha;
        let launch = [launch_local.cos(), launch_local.sin()];
        // the box: one period in x; in y from below the base to above the highest launch
        // (speed 1.5 v0 against the normal gravity g cos α) and the teeth
        let profile = local_profile(&tooth, period_teeth);
        let line = periodic_line(&profile, period_teeth);
        let top = line.iter().map(|p| p[1]).fold(0.0, f64::max);
        let apex = (1.5 * tooth.design.v0).powi(2) / (2.0 * scenario.environment.g * alpha.cos());
        let margin = 2.0 * tooth.design.l_c;
        let bounds = [[0.0, period], [-margin, top + apex + margin], [0.0, tooth.placement.depth_m]];
        Ok(Conveyor {
            return_speed_m_s: scenario.performance.downstroke_speed,
            tooth,
            period_teeth,
            strokes,
            grains,
            class_counts,
            bounds,
            launch,
        })
    }

    /// Write the case into `dir` (each file atomically).
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        let profile = local_profile(&self.tooth, self.period_teeth);
        let line = facet_line(&periodic_line(&profile, self.period_teeth), self.bounds[2][1]);
        write_atomic(&dir.join(MESH), stl_text("conveyor", &extrude(&line, self.bounds[2][1])).as_bytes())?;
        write_atomic(&dir.join(GRAINS), self.data().as_bytes())?;
        write_atomic(&dir.join("conveyor.json"), serde_json::to_string_pretty(self)?.as_bytes())?;
        write_atomic(&dir.join(SCRIPT), self.script().as_bytes())?;
        Ok(())
    }

    fn data(&self) -> String {
        let b = &self.bounds;
        let mut s = String::new();
        let _ = writeln!(s, "sawtooth dem conveyor grains (seed {})\n", self.tooth.seed);
        let _ = writeln!(s, "{} atoms\n2 atom types\n", self.grains.len());
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let _ = writeln!(s, "{:.9e} {:.9e} {axis}lo {axis}hi", b[k][0], b[k][1]);
        }
        let _ = writeln!(s, "\nAtoms\n");
        for (i, g) in self.grains.iter().enumerate() {
            let _ = writeln!(
                s,
                "{} 1 {:.9e} {} {:.9e} {:.9e} {:.9e}",
                i + 1,
                g.diameter_m,
                self.tooth.contact.density_kg_m3,
                g.pos[0],
                g.pos[1],
                g.pos[2]
            );
        }
        s
    }

    /// Whether the run dumps its track ([`TRACK`], every grain at every rest check, as the
    /// single stroke's): only when the track stays within its bound (grains × the most
    /// snapshots the deck can take × a line of at most ~100 bytes).
    pub fn tracked(&self) -> bool {
        let t = &self.tooth;
        let (v0, a) = (t.design.v0, t.design.a);
        let per_cycle = 2.0 * t.settings.max_time_s + v0 / a + v0 * v0 / (2.0 * a) / self.return_speed_m_s;
        let snapshots =
            ((MAX_SETTLE_S + self.strokes as f64 * per_cycle) / CHUNK_S).ceil() + 2.0 * self.strokes as f64 + 2.0;
        let lines = snapshots * (self.grains.len() as f64 + 9.0);
        lines * 100.0 <= crate::schema::DEM_TRACK_FILE.max_bytes as f64
    }

    fn steps(&self, seconds: f64) -> u64 {
        (seconds / self.tooth.contact.timestep_s).ceil().max(1.0) as u64
    }

    /// The placement of all teeth as one (class counts over every tooth), for the drag groups.
    fn all_teeth(&self) -> Placement {
        let mut p = self.tooth.placement.clone();
        for (c, n) in p.classes.iter_mut().zip(&self.class_counts) {
            c.grains = *n;
        }
        p
    }

    /// `fix addforce` commands (ids `sled0`, ...) of the force −γ v_sled on each drag group,
    /// with v_sled = (vx, vy) the sled's velocity (LIGGGHTS expressions); none in vacuum.
    fn sled_drag(&self, vx: &str, vy: &str) -> String {
        let mut s = String::new();
        let one = self.tooth.placement.classes.len() == 1;
        for (k, c) in self.tooth.placement.classes.iter().enumerate() {
            let Some(gamma) = c.drag_gamma_kg_s else { continue };
            let group = if one { "all".to_string() } else { format!("size{k}") };
            let _ = writeln!(
                s,
                "variable sfx{k} equal -{gamma:e}*({vx})\nvariable sfy{k} equal -{gamma:e}*({vy})\nfix sled{k} {group} addforce v_sfx{k} v_sfy{k} 0.0"
            );
        }
        s
    }

    fn unfix_sled_drag(&self) -> String {
        let mut s = String::new();
        for (k, c) in self.tooth.placement.classes.iter().enumerate() {
            if c.drag_gamma_kg_s.is_some() {
                let _ = writeln!(s, "unfix sled{k}");
            }
        }
        s
    }

    fn script(&self) -> String {
        let t = &self.tooth;
        let c = &t.contact;
        let d = t.largest_diameter_m();
        let skin = t.neighbour_skin_m();
        let area = (self.bounds[0][1] - self.bounds[0][0]) * (self.bounds[1][1] - self.bounds[1][0]);
        let binsize = (d + skin).max((area / 2e5).sqrt());
        let alpha = t.scenario.environment.alpha_deg.to_radians();
        let g = t.scenario.environment.g;
        let (l, a, v0, vd) = (self.launch, t.design.a, t.design.v0, self.return_speed_m_s);
        let chunk = self.steps(CHUNK_S);
        let settle_chunks = (MAX_SETTLE_S / CHUNK_S).ceil() as u64;
        let rest_chunks = (t.settings.max_time_s / CHUNK_S).ceil() as u64;
        let rest = t.settings.rest_speed_m_s;
        let stroke_steps = self.steps(v0 / a);
        let return_steps = self.steps(v0 * v0 / (2.0 * a) / vd);
        let dt = c.timestep_s;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# sawtooth dem conveyor: {} full teeth, periodic, {} cycles in the sled's frame (src/dem/conveyor.rs, docs/dem.md)\n\
             # design {}; seed {}\n\
             atom_style granular\natom_modify map array\nboundary p f p\nnewton off\ncommunicate single vel yes\nunits si\n\
             read_data {GRAINS}\nneighbor {skin:e} bin\nneigh_modify delay 0 binsize {binsize:e}\n\
             # material with the softened moduli (factor {:.3e})\n{}\
             # gravity in conveyor coordinates: g (-sin alpha, -cos alpha)\n\
             fix gravity all gravity {g} vector {:e} {:e} 0.0\n\
             fix sled all mesh/surface file {MESH} type 2\n\
             fix walls all wall/gran {CONTACT_MODEL} mesh n_meshes 1 meshes sled",
            self.period_teeth,
            self.strokes,
            crate::model::design::DesignRow::of(&t.design),
            t.seed,
            c.softening,
            property_commands(c),
            -alpha.sin(),
            -alpha.cos(),
        );
        s.push_str(&drag_commands(&self.all_teeth(), t.scenario.environment.k_drag.unwrap_or(0.0)));
        let _ = writeln!(
            s,
            "fix integrate all nve/sphere\n\
             compute ke all ke\nvariable m equal mass(all)\nvariable vrms equal sqrt(2*c_ke/(v_m+1e-30))\n\
             variable t equal step*{dt:e}\n\
             thermo_style custom step atoms ke v_vrms v_t\nthermo {chunk}\nthermo_modify lost ignore norm no\n\
             {track}\
             # settle\nvariable settle loop {settle_chunks}\nlabel settling\nrun {chunk}\n\
             if \"${{vrms}} < {rest:e}\" then \"jump SELF settled\"\nnext settle\njump SELF settling\nlabel settled\n\
             write_dump all custom {} id mass xu yu zu",
            cycle_dump(0),
            track = if self.tracked() {
                format!("# every grain at every rest check: where a grain LIGGGHTS deletes left the box (losses.rs)\ndump track all custom {chunk} {TRACK} id x y vx vy\n")
            } else {
                "# no track: it would be larger than schema::DEM_TRACK_FILE allows (losses.rs)\n".to_string()
            },
        );
        for k in 1..=self.strokes {
            // the stroke: -m a l on every grain while the sled accelerates; the sled's own
            // velocity a t l in the air's drag
            let _ = writeln!(
                s,
                "# cycle {k}: the stroke (the sled accelerates at {a} m/s^2 along the launch direction)\n\
                 print \"sawtooth: cycle {k} stroke\"\n\
                 variable k0 equal step\nvariable c0 equal ${{k0}}\n\
                 fix accel all gravity {a} vector {:e} {:e} 0.0",
                -l[0], -l[1]
            );
            s.push_str(&self.sled_drag(
                &format!("{:e}*(step-v_c0)*{dt:e}", a * l[0]),
                &format!("{:e}*(step-v_c0)*{dt:e}", a * l[1]),
            ));
            let _ = writeln!(
                s,
                "run {stroke_steps}\nunfix accel\n{}\
                 # the sled stops: the grains keep v0 along the launch direction relative to it\n\
                 velocity all set {:e} {:e} 0.0 sum yes units box\n\
                 variable rest{k} loop {rest_chunks}\nlabel resting{k}\nrun {chunk}\n\
                 if \"${{vrms}} < {rest:e}\" then \"jump SELF rested{k}\"\nnext rest{k}\njump SELF resting{k}\nlabel rested{k}\n\
                 # the return at the downstroke speed down the slope\n\
                 velocity all set {vd:e} 0.0 0.0 sum yes units box",
                self.unfix_sled_drag(),
                v0 * l[0],
                v0 * l[1],
            );
            s.push_str(&self.sled_drag(&format!("{:e}", -vd), "0.0"));
            let _ = writeln!(
                s,
                "run {return_steps}\n{}velocity all set {:e} 0.0 0.0 sum yes units box\n\
                 variable back{k} loop {rest_chunks}\nlabel back{k}\nrun {chunk}\n\
                 if \"${{vrms}} < {rest:e}\" then \"jump SELF still{k}\"\nnext back{k}\njump SELF back{k}\nlabel still{k}\n\
                 write_dump all custom {} id mass xu yu zu",
                self.unfix_sled_drag(),
                -vd,
                cycle_dump(k)
            );
        }
        let _ = writeln!(s, "write_dump all custom {DUMP} id type diameter mass x y z vx vy vz");
        stop_when_every_grain_is_gone(&s)
    }
}

/// The profile in conveyor coordinates (α = 0: tooth 0's p1 at the origin, the base along x).
fn local_profile(tooth: &Case, teeth: u32) -> Profile {
    let local = crate::model::geometry::check_design(&tooth.design).expect("checked when the case was built");
    Profile::new(&tooth.design, local, 0.0, teeth)
}

/// The mesh's line: `teeth` teeth from tooth 0's p1, closed by the last base to p1 of tooth
/// `teeth`, which the periodic boundary makes tooth 0's.
fn periodic_line(profile: &Profile, teeth: u32) -> Vec<[f64; 2]> {
    let mut line = profile_polyline(profile, teeth);
    line.push(profile.p1_of(teeth));
    line
}

/// One grain of a cycle's dump: id, mass, unwrapped position.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Unwrapped {
    id: u64,
    mass_kg: f64,
    pos: [f64; 3],
}

fn parse_unwrapped(text: &str) -> anyhow::Result<Vec<Unwrapped>> {
    let mut lines = text.lines();
    let header = lines.by_ref().find(|l| l.starts_with("ITEM: ATOMS")).context("dump has no `ITEM: ATOMS` section")?;
    let cols: Vec<&str> = header.split_whitespace().skip(2).collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).with_context(|| format!("dump lacks column `{name}`"));
    let idx = [at("id")?, at("mass")?, at("xu")?, at("yu")?, at("zu")?];
    let mut out = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| -> anyhow::Result<f64> {
            f.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .with_context(|| format!("dump atom line {}: bad field {i}", n + 1))
        };
        let id = num(idx[0])?;
        if !(id >= 1.0 && id.fract() == 0.0) {
            bail!("dump atom line {}: id {id} is not a positive whole number", n + 1);
        }
        let mass_kg = num(idx[1])?;
        if mass_kg <= 0.0 {
            bail!("dump atom line {}: mass {mass_kg} kg is not positive", n + 1);
        }
        out.push(Unwrapped { id: id as u64, mass_kg, pos: [num(idx[2])?, num(idx[3])?, num(idx[4])?] });
    }
    Ok(out)
}

/// One cycle's outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cycle {
    /// 1-based.
    pub stroke: u32,
    /// Mass-weighted mean displacement along the conveyor of the grains present before and
    /// after the cycle, m.
    pub advance_m: f64,
    /// Grains lost during the cycle (left the box).
    pub lost: usize,
}

/// A steady-conveying run: every cycle's advance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SteadyRun {
    pub seed: u64,
    pub period_teeth: u32,
    pub grains: usize,
    /// The grains' mass per tooth, kg (the slab's: the model's fill mass over the slab).
    pub mass_per_tooth_kg: f64,
    pub cycles: Vec<Cycle>,
    pub wall_s: f64,
    /// Where the grains that left the box went (`losses`: through the mesh or over the top,
    /// a periodic conveyor having no ends); None for a run that wrote no track.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub left_by: Option<LeftBy>,
}

/// Read the cycle dumps of a finished conveyor run in `dir`.
pub fn reduce(dir: &Path, conveyor: &Conveyor, wall_s: f64) -> anyhow::Result<SteadyRun> {
    // every grain left the box (the deck stopped at `gone`): the cycles it did not reach
    // carry nothing, so they convey nothing
    let all_lost = dir.join(ALL_LOST).is_file();
    let read = |k: u32| -> anyhow::Result<Vec<Unwrapped>> {
        let p = dir.join(cycle_dump(k));
        if all_lost && !p.exists() {
            return Ok(Vec::new());
        }
        let text = crate::io::bounded::read_text(&p, &crate::schema::DEM_DUMP_FILE)?;
        parse_unwrapped(&text).with_context(|| format!("reading {}", p.display()))
    };
    let first = read(0)?;
    let placed = conveyor.grains.len();
    if first.len() > placed || first.iter().any(|g| g.id as usize > placed) {
        bail!("{}: the settled dump holds grains that were not placed", dir.display());
    }
    let mut before = first.clone();
    let mut cycles = Vec::new();
    for k in 1..=conveyor.strokes {
        let after = read(k)?;
        let by_id: std::collections::HashMap<u64, &Unwrapped> = after.iter().map(|g| (g.id, g)).collect();
        let (mut moved, mut mass) = (0.0, 0.0);
        for g in &before {
            if let Some(h) = by_id.get(&g.id) {
                moved += g.mass_kg * (h.pos[0] - g.pos[0]);
                mass += g.mass_kg;
            }
        }
        let lost = before.len().saturating_sub(after.len());
        if mass <= 0.0 {
            if !all_lost {
                bail!("{}: no grain is left after cycle {k}", dir.display());
            }
            cycles.push(Cycle { stroke: k, advance_m: 0.0, lost });
            before = after;
            continue;
        }
        cycles.push(Cycle { stroke: k, advance_m: moved / mass, lost });
        before = after;
    }
    let total: f64 = first.iter().map(|g| g.mass_kg).sum();
    let left_by = conveyor_losses(dir, conveyor, &first, &before)?;
    Ok(SteadyRun {
        seed: conveyor.tooth.seed,
        period_teeth: conveyor.period_teeth,
        grains: placed,
        mass_per_tooth_kg: total / conveyor.period_teeth as f64,
        cycles,
        wall_s,
        left_by,
    })
}

/// The grains a finished conveyor run lost, placed from its track ([`classify_on_conveyor`]):
/// `settled` the grains after settling, `last` those after the last cycle the run reached.
/// None when the conveyor writes no track ([`Conveyor::tracked`]).
fn conveyor_losses(
    dir: &Path,
    conveyor: &Conveyor,
    settled: &[Unwrapped],
    last: &[Unwrapped],
) -> anyhow::Result<Option<LeftBy>> {
    if !conveyor.tracked() {
        return Ok(None);
    }
    let placed = conveyor.grains.len();
    let mark = |gs: &[Unwrapped]| -> anyhow::Result<Vec<bool>> {
        let mut m = vec![false; placed];
        for g in gs {
            match m.get_mut((g.id as usize).wrapping_sub(1)) {
                Some(slot) => *slot = true,
                None => bail!("{}: a cycle's dump holds grain {}, which was not placed", dir.display(), g.id),
            }
        }
        Ok(m)
    };
    let (on_conveyor, kept) = (mark(settled)?, mark(last)?);
    let deleted: Vec<bool> = kept.iter().map(|k| !k).collect();
    let seen = read_sightings(dir, placed)?;
    let line = periodic_line(&local_profile(&conveyor.tooth, conveyor.period_teeth), conveyor.period_teeth);
    let radius = 0.5 * conveyor.tooth.largest_diameter_m();
    Ok(Some(classify_on_conveyor(&line, radius, conveyor.bounds[1], &seen, &on_conveyor, &deleted)))
}

/// The steady state of several runs: the cycles after the first, split into halves.
#[derive(Clone, Debug, Serialize)]
pub struct Steady {
    /// Mean advance per stroke over the steady cycles of every run, m; its sd over the runs.
    pub advance_m: f64,
    pub advance_sd_m: f64,
    /// The first stroke's advance (onto teeth that start full, from a bed that settled
    /// rather than landed), mean over the runs, m.
    pub first_stroke_m: f64,
    /// Mean advance over the first and the second half of the steady cycles, m: no trend
    /// between them is what steady means.
    pub first_half_m: f64,
    pub second_half_m: f64,
    pub steady_cycles: usize,
}

pub fn steady(runs: &[SteadyRun]) -> anyhow::Result<Steady> {
    let Some(r0) = runs.first() else { bail!("no steady runs") };
    let n = r0.cycles.len();
    if n < 3 {
        bail!("steady conveying needs at least 3 strokes (the first is a transient), got {n}");
    }
    if runs.iter().any(|r| r.cycles.len() != n) {
        bail!("the runs differ in their number of strokes");
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let per_run: Vec<f64> =
        runs.iter().map(|r| mean(&r.cycles[1..].iter().map(|c| c.advance_m).collect::<Vec<_>>())).collect();
    let advance = mean(&per_run);
    let sd = if per_run.len() > 1 {
        (per_run.iter().map(|x| (x - advance).powi(2)).sum::<f64>() / (per_run.len() - 1) as f64).sqrt()
    } else {
        0.0
    };
    let half = 1 + (n - 1) / 2;
    let part = |range: std::ops::Range<usize>| {
        mean(&runs.iter().flat_map(|r| r.cycles[range.clone()].iter().map(|c| c.advance_m)).collect::<Vec<_>>())
    };
    Ok(Steady {
        advance_m: advance,
        advance_sd_m: sd,
        first_stroke_m: mean(&runs.iter().map(|r| r.cycles[0].advance_m).collect::<Vec<_>>()),
        first_half_m: part(1..half),
        second_half_m: part(half..n),
        steady_cycles: n - 1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::DemSettings;
    use crate::model::Design;

    fn lunar_conveyor(strokes: u32) -> (Scenario, Conveyor) {
        let s = Scenario::lunar();
        let d = Design::from_cli_units([49.950, 49.841, 35.590, 37.323, 81.67, 12.90, 0.812, 61.55]);
        let settings = DemSettings { particles: 40, teeth: Some(4), ..Default::default() };
        let tooth = Case::build(&s, &d, &settings, 3, None).unwrap();
        let c = Conveyor::build(&s, tooth, 3, strokes).unwrap();
        (s, c)
    }

    #[test]
    fn every_tooth_is_filled_inside_one_period_and_gravity_is_tilted() {
        let (s, c) = lunar_conveyor(4);
        let per_tooth = c.tooth.placement.grains.len();
        assert_eq!(c.grains.len(), 3 * per_tooth);
        let period = 3.0 * c.tooth.design.l_c;
        assert!(c.grains.iter().all(|g| g.pos[0] >= 0.0 && g.pos[0] < period), "inside one period");
        // the grains are in the pockets, above the base
        assert!(c.grains.iter().all(|g| g.pos[1] > 0.0), "above the base");
        let script = c.script();
        let alpha = s.environment.alpha_deg.to_radians();
        assert!(script.contains(&format!(
            "fix gravity all gravity 1.625 vector {:e} {:e} 0.0",
            -alpha.sin(),
            -alpha.cos()
        )));
        assert!(script.contains("boundary p f p"));
        // one stroke, stop, rest, return, rest and dump per cycle
        assert_eq!(script.matches("fix accel all gravity").count(), 4);
        assert_eq!(script.matches("unfix accel").count(), 4);
        for k in 0..=4 {
            assert!(script.contains(&format!("write_dump all custom {} id mass xu yu zu", cycle_dump(k))));
        }
        // the stop kick is v0 along the launch direction in conveyor coordinates
        let l = c.launch;
        let v0 = c.tooth.design.v0;
        assert!(script.contains(&format!("velocity all set {:e} {:e} 0.0 sum yes units box", v0 * l[0], v0 * l[1])));
        assert!((c.tooth.launch_angle_rad - alpha - l[1].atan2(l[0])).abs() < 1e-12);
        // vacuum: no drag, no sled drag
        assert!(!script.contains("viscous") && !script.contains("addforce"));
    }

    #[test]
    fn with_drag_the_air_at_rest_pushes_on_the_grains_by_the_sleds_velocity() {
        let mut s = Scenario::earth();
        s.sim.teeth = 20;
        let settings = DemSettings { particles: 40, teeth: Some(4), ..Default::default() };
        let tooth = Case::build(&s, &Design::validation_rig(), &settings, 0, None).unwrap();
        let c = Conveyor::build(&s, tooth, 2, 3).unwrap();
        let script = c.script();
        assert!(script.contains("fix drag all viscous"));
        assert_eq!(
            script.matches("fix sled0 all addforce v_sfx0 v_sfy0 0.0").count(),
            6,
            "stroke and return, 3 cycles"
        );
        assert_eq!(script.matches("unfix sled0").count(), 6);
    }

    /// The conveyor's deck, as the single stroke's, stops at `gone` rather than run or dump a
    /// case whose every grain has left the box.
    #[test]
    fn no_run_or_dump_of_the_conveyor_follows_a_run_without_the_grain_count_checked() {
        let (_, c) = lunar_conveyor(3);
        let script = c.script();
        // settle and its dump; per cycle: stroke, rest, return, rest, dump; the final dump
        assert_eq!(super::super::case::runs_and_dumps_checked(&script), 2 + 5 * c.strokes as usize + 1);
    }

    /// The conveyor tracks every grain from before settling, as the single stroke does, so
    /// that a grain it loses is placed; one whose track would outgrow its bound writes none.
    #[test]
    fn the_conveyor_tracks_every_grain_while_its_track_stays_within_bound() {
        let (_, c) = lunar_conveyor(3);
        assert!(c.tracked());
        let script = c.script();
        let dump = script.lines().position(|l| l.starts_with("dump track all custom ")).expect("a track");
        assert!(script.lines().nth(dump).unwrap().ends_with(&format!("{TRACK} id x y vx vy")));
        assert!(dump < script.lines().position(|l| l == "label settling").unwrap());
        let mut long = c.clone();
        long.strokes = 200;
        long.grains = vec![c.grains[0]; 20_000];
        assert!(!long.tracked());
        assert!(!long.script().contains("dump track"));
    }

    /// A cycle's dump of grains (id, mass, unwrapped x), at y 0.01 and z 0.001.
    fn dump(rows: &[(u64, f64, f64)]) -> String {
        let mut t = String::from("ITEM: TIMESTEP\n0\nITEM: ATOMS id mass xu yu zu\n");
        for (id, m, x) in rows {
            t.push_str(&format!("{id} {m} {x} 0.01 0.001\n"));
        }
        t
    }

    /// A run whose grains all left the box conveys nothing from the cycle where the last
    /// one went: the cycles the deck did not reach have no dump and advance nothing.
    #[test]
    fn the_cycles_after_every_grain_left_advance_nothing() {
        let dir = std::env::temp_dir().join(format!("sawtooth-conveyor-lost-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (_, mut c) = lunar_conveyor(3);
        c.grains.truncate(2);
        std::fs::write(dir.join(cycle_dump(0)), dump(&[(1, 1.0, 0.0), (2, 3.0, 0.1)])).unwrap();
        std::fs::write(dir.join(cycle_dump(1)), dump(&[(1, 1.0, 0.2), (2, 3.0, 0.3)])).unwrap();
        // without ALL_LOST a missing dump is an unfinished run
        assert!(reduce(&dir, &c, 1.0).is_err());
        std::fs::write(dir.join(ALL_LOST), "every grain left the box by step 9\n").unwrap();
        let r = reduce(&dir, &c, 1.0).unwrap();
        let advances: Vec<f64> = r.cycles.iter().map(|c| c.advance_m).collect();
        assert_eq!(r.cycles.len(), 3);
        assert!((advances[0] - 0.2).abs() < 1e-12 && advances[1] == 0.0 && advances[2] == 0.0, "{advances:?}");
        assert_eq!(r.cycles[1].lost, 2);
        assert_eq!(r.left_by, Some(LeftBy { unplaced: 2, ..LeftBy::default() }), "no track: never seen");
        assert_eq!(steady(&[r]).unwrap().advance_m, 0.0);
        // the track places them: one last seen near the box's bottom heading down (through
        // the mesh), one near its top rising (over the top)
        let [lo, hi] = c.bounds[1];
        std::fs::write(
            dir.join(TRACK),
            format!(
                "ITEM: TIMESTEP\n100\nITEM: ATOMS id x y vx vy\n1 0.01 {} 0 -1\n2 0.01 {} 0 1\n",
                lo + 1e-3,
                hi - 1e-3
            ),
        )
        .unwrap();
        let r = reduce(&dir, &c, 1.0).unwrap();
        assert_eq!(r.left_by, Some(LeftBy { through_mesh: 1, over_top: 1, ..LeftBy::default() }));
        // lost while settling: nothing on the conveyor
        std::fs::remove_file(dir.join(cycle_dump(0))).unwrap();
        std::fs::remove_file(dir.join(cycle_dump(1))).unwrap();
        let r = reduce(&dir, &c, 1.0).unwrap();
        assert!(r.cycles.iter().all(|c| c.advance_m == 0.0) && r.mass_per_tooth_kg == 0.0);
        assert_eq!(r.left_by, Some(LeftBy { while_settling: 2, ..LeftBy::default() }));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_mesh_is_one_period_from_p1_to_the_next_periods_p1() {
        let (_, c) = lunar_conveyor(3);
        let profile = local_profile(&c.tooth, 3);
        let line = periodic_line(&profile, 3);
        assert_eq!(line[0], [0.0, 0.0]);
        let last = line.last().unwrap();
        assert!((last[0] - 3.0 * c.tooth.design.l_c).abs() < 1e-12 && last[1] == 0.0);
        assert!(line.iter().all(|p| p[0] >= -1e-12 && p[0] <= last[0] + 1e-12), "inside the period");
    }

    #[test]
    fn a_stroke_advance_is_the_mass_weighted_unwrapped_displacement() {
        let dir = std::env::temp_dir().join(format!("sawtooth-conveyor-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (_, mut c) = lunar_conveyor(3);
        c.grains.truncate(2);
        std::fs::write(dir.join(cycle_dump(0)), dump(&[(1, 1.0, 0.0), (2, 3.0, 0.1)])).unwrap();
        std::fs::write(dir.join(cycle_dump(1)), dump(&[(1, 1.0, 0.2), (2, 3.0, 0.3)])).unwrap();
        std::fs::write(dir.join(cycle_dump(2)), dump(&[(2, 3.0, 0.4)])).unwrap();
        std::fs::write(dir.join(cycle_dump(3)), dump(&[(2, 3.0, 0.4)])).unwrap();
        let r = reduce(&dir, &c, 1.0).unwrap();
        assert!((r.cycles[0].advance_m - 0.2).abs() < 1e-12);
        assert!((r.cycles[1].advance_m - 0.1).abs() < 1e-12, "only the grain present in both");
        assert_eq!(r.cycles[1].lost, 1);
        assert_eq!(r.cycles[2].advance_m, 0.0);
        let st = steady(&[r]).unwrap();
        assert!((st.advance_m - 0.05).abs() < 1e-12);
        assert!((st.first_stroke_m - 0.2).abs() < 1e-12);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
