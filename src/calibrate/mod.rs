//! One calibration engine for `fit` and `diagnose` (issue 11): a parameter space of shared
//! collision/drag parameters and effect parameters ([`space`]), measured conditions
//! ([`condition`]), a batch simulator that turns many (model, point) pairs across every
//! condition into **one** engine call ([`batch`]), a solver that screens with differential
//! evolution at a small particle budget and polishes with a compass search at the full
//! budget, several models in lockstep ([`solver`]), the effort a user asks for turned into
//! the solver's settings ([`effort`]), shared parameters that vary across conditions
//! ([`varying`]), and the sample statistics of the reports ([`stats`]).

pub mod batch;
pub mod condition;
pub mod corrected;
pub mod effort;
pub mod fields;
pub mod levenberg;
pub mod measured;
pub mod objective;
pub mod param;
pub mod solver;
pub mod space;
pub mod stats;
pub mod target;
pub mod varying;

pub use batch::Simulator;
pub use condition::{Condition, KnownMotion, Normalise};
pub use effort::{particles_from_data, Effort, EffortSettings, MIN_PARTICLES};
pub use fields::Spelling;
pub use param::{parse_assignments, parse_params, Param};
pub use solver::{Fit, Model, PolishMethod, Probe, Screened, Search, Solver};
pub use space::{shared_params, Space};
pub use target::{collapse_to_weighed, subset, MeasuredSummary, ObjectiveKind, Target};
pub use varying::{parse_varying, Covariate, Varying};
