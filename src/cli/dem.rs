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
use crate::dem::compare::{compare, shown_teeth, Comparison, ComparisonPlot};
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

pub fn run(c: DemCommand, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    match c {
        DemCommand::Write(a) => write(a, out),
        DemCommand::Run(a) => run_campaign(a, out),
        DemCommand::Compare(a) => compare_cmd(a, out),
        DemCommand::Check(a) => check(a, out),
    }
}

/// A setup's stated sled return: delay (s), speed (m/s).
type KnownReturn = Option<(f64, f64)>;

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
    let file = match &a.scenario.config {
        Some(p) if crate::optim::manifest::manifest_in(p)?.is_none() => Some(ConfigFile::load(p)?),
        _ => None,
    };
    let mut settings = DemSettings::from_table(file.as_ref().and_then(|f| f.dem.as_ref()));
    if let Some(n) = grains {
        settings.particles = n;
    }
    if let Some(um) = a.grain_diameter_um {
        settings.grain_diameter_m = Some(um * 1e-6);
    }
    settings.validate().map_err(|e| {
        anyhow::anyhow!(e.replace("[dem] grain_diameter_m", "--grain-diameter-um / [dem] grain_diameter_m"))
    })?;
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
    let plan = Plan { first_seed: scenario.sim.seed, scenario, design, settings, runs: a.runs, known_return: known };
    // the case must build before the folder is taken
    plan.case(0).map_err(anyhow::Error::msg)?;
    let _owned = RunDir::acquire(&a.out, campaign::KIND, Access::Exclusive).context("--out")?;
    let results = campaign::run(&a.out, &plan, jobs, &|line| eprintln!("dem: {line}"))?;
    let c = compare(&plan.scenario, &plan.design, &results)?;
    write_table(out, &c)?;
    writeln!(
        out,
        "\nwrote {0}/{1} and {0}/{2}; `sawtooth dem compare {0}` draws the comparison",
        a.out.display(),
        campaign::CSV,
        campaign::SETUP
    )?;
    Ok(ExitCode::SUCCESS)
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
    let (plan, results) = load_campaign(&a.dir)?;
    let c = compare(&plan.scenario, &plan.design, &results)?;
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

fn write_table(out: &mut dyn Write, c: &Comparison) -> anyhow::Result<()> {
    writeln!(out, "tooth   model %   DEM % (mean ± sd over {} seeds)", c.runs)?;
    for j in 0..shown_teeth(c) {
        writeln!(out, "{:>5} {:>9.2} {:>9.2} ± {:.2}", j + 1, c.model_pct[j], c.dem_pct[j].mean, c.dem_pct[j].sd)?;
    }
    writeln!(out, " lost {:>9.2} {:>9.2} ± {:.2}", c.model_lost_pct, c.dem_lost_pct.mean, c.dem_lost_pct.sd)?;
    writeln!(
        out,
        "per-tooth |model - DEM|: mean {:.2} pp, max {:.2} pp",
        c.mean_abs_tooth_error_pp, c.max_abs_tooth_error_pp
    )?;
    writeln!(
        out,
        "d_avg: model {:.2} mm, DEM {:.2} ± {:.2} mm{}",
        c.model_d_avg_mm,
        c.dem_d_avg_mm.mean,
        c.dem_d_avg_mm.sd,
        c.d_avg_error_pct.map_or(String::new(), |e| format!(" ({e:+.1} %)"))
    )?;
    writeln!(
        out,
        "centre of mass (tooth): model {:.2}, DEM {:.2} ± {:.2}; dispersion: model {:.2}, DEM {:.2} ± {:.2}",
        c.model_centre,
        c.dem_centre.mean,
        c.dem_centre.sd,
        c.model_dispersion,
        c.dem_dispersion.mean,
        c.dem_dispersion.sd
    )?;
    writeln!(
        out,
        "cost per design: model {:.4} s ({} particles, cpu), DEM {:.1} ± {:.1} s per run",
        c.model_s, c.model_particles, c.dem_s.mean, c.dem_s.sd
    )?;
    Ok(())
}

fn check(a: CheckArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let jobs = jobs(a.jobs)?;
    let mut settings = DemSettings::default();
    if let Some(n) = a.particles {
        settings.particles = n;
    }
    settings.validate().map_err(anyhow::Error::msg)?;
    let command = format!(
        "sawtooth dem check {} --seeds {} --front {} --particles {} --out {}",
        a.run_dir.display(),
        a.seeds,
        a.front,
        settings.particles,
        a.out.display()
    );
    let plan = crate::dem::check::plan(&a.run_dir, &settings, a.seeds, a.front, &command)?;
    if a.plan {
        let _owned = crate::dem::check::write_plan(&a.out, &plan)?;
        let n = plan.members();
        let dir = a.out.display();
        writeln!(
            out,
            "wrote {dir}/{} ({} designs x {} seeds = {n} members, one DEM run each); nothing run yet",
            crate::dem::check::CHECK_PLAN,
            plan.finalists.len(),
            plan.seeds
        )?;
        writeln!(out, "  one member:      sawtooth campaign run {dir} --task I   (I in 0..{})", n - 1)?;
        writeln!(out, "  all, here:       sawtooth dem check {} --out {dir} (the same flags)", a.run_dir.display())?;
        writeln!(out, "  Slurm job array: sawtooth campaign slurm {dir} [--partition P --time T] --submit")?;
        writeln!(out, "  then:            sawtooth campaign gather {dir}   (writes {dir}/check.json)")?;
        return Ok(ExitCode::SUCCESS);
    }
    let report = crate::dem::check::check(&a.out, &plan, jobs, &|l| eprintln!("dem check: {l}"))?;
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
