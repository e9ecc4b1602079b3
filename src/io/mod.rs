//! Files in and out: configuration, trajectories, plots.

pub mod config;
pub mod plot;
pub mod trajectories;
pub mod measured;
