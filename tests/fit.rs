//! `sawtooth fit`: recovery of known parameters from synthetic data, the documented JSON, the
//! output files, and bad input answered with a named field, exit status 2 and no panic.

use std::path::Path;
use std::process::Command;

use crate::common;
use common::{assert_figure, assert_png_beside, scratch};

use sawtooth::calibrate::objective::simulated_bins;
use sawtooth::engine::{make_engine, EngineKind};
use sawtooth::io::config::ConfigFile;

fn sawtooth(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sawtooth")).args(args).output().expect("run binary");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn data(name: &str) -> String {
    format!("{}/data/validation/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The simulated bins (teeth, lost) of the Test 3 setup at `k_drag`, `particles`, seed 0.
fn simulate_test3(k_drag: f64, particles: u32) -> Vec<f64> {
    let config = ConfigFile::load(Path::new(&data("test3.toml"))).unwrap();
    let mut scenario = config.scenario().unwrap();
    scenario.sim.particles = particles;
    scenario.environment.k_drag = Some(k_drag);
    let engine = make_engine(EngineKind::Cpu).unwrap();
    let e = engine.evaluate(&scenario, &[config.design().unwrap()]).pop().unwrap().unwrap();
    simulated_bins(&e.sim)
}

/// Runs whose tooth masses are the simulated fractions times 2 g with a small deterministic
/// jitter (±1.5 %), to 1 mg, over the teeth up to the last one the simulation fills.
fn synthetic_csv(bins: &[f64], runs: usize) -> String {
    let teeth = bins[..bins.len() - 1].iter().rposition(|v| *v > 0.0).unwrap() + 1;
    let mut s = String::from("# synthetic: simulated fractions x 2 g with deterministic jitter\nrun");
    for j in 1..=teeth {
        s += &format!(",tooth_{j}");
    }
    s += "\n";
    for r in 0..runs {
        s += &format!("{}", r + 1);
        for (j, f) in bins[..teeth].iter().enumerate() {
            let jitter = 1.0 + 0.015 * ((7 * r + 3 * j) as f64).sin();
            s += &format!(",{:.3}", f * 2.0 * jitter);
        }
        s += "\n";
    }
    s
}

#[test]
fn recovers_a_known_drag_parameter() {
    const TRUTH: f64 = 4.0;
    const PARTICLES: &str = "400";
    let bins = simulate_test3(TRUTH, 400);
    assert!(bins[bins.len() - 1] == 0.0, "the truth should lose no particles: {bins:?}");
    let dir = scratch("recovery");
    let csv = dir.join("synthetic.csv");
    std::fs::write(&csv, synthetic_csv(&bins, 6)).unwrap();
    let (code, out, err) = sawtooth(&[
        "fit",
        "--data",
        csv.to_str().unwrap(),
        "--setup",
        &data("test3.toml"),
        "--params",
        "k_drag",
        "--pop",
        "10",
        "--generations",
        "8",
        "--particles",
        PARTICLES,
        "--bootstrap",
        "4",
        "--holdout",
        "2",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let k = v["params"]["k_drag"].as_f64().unwrap();
    let sse = v["sse_percent2"].as_f64().unwrap();
    // k_drag moves the split between teeth 2 and 3 by ~10 points per 1/s near 4 1/s, so
    // 0.25 1/s is a few particles' worth; the SSE at the truth is the jitter's (~1 %²).
    assert!((k - TRUTH).abs() < 0.25, "fitted k_drag {k}, truth {TRUTH}");
    assert!(sse < 5.0, "SSE {sse} %²");
    // the parameters not fitted kept the setup's values and are not reported as fitted
    assert!(v["params"].get("k_elastic").is_none());
    // the held-out fit sees the same physics
    let kh = v["heldout"]["params"]["k_drag"].as_f64().unwrap();
    assert!((kh - TRUTH).abs() < 0.25, "held-out fit k_drag {kh}");
    assert!(v["heldout"]["sse_heldout_percent2"].as_f64().unwrap() < 10.0);
    let sd = v["uncertainty"]["k_drag"]["sd"].as_f64().unwrap();
    assert!(sd.is_finite() && sd < 0.5, "bootstrap sd {sd}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn recovers_two_parameters_with_the_likelihood() {
    // k_drag and mu_fric at once, likelihood objective: the fitted point must reproduce the
    // synthetic distribution even if the two parameters trade off against each other.
    let bins = simulate_test3(4.0, 300);
    let dir = scratch("likelihood");
    let csv = dir.join("synthetic.csv");
    std::fs::write(&csv, synthetic_csv(&bins, 6)).unwrap();
    let (code, out, err) = sawtooth(&[
        "fit",
        "--data",
        csv.to_str().unwrap(),
        "--setup",
        &data("test3.toml"),
        "--params",
        "mu_fric,k_drag",
        "--objective",
        "likelihood",
        "--pop",
        "12",
        "--generations",
        "8",
        "--particles",
        "300",
        "--bootstrap",
        "0",
        "--holdout",
        "0",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let sse = v["sse_percent2"].as_f64().unwrap();
    assert!(sse < 5.0, "SSE {sse} %² at {}", v["params"]);
    let k = v["params"]["k_drag"].as_f64().unwrap();
    assert!((k - 4.0).abs() < 1.5, "k_drag {k}");
    assert_eq!(v["objective_kind"], "likelihood");
    assert!(v["heldout"].is_null());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn json_on_test3_has_the_documented_keys_and_files_are_written() {
    let dir = scratch("json");
    let (code, out, err) = sawtooth(&[
        "fit",
        "--data",
        &data("test3.csv"),
        "--setup",
        &data("test3.toml"),
        "--pop",
        "5",
        "--generations",
        "1",
        "--polish",
        "2",
        "--particles",
        "50",
        "--bootstrap",
        "2",
        "--holdout",
        "3",
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in ["params", "objective", "sse_percent2", "heldout", "uncertainty", "distribution", "metrics"] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    for p in ["k_elastic", "mu_fric", "k_drag"] {
        let x = v["params"][p].as_f64().unwrap_or_else(|| panic!("params.{p}"));
        assert!(x.is_finite());
        assert!(v["uncertainty"][p]["sd"].is_number(), "uncertainty.{p}.sd");
        assert_eq!(v["uncertainty"][p]["interval"].as_array().unwrap().len(), 2);
    }
    let measured = v["distribution"]["measured"].as_array().unwrap();
    let fitted = v["distribution"]["fitted"].as_array().unwrap();
    assert_eq!(measured.len(), 20);
    assert_eq!(fitted.len(), 20);
    // Test 3 records input_mass: fractions of the loaded mass (Σ tooth 1 / Σ input) and a
    // "not recovered" bin
    assert!((measured[0].as_f64().unwrap() - 41.314).abs() < 0.01, "Test 3 tooth 1 in percent of the loaded mass");
    assert_eq!(v["distribution"]["last_bin"], "not recovered");
    assert!((v["distribution"]["last_bin_measured"].as_f64().unwrap() - 2.290).abs() < 0.01);
    for k in ["sse_heldout_percent2", "sse_in_sample_percent2", "nll_heldout", "params"] {
        assert!(v["heldout"].get(k).is_some(), "missing heldout.{k}");
    }
    for k in ["centre_of_mass_teeth", "dispersion_teeth"] {
        assert!(v["metrics"]["measured"][k].is_number() && v["metrics"]["fitted"][k].is_number(), "metrics.*.{k}");
    }
    assert!((v["metrics"]["measured"]["centre_of_mass_teeth"].as_f64().unwrap() - 1.85).abs() < 0.01);
    // --out: the same object, a per-tooth CSV and an SVG
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("fit.json")).unwrap()).unwrap();
    assert_eq!(file, v);
    let csv = std::fs::read_to_string(dir.join("fit.csv")).unwrap();
    assert!(csv.starts_with(
        "tooth,measured_mean_percent,measured_sd_percent,measured_min_percent,measured_max_percent,fitted_percent\n"
    ));
    assert_eq!(csv.lines().count(), 1 + 20);
    let svg = std::fs::read_to_string(dir.join("fit.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_png_beside(&dir.join("fit.svg"));
    // axes with tick numbers and units, tooth categories, the legend
    assert_figure(&svg, 5, &["tooth", "particle fraction [%]", "1", "2", "measured mean", "fitted simulation"]);
    assert!(!std::fs::read_dir(&dir).unwrap().any(|e| e.unwrap().file_name().to_string_lossy().contains(".tmp")));
    // the corrected model (issue 43, 3): the setup with the fitted values, read as any config
    let corrected = dir.join("corrected.toml");
    let text = std::fs::read_to_string(&corrected).unwrap();
    assert!(text.contains("# sawtooth ") && text.contains("test3.csv"), "provenance: {text}");
    let (code, out, err) = sawtooth(&["simulate", "--config", corrected.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let fitted = |p: &str| v["params"][p].as_f64().unwrap();
    let line = out.lines().find(|l| l.starts_with("scenario")).unwrap();
    for shown in [
        format!("k_elastic {}", fitted("k_elastic")),
        format!("mu {}", fitted("mu_fric")),
        format!("drag {} 1/s", fitted("k_drag")),
    ] {
        assert!(line.contains(&shown), "simulate --config corrected.toml shows `{line}`, not {shown}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn table_output_and_determinism() {
    let args = [
        "fit",
        "--data",
        &data("test2.csv"),
        "--setup",
        &data("test2.toml"),
        "--params",
        "k_drag",
        "--pop",
        "5",
        "--generations",
        "1",
        "--polish",
        "2",
        "--particles",
        "40",
        "--bootstrap",
        "2",
        "--holdout",
        "1",
    ];
    let (code, out, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    for needle in ["k_drag", "measured %", "fitted %", "centre of mass", "SSE (in-sample)", "SSE held-out"] {
        assert!(out.contains(needle), "missing `{needle}` in\n{out}");
    }
    assert_eq!(sawtooth(&args).1, out, "same inputs and seed give the same output");
}

#[test]
fn at_scores_given_parameters_without_fitting() {
    // the thesis's Test 3 fit (4.3.5), scored against Test 3: the SSE of the simulated
    // distribution at exactly these values, equal to the library's
    let (code, out, err) = sawtooth(&[
        "fit",
        "--data",
        &data("test3.csv"),
        "--setup",
        &data("test3.toml"),
        "--at",
        "k_elastic=0.854,mu_fric=0.133,k_drag=5.347",
        "--normalise",
        "recovered",
        "--particles",
        "200",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["params"]["k_drag"].as_f64(), Some(5.347));
    assert_eq!(v["settings"]["fitted"], false);
    assert!(v["heldout"].is_null());
    let bins = simulate_test3(5.347, 200);
    let measured = [42.282_221, 33.469_180, 20.733_571, 3.515_028];
    let want: f64 =
        bins.iter().enumerate().map(|(j, b)| (100.0 * b - measured.get(j).copied().unwrap_or(0.0)).powi(2)).sum();
    let got = v["sse_percent2"].as_f64().unwrap();
    assert!((got - want).abs() < 1e-3 * want, "{got} vs {want}");
}

fn assert_bad_input(args: &[&str], needles: &[&str]) {
    let (code, out, err) = sawtooth(args);
    assert_eq!(code, 2, "{args:?}: expected exit 2, got {code}\nstdout {out}\nstderr {err}");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: `{n}` not in `{err}`");
    }
}

#[test]
fn bad_input_exits_2_naming_the_field() {
    let dir = scratch("bad");
    let (csv3, toml3) = (data("test3.csv"), data("test3.toml"));
    let base = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = ["fit", "--data", &csv3, "--setup", &toml3, "--generations", "0", "--bootstrap", "0"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |extra: &[&str], needles: &[&str]| {
        let v = base(extra);
        assert_bad_input(&v.iter().map(String::as_str).collect::<Vec<_>>(), needles);
    };
    // missing files
    assert_bad_input(&["fit", "--data", "/nonexistent/runs.csv", "--setup", &toml3], &["--data", "runs.csv"]);
    assert_bad_input(&["fit", "--data", &csv3, "--setup", "/nonexistent/rig.toml"], &["--setup", "rig.toml"]);
    // malformed CSV and TOML
    let bad_csv = dir.join("bad.csv");
    std::fs::write(&bad_csv, "run,tooth_1,tooth_2\n1,0.5,abc\n").unwrap();
    assert_bad_input(
        &["fit", "--data", bad_csv.to_str().unwrap(), "--setup", &toml3],
        &["bad.csv:2", "tooth_2", "not a number"],
    );
    let bad_toml = dir.join("bad.toml");
    std::fs::write(&bad_toml, "env = \"earth\"\n[collision]\nk_elastik = 0.5\n").unwrap();
    assert_bad_input(&["fit", "--data", &csv3, "--setup", bad_toml.to_str().unwrap()], &["--setup", "k_elastik"]);
    let no_design = dir.join("nodesign.toml");
    std::fs::write(&no_design, "env = \"earth\"\n[sim]\nteeth = 20\n").unwrap();
    assert_bad_input(&["fit", "--data", &csv3, "--setup", no_design.to_str().unwrap()], &["[design]"]);
    let few_teeth = dir.join("few.toml");
    let text = std::fs::read_to_string(&toml3).unwrap().replace("teeth = 20", "teeth = 3");
    std::fs::write(&few_teeth, text).unwrap();
    assert_bad_input(&["fit", "--data", &csv3, "--setup", few_teeth.to_str().unwrap()], &["sim.teeth", "4 teeth"]);
    // flags (each rejected before anything is simulated)
    run(&["--params", "k_elastic,gravity"], &["--params", "`gravity`", "k_elastic, mu_fric, k_drag"]);
    run(&["--params", "k_drag,k_drag"], &["--params", "twice"]);
    // the plastic limit speed is a parameter of the thesis's law in the physical mode only
    let listing = dir.join("listing.toml");
    let text = std::fs::read_to_string(&toml3).unwrap();
    std::fs::write(&listing, format!("mode = \"listing\"\n{}", text.replace("mode = \"physical\"\n", ""))).unwrap();
    assert_bad_input(
        &["fit", "--data", &csv3, "--setup", listing.to_str().unwrap(), "--params", "k_elastic,v_limit"],
        &["v_limit does not apply", "listing"],
    );
    run(&["--pop", "4"], &["--pop", "[5, 10000]"]);
    run(&["--max-particles", "10"], &["--max-particles", "[1000, 10000000]"]);
    run(&["--pop", "1000000000"], &["--pop", "[5, 10000]"]);
    run(&["--holdout", "0", "--max-particles", "100000000"], &["--max-particles", "[1000, 10000000]"]);
    run(&["--particles", "0"], &["--particles", "[1, 10000000]"]);
    run(&["--holdout", "10"], &["--holdout", "number of runs", "10"]);
    run(&["--objective", "mae"], &["--objective"]);
    run(&["--pop=-1"], &["--pop"]);
    run(&["--at", "k_drag=fast"], &["--at", "k_drag", "not a number"]);
    run(&["--at", "k_drag=-1"], &["--at", "k_drag", "must lie in [1e-4, 10000]"]);
    run(&["--at", "gravity=1"], &["--at", "`gravity`"]);
    // D.4's fractions need no input mass, the loaded-mass ones do
    assert_bad_input(
        &["fit", "--data", &data("test2.csv"), "--setup", &data("test2.toml"), "--normalise", "loaded"],
        &["--normalise loaded", "test2.csv", "input_mass"],
    );
    // an output folder holding someone else's files is refused before any work
    let foreign = dir.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("my-notes.txt"), "mine").unwrap();
    run(&["--out", foreign.to_str().unwrap()], &["--out", "holds files"]);
    assert_eq!(std::fs::read_to_string(foreign.join("my-notes.txt")).unwrap(), "mine");
    // k_drag has no meaning in vacuum
    let vacuum = dir.join("vacuum.toml");
    let text = std::fs::read_to_string(&toml3).unwrap();
    let text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("k_drag"))
        .map(|l| if l.starts_with("env =") { "env = \"lunar\"\n".to_string() } else { format!("{l}\n") })
        .collect();
    std::fs::write(&vacuum, text).unwrap();
    assert_bad_input(
        &["fit", "--data", &csv3, "--setup", vacuum.to_str().unwrap(), "--params", "k_drag", "--generations", "0"],
        &["k_drag", "vacuum"],
    );
    std::fs::remove_dir_all(&dir).ok();
}
