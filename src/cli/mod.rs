//! The command-line layer: raw arguments (clap derive) are turned into validated settings
//! (a `Scenario`, designs, an engine), then handed to the library. Nothing here does physics.

pub mod args;
pub mod bench;
pub mod campaign;
pub mod conformance;
pub mod dem;
pub mod diagnose;
pub mod fit;
pub mod optimize;
pub mod simulate;
pub mod study;
pub mod sweep;
pub mod synth;

use std::io::Write;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "sawtooth", version, about = "Simulate and optimise a sawtooth conveyor for lunar regolith")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

// Every command's --help ends with examples that run as written from the repository root
// (tests/cli.rs runs the help of each; the docs/ pages show the same commands).
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate one design: tooth distribution, d_avg, performance.
    #[command(after_help = "Examples:
  sawtooth simulate --config examples/lunar_solution_c.toml
  sawtooth simulate --env earth --design 47.376,45.884,34.375,36.916,62.853,17.552,1.299,58.595 --json
  sawtooth simulate --config examples/lunar_solution_c.toml --requirements table-2.2 --alpha 0..40
  sawtooth simulate --config data/validation/test3.toml --effect polydisperse=0.5 --plot flights.png")]
    Simulate(simulate::SimulateArgs),
    /// Measure particle-bounces per second of the engines side by side.
    #[command(after_help = "Examples:
  sawtooth bench --env lunar --repeats 7 --engines listing,cpu,gpu
  sawtooth bench --env earth --repeats 7 --engines listing,cpu --compat listing")]
    Bench(bench::BenchArgs),
    /// Compare the GPU engine with the CPU reference on random designs; exit 1 on failure.
    #[command(after_help = "Example:\n  sawtooth conformance --env lunar")]
    Conformance(conformance::ConformanceArgs),
    /// Constrained multi-objective optimisation (NSGA-II), resumable.
    #[command(after_help = "Examples:
  sawtooth optimize --env earth --pop 100 --generations 50 --algorithm nsga2 --out runs/earth-quick
  sawtooth optimize --env earth --pop 100 --generations 50 --algorithm nsga2 --out runs/earth-quick --resume
  sawtooth optimize --env lunar --pop 1000 --tol 1e-6 --engine auto --out runs/lunar-hf
  sawtooth optimize --env lunar --requirements table-2.2 --alpha 0..40 --alpha-points 5 --pop 500 --out runs/lunar-req")]
    Optimize(optimize::OptimizeArgs),
    /// Calibrate collision and drag parameters against measured tooth masses.
    #[command(after_help = "Examples:
  sawtooth fit --data data/validation/test3.csv --setup data/validation/test3.toml --out runs/fit3
  sawtooth fit --data data/validation/test1.csv --setup data/validation/test1.toml --at k_elastic=0.854,mu_fric=0.133,k_drag=5.347")]
    Fit(fit::FitArgs),
    /// One optimisation per conveyor angle (--alpha FROM..TO), angles batched per generation.
    #[command(
        name = "gpu-sweep",
        after_help = "Examples:
  sawtooth gpu-sweep --env lunar --alpha 1..40 --step 1 --engine auto --out runs/sweep
  sawtooth gpu-sweep --env lunar --alpha 1..40 --pop 500 --tol 1e-4 --out /scratch/$USER/sweep --plan"
    )]
    GpuSweep(sweep::SweepArgs),
    /// Repeatability and sensitivity studies of the optimiser (5.4.1-5.4.2).
    #[command(
        subcommand,
        after_help = "Examples:
  sawtooth study repeatability --env lunar --runs 45 --pop 500 --tol 1e-4 --out runs/rep
  sawtooth study sensitivity --env earth --pop 500 --tol 1e-4 --repeatability runs/rep --out runs/sens"
    )]
    Study(study::StudyCommand),
    /// Run, gather, inspect a campaign planned with `gpu-sweep --plan` / `study … --plan`,
    /// or turn it into a Slurm job array.
    #[command(
        subcommand,
        after_help = "Examples:
  sawtooth campaign slurm /scratch/$USER/sweep --partition cpu --time 4:00:00 --cpus-per-task 8 --submit
  sawtooth campaign run /scratch/$USER/sweep --task 3"
    )]
    Campaign(campaign::CampaignCommand),
    /// Measurement-like tooth masses from the model, optionally with effects switched on.
    #[command(after_help = "Example:
  sawtooth synth --setup data/validation/test3.toml --effect impact-scatter=8 --runs 10 --seed 1 --out runs/synth.csv")]
    Synth(synth::SynthArgs),
    /// Locate the sim-to-real gap and rank candidate effects by held-out error.
    #[command(after_help = "Example:
  sawtooth diagnose --data data/validation/test3.csv --setup data/validation/test3.toml --out runs/diag3")]
    Diagnose(diagnose::DiagnoseArgs),
    /// Hold the model against a real DEM engine (LIGGGHTS): cases, campaigns, comparisons.
    #[command(
        subcommand,
        after_help = "Examples:
  sawtooth dem write --config data/validation/test3.toml --particles 150 --out runs/dem-case
  sawtooth dem run --config data/validation/test3.toml --particles 150 --runs 3 --out runs/dem-test3
  sawtooth dem compare runs/dem-test3 --json
  sawtooth optimize --env lunar --pop 60 --generations 15 --algorithm nsga2 --requirements table-2.2 --out runs/lunar-quick
  sawtooth dem check runs/lunar-quick --seeds 2 --front 1 --out runs/dem-check"
    )]
    Dem(dem::DemCommand),
}

/// Exit status: 0 success, 1 a check failed, 2 bad input or an error.
pub fn run(cli: Cli, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    // the SIMD path the environment names (`SAWTOOTH_SIMD`) must be one this CPU has
    crate::simd::check().map_err(anyhow::Error::msg)?;
    match cli.command {
        Command::Simulate(a) => simulate::run(a, out),
        Command::Bench(a) => bench::run(a, out),
        Command::Conformance(a) => conformance::run_cli(a, out),
        Command::Optimize(a) => optimize::run(a, out),
        Command::Fit(a) => fit::run(a, out),
        Command::GpuSweep(a) => sweep::run(a, out),
        Command::Study(c) => study::run(c, out),
        Command::Campaign(c) => campaign::run(c, out),
        Command::Synth(a) => synth::run(a, out),
        Command::Diagnose(a) => diagnose::run(a, out),
        Command::Dem(c) => dem::run(c, out),
    }
}
