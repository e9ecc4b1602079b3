//! `sawtooth fit`: calibrate k_elastic, mu_fric and k_drag against measured tooth masses
//! (thesis 4.3.4-4.3.5, listing D.4). The flags become a [`FitRequest`], which the library
//! checks and runs ([`crate::fit::request`], as the Python package does); the work is in
//! [`crate::fit`], on the calibration engine `diagnose` uses ([`crate::calibrate`]).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use super::args::{EffortArgs, EngineArgs};
use crate::calibrate::{parse_assignments, parse_params, parse_varying, Normalise, ObjectiveKind, Spelling};
use crate::fit::report;
use crate::fit::request::{self, FitOutcome, FitRequest, JointRequest};

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Measured runs: CSV `run,tooth_1,..,tooth_n[,input_mass]` (grams), as data/validation.
    /// Repeat `--data D --setup S` for a joint fit of several conditions (other speeds,
    /// slopes, fills, campaigns): one calibration of them all, each judged against its own
    /// noise floor and predicted by a fit of the others.
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// The rig's setup: a config TOML with [design] (and optionally [measurement]); one per
    /// --data, in the same order.
    #[arg(long, required = true)]
    pub setup: Vec<PathBuf>,
    /// Joint fit: parameters that vary linearly with a condition's variable instead of being
    /// shared, `PARAM:VARIABLE` comma list (variables v0_m_s, a_m_s2, alpha_deg), e.g.
    /// `k_elastic:v0_m_s`.
    #[arg(long)]
    pub vary: Option<String>,
    /// Joint fit: do not predict each condition from a fit of the others (one fit fewer per
    /// condition).
    #[arg(long)]
    pub no_leave_out: bool,
    /// Parameters to fit, a comma list of k_elastic, mu_fric, k_drag, v_limit (the plastic
    /// limit speed of Eq. 4.9, m/s); the others keep the setup's values. Default:
    /// k_elastic,mu_fric, and k_drag where the setup has drag.
    #[arg(long)]
    pub params: Option<String>,
    /// What the solver minimises.
    #[arg(long, value_enum, default_value = "sse")]
    pub objective: ObjectiveKind,
    #[command(flatten)]
    pub effort: EffortArgs,
    /// What the compared fractions are fractions of: `loaded` (the input mass: the weighed
    /// teeth plus a "not recovered" bin; the default when every run records input_mass) or
    /// `recovered` (listing D.4: the weighed teeth's sum, plus a lost bin).
    #[arg(long, value_enum)]
    pub normalise: Option<Normalise>,
    /// Seed of the particle streams, the solver and the bootstrap (default: the setup's
    /// sim.seed).
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub engine: EngineArgs,
    /// Hold out the last K runs: fit on the others, score on them (0 = off) [default: 3, or
    /// half the runs where the data hold fewer than 6; none with --at, which scores every run].
    #[arg(long)]
    pub holdout: Option<usize>,
    /// Bootstrap replicates over the runs for the parameter uncertainty (0 = off) [default:
    /// 20; one --data only].
    #[arg(long, value_parser = super::args::count::<usize>(&crate::schema::FIT_BOOTSTRAP))]
    pub bootstrap: Option<usize>,
    /// Do not fit: score these values (`k_elastic=0.854,mu_fric=0.133,k_drag=5.347`) against
    /// the runs; the parameters not named keep the setup's values.
    #[arg(long, conflicts_with = "params")]
    pub at: Option<String>,
    /// Write fit.json, fit.csv, fit.svg, fit.png and corrected.toml into this directory (a
    /// joint fit: joint.json, corrected-NAME.toml per condition, and corrected.toml where no
    /// parameter varies).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl FitArgs {
    /// The library's request from the flags; the lists are parsed here, where an error can
    /// name the flag.
    pub fn request(&self) -> anyhow::Result<FitRequest> {
        let mut r = FitRequest::new(self.data[0].clone(), self.setup[0].clone(), Spelling::Flags);
        match (&self.at, &self.params) {
            (Some(list), _) => r.at = Some(parse_assignments(list).context("--at")?),
            (None, Some(list)) => r.params = Some(parse_params(list).context("--params")?),
            (None, None) => {}
        }
        r.objective = self.objective;
        r.effort = self.effort.settings(crate::calibrate::EffortSettings::default());
        r.normalise = self.normalise;
        r.seed = self.seed;
        r.engine = self.engine.kind();
        r.holdout = self.holdout;
        r.bootstrap = self.bootstrap.unwrap_or(FitRequest::DEFAULT_BOOTSTRAP);
        r.out = self.out.clone();
        Ok(r)
    }

    /// The joint fit's request (several --data/--setup pairs); the single fit's flags that do
    /// not apply are refused by name.
    pub fn joint_request(&self) -> anyhow::Result<JointRequest> {
        let single_only = [
            ("--holdout", self.holdout.is_some()),
            ("--bootstrap", self.bootstrap.is_some()),
            ("--at", self.at.is_some()),
        ];
        if let Some((flag, _)) = single_only.iter().find(|(_, given)| *given) {
            bail!(
                "{flag} applies to a fit of one --data; a joint fit predicts each condition from a fit of the others \
                 instead (--no-leave-out: not)"
            );
        }
        Ok(JointRequest {
            pairs: self.data.iter().cloned().zip(self.setup.iter().cloned()).collect(),
            params: self.params.as_deref().map(parse_params).transpose().context("--params")?,
            varying: self.vary.as_deref().map(parse_varying).transpose().context("--vary")?.unwrap_or_default(),
            objective: self.objective,
            effort: self.effort.settings(crate::calibrate::EffortSettings::default()),
            normalise: self.normalise,
            seed: self.seed,
            engine: self.engine.kind(),
            leave_out: !self.no_leave_out,
            out: self.out.clone(),
            spelling: Spelling::Flags,
        })
    }
}

pub fn run(a: FitArgs, out: &mut dyn Write) -> anyhow::Result<ExitCode> {
    if a.data.len() != a.setup.len() {
        bail!("--data and --setup come in pairs: {} --data, {} --setup", a.data.len(), a.setup.len());
    }
    if a.data.len() > 1 {
        let (report, json) = request::run_joint(&a.joint_request()?, &mut |line| eprintln!("{line}"))?;
        if a.json {
            writeln!(out, "{}", serde_json::to_string_pretty(&json)?).context("writing output")?;
        } else {
            report::write_joint_table(out, &report).context("writing output")?;
            if let Some(dir) = &a.out {
                writeln!(out, "\nwrote {0}/{1} and the corrected configs", dir.display(), request::JOINT_JSON)
                    .context("writing output")?;
            }
        }
        return Ok(ExitCode::SUCCESS);
    }
    if a.vary.is_some() || a.no_leave_out {
        bail!("--vary and --no-leave-out apply to a joint fit of several --data/--setup pairs");
    }
    let r = a.request()?;
    let FitOutcome { report, meta, json } = request::run(&r, &mut |line| eprintln!("{line}"))?;
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&json)?).context("writing output")?;
    } else {
        report::write_table(out, &report, &meta).context("writing output")?;
        if let Some(dir) = &a.out {
            writeln!(out, "\nwrote {0}/fit.json, {0}/fit.csv, {0}/fit.svg, {0}/fit.png", dir.display())
                .context("writing output")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
