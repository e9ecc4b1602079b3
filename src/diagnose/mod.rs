//! The sim-to-real gap (issue 5). So far: synthetic measurement campaigns from the extended
//! model (`synth`), the data that checks a diagnosis whose true effect is known.

#[allow(clippy::module_inception)]
pub mod diagnose;
pub mod render;
pub mod synth;
