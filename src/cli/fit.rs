//! `sawtooth fit` (placeholder; being written).

use std::io::Write;
use std::process::ExitCode;

use clap::Args;

#[derive(Debug, Args)]
pub struct FitArgs {}

pub fn run(_a: FitArgs, _out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    anyhow::bail!("fit is not implemented yet")
}
