//! Files in and out: configuration, measured data, trajectories, atomic writes, run folders.

pub mod atomic;
pub mod bounded;
pub mod config;
pub mod measured;
pub mod progress;
pub mod run_dir;
pub mod table;
pub mod trajectories;
