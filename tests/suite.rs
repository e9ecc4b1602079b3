//! Every integration test of the crate, in one test binary: `cargo test` compiles and links
//! this one crate instead of one per file (docs/testing.md, "One test binary"). Each file of
//! `tests/` is a module of it; run one file's tests with its module path as the filter,
//! `cargo test --test suite diagnose::` (the `::` keeps `diagnose_beyond` out).

mod common;

mod campaign;
mod campaign_slurm;
mod cli;
mod dem;
mod diagnose;
mod diagnose_beyond;
mod diagnose_dem;
mod diagnose_dem_candidate;
mod documented_commands;
mod effects;
mod engine_agreement;
mod fit;
mod fuzz_readers;
mod gpu_conformance;
mod help;
mod hostile_input;
mod independent_campaigns;
mod kill_resume;
mod layers;
mod nsga2;
mod optimize;
mod properties;
mod provenance;
mod requirements;
mod shaders;
mod studies;
mod synth;
mod thesis_figures;
mod twins;
