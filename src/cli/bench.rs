//! `sawtooth bench`: particle-bounces per second of each engine on one batch, measured side
//! by side in one run, with the ratio to the `listing` baseline.

use std::io::Write;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use clap::Args;
use serde_json::json;

use crate::engine::{make_engine, BatchEvaluator, EngineKind};
use crate::model::prepare;
use crate::model::sampling::{sample_neighbourhood, sample_valid_designs};
use crate::model::scenario::EnvPreset;
use crate::model::{Design, Scenario};
use rayon::prelude::*;

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Sample {
    Neighbourhood,
    Random,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Environment preset.
    #[arg(long, value_enum, default_value = "lunar")]
    pub env: EnvPreset,
    /// Designs in the batch.
    #[arg(long, default_value_t = 64, value_parser = super::args::count::<usize>(&crate::schema::BENCH_DESIGNS))]
    pub designs: usize,
    /// Where the batch comes from: the solution-C neighbourhood (±5 %, issue 2's batch) or
    /// random valid designs from the optimisation bounds (a GA generation).
    #[arg(long, value_enum, default_value = "neighbourhood")]
    pub sample: Sample,
    #[arg(long, default_value_t = 100)]
    pub particles: u32,
    #[arg(long, default_value_t = 100)]
    pub bounces: u32,
    /// Engines to compare, comma-separated (listing, cpu, gpu, auto).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "listing,cpu")]
    pub engines: Vec<EngineKind>,
    /// Timed repetitions per engine (the best is reported; the gpu engine also runs the batch
    /// once untimed first, which compiles its kernels).
    #[arg(long, default_value_t = 3, value_parser = super::args::count::<u32>(&crate::schema::BENCH_REPEATS))]
    pub repeats: u32,
    /// Listing compatibility mode instead of the physical mode.
    #[arg(long)]
    pub compat_listing: bool,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub json: bool,
    /// Time one calibration generation instead (`diagnose`'s screen): every setup TOML in
    /// this folder is a condition (e.g. data/campaign_rig); the baseline and each of the
    /// effects (`EffectKind::ALL`) contribute `--designs` candidates with random parameters in their search
    /// bounds, each simulated in every condition at `--particles`, as one
    /// `evaluate_groups` call of one-design groups.
    #[arg(long)]
    pub calibration: Option<std::path::PathBuf>,
}

/// One engine's measurement.
#[derive(Debug, Clone)]
pub struct Measurement {
    pub engine: &'static str,
    /// Best wall time of one batch, s.
    pub seconds: f64,
    /// Particle flights (impacts) computed in one batch.
    pub particle_bounces: f64,
}

/// The best wall time of `repeats` runs of `run` (at least one), and the last run's result.
/// An engine that compiles its kernels on first use runs once untimed first: the compilation
/// is not the batch's time.
fn best_of<R>(engine: &dyn BatchEvaluator, repeats: u32, mut run: impl FnMut() -> R) -> (f64, R) {
    if engine.compiles_on_first_use() {
        run();
    }
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let r = run();
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    (best, last.expect("at least one run"))
}

/// Time `engine` on the batch; the best of `repeats` runs.
pub fn measure(engine: &dyn BatchEvaluator, scenario: &Scenario, designs: &[Design], repeats: u32) -> Measurement {
    let (seconds, res) = best_of(engine, repeats, || engine.evaluate(scenario, designs));
    let pb = res.iter().flatten().map(|e| e.sim.mean_bounces * scenario.sim.particles as f64).sum();
    Measurement { engine: engine.backend(), seconds, particle_bounces: pb }
}

/// The groups of one calibration generation (see `BenchArgs::calibration`).
fn calibration_groups(
    dir: &std::path::Path,
    per_model: usize,
    particles: u32,
    seed: u64,
) -> anyhow::Result<Vec<(Scenario, Vec<Design>)>> {
    use crate::calibrate::{Condition, KnownMotion, Normalise, Space};
    use crate::diagnose::diagnose::shared_params;
    use crate::model::effects::EffectKind;
    use rand::{Rng, SeedableRng};
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| format!("--calibration {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        anyhow::bail!("--calibration {}: no setup TOML files in the folder", dir.display());
    }
    let mut conditions = Vec::new();
    for f in &files {
        let config =
            crate::io::config::ConfigFile::load(f).with_context(|| format!("--calibration {}", f.display()))?;
        let design = config.design().with_context(|| format!("--calibration {}: no [design] table", f.display()))?;
        let base = config.scenario().with_context(|| format!("--calibration {}", f.display()))?;
        let runs = crate::io::measured::MeasuredRuns {
            path: String::new(),
            provenance: Vec::new(),
            teeth: 1,
            runs: Vec::new(),
        };
        conditions.push(Condition {
            name: f.display().to_string(),
            data: String::new(),
            setup: f.display().to_string(),
            runs,
            base,
            design,
            resolution_g: 0.01,
            motion: KnownMotion::default(),
            motion_profile: None,
            normalise: Normalise::Recovered,
            handling_loss_max: 1.0,
        });
    }
    let shared = shared_params(&conditions);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut groups = Vec::new();
    let models = std::iter::once(Vec::new()).chain(EffectKind::ALL.iter().map(|e| vec![*e]));
    for effects in models {
        let space = Space::new(shared.clone(), &effects, &conditions);
        for _ in 0..per_model {
            let u: Vec<f64> = (0..space.dim()).map(|_| rng.random::<f64>()).collect();
            let x = space.from_unit(&u);
            for c in &conditions {
                let mut s = space.scenario_at(c, &x);
                s.sim.particles = particles;
                s.sim.seed = seed;
                groups.push((s, vec![c.design]));
            }
        }
    }
    Ok(groups)
}

fn run_calibration(a: &BenchArgs, dir: &std::path::Path, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    let groups = calibration_groups(dir, a.designs, a.particles, a.seed)?;
    let mut rows = Vec::new();
    for k in &a.engines {
        let engine = make_engine(*k)?;
        let mut short = None; // a run that returned the wrong number of results
        let (best, _) = best_of(&engine, a.repeats, || {
            let n = engine.evaluate_groups(&groups).len();
            if n != groups.len() {
                short = Some(n);
            }
        });
        if let Some(n) = short {
            anyhow::bail!("the engine returned {n} results for {} groups", groups.len());
        }
        rows.push((engine.backend(), best));
    }
    if a.json {
        let secs: serde_json::Map<String, serde_json::Value> =
            rows.iter().map(|(e, s)| (e.to_string(), json!(s))).collect();
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(
                &json!({"seconds_per_generation": secs, "groups": groups.len(), "particles": a.particles, "threads": rayon::current_num_threads()})
            )?
        )?;
    } else {
        writeln!(
            out,
            "calibration generation: {} one-design groups (6 models x {} candidates x {} conditions) x {} particles, one evaluate_groups call, {} threads",
            groups.len(),
            a.designs,
            groups.len() / (6 * a.designs.max(1)),
            a.particles,
            rayon::current_num_threads()
        )?;
        for (e, s) in &rows {
            writeln!(out, "{e:<10} {s:>10.3} s/generation")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

pub fn run(a: BenchArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    if let Some(dir) = a.calibration.clone() {
        return run_calibration(&a, &dir, out);
    }
    let mut scenario = Scenario::preset(a.env);
    if a.compat_listing {
        scenario = scenario.into_listing_compat();
    }
    scenario.sim.particles = a.particles;
    scenario.sim.max_bounces = a.bounces;
    scenario.validate().map_err(|e| anyhow::anyhow!("invalid setting: {}", super::args::in_user_terms(&e)))?;
    let centre = match a.env {
        EnvPreset::Lunar => Design::lunar_solution_c(),
        EnvPreset::Earth => Design::earth_solution_c(),
    };
    let designs = match a.sample {
        Sample::Neighbourhood => sample_neighbourhood(&scenario, &centre, a.designs, 0.05, a.seed),
        Sample::Random => sample_valid_designs(&scenario, a.designs, a.seed),
    }
    .map_err(|e| anyhow::anyhow!("--designs {} with --sample: {e}", a.designs))?;
    // The CPU-side preparation (validity, fill area, launch points) every engine pays; the
    // best of the repeats, as for the engines (a single run counted the thread pool's start).
    let prepare_s = (0..a.repeats.max(1))
        .map(|_| {
            let t = Instant::now();
            let _: Vec<_> = designs.par_iter().map(|d| prepare(&scenario, d)).collect();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    let (mut results, mut devices) = (Vec::new(), Vec::new());
    for k in &a.engines {
        let engine = make_engine(*k)?;
        results.push(measure(&engine, &scenario, &designs, a.repeats));
        devices.push(engine.device());
    }
    let rate = |m: &Measurement| m.particle_bounces / m.seconds;
    let base = results.iter().find(|m| m.engine == "listing").map(rate);
    if a.json {
        let rates: serde_json::Map<String, serde_json::Value> =
            results.iter().map(|m| (m.engine.to_string(), json!(rate(m)))).collect();
        let secs: serde_json::Map<String, serde_json::Value> =
            results.iter().map(|m| (m.engine.to_string(), json!(m.seconds))).collect();
        let ratios: serde_json::Map<String, serde_json::Value> =
            results.iter().filter_map(|m| base.map(|b| (m.engine.to_string(), json!(rate(m) / b)))).collect();
        let v = json!({
            "particle_bounces_per_s": rates,
            "seconds_per_batch": secs,
            "ratio_to_listing": ratios,
            "designs": designs.len(),
            "particles": a.particles,
            "max_bounces": a.bounces,
            "env": a.env,
            "mode": scenario.mode,
            "threads": rayon::current_num_threads(),
            "prepare_seconds_per_batch": prepare_s,
            "sample": format!("{:?}", a.sample).to_lowercase(),
            "devices": results.iter().zip(&devices).map(|(m, d)| (m.engine.to_string(), json!(d))).collect::<serde_json::Map<_, _>>(),
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?).context("writing output")?;
    } else {
        writeln!(
            out,
            "batch: {} designs x {} particles, up to {} bounces, {:?} env, {:?} mode, {} threads",
            designs.len(),
            a.particles,
            a.bounces,
            a.env,
            scenario.mode,
            rayon::current_num_threads()
        )?;
        writeln!(out, "preparation (validity, fill, launch points; in every engine's time): {prepare_s:.5} s/batch")?;
        writeln!(
            out,
            "{:<10} {:>14} {:>16} {:>18} {:>10}",
            "engine", "s/batch", "particle-bounces", "particle-bounces/s", "ratio"
        )?;
        for m in &results {
            let ratio = base.map_or("-".to_string(), |b| format!("{:.1}x", rate(m) / b));
            writeln!(
                out,
                "{:<10} {:>14.5} {:>16.0} {:>18.3e} {:>10}",
                m.engine,
                m.seconds,
                m.particle_bounces,
                rate(m),
                ratio
            )?;
        }
        for (m, d) in results.iter().zip(&devices) {
            writeln!(out, "{}: {d}", m.engine)?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
