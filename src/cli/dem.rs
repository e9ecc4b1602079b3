//! `sawtooth dem`: LIGGGHTS cases of a design (write), campaigns of them (run), the model
//! beside a campaign (compare), and an optimisation's picks held against the DEM (check).
//! The work is in [`crate::dem`].

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::{Args, Subcommand};

use super::args::ScenarioArgs;
use crate::dem::campaign::{self, Plan};
use crate::dem::compare::{compare, compare_steady, shown_teeth, Comparison, ComparisonPlot, SteadyComparison};
use crate::dem::impact;
use crate::dem::{Case, DemSettings};
use crate::io::atomic::write_atomic;
use crate::io::config::ConfigFile;
use crate::io::run_dir::{Access, RunDir};
use crate::model::{Design, Scenario};

#[derive(Debug, Subcommand)]
pub enum DemCommand {
    /// Write a LIGGGHTS case of one design (run it with `cd DIR && liggghts -in in.sawtooth`).
    Write(WriteArgs),
    /// Write, run and gather R seeds of one design: tooth masses as measured data.
    Run(RunArgs),
    /// The model beside a DEM campaign: per tooth %, d_avg, lost, centre of mass, dispersion.
    Compare(CompareArgs),
    /// An optimisation's picks and front designs in DEM: d_avg, mass flow, W_spec, verdicts.
    Check(CheckArgs),
    /// A design of experiments: N designs drawn over the optimiser's space (space-filling,
    /// under its constraints, optionally the requirements), each run with S seeds, reported
    /// as a check (model beside DEM) with each design's campaign readable by `fit`.
    Doe(DoeArgs),
    /// Single grains of a case in LIGGGHTS beside the model's restitution law: normal COR,
    /// tangential ratio and spin per impact speed and angle; --law-out writes the DEM's law.
    Impact(ImpactArgs),
}

#[derive(Debug, Args)]
pub struct ImpactArgs {
    #[command(flatten)]
    pub case: CaseArgs,
    /// Impact speeds, m/s (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.02,0.3,1.0,1.5")]
    pub speeds: Vec<f64>,
    /// Impact angles from the surface normal, degrees (comma-separated; 0 = head-on).
    #[arg(long, value_delimiter = ',', default_value = "0,5,10,20,30,45,60,75")]
    pub angles: Vec<f64>,
    /// Also measure the DEM's restitution law for the model (k_t at each psi node) and write
    /// it as a `[collision]` table (`law = "dem"`) to this file.
    #[arg(long)]
    pub law_out: Option<PathBuf>,
    /// LIGGGHTS processes at a time [default: the cores].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Where the impacts' folders, impact.json and the figure go.
    #[arg(long)]
    pub out: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// What a case is built from: the scenario as `simulate` takes it, a design, and the DEM's
/// own settings (`[dem]` in the config; the flags override). `--particles` is the DEM's grain
/// count here (the model keeps the config's particle count).
#[derive(Debug, Args)]
#[command(mut_arg("particles", |a| a.help(dem_particles_help(true)).value_parser(super::args::count::<u32>(&crate::schema::DEM_PARTICLES))))]
pub struct CaseArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Design `l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a` in mm,mm,mm,mm,deg,deg,m/s,m/s^2.
    #[arg(long, allow_hyphen_values = true)]
    pub design: Option<String>,
    /// Grain diameter in micrometres [default: [dem] grain_diameter_m, else the diameter at
    /// which --particles grains hold the model's fill mass].
    #[arg(long, allow_negative_numbers = true)]
    pub grain_diameter_um: Option<f64>,
}

/// `--particles` of a DEM command: the grains of the case, with the DEM's own default
/// (`config`: the command reads a --config file, whose `[dem] particles` comes first).
fn dem_particles_help(config: bool) -> String {
    let default = DemSettings::default().particles;
    let default =
        if config { format!("the --config file's [dem] particles, else {default}") } else { default.to_string() };
    format!("DEM grains per run (LIGGGHTS particles in tooth 0's fill) [default: {default}]")
}

#[derive(Debug, Args)]
pub struct WriteArgs {
    #[command(flatten)]
    pub case: CaseArgs,
    /// The case folder (created; refused if it holds anything else).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub case: CaseArgs,
    /// Runs, seeds --seed, --seed + 1, ...
    #[arg(long, default_value_t = 3, value_parser = super::args::count::<u32>(&crate::schema::DEM_RUNS))]
    pub runs: u32,
    /// LIGGGHTS processes at a time [default: the cores].
    #[arg(long, value_parser = super::args::count::<usize>(&crate::schema::JOBS))]
    pub jobs: Option<usize>,
    /// Steady conveying: each run is K cycles of the sled (stroke, stop, rest, return at the
    /// downstroke speed, rest) on a periodic conveyor of full teeth, and reports the advance
    /// per stroke once steady, beside the model's d_avg and feed rate (K >= 3; the first
    /// stroke is a transient) [default: one stroke from a full tooth onto bare teeth].
    #[arg(long)]
    pub strokes: Option<u32>,
    /// Teeth of the periodic conveyor of --strokes, each with a full fill.
    #[arg(long, default_value_t = 3)]
    pub period_teeth: u32,
    /// Convergence: after the campaign, run its seeds again at half the allowed overlap and at
    /// twice the grains (each a campaign in DIR/refine-*), and repeat from both at once for up
    /// to this many levels until neither moves d_avg by more than max(3 %, 2 seed spreads);
    /// the levels and the verdict go to DIR/refine.json [default without a value: 1].
    #[arg(long, num_args = 0..=1, default_missing_value = "1")]
    pub refine: Option<u32>,
    /// The campaign folder; the same command into it again resumes a killed campaign.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// A `dem run` campaign folder.
    pub dir: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// An `optimize` run folder (run.toml, pareto.csv).
    pub run_dir: PathBuf,
    /// The physics the DEM runs: a config TOML (`env`, [material], [collision], [environment],
    /// [dem]) whose scenario replaces the run's, each design at its front slope. Check a run
    /// optimised on a corrected model (`optimize --config lunar-corrected.toml`) against the
    /// physics it was corrected to, e.g. a file holding `env = "lunar"` [default: the run's own].
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Front designs checked besides the picks A, B, C, spread over the front's mass flow.
    #[arg(long, default_value_t = 2, value_parser = super::args::count::<usize>(&crate::schema::DEM_FRONT))]
    pub front: usize,
    /// DEM seeds per design.
    #[arg(long, default_value_t = 3, value_parser = super::args::count::<u32>(&crate::schema::DEM_SEEDS))]
    pub seeds: u32,
    #[arg(long, help = dem_particles_help(false), value_parser = super::args::count::<u32>(&crate::schema::DEM_PARTICLES))]
    pub particles: Option<u32>,
    /// LIGGGHTS processes at a time [default: the cores].
    #[arg(long, value_parser = super::args::count::<usize>(&crate::schema::JOBS))]
    pub jobs: Option<usize>,
    /// Where the campaigns and check.json go.
    #[arg(long)]
    pub out: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Only write the plan (DIR/plan.json: one member per design and seed) and stop: run
    /// its members with `sawtooth campaign run DIR --task I` or as a Slurm job array
    /// (`sawtooth campaign slurm DIR`), then `sawtooth campaign gather DIR` writes check.json.
    #[arg(long)]
    pub plan: bool,
}

#[derive(Debug, Args)]
#[command(mut_arg("particles", |a| a.help(dem_particles_help(true)).value_parser(super::args::count::<u32>(&crate::schema::DEM_PARTICLES))))]
pub struct DoeArgs {
    /// The scenario the designs are drawn and run in (`--env`, `--config`, `--alpha`, …);
    /// `--particles` is the DEM's grain count, the model keeps the config's.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Designs to draw.
    #[arg(long, default_value_t = 6, value_parser = super::args::count::<usize>(&crate::schema::DEM_DESIGNS))]
    pub designs: usize,
    /// DEM seeds per design (seeds 0, 1, …).
    #[arg(long, default_value_t = 2, value_parser = super::args::count::<u32>(&crate::schema::DEM_SEEDS))]
    pub seeds: u32,
    /// The draw's seed: the same seed draws the same designs.
    #[arg(long, default_value_t = 1)]
    pub draw_seed: u64,
    /// Only designs whose DEM grains are at least this wide, mm: the DEM's time step scales
    /// with the grain, and a fill too small for the grain count costs hours a run [default:
    /// 3 mm at 150 grains, 3·√(150/N) mm at N (1.5 mm at 600): a rule on the fill's size, the
    /// same designs at any count].
    #[arg(long, allow_negative_numbers = true)]
    pub min_grain_mm: Option<f64>,
    /// The grain count --min-grain-mm is judged at [default: --particles]: a draw remade at
    /// more grains (a convergence check) keeps the designs it was drawn with at fewer, e.g.
    /// `--particles 300 --draw-particles 150`.
    #[arg(long, value_parser = super::args::count::<u32>(&crate::schema::DEM_PARTICLES))]
    pub draw_particles: Option<u32>,
    /// Only designs whose model d_avg is at most this, mm: a long flight needs a long mesh and
    /// a long run (the lunar pick B's 2 m take hours a run) [default: any].
    #[arg(long, allow_negative_numbers = true)]
    pub max_d_avg_mm: Option<f64>,
    /// Only designs the model says meet these at the scenario's slope: `table-2.2` or a TOML
    /// file with a [requirements] table [default: none, the whole feasible space].
    #[arg(long, value_name = "table-2.2|FILE")]
    pub requirements: Option<String>,
    /// LIGGGHTS processes at a time [default: the cores].
    #[arg(long, value_parser = super::args::count::<usize>(&crate::schema::JOBS))]
    pub jobs: Option<usize>,
    /// Where the plan, the designs' campaigns and check.json go.
    #[arg(long)]
    pub out: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Only write the plan and stop (run it as a `dem check --plan`'s: `campaign run DIR
    /// --task I`, `campaign slurm DIR`, `campaign gather DIR`).
    #[arg(long)]
    pub plan: bool,
}

pub fn run(c: DemCommand, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    match c {
        DemCommand::Write(a) => write(a, out),
        DemCommand::Run(a) => run_campaign(a, out),
        DemCommand::Compare(a) => compare_cmd(a, out),
        DemCommand::Check(a) => check(a, out),
        DemCommand::Doe(a) => doe(a, out),
        DemCommand::Impact(a) => impact_cmd(a, out),
    }
}

fn impact_cmd(a: ImpactArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let jobs = jobs(a.jobs)?;
    for &v in &a.speeds {
        if !(v.is_finite() && (1e-3..=20.0).contains(&v)) {
            bail!("--speeds: each impact speed must lie in [0.001, 20] m/s, got {v}");
        }
    }
    for &d in &a.angles {
        if !(d.is_finite() && (0.0..=89.0).contains(&d)) {
            bail!("--angles: each angle from the normal must lie in [0, 89] deg, got {d}");
        }
    }
    if a.speeds.len() * a.angles.len() > 400 {
        bail!("--speeds x --angles: at most 400 impacts, got {}", a.speeds.len() * a.angles.len());
    }
    let (scenario, design, settings, known) = resolve(&a.case)?;
    let case = Case::build(&scenario, &design, &settings, scenario.sim.seed, known).map_err(anyhow::Error::msg)?;
    let binary = crate::dem::run::find_liggghts()?;
    let _owned = RunDir::acquire(&a.out, "dem-impact", Access::Exclusive).context("--out")?;
    let impacts = impact::measure(&case, &binary, &a.out, &a.speeds, &a.angles, jobs)?;
    let json = serde_json::to_string_pretty(&impacts)?;
    write_atomic(&a.out.join("impact.json"), json.as_bytes())?;
    crate::plot::write_figure_files(&a.out, "impact", &impact::ImpactPlot::new(&impacts, &case))?;
    let law = match &a.law_out {
        Some(path) => {
            let law = impact::measure_law(&case, &binary, &a.out.join("law"), jobs)?;
            write_atomic(path, impact::law_toml(&law, &case).as_bytes())
                .with_context(|| format!("--law-out {}", path.display()))?;
            Some(law)
        }
        None => None,
    };
    if a.json {
        writeln!(out, "{json}")?;
        return Ok(ExitCode::SUCCESS);
    }
    writeln!(out, "speed m/s  angle deg    psi   DEM k_n  model k_n   DEM k_t  model k_t  DEM spin")?;
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
    for i in &impacts {
        writeln!(
            out,
            "{:>9.3} {:>10.1} {:>6.2} {:>9.3} {:>10.3} {:>9} {:>10} {:>9}",
            i.speed_m_s,
            i.angle_deg,
            i.psi,
            i.dem_normal_cor,
            i.model_normal_cor,
            opt(i.dem_tangential_ratio),
            opt(i.model_tangential_ratio),
            opt(i.dem_spin_ratio)
        )?;
    }
    if let (Some(law), Some(path)) = (law, &a.law_out) {
        writeln!(
            out,
            "\nthe DEM's law (k_t at psi {:?}): {:?}\nwrote {}",
            crate::model::collision::TANGENTIAL_PSI,
            law.tangential_ratio.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>(),
            path.display()
        )?;
    }
    writeln!(out, "wrote {0}/impact.json, {0}/impact.svg, {0}/impact.png", a.out.display())?;
    Ok(ExitCode::SUCCESS)
}

/// A setup's stated sled return: delay (s), speed (m/s).
type KnownReturn = Option<(f64, f64)>;

/// The config file (not a run folder's manifest, which has no `[dem]`) and the DEM settings:
/// its `[dem]` table over the defaults, `--particles` over that; not yet validated (the
/// caller adds its own flags first).
fn dem_settings(
    config: Option<&Path>,
    particles: Option<u32>,
    grain_diameter_um: Option<f64>,
) -> anyhow::Result<(Option<ConfigFile>, DemSettings)> {
    let file = match config {
        Some(p) if crate::optim::manifest::manifest_in(p)?.is_none() => Some(ConfigFile::load(p)?),
        _ => None,
    };
    let mut settings = DemSettings::from_table(file.as_ref().and_then(|f| f.dem.as_ref()));
    if let Some(n) = particles {
        // a stated grain belongs to the config's count: another count of that grain would not
        // carry the model's fill mass (a campaign's setup.toml states both)
        if let (Some(d), true, None) = (settings.grain_diameter_m, n != settings.particles, grain_diameter_um) {
            bail!(
                "--particles {n} differs from the config's [dem] particles {}, for which its [dem] grain_diameter_m \
                 ({:.3} mm) was chosen: {n} grains of that size would not carry the model's fill mass; remove \
                 grain_diameter_m from the config (the diameter then follows the count) or state the grain with \
                 --grain-diameter-um",
                settings.particles,
                d * 1e3
            );
        }
        settings.particles = n;
    }
    if let Some(um) = grain_diameter_um {
        settings.grain_diameter_m = Some(um * 1e-6);
    }
    Ok((file, settings))
}

/// Scenario, design, settings and a stated sled return from the flags and the config.
fn resolve(a: &CaseArgs) -> anyhow::Result<(Scenario, Design, DemSettings, KnownReturn)> {
    // --particles is the DEM's grain count here; the model keeps the config's particle count
    let mut scenario_args = a.scenario.clone();
    let grains = scenario_args.particles.take();
    let (scenario, file_design) = scenario_args.resolve()?;
    let design = match (&a.design, file_design) {
        (Some(s), _) => Design::parse_cli(s).map_err(|e| anyhow::anyhow!("--design: {e}"))?,
        (None, Some(d)) => d,
        (None, None) => {
            bail!("no design: pass --design l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a or a config file with [design]")
        }
    };
    let (file, settings) = dem_settings(a.scenario.config.as_deref(), grains, a.grain_diameter_um)?;
    settings.validate().map_err(|e| {
        anyhow::anyhow!(e.replace("[dem] grain_diameter_m", "--grain-diameter-um / [dem] grain_diameter_m"))
    })?;
    // a new case states its mesh (the plan records it), so a later rule cannot move it
    let settings = crate::dem::case::with_stated_mesh(&settings, &scenario, &design);
    let known = file
        .as_ref()
        .and_then(|f| f.measurement.as_ref())
        .and_then(|m| Some((m.motion_delay_s?, m.motion_return_speed_m_s?)));
    Ok((scenario, design, settings, known))
}

fn write(a: WriteArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let (scenario, design, settings, known) = resolve(&a.case)?;
    let case = Case::build(&scenario, &design, &settings, scenario.sim.seed, known).map_err(anyhow::Error::msg)?;
    let _owned = RunDir::acquire(&a.out, "dem-case", Access::Exclusive).context("--out")?;
    case.write(&a.out)?;
    let p = &case.placement;
    writeln!(
        out,
        "wrote {dir}/{} ({} facets), {dir}/{} ({} grains of {:.1} um, {:.1} % of the model's fill mass over a {:.3} mm slab), {dir}/{}, {dir}/{}",
        crate::dem::case::MESH,
        case.facets,
        crate::dem::case::GRAINS,
        p.grains.len(),
        p.diameter_m * 1e6,
        100.0 * p.fill_fraction,
        p.depth_m * 1e3,
        crate::dem::case::MANIFEST,
        crate::dem::case::SCRIPT,
        dir = a.out.display()
    )?;
    writeln!(
        out,
        "{} teeth; Young's moduli softened x{:.2e} (grain {:.3e} Pa, conveyor {:.3e} Pa: peak overlap {:.1} % of the radius at {:.2} m/s); time step {:.3e} s\nrun it: cd {} && liggghts -in {}",
        case.teeth,
        case.contact.softening,
        case.contact.grain_youngs_pa,
        case.contact.wall_youngs_pa,
        100.0 * case.contact.overlap_fraction,
        case.contact.design_speed_m_s,
        case.contact.timestep_s,
        a.out.display(),
        crate::dem::case::SCRIPT
    )?;
    Ok(ExitCode::SUCCESS)
}

/// `--jobs` (bounded by its parser), else the cores.
fn jobs(j: Option<usize>) -> anyhow::Result<usize> {
    Ok(j.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())))
}

fn run_campaign(a: RunArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let jobs = jobs(a.jobs)?;
    let (scenario, design, settings, known) = resolve(&a.case)?;
    if a.strokes.is_some() && a.refine.is_some() {
        bail!("--refine refines single strokes (d_avg); refine a steady campaign by running it again with another [dem] max_overlap_fraction and --particles");
    }
    if let Some(k) = a.strokes {
        if !(3..=200).contains(&k) {
            bail!("--strokes must lie in [3, 200] (the first stroke is a transient), got {k}");
        }
        if !(2..=64).contains(&a.period_teeth) {
            bail!("--period-teeth must lie in [2, 64], got {}", a.period_teeth);
        }
    }
    let plan = Plan {
        first_seed: scenario.sim.seed,
        scenario,
        design,
        settings,
        runs: a.runs,
        known_return: known,
        strokes: a.strokes.unwrap_or(0),
        period_teeth: if a.strokes.is_some() { a.period_teeth } else { 0 },
    };
    // the case must build before the folder is taken
    plan.case(0).map_err(anyhow::Error::msg)?;
    if plan.is_steady() {
        plan.conveyor(0).map_err(anyhow::Error::msg)?;
        let _owned = RunDir::acquire(&a.out, campaign::KIND, Access::Exclusive).context("--out")?;
        let plan = campaign::recorded_or(&a.out, &plan)?;
        let runs = campaign::run_steady(&a.out, &plan, jobs, &|line| eprintln!("dem: {line}"))?;
        let report = steady_report(&plan, &runs)?;
        write_atomic(&a.out.join("steady.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
        write_steady(out, &report)?;
        return Ok(ExitCode::SUCCESS);
    }
    let _owned = RunDir::acquire(&a.out, campaign::KIND, Access::Exclusive).context("--out")?;
    // a campaign already there goes on with the plan its runs were made on
    let plan = campaign::recorded_or(&a.out, &plan)?;
    if let Some(levels) = a.refine {
        if !(1..=crate::dem::refine::MAX_LEVELS as u32).contains(&levels) {
            bail!("--refine must lie in [1, {}] levels, got {levels}", crate::dem::refine::MAX_LEVELS);
        }
        if a.runs < 2 {
            bail!("--refine needs --runs >= 2: a refinement is judged against the seeds' spread");
        }
    }
    let results = campaign::run(&a.out, &plan, jobs, &|line| eprintln!("dem: {line}"))?;
    let mut c = compare(&plan.scenario, &plan.design, &results, campaign::law(&a.out)?.as_ref())?;
    if a.refine.is_none() {
        // with --refine the ladder follows the table
        c.attach_numerics(crate::dem::refine::read_refinement(&a.out)?.as_ref());
    }
    write_table(out, &c)?;
    writeln!(
        out,
        "\nwrote {0}/{1} and {0}/{2}; `sawtooth dem compare {0}` draws the comparison",
        a.out.display(),
        campaign::CSV,
        campaign::SETUP
    )?;
    if let Some(levels) = a.refine {
        let r = crate::dem::refine::refine(&a.out, &plan, &results, levels, jobs, &|line| eprintln!("dem: {line}"))?;
        writeln!(out, "\nconvergence (half the overlap, twice the grains; allowed: max(3 %, 2 seed spreads)):")?;
        for (i, l) in r.levels.iter().enumerate() {
            writeln!(
                out,
                "level {}: overlap {} x {} grains: d_avg {:.2} ± {:.2} mm; half the overlap {:+.2} mm, twice the grains {:+.2} mm (allowed {:.2}): {}",
                i + 1,
                l.base.max_overlap_fraction,
                l.base.particles,
                l.base.d_avg_mm,
                l.base.d_avg_sd_mm,
                l.overlap_move_mm,
                l.grains_move_mm,
                l.allowed_mm,
                if l.converged { "converged" } else { "not converged" }
            )?;
        }
        writeln!(out, "wrote {}/{}", a.out.display(), crate::dem::refine::REFINE)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The plan of a steady campaign in `dir`, or None for a single-stroke one.
fn steady_plan(dir: &Path) -> anyhow::Result<Option<Plan>> {
    let path = dir.join(campaign::PLAN);
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    // checked by every rule of a plan, as every plan read back is
    let (plan, _) = campaign::read_plan(dir)?;
    Ok(plan.is_steady().then_some(plan))
}

/// Read a campaign folder back: its plan and every run's result.
fn load_campaign(dir: &Path) -> anyhow::Result<(Plan, Vec<crate::dem::gather::RunResult>)> {
    if std::fs::symlink_metadata(dir.join(campaign::PLAN)).is_err() {
        bail!("{} is not a `sawtooth dem run` campaign (no {})", dir.display(), campaign::PLAN);
    }
    let (plan, first) = campaign::read_plan(dir)?;
    let results = campaign::results(dir, &plan, &first)?;
    let missing = results.iter().filter(|r| r.is_none()).count();
    if missing > 0 {
        bail!(
            "{}: {missing} of {} runs have no result yet; run the same `sawtooth dem run` command again to finish the campaign",
            dir.display(),
            plan.runs
        );
    }
    Ok((plan, results.into_iter().flatten().collect()))
}

fn compare_cmd(a: CompareArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    if let Some(plan) = steady_plan(&a.dir)? {
        let found = campaign::steady_results(&a.dir, plan.runs)?;
        let missing = found.iter().filter(|r| r.is_none()).count();
        if missing > 0 {
            bail!(
                "{}: {missing} of {} runs have no result yet; run the same `sawtooth dem run` command again to finish the campaign",
                a.dir.display(),
                plan.runs
            );
        }
        let runs: Vec<_> = found.into_iter().flatten().collect();
        let report = steady_report(&plan, &runs)?;
        let _owned = RunDir::acquire(&a.dir, "dem", Access::Exclusive).context("DIR")?;
        let json = serde_json::to_string_pretty(&report)?;
        write_atomic(&a.dir.join("steady.json"), json.as_bytes())?;
        if a.json {
            writeln!(out, "{json}")?;
        } else {
            write_steady(out, &report)?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    let (plan, results) = load_campaign(&a.dir)?;
    let mut c = compare(&plan.scenario, &plan.design, &results, campaign::law(&a.dir)?.as_ref())?;
    c.attach_numerics(crate::dem::refine::read_refinement(&a.dir)?.as_ref());
    let _owned = RunDir::acquire(&a.dir, campaign::KIND, Access::Exclusive).context("DIR")?;
    let json = serde_json::to_string_pretty(&c)?;
    write_atomic(&a.dir.join("compare.json"), json.as_bytes())?;
    let figure = ComparisonPlot::new(&c, &plan.scenario, &plan.design, results.len());
    crate::plot::write_figure_files(&a.dir, "compare", &figure)?;
    if a.json {
        writeln!(out, "{json}")?;
    } else {
        write_table(out, &c)?;
        writeln!(out, "\nwrote {0}/compare.json, {0}/compare.svg, {0}/compare.png", a.dir.display())?;
    }
    Ok(ExitCode::SUCCESS)
}

fn steady_report(plan: &Plan, runs: &[crate::dem::conveyor::SteadyRun]) -> anyhow::Result<SteadyComparison> {
    compare_steady(&plan.scenario, &plan.design, runs)
}

fn write_steady(out: &mut dyn Write, c: &SteadyComparison) -> anyhow::Result<()> {
    let d = &c.dem;
    writeln!(
        out,
        "steady conveying: {} runs of {} strokes on a periodic conveyor of {} full teeth",
        c.runs, c.strokes, c.period_teeth
    )?;
    writeln!(
        out,
        "advance per stroke along the conveyor: DEM {:.1} ± {:.1} mm (steady, strokes 2-{}; first half {:.1}, second half {:.1}; first stroke {:.1}), model {:.1} mm{}",
        d.advance_m * 1e3,
        d.advance_sd_m * 1e3,
        c.strokes,
        d.first_half_m * 1e3,
        d.second_half_m * 1e3,
        d.first_stroke_m * 1e3,
        c.model_advance_mm,
        c.advance_error_pct.map_or(String::new(), |e| format!(" ({e:+.1} %)"))
    )?;
    writeln!(
        out,
        "feed rate at {:.4} Hz (Eq. 5.16): DEM {:.1} ± {:.1} kg/h; model {:.1} kg/h with its d_avg {:.1} mm (D.7), {:.1} kg/h with its advance",
        c.f_stroke_hz,
        c.dem_m_dot_kg_h,
        c.dem_m_dot_sd_kg_h,
        c.model_m_dot_kg_h,
        c.model_d_avg_mm,
        c.model_m_dot_advance_kg_h
    )?;
    let per_run: Vec<String> = c.dem_per_run_mm.iter().map(|x| format!("{x:.1}")).collect();
    writeln!(
        out,
        "DEM runs' steady advance: {} mm; {:.0} ± {:.0} s per run",
        per_run.join(", "),
        c.dem_s.mean,
        c.dem_s.sd
    )?;
    if let Some(b) = &c.dem_left_by {
        writeln!(out, "DEM grains out of the box, over the runs: {}", b.describe())?;
    }
    for w in &c.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}

fn write_table(out: &mut dyn Write, c: &Comparison) -> anyhow::Result<()> {
    writeln!(out, "tooth   model %   DEM % (mean ± sd over {} seeds)", c.runs)?;
    for j in 0..shown_teeth(c) {
        writeln!(out, "{:>5} {:>9.2} {:>9.2} ± {:.2}", j + 1, c.model_pct[j], c.dem_pct[j].mean, c.dem_pct[j].sd)?;
    }
    writeln!(out, " lost {:>9.2} {:>9.2} ± {:.2}", c.model_lost_pct, c.dem_lost_pct.mean, c.dem_lost_pct.sd)?;
    if let Some(b) = &c.dem_left_by {
        writeln!(out, "DEM grains out of the box, over the runs: {}", b.describe())?;
    }
    writeln!(
        out,
        "per-tooth |model - DEM|: mean {:.2} pp, max {:.2} pp",
        c.mean_abs_tooth_error_pp, c.max_abs_tooth_error_pp
    )?;
    writeln!(
        out,
        "d_avg: model {:.2} mm, DEM {:.2} ± {:.2} mm{}{}",
        c.model_d_avg_mm,
        c.dem_d_avg_mm.mean,
        c.dem_d_avg_mm.sd,
        c.numerics_error_mm.map_or(String::new(), |e| format!(" (numerics ± {e:.2} mm, refine.json)")),
        c.d_avg_error_pct.map_or(String::new(), |e| format!(" ({e:+.1} %)"))
    )?;
    writeln!(
        out,
        "centre of mass (tooth): model {:.2}, DEM {:.2} ± {:.2}; dispersion: model {:.2}, DEM {:.2} ± {:.2}{}",
        c.model_centre,
        c.dem_centre.mean,
        c.dem_centre.sd,
        c.model_dispersion,
        c.dem_dispersion.mean,
        c.dem_dispersion.sd,
        if c.dem_centre.mean.is_nan() { " (no DEM run kept a grain on the teeth)" } else { "" }
    )?;
    writeln!(
        out,
        "model variants (d_avg): on a {}-tooth conveyor {:.2} mm{}{}",
        crate::dem::case::REACH_CONVEYOR_TEETH,
        c.model_untruncated_d_avg_mm,
        c.model_from_bed_d_avg_mm.map_or(String::new(), |d| format!("; from the DEM's settled bed {d:.2} mm")),
        c.model_dem_law_d_avg_mm.map_or(String::new(), |d| format!("; with the DEM's restitution law {d:.2} mm"))
    )?;
    writeln!(
        out,
        "past the mesh's last tooth: model {:.2} %, DEM {:.2} ± {:.2} %",
        c.model_past_end_pct, c.dem_past_end_pct.mean, c.dem_past_end_pct.sd
    )?;
    writeln!(
        out,
        "cost per design: model {:.4} s ({} particles, cpu), DEM {:.1} ± {:.1} s per run",
        c.model_s, c.model_particles, c.dem_s.mean, c.dem_s.sd
    )?;
    for w in &c.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}

fn check(a: CheckArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let jobs = jobs(a.jobs)?;
    let (physics, table) = match &a.config {
        Some(path) => {
            let file = ConfigFile::load(path).context("--config")?;
            let scenario = file.scenario().with_context(|| format!("--config {}", path.display()))?;
            (Some(scenario), file.dem)
        }
        None => (None, None),
    };
    let mut settings = DemSettings::from_table(table.as_ref());
    if let Some(n) = a.particles {
        settings.particles = n;
    }
    settings.validate().map_err(anyhow::Error::msg)?;
    let command = format!(
        "sawtooth dem check {}{} --seeds {} --front {} --particles {} --out {}",
        a.run_dir.display(),
        a.config.as_ref().map_or(String::new(), |c| format!(" --config {}", c.display())),
        a.seeds,
        a.front,
        settings.particles,
        a.out.display()
    );
    let plan = crate::dem::check::plan(&a.run_dir, physics.as_ref(), &settings, a.seeds, a.front, &command)?;
    if a.plan {
        return plan_only(
            &plan,
            &a.out,
            &format!("sawtooth dem check {} --out {} (the same flags)", a.run_dir.display(), a.out.display()),
            out,
        );
    }
    let report = crate::dem::check::check(&a.out, &plan, jobs, &|l| eprintln!("dem check: {l}"))?;
    report_check(&report, &a.out, a.json, out)
}

/// Write a check's plan (`--plan`) and say how to run its members.
fn plan_only(
    plan: &crate::dem::check::CheckPlan,
    root: &Path,
    all_here: &str,
    out: &mut dyn Write,
) -> anyhow::Result<ExitCode> {
    let (_owned, plan) = crate::dem::check::write_plan(root, plan)?;
    let n = plan.members();
    let dir = root.display();
    writeln!(
        out,
        "wrote {dir}/{} ({} designs x {} seeds = {n} members, one DEM run each); nothing run yet",
        crate::dem::check::CHECK_PLAN,
        plan.finalists.len(),
        plan.seeds
    )?;
    writeln!(out, "  one member:      sawtooth campaign run {dir} --task I   (I in 0..{})", n - 1)?;
    writeln!(out, "  all, here:       {all_here}")?;
    writeln!(out, "  Slurm job array: sawtooth campaign slurm {dir} [--partition P --time T] --submit")?;
    writeln!(out, "  then:            sawtooth campaign gather {dir}   (writes {dir}/check.json)")?;
    Ok(ExitCode::SUCCESS)
}

/// `dem doe`'s grain floor when --min-grain-mm is not given: 3 mm at 150 grains (the draws of
/// docs/design-on-the-evidence.md), scaled as the fill's mass-matching diameter scales
/// (d ∝ N^(-1/2), `dem::grains::mass_matching_diameter`), so the floor is a floor on the
/// fill's size and a draw keeps its designs at any grain count.
fn default_min_grain_mm(draw_particles: u32) -> f64 {
    3.0 * (150.0 / f64::from(draw_particles)).sqrt()
}

fn doe(a: DoeArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let jobs = jobs(a.jobs)?;
    if let Some(m) = a.min_grain_mm.filter(|m| !(m.is_finite() && (0.0..=50.0).contains(m))) {
        bail!("--min-grain-mm must lie in [0, 50] mm, got {m}");
    }
    if let Some(m) = a.max_d_avg_mm.filter(|m| !(m.is_finite() && *m > 0.0)) {
        bail!("--max-d-avg-mm must be a length > 0 mm, got {m}");
    }
    let mut scenario_args = a.scenario.clone();
    let grains = scenario_args.particles.take();
    let (scenario, _) = scenario_args.resolve()?;
    let (_, settings) = dem_settings(a.scenario.config.as_deref(), grains, None)?;
    settings.validate().map_err(anyhow::Error::msg)?;
    let min_grain_mm =
        a.min_grain_mm.unwrap_or_else(|| default_min_grain_mm(a.draw_particles.unwrap_or(settings.particles)));
    let requirements = match &a.requirements {
        Some(spec) => Some(crate::io::config::load_requirements(spec).context("--requirements")?),
        None => None,
    };
    let request = crate::dem::doe::DoeRequest {
        designs: a.designs,
        seeds: a.seeds,
        draw_seed: a.draw_seed,
        min_grain_m: min_grain_mm * 1e-3,
        draw_particles: a.draw_particles,
        max_d_avg_m: a.max_d_avg_mm.map(|m| m * 1e-3),
        requirements,
    };
    let command = format!(
        "sawtooth dem doe {}--designs {} --seeds {} --draw-seed {} --min-grain-mm {}{}{} --particles {}{} --out {}",
        a.scenario.config.as_ref().map_or(String::new(), |c| format!("--config {} ", c.display())),
        a.designs,
        a.seeds,
        a.draw_seed,
        min_grain_mm,
        a.draw_particles.map_or(String::new(), |n| format!(" --draw-particles {n}")),
        a.max_d_avg_mm.map_or(String::new(), |m| format!(" --max-d-avg-mm {m}")),
        settings.particles,
        a.requirements.as_ref().map_or(String::new(), |r| format!(" --requirements {r}")),
        a.out.display()
    );
    let engine = crate::engine::make_engine_for(crate::engine::EngineKind::Cpu, &scenario)?;
    let (plan, tally) = crate::dem::doe::plan(engine.as_ref(), &scenario, &settings, &request, &command)?;
    eprintln!(
        "dem doe: {} of {} designs drawn in the pool ({} outside the geometric constraints, {} rejected by the model, {} without a mass flow, {} needing grains under {} mm, {} flying too far, {} failing the requirements)",
        tally.pool,
        tally.drawn,
        tally.geometry,
        tally.rejected_by_model,
        tally.no_mass_flow,
        tally.grains_too_small,
        min_grain_mm,
        tally.flight_too_long,
        tally.requirements
    );
    for f in &plan.finalists {
        eprintln!(
            "dem doe: {} --design {} (model d_avg {:.1} mm, {:.1} kg/h)",
            f.label,
            crate::model::design::DesignRow::of(&f.campaign.design).cli_argument(),
            f.model_d_avg_m * 1e3,
            f.model_m_dot_kg_s * 3600.0
        );
    }
    if a.plan {
        return plan_only(&plan, &a.out, "the same `sawtooth dem doe` without --plan", out);
    }
    let report = crate::dem::check::check(&a.out, &plan, jobs, &|l| eprintln!("dem doe: {l}"))?;
    report_check(&report, &a.out, a.json, out)
}

fn report_check(
    report: &crate::dem::check::CheckReport,
    dir: &Path,
    json: bool,
    out: &mut dyn Write,
) -> anyhow::Result<ExitCode> {
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(report)?)?;
    } else {
        crate::dem::check::write_summary(out, report, dir)?;
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::default_min_grain_mm;
    use crate::dem::grains::mass_matching_diameter;

    /// The default floor passes the same fills at any grain count: a fill whose 150 grains are
    /// at least 3 mm wide has grains at least the floor wide at 600 or 1 200, and one whose
    /// 150 grains are narrower has not.
    #[test]
    fn the_default_grain_floor_is_a_floor_on_the_fills_size() {
        assert_eq!(default_min_grain_mm(150), 3.0);
        assert!((default_min_grain_mm(600) - 1.5).abs() < 1e-12);
        let d = |area: f64, n: u32| mass_matching_diameter(area, n, 4.0, 890.0, 2850.0) * 1e3;
        for area in [2e-4, 5e-4, 8e-4, 1.2e-3, 3e-3] {
            let passes_at_150 = d(area, 150) >= default_min_grain_mm(150);
            for n in [300, 600, 1200] {
                assert_eq!(d(area, n) >= default_min_grain_mm(n) - 1e-12, passes_at_150, "{area} m2 at {n} grains");
            }
        }
        assert!(d(2e-4, 150) < 3.0 && d(3e-3, 150) > 3.0, "the areas straddle the floor");
    }
}
