//! The command-line layer: raw arguments (clap derive) are turned into validated settings
//! (a `Scenario`, designs, an engine), then handed to the library. Nothing here does physics.

pub mod args;
pub mod bench;
pub mod campaign;
pub mod conformance;
pub mod diagnose;
pub mod fit;
pub mod measured_condition;
pub mod multi;
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

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate one design: tooth distribution, d_avg, performance.
    Simulate(simulate::SimulateArgs),
    /// Measure particle-bounces per second of the engines side by side.
    Bench(bench::BenchArgs),
    /// Compare the GPU engine with the CPU reference on random designs; exit 1 on failure.
    Conformance(conformance::ConformanceArgs),
    /// Constrained multi-objective optimisation (NSGA-II), resumable.
    Optimize(optimize::OptimizeArgs),
    /// Calibrate collision and drag parameters against measured tooth masses.
    Fit(fit::FitArgs),
    /// One optimisation per conveyor angle (--alpha FROM..TO), angles batched per generation.
    #[command(name = "gpu-sweep")]
    GpuSweep(sweep::SweepArgs),
    /// Repeatability and sensitivity studies of the optimiser (5.4.1-5.4.2).
    #[command(subcommand)]
    Study(study::StudyCommand),
    /// Run, gather, inspect a campaign planned with `gpu-sweep --plan` / `study … --plan`,
    /// or turn it into a Slurm job array.
    #[command(subcommand)]
    Campaign(campaign::CampaignCommand),
    /// Measurement-like tooth masses from the model, optionally with effects switched on.
    Synth(synth::SynthArgs),
    /// Locate the sim-to-real gap and rank candidate effects by held-out error.
    Diagnose(diagnose::DiagnoseArgs),
}

/// Exit status: 0 success, 1 a check failed, 2 bad input or an error.
pub fn run(cli: Cli, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
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
    }
}
