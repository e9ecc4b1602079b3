//! The engine's end positions read back: each grain assigned to a tooth by the model's own
//! boundaries (Eq. 4.56, `Profile::tooth_of_x`, in the frame of the mesh where the stroke
//! left it), tooth masses in grams, and the campaign written as measured data
//! (`io::measured`'s CSV) with a setup TOML that `fit`, `diagnose` and `dem compare` read as
//! they read a rig's.
//!
//! A grain is lost when LIGGGHTS deleted it (it left the box), when it ends behind tooth 0's
//! start (no surface there), or past the mesh's last tooth.
//!
//! What the engine wrote is checked before it becomes a number ([`check_dump`]): a run that
//! blew up (NaN or infinite positions, grains outside the box, duplicated or unknown ids,
//! masses that are not the placed grains', a stroke time that is not a time) is a failed
//! run, not a perfect one. A `result.json` read back is checked again ([`check_result`]):
//! it is input like any other, and an edited one must not reach `dem.csv` or a comparison.

use std::fmt::Write as _;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::case::Case;
use super::losses::LeftBy;
use super::sizes::grain_mass;

/// One grain of the dump.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DumpGrain {
    pub id: u64,
    pub mass_kg: f64,
    pub pos: [f64; 3],
    pub vel: [f64; 3],
}

/// Read `write_dump ... custom id type diameter mass x y z vx vy vz`.
pub fn parse_dump(text: &str) -> anyhow::Result<Vec<DumpGrain>> {
    let mut lines = text.lines();
    let header = lines.by_ref().find(|l| l.starts_with("ITEM: ATOMS")).context("dump has no `ITEM: ATOMS` section")?;
    let cols: Vec<&str> = header.split_whitespace().skip(2).collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).with_context(|| format!("dump lacks column `{name}`"));
    let idx = [at("id")?, at("mass")?, at("x")?, at("y")?, at("z")?, at("vx")?, at("vy")?, at("vz")?];
    let mut out = Vec::new();
    for (n, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| -> anyhow::Result<f64> {
            f.get(i).and_then(|s| s.parse().ok()).with_context(|| format!("dump atom line {}: bad field {i}", n + 1))
        };
        let id = f
            .get(idx[0])
            .and_then(|s| s.parse::<u64>().ok())
            .with_context(|| format!("dump atom line {}: the id is not a whole number >= 0", n + 1))?;
        out.push(DumpGrain {
            id,
            mass_kg: num(idx[1])?,
            pos: [num(idx[2])?, num(idx[3])?, num(idx[4])?],
            vel: [num(idx[5])?, num(idx[6])?, num(idx[7])?],
        });
    }
    Ok(out)
}

/// Relative tolerance of a grain's mass, and of the sum of the masses, against what was
/// placed: LIGGGHTS writes a dump's numbers with 6 significant digits (`%g`), so a grain's
/// mass reads back within 5e-6 of the placed one; 1e-4 leaves room for that and nothing else.
pub const MASS_TOLERANCE: f64 = 1e-4;

/// Every grain of the dump a grain that was placed, where a grain can be: a finite position
/// inside the case's box (LIGGGHTS deletes a grain that leaves it), a finite velocity, an id
/// in 1..=placed that no other grain has, the mass of the grain placed with that id (within
/// [`MASS_TOLERANCE`], so the masses add up to what was placed); and a stroke time that is
/// finite and not negative (`None`: a case of an older sawtooth, which recorded none).
pub fn check_dump(case: &Case, grains: &[DumpGrain], stroke_time_s: Option<f64>) -> Result<(), String> {
    if let Some(t) = stroke_time_s {
        if !(t.is_finite() && t >= 0.0) {
            return Err(format!("the stroke time at the end of the run is {t} s; a run ends at a finite time >= 0"));
        }
    }
    let placed = &case.placement.grains;
    if grains.len() > placed.len() {
        return Err(format!("the dump holds {} grains; {} were placed", grains.len(), placed.len()));
    }
    let rho = case.contact.density_kg_m3;
    let b = &case.bounds;
    // a grain on the box's face is inside; rounding of the dump's 6 digits is allowed for, and
    // in z, the periodic depth (`boundary f f p`), the distance a grain may stand past a face
    // until LIGGGHTS maps it back at its next neighbour-list rebuild
    let mut slack: Vec<f64> = b.iter().map(|[lo, hi]| 1e-5 * (hi - lo).abs().max(lo.abs()).max(hi.abs())).collect();
    slack[2] += case.neighbour_skin_m();
    let mut seen = vec![false; placed.len()];
    let mut sum_g = 0.0;
    for g in grains {
        let what = format!("grain {}", g.id);
        if let Some(k) = (0..3).find(|&k| !g.pos[k].is_finite()) {
            return Err(format!("{what}: position {} is {} (a run that blew up)", ["x", "y", "z"][k], g.pos[k]));
        }
        if let Some(k) = (0..3).find(|&k| !g.vel[k].is_finite()) {
            return Err(format!("{what}: velocity v{} is {} (a run that blew up)", ["x", "y", "z"][k], g.vel[k]));
        }
        for k in 0..3 {
            let [lo, hi] = b[k];
            if g.pos[k] < lo - slack[k] || g.pos[k] > hi + slack[k] {
                return Err(format!(
                    "{what}: {} = {:e} m lies outside the case's box [{lo:e}, {hi:e}] m (LIGGGHTS deletes a grain that leaves it)",
                    ["x", "y", "z"][k],
                    g.pos[k]
                ));
            }
        }
        let i = match usize::try_from(g.id).ok().and_then(|id| id.checked_sub(1)).filter(|&i| i < placed.len()) {
            Some(i) => i,
            None => return Err(format!("{what}: the id is not one of the placed grains' (1..={})", placed.len())),
        };
        if std::mem::replace(&mut seen[i], true) {
            return Err(format!("{what}: the id appears twice in the dump"));
        }
        let expected = grain_mass(placed[i].diameter_m, rho);
        if !(g.mass_kg.is_finite() && g.mass_kg > 0.0 && (g.mass_kg / expected - 1.0).abs() <= MASS_TOLERANCE) {
            return Err(format!(
                "{what}: mass {:e} kg is not the {expected:e} kg placed (within a relative {MASS_TOLERANCE:e})",
                g.mass_kg
            ));
        }
        sum_g += g.mass_kg * 1e3;
    }
    let missing_g: f64 =
        placed.iter().zip(&seen).filter(|(_, s)| !**s).map(|(p, _)| grain_mass(p.diameter_m, rho) * 1e3).sum();
    let placed_g = case.placement.mass_kg * 1e3;
    if ((sum_g + missing_g) / placed_g - 1.0).abs() > MASS_TOLERANCE {
        return Err(format!(
            "the grains weigh {:e} g with the deleted ones; {placed_g:e} g were placed (within a relative {MASS_TOLERANCE:e})",
            sum_g + missing_g
        ));
    }
    Ok(())
}

/// A result read back from `result.json` against the run it claims to be: run `run` of a
/// campaign whose first case is `case` (the mesh's teeth, the placed grains and their mass
/// are the same for every seed) and whose first seed is `first_seed`. The first broken rule,
/// naming its field.
pub fn check_result(r: &RunResult, case: &Case, first_seed: u64, run: u32) -> Result<(), String> {
    let seed = first_seed.checked_add(u64::from(run));
    if Some(r.seed) != seed {
        return Err(format!(
            "`seed` {} is not run {}'s seed {} in the campaign's plan",
            r.seed,
            run + 1,
            seed.map_or("(beyond 2^64)".into(), |s| s.to_string())
        ));
    }
    if r.teeth_g.len() != case.teeth as usize {
        return Err(format!("`teeth_g` holds {} teeth; the campaign's mesh has {}", r.teeth_g.len(), case.teeth));
    }
    if let Some((j, m)) = r.teeth_g.iter().enumerate().find(|(_, m)| !(m.is_finite() && **m >= 0.0)) {
        return Err(format!("`teeth_g[{j}]` is {m:?} g; a tooth holds a finite mass >= 0"));
    }
    let placed_g = case.placement.mass_kg * 1e3;
    if !(r.input_mass_g.is_finite()
        && r.input_mass_g > 0.0
        && (r.input_mass_g / placed_g - 1.0).abs() <= MASS_TOLERANCE)
    {
        return Err(format!(
            "`input_mass_g` {:?} is not the {placed_g:e} g the campaign's case places (within a relative {MASS_TOLERANCE:e})",
            r.input_mass_g
        ));
    }
    let in_teeth: f64 = r.teeth_g.iter().sum();
    if in_teeth > r.input_mass_g * (1.0 + MASS_TOLERANCE) {
        return Err(format!(
            "`teeth_g` adds up to {in_teeth:?} g, more than the {:?} g loaded (`input_mass_g`)",
            r.input_mass_g
        ));
    }
    let placed = case.placement.grains.len();
    if r.grains != placed {
        return Err(format!("`grains` {} is not the {placed} grains the campaign's case places", r.grains));
    }
    for (name, v) in [("lost", r.lost), ("moving", r.moving)] {
        if v > r.grains {
            return Err(format!("`{name}` {v} exceeds `grains` {}", r.grains));
        }
    }
    if r.left_box > r.lost {
        return Err(format!("`left_box` {} exceeds `lost` {} (a grain that left the box is lost)", r.left_box, r.lost));
    }
    if let Some(by) = &r.left_by {
        if by.total() != r.left_box {
            return Err(format!("`left_by` places {} grains; {} left the box (`left_box`)", by.total(), r.left_box));
        }
    }
    let farthest = case.profile().credited_distance(case.teeth as i64);
    if !(r.d_avg_m.is_finite() && r.d_avg_m >= 0.0 && r.d_avg_m <= farthest * (1.0 + MASS_TOLERANCE)) {
        return Err(format!("`d_avg_m` {:?} m lies outside [0, {farthest}] m (the mesh's last tooth)", r.d_avg_m));
    }
    if !(r.wall_s.is_finite() && r.wall_s >= 0.0) {
        return Err(format!("`wall_s` {:?} is not a duration (finite, >= 0)", r.wall_s));
    }
    Ok(())
}

/// Read a dump's `x y z` columns (`write_dump ... custom id x y z`), in the dump's order.
pub fn parse_positions(text: &str) -> anyhow::Result<Vec<[f64; 3]>> {
    let mut lines = text.lines();
    let header = lines.by_ref().find(|l| l.starts_with("ITEM: ATOMS")).context("dump has no `ITEM: ATOMS` section")?;
    let cols: Vec<&str> = header.split_whitespace().skip(2).collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).with_context(|| format!("dump lacks column `{name}`"));
    let idx = [at("x")?, at("y")?, at("z")?];
    let mut out = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| -> anyhow::Result<f64> {
            f.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .with_context(|| format!("dump atom line {}: bad field {i}", n + 1))
        };
        out.push([num(idx[0])?, num(idx[1])?, num(idx[2])?]);
    }
    Ok(out)
}

/// One DEM run reduced to what the rig measured, and a little more.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    pub seed: u64,
    /// Grams per tooth, tooth 1 first (the mesh's teeth).
    pub teeth_g: Vec<f64>,
    /// Grams loaded (every grain placed).
    pub input_mass_g: f64,
    pub grains: usize,
    pub lost: usize,
    /// Grains left the box (a subset of `lost`).
    pub left_box: usize,
    /// Grains still faster than the rest speed at the end.
    pub moving: usize,
    /// The model's d_avg rule on the DEM's grains: global x of the resting tooth's p4 (0 for
    /// tooth 1 and for lost grains), mass-weighted over every grain, m.
    pub d_avg_m: f64,
    /// Wall-clock seconds LIGGGHTS ran.
    pub wall_s: f64,
    /// Grains lost past the mesh's last tooth (a subset of `lost`): a mesh too short for
    /// the design's flights (`dem compare` warns).
    #[serde(default)]
    pub past_end: usize,
    /// Where the grains lay after settling, before the stroke (x, y in the model's global
    /// frame, m): the bed the model can be launched from (`dem compare`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub settled_xy_m: Vec<[f64; 2]>,
    /// Where the grains that left the box went (`losses`); None for a case that wrote no
    /// track.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub left_by: Option<LeftBy>,
}

/// Reduce the dump of `case`, written `stroke_time_s` after the stroke began (infinity:
/// after every movement of the mesh), to a [`RunResult`].
pub fn reduce(case: &Case, grains: &[DumpGrain], stroke_time_s: f64, wall_s: f64) -> RunResult {
    let profile = case.profile();
    let shift = case.motion.displacement(stroke_time_s);
    let placed = case.placement.grains.len();
    let rho = case.contact.density_kg_m3;
    let mut present = vec![false; placed];
    let mut teeth_g = vec![0.0; case.teeth as usize];
    let (mut lost, mut moving, mut credited, mut past_end) = (0usize, 0usize, 0.0, 0usize);
    let mut mass_total = 0.0;
    for g in grains {
        let m = g.mass_kg * 1e3;
        mass_total += m;
        if let Some(p) = (g.id as usize).checked_sub(1).and_then(|i| present.get_mut(i)) {
            *p = true;
        }
        let speed = (g.vel[0].powi(2) + g.vel[1].powi(2) + g.vel[2].powi(2)).sqrt();
        if speed > case.settings.rest_speed_m_s {
            moving += 1;
        }
        let x = g.pos[0] - shift[0];
        let tooth = profile.tooth_of_x(x);
        if x < 0.0 || tooth > case.teeth as i64 {
            lost += 1;
            past_end += (x >= 0.0) as usize;
            continue;
        }
        let j = tooth.max(1);
        teeth_g[(j - 1) as usize] += m;
        credited += m * profile.credited_distance(j);
    }
    let left_box = placed.saturating_sub(grains.len());
    // the grains LIGGGHTS deleted weigh what they weighed when placed (grain i has id i + 1)
    let left_mass_g: f64 = case
        .placement
        .grains
        .iter()
        .zip(&present)
        .filter(|(_, p)| !**p)
        .map(|(g, _)| grain_mass(g.diameter_m, rho) * 1e3)
        .sum();
    let input_mass_g = mass_total + left_mass_g;
    RunResult {
        seed: case.seed,
        teeth_g,
        input_mass_g,
        grains: placed,
        lost: lost + left_box,
        left_box,
        moving,
        d_avg_m: if input_mass_g > 0.0 { credited / input_mass_g } else { 0.0 },
        wall_s,
        past_end,
        settled_xy_m: Vec::new(),
        left_by: None,
    }
}

/// The campaign's tooth masses as a measured-data CSV (`io::measured`): `#` provenance,
/// `run,tooth_1..tooth_n,input_mass`, grams.
pub fn measured_csv(provenance: &[String], runs: &[RunResult]) -> anyhow::Result<String> {
    let Some(first) = runs.first() else { bail!("no runs to write") };
    let teeth = first.teeth_g.len();
    let mut s = String::new();
    for p in provenance {
        let _ = writeln!(s, "# {p}");
    }
    let cols: Vec<String> = (1..=teeth).map(|j| format!("tooth_{j}")).collect();
    let _ = writeln!(s, "run,{},input_mass", cols.join(","));
    for (i, r) in runs.iter().enumerate() {
        if r.teeth_g.len() != teeth {
            bail!("run {} has {} teeth, the first has {teeth}", i + 1, r.teeth_g.len());
        }
        let masses: Vec<String> = r.teeth_g.iter().map(|m| format!("{m:.9e}")).collect();
        let _ = writeln!(s, "seed{},{},{:.9e}", r.seed, masses.join(","), r.input_mass_g);
    }
    Ok(s)
}

/// A setup TOML for the campaign: the scenario and design as config keys (so that `fit`
/// and `diagnose` rebuild the same scenario), `[measurement]` with one grain's mass as the
/// scale's resolution and the stated sled return, and `[dem]` so that the case can be
/// built again (`dem compare`, `dem run --config`).
pub fn setup_toml(case: &Case, known_return: Option<(f64, f64)>, description: &str) -> anyhow::Result<String> {
    let s = &case.scenario;
    let d = &case.design;
    let e = &s.environment;
    let p = &s.performance;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# DEM campaign setup written by `sawtooth dem run` (docs/dem.md): the scenario of the runs as config keys."
    );
    let _ = writeln!(t, "mode = \"physical\"\n");
    let _ = writeln!(t, "{}", crate::model::design::DesignRow::of(d).config_table());
    let _ = writeln!(
        t,
        "[environment]\ng_m_s2 = {}\nalpha_deg = {}\nk_drag_per_s = {}\n",
        e.g,
        e.alpha_deg,
        e.k_drag.unwrap_or(0.0)
    );
    let m = &s.material;
    let _ = writeln!(
        t,
        "[material]\nname = \"{}\"\naor_deg = {}\nbulk_density_kg_m3 = {}\n",
        m.name, m.aor_deg, m.bulk_density
    );
    let _ =
        writeln!(t, "[collision]\nk_elastic = {}\nmu_friction = {}\n", s.collision.k_elastic, s.collision.mu_friction);
    let sim = &s.sim;
    let _ = writeln!(
        t,
        "[sim]\nteeth = {}\nparticles = {}\nmax_bounces = {}\nrandomise = {}\nrandom_band = {}\nseed = {}\nrest_threshold_m = {}\nlaunch_offset_deg = {}\nlaunch_points = \"{}\"\n",
        sim.teeth.max(case.teeth),
        sim.particles,
        sim.max_bounces,
        sim.randomise,
        sim.random_band,
        sim.seed,
        sim.rest_threshold,
        sim.launch_offset_deg,
        match sim.launch_points {
            crate::model::scenario::LaunchPoints::Halton => "halton",
            crate::model::scenario::LaunchPoints::Random => "random",
        }
    );
    let _ = writeln!(
        t,
        "[performance]\nconveyor_length_m = {}\nregolith_width_m = {}\nsled_width_m = {}\ndownstroke_speed_m_s = {}\nf_max_hz = {}\nsled_thickness_m = {}\nsled_density_kg_m3 = {}\ncontraction_ratio = {}\n",
        p.conveyor_length, p.regolith_width, p.sled_width, p.downstroke_speed, p.f_max, p.sled_thickness, p.sled_density, p.contraction_ratio
    );
    // The size law is the DEM's physics, as grain-grain contacts are: the setup describes the
    // rig as a rig's setup would (its sieve range in words), so that `fit` and `diagnose`
    // judge the campaign as measured data and do not start from the answer.
    let mut effects = s.effects;
    if let Some(law) = effects.polydisperse.take() {
        let classes: Vec<String> =
            case.placement.classes.iter().map(|c| format!("{} x {:.0} um", c.grains, c.diameter_m * 1e6)).collect();
        let _ = writeln!(
            t,
            "# The DEM's grains follow the polydisperse size law (sigma_ln {}, {:?}; classes {}), not switched on here.\n",
            law.sigma_ln,
            law.form,
            classes.join(", ")
        );
    }
    if effects.any() {
        let mut wrapper = toml::map::Map::new();
        wrapper.insert("effects".into(), toml::Value::try_from(effects)?);
        let _ = writeln!(t, "{}", toml::to_string(&toml::Value::Table(wrapper))?);
    }
    let c = &case.settings;
    // one grain is what the scale resolves: the smallest grain of a size law
    let smallest_grain_g = case
        .placement
        .classes
        .iter()
        .map(|c| grain_mass(c.diameter_m, case.contact.density_kg_m3) * 1e3)
        .fold(case.placement.grain_mass_kg * 1e3, f64::min);
    let _ = writeln!(
        t,
        "[dem]\nparticles = {}\ngrain_diameter_m = {:e}\ndepth_grains = {}\nrolling_friction = {}\nmax_overlap_fraction = {}\nmax_time_s = {}\nrest_speed_m_s = {}\nteeth = {}\n",
        c.particles,
        case.placement.diameter_m,
        c.depth_grains,
        c.rolling_friction,
        c.max_overlap_fraction,
        c.max_time_s,
        c.rest_speed_m_s,
        case.teeth
    );
    let _ = writeln!(
        t,
        "[measurement]\nscale_resolution_g = {:e}\nparticle_mass_g = {:e}\n\
         # every grain a DEM run did not recover left the box or the mesh: physics the model must\n\
         # predict, not a spill between conveyor and scale (the diagnosis allows a rig's spill)\n\
         handling_loss_max = 0",
        smallest_grain_g,
        case.placement.mass_kg * 1e3
    );
    if let Some((delay, speed)) = known_return {
        let _ = writeln!(t, "motion_delay_s = {delay}\nmotion_return_speed_m_s = {speed}");
    }
    let _ = writeln!(t, "description = {}", toml::Value::String(description.to_string()));
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// z is the slab's periodic depth: LIGGGHTS maps a grain that crossed a periodic face back
    /// only at its next neighbour-list rebuild, so a dump may show it up to the skin outside
    /// (a real Earth run at v0 1.4 m/s did, by 0.03 mm); x and y are walls, and there the box
    /// is the box.
    #[test]
    fn a_grain_past_the_periodic_face_by_less_than_the_skin_is_inside_the_box() {
        let mut s = crate::model::Scenario::earth();
        s.sim.teeth = 20;
        let settings = crate::dem::DemSettings { particles: 60, teeth: Some(8), ..Default::default() };
        let case = Case::build(&s, &crate::model::Design::validation_rig(), &settings, 0, None).unwrap();
        let at = |pos: [f64; 3]| {
            let p = &case.placement.grains[0];
            let g =
                DumpGrain { id: 1, mass_kg: grain_mass(p.diameter_m, case.contact.density_kg_m3), pos, vel: [0.0; 3] };
            check_dump(&case, &[g], Some(0.0))
        };
        let [x, y, z] = case.placement.grains[0].pos;
        let skin = case.neighbour_skin_m();
        let [zlo, zhi] = case.bounds[2];
        assert!(at([x, y, z]).is_ok());
        assert!(at([x, y, zhi + 0.5 * skin]).is_ok(), "{:?}", at([x, y, zhi + 0.5 * skin]));
        assert!(at([x, y, zlo - 0.5 * skin]).is_ok());
        assert!(at([x, y, zhi + 1.5 * skin]).unwrap_err().contains("lies outside the case's box"));
        let [_, yhi] = case.bounds[1];
        assert!(at([x, yhi + 0.5 * skin, z]).unwrap_err().contains("lies outside the case's box"));
    }

    #[test]
    fn a_dump_is_read_by_its_column_names() {
        let text = "ITEM: TIMESTEP\n10\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff pp\n0 1\n0 1\n0 1\n\
                    ITEM: ATOMS id type diameter mass x y z vx vy vz \n\
                    1 1 0.0005 1.8e-07 0.01 0.002 0.001 0 -1e-3 0\n2 1 0.0005 1.8e-07 0.05 0.02 0.001 0.5 0 0\n";
        let g = parse_dump(text).unwrap();
        assert_eq!(g.len(), 2);
        assert_eq!(g[1].id, 2);
        assert_eq!(g[1].pos, [0.05, 0.02, 0.001]);
        assert_eq!(g[0].mass_kg, 1.8e-7);
        assert!(parse_dump("ITEM: ATOMS id x\n1 0\n").unwrap_err().to_string().contains("mass"));
    }

    #[test]
    fn the_csv_is_measured_data() {
        let r = |seed, t: Vec<f64>| RunResult {
            seed,
            input_mass_g: t.iter().sum::<f64>() + 0.1,
            teeth_g: t,
            grains: 10,
            lost: 1,
            left_box: 1,
            moving: 0,
            d_avg_m: 0.01,
            wall_s: 1.0,
            past_end: 0,
            settled_xy_m: Vec::new(),
            left_by: None,
        };
        let csv = measured_csv(&["DEM".into()], &[r(1, vec![0.5, 0.3, 0.1]), r(2, vec![0.4, 0.4, 0.1])]).unwrap();
        let m = crate::io::measured::parse(&csv, "dem.csv").unwrap();
        assert_eq!(m.teeth, 3);
        assert_eq!(m.runs[1].id, "seed2");
        assert!((m.runs[0].input_mass_g.unwrap() - 1.0).abs() < 1e-9);
        assert_eq!(m.provenance, vec!["DEM".to_string()]);
    }
}
