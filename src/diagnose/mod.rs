//! The sim-to-real gap (issue 5): the diagnosis itself (`diagnose`: where the gap lies, which
//! unmodelled effect causes it, how far it shrinks), its verdict against the data's noise
//! floor (`verdict`: explained, or "none of these"), its report and figures (`render`), and
//! synthetic measurement campaigns from the extended model (`synth`), the data that checks a
//! diagnosis whose true effect is known.

pub mod baseline;
pub mod candidates;
#[allow(clippy::module_inception)]
pub mod diagnose;
pub mod json;
pub mod limits;
pub mod locate;
pub mod markdown;
pub mod model_result;
pub mod motion_screen;
pub mod pair;
pub mod profile;
pub mod render;
pub mod request;
pub mod run;
pub mod scoring;
pub mod suggest;
pub mod synth;
pub mod verdict;
