//! One LIGGGHTS case: the model's design and scenario made into a mesh, grains, contact
//! parameters, a sled motion and an input script, written into a folder that LIGGGHTS runs
//! in (`cd DIR && liggghts -in in.sawtooth`).
//!
//! The script: read the grains; Hertz contacts with history and rolling friction (`pair_style
//! gran model hertz tangential history rolling_friction cdt`), the same model on the mesh
//! (`fix wall/gran`); gravity straight down (the mesh carries the slope); Stokes drag with
//! drag (`fix viscous`, γ = m k_drag, Eq. 4.20); settle in chunks until the grains rest; the
//! stroke (`fix move/mesh linear/variable`); chunks until the grains rest again or
//! `max_time_s`; the end positions dumped (`write_dump`). Grains that leave the box are
//! deleted (`thermo_modify lost ignore`) and counted lost when gathered.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::contact::{contact, model_normal_cor, property_commands, Contact, CONTACT_MODEL};
use super::grains::{mass_matching_diameter, place, place_sized, Placement};
use super::motion::SledMotion;
use super::settings::{check_representable, DemSettings};
use super::sizes::{reference_diameter, size_classes};
use super::stl::{extrude, facet_line, profile_polyline, stl_text};
use crate::engine::{evaluate_detailed, make_engine, EngineKind};
use crate::io::atomic::write_atomic;
use crate::io::config::DemRestitution;
use crate::model::geometry::Profile;
use crate::model::{prepare, Design, ParticleState, Scenario};

pub const SCRIPT: &str = "in.sawtooth";
pub const MESH: &str = "sled.stl";
pub const GRAINS: &str = "grains.data";
pub const MANIFEST: &str = "case.json";
pub const DUMP: &str = "final.dump";
/// The grains' positions after settling, before the stroke (the bed the model can be told).
pub const SETTLED: &str = "settled.dump";
/// Every grain's `id x y vx vy` at every rest check, settling included: where a grain
/// LIGGGHTS deletes left the box (`losses`).
pub const TRACK: &str = "track.dump";
/// The LIGGGHTS step at which the stroke began (stroke time 0; `losses`).
pub const STROKE_START: &str = "stroke_start.txt";
/// The stroke time at which the run ended, s (the mesh's position then is the binning frame).
pub const STROKE_TIME: &str = "stroke_time.txt";
/// Written instead of [`DUMP`] when every grain has left the box: LIGGGHTS refuses to `run`
/// (or dump) a granular case with no grains ("Atom types must start from 1": the mesh's type 2
/// is then the lowest type present), so the deck stops there and says so, and the run is a
/// result with every grain lost rather than a failure.
pub const ALL_LOST: &str = "all_lost.txt";

/// `deck` with the grain count checked before every `run` and `write_dump`: LIGGGHTS stops
/// with an error ("Atom types must start from 1") on a run or a dump of a granular case with
/// no grains left, so a case whose every grain has left the box jumps to `gone` instead,
/// which writes ALL_LOST and ends. A deck's normal end jumps past it.
pub(super) fn stop_when_every_grain_is_gone(deck: &str) -> String {
    const GUARD: &str = "if \"${grains} == 0\" then \"jump SELF gone\"\n";
    let mut s = String::with_capacity(deck.len() + 4096);
    for line in deck.lines() {
        if line.starts_with("run ") || line.starts_with("write_dump ") {
            s.push_str(GUARD);
        }
        s.push_str(line);
        s.push('\n');
        if line.starts_with("read_data ") {
            s.push_str("# before every run and dump: a case with no grains left cannot run (ALL_LOST)\nvariable grains equal atoms\n");
        }
    }
    let _ = write!(
        s,
        "jump SELF finished\n\
         label gone\nvariable at equal step\nprint \"sawtooth: every grain left the box by step ${{at}}\"\n\
         print \"every grain left the box by step ${{at}}\" file {ALL_LOST} screen no\n\
         label finished"
    );
    s
}

/// Simulated time per rest check, s.
const CHUNK_S: f64 = 0.02;
/// Longest settling before the stroke, s (the grains start a fraction of a diameter apart).
const MAX_SETTLE_S: f64 = 1.0;
/// Teeth the mesh keeps beyond the model's farthest resting grain: at least this many ...
const REACH_MARGIN_TEETH: u32 = 3;
/// ... and at least this share of the reach ([`mesh_teeth`]). A fixed 3 was short on a
/// held-out lunar design (draw 2's doe-04, reach 15: 2.0 % of the DEM's grains at 150, 2.5 % at
/// 300 left past tooth 18, docs/dem.md): the DEM's grains fly further than the model's as
/// they get finer.
const REACH_MARGIN_SHARE: f64 = 0.5;
/// The conveyor the model's reach is measured on, teeth: longer than any flight of the
/// optimiser's range (lunar pick B, v0 1.93 m/s, rests within 40 teeth).
pub const REACH_CONVEYOR_TEETH: u32 = 400;

/// Everything the case is made of; `case.json` is this, serialised.
#[derive(Clone, Debug, Serialize)]
pub struct Case {
    pub scenario: Scenario,
    pub design: Design,
    pub settings: DemSettings,
    pub seed: u64,
    /// Teeth of the mesh.
    pub teeth: u32,
    /// The model's fill area, m² (4.2.3).
    pub fill_area_m2: f64,
    pub launch_angle_rad: f64,
    pub placement: Placement,
    pub contact: Contact,
    pub motion: SledMotion,
    /// Stokes drag γ = m k_drag of a grain of the placement's diameter (polydisperse: of
    /// the mass median; each class has its own, `placement.classes`), kg/s; None in vacuum.
    pub drag_gamma_kg_s: Option<f64>,
    /// Simulation box [lo, hi] in x, y, z, m.
    pub bounds: [[f64; 2]; 3],
    pub facets: usize,
}

/// The case's files as text.
pub struct CaseFiles {
    pub script: String,
    pub stl: String,
    pub data: String,
    pub manifest: String,
}

impl Case {
    /// Build the case of `design` under `scenario`; `known_return` is a setup's stated sled
    /// return (delay s, speed m/s). Errors name the rule (a design the model rejects, a
    /// scenario the mesh cannot represent, a fill that cannot seat the grains).
    pub fn build(
        scenario: &Scenario,
        design: &Design,
        settings: &DemSettings,
        seed: u64,
        known_return: Option<(f64, f64)>,
    ) -> Result<Case, String> {
        settings.validate()?;
        check_representable(scenario)?;
        let prep = prepare(scenario, design).map_err(|e| format!("invalid design ({}): {e}", e.rule()))?;
        let teeth = match settings.teeth {
            Some(t) => t,
            // a plan that left the mesh to the case (every plan before plans stated it,
            // [`with_stated_mesh`]) keeps the mesh its runs were made on
            None => unstated_mesh_teeth(farthest_resting_tooth(scenario, design)?),
        };
        let m = &scenario.material;
        let mono_d = || fill_grain_diameter(scenario, prep.fill.area, settings);
        let k_drag = scenario.environment.k_drag;
        let placement = match scenario.effects.polydisperse {
            // the size law's classes (`sizes`): the stated diameter is the mass median
            Some(law) => {
                let d_ref = settings.grain_diameter_m.unwrap_or_else(|| reference_diameter(&law, mono_d()));
                let depth = settings.depth_grains * d_ref;
                let fill_mass = prep.fill.area * depth * m.bulk_density;
                let classes = size_classes(&law, d_ref, fill_mass, m.particle.density, k_drag);
                place_sized(&prep.fill, &classes, d_ref, depth, m.particle.density, m.bulk_density, seed)?
            }
            None => {
                let d = settings.grain_diameter_m.unwrap_or_else(mono_d);
                let mut p = place(
                    &prep.fill,
                    settings.particles,
                    d,
                    settings.depth_grains,
                    m.particle.density,
                    m.bulk_density,
                    seed,
                )?;
                p.classes[0].drag_gamma_kg_s = k_drag.map(|k| p.grain_mass_kg * k);
                p
            }
        };
        let motion = SledMotion::new(scenario, design, prep.launch_angle, known_return);
        // the fastest contact: a grain leaving at v0 and its randomised excess, falling a
        // tooth's height onto the next; the smallest grain has the shortest contact (t_c ∝ d)
        let design_speed = 1.5 * design.v0;
        let d_min = placement.classes.iter().map(|c| c.diameter_m).fold(f64::INFINITY, f64::min);
        let mut contact =
            contact(scenario, d_min, design_speed, settings.rolling_friction, settings.max_overlap_fraction);
        if settings.restitution == DemRestitution::Model {
            contact.restitution = model_normal_cor(scenario, design.v0).clamp(0.01, 1.0);
        }
        let drag_gamma_kg_s = k_drag.map(|k| placement.grain_mass_kg * k);
        let profile = Profile::new(design, prep.profile.local, scenario.environment.alpha_deg, teeth);
        let line = facet_line(&profile_polyline(&profile, teeth), placement.depth_m);
        let bounds = bounds(&line, &motion, design, scenario.environment.g, placement.depth_m);
        Ok(Case {
            scenario: scenario.clone(),
            design: *design,
            settings: settings.clone(),
            seed,
            teeth,
            fill_area_m2: prep.fill.area,
            launch_angle_rad: prep.launch_angle,
            placement,
            contact,
            motion,
            drag_gamma_kg_s,
            bounds,
            facets: 2 * (line.len() - 1),
        })
    }

    /// The model's profile with the mesh's tooth count (the teeth grains are binned by).
    pub fn profile(&self) -> Profile {
        let local = crate::model::geometry::check_design(&self.design).expect("checked when the case was built");
        Profile::new(&self.design, local, self.scenario.environment.alpha_deg, self.teeth)
    }

    pub fn files(&self) -> anyhow::Result<CaseFiles> {
        let profile = self.profile();
        let line = facet_line(&profile_polyline(&profile, self.teeth), self.placement.depth_m);
        let stl = stl_text("sled", &extrude(&line, self.placement.depth_m));
        Ok(CaseFiles { script: self.script(), stl, data: self.data(), manifest: serde_json::to_string_pretty(self)? })
    }

    /// Write the case into `dir` (each file atomically).
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        let f = self.files()?;
        write_atomic(&dir.join(MESH), f.stl.as_bytes())?;
        write_atomic(&dir.join(GRAINS), f.data.as_bytes())?;
        write_atomic(&dir.join(MANIFEST), f.manifest.as_bytes())?;
        write_atomic(&dir.join(SCRIPT), f.script.as_bytes())?;
        Ok(())
    }

    /// `read_data` file: granular atoms `id type diameter density x y z`.
    fn data(&self) -> String {
        let b = &self.bounds;
        let mut s = String::new();
        let _ = writeln!(s, "sawtooth dem grains (seed {})\n", self.seed);
        let _ = writeln!(s, "{} atoms\n2 atom types\n", self.placement.grains.len());
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let _ = writeln!(s, "{:.9e} {:.9e} {axis}lo {axis}hi", b[k][0], b[k][1]);
        }
        let _ = writeln!(s, "\nAtoms\n");
        for (i, g) in self.placement.grains.iter().enumerate() {
            let _ = writeln!(
                s,
                "{} 1 {:.9e} {} {:.9e} {:.9e} {:.9e}",
                i + 1,
                g.diameter_m,
                self.contact.density_kg_m3,
                g.pos[0],
                g.pos[1],
                g.pos[2]
            );
        }
        s
    }

    /// The largest grain's diameter, m: it sets the neighbour skin and the bins.
    pub fn largest_diameter_m(&self) -> f64 {
        self.placement.classes.iter().map(|c| c.diameter_m).fold(self.placement.diameter_m, f64::max)
    }

    /// Whether the run dumps its track ([`TRACK`]): only when the track stays within its
    /// bound (grains × snapshots × a line of at most ~100 bytes).
    pub fn tracked(&self) -> bool {
        let snapshots = ((MAX_SETTLE_S + self.settings.max_time_s + self.motion.t_launch()) / CHUNK_S).ceil() + 2.0;
        let lines = snapshots * (self.placement.grains.len() as f64 + 9.0);
        lines * 100.0 <= crate::schema::DEM_TRACK_FILE.max_bytes as f64
    }

    /// LIGGGHTS's neighbour skin, m (`neighbor SKIN bin`). A grain past a periodic face is
    /// mapped back into the box only when the neighbour lists are rebuilt, which happens before
    /// any grain has moved half the skin, so a dump may show a grain that far outside.
    pub fn neighbour_skin_m(&self) -> f64 {
        0.5 * self.largest_diameter_m()
    }

    /// Steps of `seconds` at the case's time step.
    fn steps(&self, seconds: f64) -> u64 {
        (seconds / self.contact.timestep_s).ceil().max(1.0) as u64
    }

    fn script(&self) -> String {
        let c = &self.contact;
        // the largest grain sets the neighbour skin and the bins
        let d = self.largest_diameter_m();
        let dt = c.timestep_s;
        let [vx, vy] = self.motion.velocity_expressions("t");
        let chunk = self.steps(CHUNK_S);
        let settle_chunks = (MAX_SETTLE_S / CHUNK_S).ceil() as u64;
        let rest_chunks = (self.settings.max_time_s / CHUNK_S).ceil() as u64;
        // the run after the launch checks for rest; grains may count as resting before a
        // stated return starts (the model's grains have landed by then; a rig's delayed return
        // carries them in their teeth) or after it ends, never while the mesh moves
        let stroke = self.steps(self.motion.t_launch());
        let rested = match self.motion.return_window() {
            Some((t0, t1)) => format!(
                "${{vrms}} < {rest:e} && (${{t}} >= {t1:e} || ${{t}} < {t0:e})",
                rest = self.settings.rest_speed_m_s
            ),
            None => format!("${{vrms}} < {:e}", self.settings.rest_speed_m_s),
        };
        let skin = self.neighbour_skin_m();
        // bins no finer than the box can afford (LIGGGHTS bins the whole box)
        let area = (self.bounds[0][1] - self.bounds[0][0]) * (self.bounds[1][1] - self.bounds[1][0]);
        let binsize = (d + skin).max((area / 2e5).sqrt());
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# sawtooth dem case (generated by `sawtooth dem write`; every number is explained in case.json and docs/dem.md)\n\
             # design {}; seed {}\n\
             atom_style granular\natom_modify map array\nboundary f f p\nnewton off\ncommunicate single vel yes\nunits si\n\
             read_data {GRAINS}\nneighbor {skin:e} bin\nneigh_modify delay 0 binsize {binsize:e}\n",
            crate::model::design::DesignRow::of(&self.design),
            self.seed
        );
        let _ = writeln!(
            s,
            "# material (Table 4.1) with the softened moduli (factor {:.3e}), collision k_elastic and mu_friction, [dem] rolling_friction\n\
             {}fix gravity all gravity {} vector 0.0 -1.0 0.0\n\
             fix sled all mesh/surface file {MESH} type 2\n\
             fix walls all wall/gran {CONTACT_MODEL} mesh n_meshes 1 meshes sled",
            c.softening,
            property_commands(c),
            self.scenario.environment.g,
        );
        s.push_str(&drag_commands(&self.placement, self.scenario.environment.k_drag.unwrap_or(0.0)));
        let _ = writeln!(
            s,
            "# the stroke starts at step s0 (set after settling); t is the stroke time\n\
             variable s0 equal 1e15\nvariable t equal (step-v_s0)*{dt:e}\n\
             variable vx equal {vx}\nvariable vy equal {vy}\nvariable vz equal 0\n\
             fix stroke all move/mesh mesh sled linear/variable v_vx v_vy v_vz\n\
             fix integrate all nve/sphere\n\
             compute ke all ke\nvariable m equal mass(all)\nvariable vrms equal sqrt(2*c_ke/(v_m+1e-30))\n\
             thermo_style custom step atoms ke v_vrms v_t\nthermo {chunk}\nthermo_modify lost ignore norm no\n\
             {track}\
             # settle\nvariable settle loop {settle_chunks}\nlabel settling\nrun {chunk}\n\
             if \"${{vrms}} < {rest:e}\" then \"jump SELF settled\"\nnext settle\njump SELF settling\nlabel settled\n\
             write_dump all custom {SETTLED} id x y z\n\
             variable now equal step\nvariable s0 equal ${{now}}\nprint \"sawtooth: stroke starts at step ${{s0}}\"\n\
             print \"${{s0}}\" file {STROKE_START} screen no\n\
             # the stroke\nrun {stroke}\n\
             # until the grains rest (and a return is not under way)\nvariable rest loop {rest_chunks}\nlabel resting\nrun {chunk}\n\
             if \"{rested}\" then \"jump SELF rested\"\nnext rest\njump SELF resting\nlabel rested\n\
             print \"sawtooth: stroke time at the end ${{t}} s\"\n\
             # where the mesh stopped: the gather bins the grains in its frame then\n\
             print \"${{t}}\" file {STROKE_TIME} screen no\n\
             write_dump all custom {DUMP} id type diameter mass x y z vx vy vz",
            rest = self.settings.rest_speed_m_s,
            track = if self.tracked() {
                format!(
                    "# every grain at every rest check: where a grain LIGGGHTS deletes left the box (losses.rs)\ndump track all custom {chunk} {TRACK} id x y vx vy\n"
                )
            } else {
                "# no track: it would be larger than schema::DEM_TRACK_FILE allows (losses.rs)\n".to_string()
            },
        );
        stop_when_every_grain_is_gone(&s)
    }
}

/// Stokes drag (`fix viscous`, γ = m k_drag, Eq. 4.20) on the grains of `placement`, whose
/// LIGGGHTS ids run class by class from 1: one fix on every grain for one size, one group of
/// ids and one fix per class for a size law. Nothing in vacuum.
pub fn drag_commands(placement: &Placement, k_drag: f64) -> String {
    let mut s = String::new();
    match placement.classes.as_slice() {
        [one] => {
            if let Some(gamma) = one.drag_gamma_kg_s {
                let _ = writeln!(
                    s,
                    "# Stokes drag, gamma = m k_drag (Eq. 4.20, k_drag {k_drag} 1/s)\nfix drag all viscous {gamma:e}"
                );
            }
        }
        classes => {
            // one group per size class (its grains' ids are one range) with its own gamma
            let _ = writeln!(
                s,
                "# size classes of the polydisperse law (sizes.rs); Stokes drag per class, gamma = m k_drag (d_ref/d)^2 (Eq. 4.16, 4.20, k_drag {k_drag} 1/s at d_ref {:e} m)",
                placement.diameter_m
            );
            let mut first = 1;
            for (k, c) in classes.iter().enumerate() {
                if c.grains == 0 {
                    continue;
                }
                let last = first + c.grains as usize - 1;
                let _ = writeln!(
                    s,
                    "group size{k} id {first}:{last}  # {} grains of {:e} m, {:.1} % of the mass",
                    c.grains,
                    c.diameter_m,
                    100.0 * c.mass_fraction
                );
                if let Some(gamma) = c.drag_gamma_kg_s {
                    let _ = writeln!(s, "fix drag{k} size{k} viscous {gamma:e}");
                }
                first = last + 1;
            }
        }
    }
    s
}

/// The diameter at which `settings.particles` grains of one size hold the model's fill mass
/// (fill area × the fill's depth × bulk density, in grains of the particle density): the
/// grain of a case that states none (`[dem] grain_diameter_m`).
pub fn fill_grain_diameter(scenario: &Scenario, fill_area_m2: f64, settings: &DemSettings) -> f64 {
    let m = &scenario.material;
    mass_matching_diameter(fill_area_m2, settings.particles, settings.depth_grains, m.bulk_density, m.particle.density)
}

/// The Earth rig (the validation design, 20 teeth) as a case of `particles` grains on a mesh
/// of `teeth`: the DEM modules' unit tests' fixture.
#[cfg(test)]
pub(crate) fn rig_case(particles: u32, teeth: u32, seed: u64) -> Case {
    let mut s = Scenario::earth();
    s.sim.teeth = 20;
    let settings = DemSettings { particles, teeth: Some(teeth), ..Default::default() };
    Case::build(&s, &Design::validation_rig(), &settings, seed, None).unwrap()
}

/// The settings with the mesh stated ([`mesh_teeth`]) where `[dem] teeth` leaves it unset:
/// what a new campaign's plan records, so that a later change of the rule cannot change the
/// mesh of runs already made. A design the model rejects is left as it is, for
/// [`Case::build`] to refuse by its rule.
pub fn with_stated_mesh(settings: &DemSettings, s: &Scenario, d: &Design) -> DemSettings {
    let mut out = settings.clone();
    if out.teeth.is_none() && check_representable(s).is_ok() {
        out.teeth = mesh_teeth(s, d).ok();
    }
    out
}

/// Teeth the mesh needs: the model's farthest resting grain on a conveyor long enough that
/// none of its grains leaves past the end ([`REACH_CONVEYOR_TEETH`]), plus a margin
/// ([`mesh_teeth_for_reach`]), so that neither side truncates (issue 42: a 20-tooth mesh cut
/// the lunar rig's flights short, and compared one truncation with another). `[dem] teeth`
/// states the mesh instead; `dem compare` judges the model on the DEM's mesh and warns where
/// either side loses grains past its end.
pub fn mesh_teeth(s: &Scenario, d: &Design) -> Result<u32, String> {
    Ok(mesh_teeth_for_reach(farthest_resting_tooth(s, d)?))
}

/// The tooth of the model's farthest resting particle on a long conveyor.
fn farthest_resting_tooth(s: &Scenario, d: &Design) -> Result<u32, String> {
    let engine = make_engine(EngineKind::Cpu).map_err(|e| e.to_string())?;
    let mut long = s.clone();
    long.sim.teeth = long.sim.teeth.max(REACH_CONVEYOR_TEETH);
    let det = evaluate_detailed(engine.as_ref(), &long, d, false)
        .map_err(|e| format!("invalid design ({}): {e}", e.rule()))?;
    Ok(det
        .particles
        .iter()
        .filter(|p| p.state != ParticleState::Lost)
        .map(|p| crate::model::outcome::end_tooth(&det.prepared.profile, p.end))
        .max()
        .unwrap_or(1))
}

/// The mesh for a model whose farthest resting grain is in tooth `far`: the reach plus a
/// margin of [`REACH_MARGIN_TEETH`] or [`REACH_MARGIN_SHARE`] of it, whichever is more.
fn mesh_teeth_for_reach(far: u32) -> u32 {
    let margin = REACH_MARGIN_TEETH.max((f64::from(far) * REACH_MARGIN_SHARE).ceil() as u32);
    far.saturating_add(margin).max(2 + REACH_MARGIN_TEETH).min(crate::schema::DEM_TEETH.max as u32)
}

/// The mesh of a case whose settings leave it unset: the rule plans were made with before
/// they stated the mesh (the reach plus [`REACH_MARGIN_TEETH`]), so that their runs read back.
fn unstated_mesh_teeth(far: u32) -> u32 {
    far.saturating_add(REACH_MARGIN_TEETH).max(2 + REACH_MARGIN_TEETH).min(crate::schema::DEM_TEETH.max as u32)
}

/// The box: the mesh over its whole motion, room behind tooth 0 and below the profile for
/// grains to fall out of, and above for the highest launch (speed 1.5 v0).
fn bounds(line: &[[f64; 2]], motion: &SledMotion, d: &Design, g: f64, depth: f64) -> [[f64; 2]; 3] {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in line {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let far = motion.displacement(motion.t_launch());
    let home = motion.displacement(f64::INFINITY);
    let (dx0, dx1) = (far[0].min(home[0]).min(0.0), far[0].max(home[0]).max(0.0));
    let (dy0, dy1) = (far[1].min(home[1]).min(0.0), far[1].max(home[1]).max(0.0));
    let margin = 2.0 * d.l_c;
    let apex = (1.5 * d.v0).powi(2) / (2.0 * g);
    [[x0 + dx0 - margin, x1 + dx1 + margin], [y0 + dy0 - margin, y1.max(d.l_b + apex) + dy1 + margin], [0.0, depth]]
}

/// Every `run` and `write_dump` in `script` is preceded by a check of the grain count since
/// the last run, and `gone` writes ALL_LOST after the normal end; the number of runs and
/// dumps (a panic naming the first unchecked one otherwise).
#[cfg(test)]
pub(super) fn runs_and_dumps_checked(script: &str) -> usize {
    let guard = "if \"${grains} == 0\" then \"jump SELF gone\"";
    let lines: Vec<&str> = script.lines().collect();
    let defined = lines.iter().position(|l| *l == "variable grains equal atoms").expect("the count is defined");
    let mut checked = true; // read_data's grains are all there
    let mut acts = 0;
    for (i, line) in lines.iter().enumerate() {
        if *line == guard {
            assert!(i > defined, "the count is checked before it is defined: {script}");
            checked = true;
        } else if line.starts_with("run ") || line.starts_with("write_dump ") {
            assert!(checked, "`{line}` may meet a case with no grains: {script}");
            acts += 1;
            if line.starts_with("run ") {
                checked = false;
            }
        }
    }
    let gone = lines.iter().position(|l| *l == "label gone").expect("a `gone` label");
    assert!(lines[gone..].iter().any(|l| l.contains(&format!("file {ALL_LOST}"))), "{script}");
    // the normal end jumps past it
    let finished = lines.iter().position(|l| *l == "jump SELF finished").unwrap();
    assert!(finished < gone && lines.last() == Some(&"label finished"), "{script}");
    acts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::{Polydisperse, SizeForm};

    fn rig() -> (Scenario, Design) {
        let mut s = Scenario::earth();
        s.sim.teeth = 20;
        (s, Design::validation_rig())
    }

    fn settings(particles: u32) -> DemSettings {
        DemSettings { particles, teeth: Some(8), ..Default::default() }
    }

    #[test]
    fn the_mesh_reaches_half_again_past_the_models_farthest_grain_and_at_least_three_teeth() {
        // draw 2's doe-04: the model rests within tooth 15; 18 teeth lost 2-2.5 % in the DEM
        assert_eq!(mesh_teeth_for_reach(15), 23);
        for far in [1, 2, 4, 6, 10, 15, 40] {
            let teeth = mesh_teeth_for_reach(far);
            assert!(teeth >= far + 3 && f64::from(teeth) >= 1.5 * f64::from(far), "reach {far}: {teeth}");
        }
        assert_eq!(mesh_teeth_for_reach(1), 5, "a short reach keeps room for a bounce");
        assert!(mesh_teeth_for_reach(u32::MAX / 4) <= crate::schema::DEM_TEETH.max as u32);
        // a new plan states it where `[dem] teeth` is unset; a plan that left it unset keeps
        // the mesh its runs were made on (the reach plus 3)
        let (s, d) = rig();
        let unset = DemSettings { particles: 60, teeth: None, ..Default::default() };
        let far = farthest_resting_tooth(&s, &d).unwrap();
        let stated = with_stated_mesh(&unset, &s, &d);
        assert_eq!(stated.teeth, Some(mesh_teeth_for_reach(far)), "the reach's mesh, not `sim.teeth`");
        assert_eq!(with_stated_mesh(&stated, &s, &d), stated);
        let set = DemSettings { teeth: Some(7), ..unset.clone() };
        assert_eq!(with_stated_mesh(&set, &s, &d).teeth, Some(7), "a stated mesh stays");
        assert_eq!(Case::build(&s, &d, &unset, 0, None).unwrap().teeth, (far + 3).max(5));
    }

    #[test]
    fn the_model_restitution_gives_the_dem_the_thesis_laws_cor_at_the_launch_speed() {
        let s = Scenario::lunar();
        let d = Design::lunar_solution_c();
        let plain = Case::build(&s, &d, &settings(60), 0, None).unwrap();
        assert_eq!(plain.contact.restitution, s.collision.k_elastic);
        let model = DemSettings { restitution: DemRestitution::Model, ..settings(60) };
        let case = Case::build(&s, &d, &model, 0, None).unwrap();
        // Eq. 4.9 at |v_n| = v0, above the limit velocity: k_el (v_limit / v0)^(1/4)
        let v_limit = crate::model::collision::limit_speed(&s.collision, &s.material);
        let expect = s.collision.k_elastic * (v_limit / d.v0).powf(0.25);
        assert!((case.contact.restitution - expect).abs() < 1e-12, "{} vs {expect}", case.contact.restitution);
        assert!(case
            .script()
            .contains(&format!("coefficientRestitution peratomtypepair 2 {0} {0} {0} {0}", case.contact.restitution)));
    }

    #[test]
    fn one_size_keeps_one_drag_on_every_grain() {
        let (s, d) = rig();
        let case = Case::build(&s, &d, &settings(60), 0, None).unwrap();
        assert_eq!(case.placement.classes.len(), 1);
        let script = case.script();
        let gamma = case.placement.grain_mass_kg * s.environment.k_drag.unwrap();
        assert!(script.contains(&format!("fix drag all viscous {gamma:e}")), "{script}");
        assert!(!script.contains("group size"));
    }

    #[test]
    fn a_size_law_becomes_classes_each_with_its_own_stokes_drag() {
        let (mut s, d) = rig();
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.3, form: SizeForm::Lognormal });
        let case = Case::build(&s, &d, &settings(150), 0, None).unwrap();
        let p = &case.placement;
        assert_eq!(p.classes.len(), crate::dem::sizes::SIZE_CLASSES);
        let n = p.grains.len() as f64;
        assert!((n / 150.0 - 1.0).abs() < 0.05, "{n} grains for 150");
        // the same fill mass as the model's over the slab of the mass-median size
        assert!((p.fill_fraction - 1.0).abs() < 0.03, "{}", p.fill_fraction);
        let script = case.script();
        let k = s.environment.k_drag.unwrap();
        let mut first = 1;
        for (i, c) in p.classes.iter().enumerate() {
            let last = first + c.grains as usize - 1;
            assert!(script.contains(&format!("group size{i} id {first}:{last} ")), "{script}");
            // γ = m k_drag (d_ref/d)²
            let m = crate::dem::sizes::grain_mass(c.diameter_m, case.contact.density_kg_m3);
            let gamma = m * k * (p.diameter_m / c.diameter_m).powi(2);
            let line = format!("fix drag{i} size{i} viscous {:e}", c.drag_gamma_kg_s.unwrap());
            assert!(script.contains(&line), "{script}");
            assert!((c.drag_gamma_kg_s.unwrap() / gamma - 1.0).abs() < 1e-12);
            first = last + 1;
        }
        assert!(!script.contains("fix drag all"));
        // each grain's diameter in the data file is its class's
        let data = case.data();
        let atoms: Vec<&str> = data.lines().skip_while(|l| *l != "Atoms").skip(2).collect();
        assert_eq!(atoms.len(), p.grains.len());
        let last_d: f64 = atoms.last().unwrap().split_whitespace().nth(2).unwrap().parse().unwrap();
        assert!((last_d / p.classes.last().unwrap().diameter_m - 1.0).abs() < 1e-8);
        // the smallest grain sets the step: shorter than the one-size case's
        let mono = Case::build(&rig().0, &d, &settings(150), 0, None).unwrap();
        assert!(case.contact.timestep_s < mono.contact.timestep_s);
    }

    /// A rig whose sled rests 5 s before it returns (the campaign rig) must not simulate
    /// those 5 s: the grains may rest before the return starts, and the run ends then.
    #[test]
    fn the_run_may_end_at_rest_before_a_late_return_but_never_while_the_mesh_moves() {
        let (s, d) = rig();
        let case = Case::build(&s, &d, &settings(60), 0, Some((5.0, 0.05))).unwrap();
        let (t0, t1) = case.motion.return_window().unwrap();
        let script = case.script();
        // the stroke's own run covers the launch only
        let stroke = format!(
            "# the stroke\nif \"${{grains}} == 0\" then \"jump SELF gone\"\nrun {}\n",
            case.steps(case.motion.t_launch())
        );
        assert!(script.contains(&stroke), "{script}");
        assert!(
            script.contains(&format!(
                "if \"${{vrms}} < 5e-3 && (${{t}} >= {t1:e} || ${{t}} < {t0:e})\" then \"jump SELF rested\""
            )),
            "{script}"
        );
        assert!(script.contains(&format!("print \"${{t}}\" file {STROKE_TIME} screen no")));
        // without a return, rest alone ends the run
        let still = Case::build(&s, &d, &settings(60), 0, None).unwrap().script();
        assert!(still.contains("if \"${vrms} < 5e-3\" then \"jump SELF rested\""), "{still}");
    }

    /// LIGGGHTS stops with an error on a run (or a dump) of a granular case with no grains
    /// left; the deck checks the count after every run, before the next run or dump, and
    /// stops at `gone` (ALL_LOST) instead.
    #[test]
    fn no_run_or_dump_follows_a_run_without_the_grain_count_checked() {
        let (s, d) = rig();
        let script = Case::build(&s, &d, &settings(60), 0, None).unwrap().script();
        assert_eq!(runs_and_dumps_checked(&script), 5, "settle, dump, stroke, rest, dump: {script}");
    }

    #[test]
    fn the_setup_does_not_switch_the_dems_size_law_on() {
        let (mut s, d) = rig();
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.3, form: SizeForm::Lognormal });
        let case = Case::build(&s, &d, &settings(150), 0, None).unwrap();
        let setup = crate::dem::gather::setup_toml(&case, None, "test").unwrap();
        assert!(!setup.contains("[effects"), "{setup}");
        assert!(setup.contains("polydisperse size law (sigma_ln 0.3"), "{setup}");
        let v: toml::Value = toml::from_str(&setup).unwrap();
        let smallest = crate::dem::sizes::grain_mass(case.placement.classes[0].diameter_m, case.contact.density_kg_m3);
        let res = v["measurement"]["scale_resolution_g"].as_float().unwrap();
        assert!((res / (smallest * 1e3) - 1.0).abs() < 1e-9);
        // a DEM run spills nothing between conveyor and scale: its lost grains are physics
        assert_eq!(v["measurement"]["handling_loss_max"].as_integer(), Some(0), "{setup}");
    }
}
