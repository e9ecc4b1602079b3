//! One calibration engine for `fit` and `diagnose` (issue 11): a parameter space of shared
//! collision/drag parameters and effect parameters ([`space`]), measured conditions
//! ([`condition`]), a batch simulator that turns many (model, point) pairs across every
//! condition into **one** engine call ([`batch`]), and a solver that screens with
//! differential evolution at a small particle budget and polishes with a compass search at
//! the full budget, several models in lockstep ([`solver`]).

pub mod batch;
pub mod condition;
pub mod solver;
pub mod space;

pub use batch::Simulator;
pub use condition::{Condition, KnownMotion, Normalise};
pub use solver::{fit_models, Fit, Model, SolverBudget};
pub use space::Space;
