//! The physics model of the thesis, one concept per module.

pub mod collision;
pub mod design;
pub mod effects;
pub mod fill;
pub mod flight;
pub mod geometry;
pub mod outcome;
pub mod performance;
pub mod prepare;
pub mod real;
pub mod requirements;
pub mod rng;
pub mod sampling;
pub mod scenario;
pub mod validity;

pub use design::Design;
pub use outcome::{ParticleEnd, ParticleState, SimOutcome};
pub use performance::Performance;
pub use prepare::{prepare, Prepared};
pub use scenario::{Collision, ContactLaw, EnvPreset, PhysicsMode, Scenario};
pub use validity::Invalid;
