//! Files in and out: configuration, trajectories, plots.

pub mod atomic;
pub mod bounded;
pub mod config;
pub mod measured;
pub mod plot;
pub mod progress;
pub mod run_dir;
pub mod table;
pub mod trajectories;
