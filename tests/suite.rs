//! Every integration test of the crate, in one test binary: `cargo test` compiles and links
//! this one crate instead of one per file (docs/testing.md, "One test binary"). Each file of
//! `tests/` is a module of it; run one file's tests with its module path as the filter,
//! `cargo test --test suite diagnose::` (the `::` keeps `diagnose_beyond` out).

mod common;

mod campaign;
mod campaign_slurm;
mod cli;
mod dem;
mod dem_reference;
mod diagnose;
mod diagnose_beyond;
mod diagnose_dem;
mod diagnose_dem_candidate;
mod documented_commands;
mod effects;
mod engine_agreement;
mod fit;
mod fit_joint;
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

/// With `autotests = false`, a file added to `tests/` and not named above would be compiled
/// by nobody and its tests would silently never run.
#[test]
fn every_file_of_tests_is_a_module_of_the_suite() {
    let dir = common::repo().join("tests");
    let suite = std::fs::read_to_string(dir.join("suite.rs")).unwrap();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else { continue };
        if path.extension().is_some_and(|e| e == "rs")
            && stem != "suite"
            && !suite.contains(&format!("\nmod {stem};\n"))
        {
            missing.push(format!("tests/{stem}.rs"));
        }
    }
    assert!(
        missing.is_empty(),
        "tests/{{{}}}.rs: not a module of tests/suite.rs, so never compiled",
        missing.join(",")
    );
}
