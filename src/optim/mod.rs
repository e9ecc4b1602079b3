//! Multi-objective optimisation of conveyor designs.
//!
//! - [`nsga2`]: constrained NSGA-II (Deb et al. 2002; constraint handling after Deb 2000) with
//!   whole-generation batch evaluation and exact checkpoint/resume.
//! - [`hypervolume`]: exact 2-D hypervolume, the quality measure used by the tests.
//! - [`test_problems`]: ZDT1, ZDT2 and BNH with their known Pareto fronts.
//! - [`observe`]: the loop that drives a solver and the observers of its side jobs
//!   (checkpoints, Ctrl-C); [`runner`] adds the run folder's logs and progress.

pub mod checkpoint;
pub mod hypervolume;
pub mod nsga2;
pub mod test_problems;

pub use hypervolume::hypervolume_2d;
pub use nsga2::{
    constrained_dominates, load_checkpoint, pareto_front, save_checkpoint, BatchProblem, Config, Evaluation,
    GenerationStats, Individual, Mode, Nsga2, State, Termination,
};
pub mod front;
pub mod lockstep;
pub mod manifest;
pub mod observe;
pub mod runner;
pub mod sawtooth;
