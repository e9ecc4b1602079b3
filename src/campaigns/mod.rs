//! Campaigns: many optimisation runs as one study (the conveyor-angle sweep of 5.4.3, the
//! repeatability and sensitivity studies of 5.4.1-5.4.2). A campaign is a folder with a plan
//! ([`plan`]: its members, each an `optimize` run with its own folder, seed and settings)
//! that runs in one process or member by member (a Slurm array task each); once every
//! member is finished, its summary files, table and figure ([`panels`]) are built from the
//! members' files by the study's own summariser ([`sweep`], [`study`]); on a cluster, one
//! Slurm array task per member ([`slurm`]: the sbatch scripts). A campaign is one kind of
//! `protocol::Campaign` (a DEM check is another): [`open`] tells a folder's kind, and the
//! protocol runs, gathers and reports any kind. The CLI's `gpu-sweep`, `study` and
//! `campaign` commands parse arguments into a [`plan::Plan`] and print; the work is here.

pub mod panels;
pub mod plan;
pub mod slurm;
pub mod study;
pub mod sweep;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::optim::front::FrontPoint;
use crate::protocol::{Campaign, MemberState, Ran};
use plan::{Plan, Study};

/// The campaign planned in `root`, whatever its kind: a DEM check's plan (`dem check
/// --plan`) or an optimisation campaign's (`gpu-sweep --plan`, `study … --plan`). The one
/// place a folder's kind is told; a new kind of campaign is one more arm.
pub fn open(root: &Path) -> anyhow::Result<Box<dyn Campaign>> {
    if crate::dem::check::is_check(root) {
        return Ok(Box::new(crate::dem::check::read_plan(root)?));
    }
    Ok(Box::new(plan::read_plan(root)?))
}

/// An optimisation campaign: members are `optimize` runs in lockstep here (one engine job
/// per generation) or one per task, each resumed from its checkpoint.
impl Campaign for Plan {
    fn kind(&self) -> &'static str {
        plan::CAMPAIGN_KIND
    }
    fn what(&self) -> &'static str {
        "plan"
    }
    fn command(&self) -> &str {
        &self.command
    }
    fn members(&self) -> usize {
        self.members.len()
    }
    fn label(&self, i: usize) -> String {
        self.members[i].label.clone()
    }
    fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
        Plan::member_dir(self, root, i)
    }
    fn state(&self, root: &Path, i: usize) -> MemberState {
        plan::member_state(&Plan::member_dir(self, root, i))
    }
    fn run_member(&self, root: &Path, i: usize) -> anyhow::Result<Ran> {
        plan::run_member(root, self, i)
    }
    fn run_all(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<Ran> {
        if !plan::execute(root, self)? {
            return Ok(Ran::Interrupted);
        }
        Campaign::gather(self, root, out)?;
        Ok(Ran::Finished(String::new()))
    }
    fn gather(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
        let fronts = plan::finished_fronts(root, self)?;
        summarise(root, self, &fronts, out)
    }
}

/// Summary files and table of a campaign whose members are all finished.
pub fn summarise(root: &Path, plan: &Plan, fronts: &[Vec<FrontPoint>], out: &mut dyn Write) -> anyhow::Result<()> {
    match &plan.study {
        Study::Sweep => sweep::summarise(root, plan, fronts, out),
        Study::Repeatability { target_mass_flow } => {
            study::summarise_repeatability(root, plan, *target_mass_flow, fronts, out)
        }
        Study::Sensitivity { target_mass_flow, repeatability_ci } => {
            study::summarise_sensitivity(root, plan, *target_mass_flow, *repeatability_ci, fronts, out)
        }
    }
}
