//! Campaigns: many optimisation runs as one study (the conveyor-angle sweep of 5.4.3, the
//! repeatability and sensitivity studies of 5.4.1-5.4.2). A campaign is a folder with a plan
//! ([`plan`]: its members, each an `optimize` run with its own folder, seed and settings)
//! that runs in one process or member by member (a Slurm array task each); once every
//! member is finished, its summary files, table and figure ([`panels`]) are built from the
//! members' files by the study's own summariser ([`sweep`], [`study`]); on a cluster, one
//! Slurm array task per member ([`slurm`]: the sbatch scripts). The CLI's
//! `gpu-sweep`, `study` and `campaign` commands parse arguments into a [`plan::Plan`] and
//! print; the work is here.

pub mod panels;
pub mod plan;
pub mod slurm;
pub mod study;
pub mod sweep;

use std::io::Write;
use std::path::Path;

use crate::optim::front::FrontPoint;
use plan::{Plan, Study};

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
