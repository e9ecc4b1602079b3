//! Designing to the thesis's own requirements (issue 13): Table 2.2's verdicts in `simulate`,
//! the requirements as constraints of `optimize`, and one design judged over the slope range.

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::common;
use common::{fresh_dir, run, sawtooth};

/// Lunar solution C (Table C.6), in the CLI's units.
const SOLUTION_C: &str = "47.346,46.898,32.183,43.687,94.424,11.964,0.840,32.051";

#[test]
fn simulate_judges_solution_c_at_its_operating_point() {
    let (code, out, err) =
        run(&["simulate", "--design", SOLUTION_C, "--requirements", "table-2.2", "--particles", "600", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let p = &v["performance"];
    let r = &v["requirements"];
    let w = &r["worst"];
    // the operating point by hand from the run's own figures: the highest feed rate up to
    // 48 kg/h that draws at most 5 W (module doc of model::requirements)
    let m_max = p["m_dot_kg_s"].as_f64().unwrap() * 3600.0;
    let w_spec = p["w_spec_j_kg"].as_f64().unwrap();
    let m_op = m_max.min(48.0).min(5.0 / w_spec * 3600.0).max(6.0f64.min(m_max));
    let op = &w["operating_point"];
    assert!((op["m_dot_kg_h"].as_f64().unwrap() - m_op).abs() < 1e-9, "{op}");
    assert!((op["p_avg_w"].as_f64().unwrap() - w_spec * m_op / 3600.0).abs() < 1e-9);
    let f = p["f_stroke_hz"].as_f64().unwrap();
    assert!((op["f_stroke_hz"].as_f64().unwrap() - f * m_op / m_max).abs() < 1e-12);
    // 5.5: 11.01 mm stroke / 5 % = 220 mm of wire in a 1.3054 m sled (Eq. 3.1)
    assert!((w["wire_length_m"].as_f64().unwrap() - 0.2201).abs() < 1e-4);
    assert!((w["sled_length_m"].as_f64().unwrap() - 1.3054).abs() < 1e-4);
    assert_eq!(r["slope_range_assessed"], false, "one slope does not cover 0-40 deg");
    assert_eq!(r["not_assessed"].as_array().unwrap().len(), 6);
    // the scenario is in the JSON too
    assert_eq!(v["scenario"]["environment"]["alpha_deg"], 35.0);

    let (code, table, _) =
        run(&["simulate", "--design", SOLUTION_C, "--requirements", "table-2.2", "--particles", "600"]);
    assert_eq!(code, 0);
    for line in
        ["operating point", "1.1   feed rate >= 6 kg/h", "1.4   power <= 5 W", "5.5   wire", "1.2   material loss"]
    {
        assert!(table.contains(line), "missing `{line}` in\n{table}");
    }
    assert!(table.contains("not assessed by the model: 1.3 system mass"));
    assert!(table.contains("give --alpha 0..40 to judge the range"));
}

#[test]
fn simulate_over_slopes_names_the_slopes_the_model_rejects() {
    // solution C was optimised at 35 deg; on shallow slopes its accelerated fill surface is
    // steeper than the conveyor, which 5.3.1's spill check rejects
    let (code, out, err) = run(&[
        "simulate",
        "--design",
        SOLUTION_C,
        "--requirements",
        "table-2.2",
        "--alpha",
        "1..40",
        "--alpha-points",
        "4",
        "--particles",
        "400",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.matches("invalid here (fill_spills)").count(), 2, "{out}");
    assert!(
        out.contains("verdict          NOT compliant: the model rejects the design at 1 deg (fill_spills)"),
        "{out}"
    );
    // at 27 and 40 deg it is simulated and its figures shown
    assert!(out.lines().any(|l| l.trim_start().starts_with("40.00")), "{out}");
}

#[test]
fn requirements_come_from_files_and_bad_ones_are_named() {
    let dir = fresh_dir("files");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("req.toml");
    std::fs::write(&file, "[requirements]\npreset = \"table-2.2\"\npower_max_w = 3.0\n").unwrap();
    let (code, out, err) = run(&[
        "simulate",
        "--design",
        SOLUTION_C,
        "--requirements",
        file.to_str().unwrap(),
        "--particles",
        "300",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["requirements"]["requirements"]["power_max_w"], 3.0);
    // the scenario's own config file may hold the table: used without --requirements
    let config = dir.join("scenario.toml");
    std::fs::write(&config, "env = \"lunar\"\n[requirements]\npreset = \"table-2.2\"\nfeed_rate_min_kg_h = 10.0\n")
        .unwrap();
    let (code, out, _) =
        run(&["simulate", "--design", SOLUTION_C, "--config", config.to_str().unwrap(), "--particles", "300"]);
    assert_eq!(code, 0);
    assert!(out.contains("feed rate >= 10 kg/h"), "{out}");

    // a steeper conveyor than the thesis's is simulated, with a note rather than silently
    let (code, _, err) = run(&["simulate", "--design", SOLUTION_C, "--particles", "100", "--alpha", "50"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("beyond the thesis's slope range 0..40 deg"), "{err}");

    let bad = [
        (vec!["--requirements", "table-9"], "neither a preset"),
        (vec!["--alpha-points", "3"], "--alpha-points needs a slope range"),
        (vec!["--alpha", "1..40", "--alpha-points", "1"], "--alpha-points must lie in [2, 41]"),
        (vec!["--alpha", "1..95"], "environment.alpha_deg"),
    ];
    for (flags, message) in bad {
        let mut args = vec!["simulate", "--design", SOLUTION_C, "--particles", "100"];
        args.extend(flags.iter().copied());
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{flags:?} was accepted");
        assert!(err.contains(message), "{flags:?}: {err}");
    }
    std::fs::write(&file, "[requirements]\npreset = \"table-2.2\"\npower_max_w = -5\n").unwrap();
    let (code, _, err) = run(&["simulate", "--design", SOLUTION_C, "--requirements", file.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("requirements.power_max_w must lie in [0.001, 1000000] W"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

const OPTIMIZE: &[&str] = &[
    "optimize",
    "--pop",
    "32",
    "--algorithm",
    "nsga2",
    "--particles",
    "120",
    "--final-particles",
    "200",
    "--replicates",
    "2",
    "--seed",
    "5",
    "--quiet",
    "--requirements",
    "table-2.2",
    "--alpha",
    "0..40",
    "--alpha-points",
    "3",
];

fn rows(path: &Path) -> usize {
    std::fs::read_to_string(path).map(|t| t.lines().count().saturating_sub(1)).unwrap_or(0)
}

/// pareto.csv as a pandas user reads it: by column name.
fn pareto(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(dir.join("pareto.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    r.records().map(|rec| header.iter().cloned().zip(rec.unwrap().iter().map(str::to_string)).collect()).collect()
}

fn check_front(dir: &Path) {
    let front = pareto(dir);
    assert!(!front.is_empty());
    for row in &front {
        let num = |k: &str| row[k].parse::<f64>().unwrap_or_else(|_| panic!("{k} = {:?}", row[k]));
        assert!([0.0, 20.0, 40.0].contains(&num("alpha_deg")), "{row:?}");
        assert!((num("wire_length_m") - num("stroke_m") / 0.05).abs() < 1e-12);
        assert!(["capacity", "target", "power", "minimum"].contains(&row["operating_limit"].as_str()));
        if row["compliant"] == "true" {
            // what "compliant" promises, checked from the columns alone
            assert!(num("m_dot_op_kg_h") >= 6.0 - 1e-9 && num("p_op_w") <= 5.0 + 1e-9, "{row:?}");
            assert!(num("wire_length_m") <= 1.3055);
            assert!(row["binding_requirement"].is_empty());
        } else {
            assert_eq!(row["compliant"], "false");
            assert!(!row["binding_requirement"].is_empty(), "{row:?}");
        }
    }
}

#[test]
fn optimize_constrains_by_the_requirements_over_the_slopes_and_resumes_exactly() {
    let full = fresh_dir("full");
    let o = sawtooth().args(OPTIMIZE).args(["--generations", "10", "--out", full.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("m_dot_op") && stdout.contains("note: "), "{stdout}");
    check_front(&full);
    let manifest = std::fs::read_to_string(full.join("run.toml")).unwrap();
    let manifest: toml::Value = toml::from_str(&manifest).unwrap();
    assert_eq!(manifest["requirements"]["power_max_w"].as_float(), Some(5.0));
    let slopes: Vec<f64> = manifest["slopes_deg"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect();
    assert_eq!(slopes, [0.0, 20.0, 40.0]);
    assert_eq!(rows(&full.join("evaluations.csv")), 32 * 11);

    // killed mid-run and resumed: the same front, byte for byte
    let cut = fresh_dir("cut");
    let mut child = sawtooth()
        .args(OPTIMIZE)
        .args(["--generations", "10", "--out", cut.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while rows(&cut.join("generations.csv")) < 3 && t.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(rows(&cut.join("generations.csv")) < 10, "the run finished before it could be killed");
    let o = sawtooth()
        .args(OPTIMIZE)
        .args(["--generations", "10", "--out", cut.to_str().unwrap(), "--resume"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["pareto.csv", "evaluations.csv"] {
        assert_eq!(
            std::fs::read_to_string(full.join(f)).unwrap(),
            std::fs::read_to_string(cut.join(f)).unwrap(),
            "{f} differs after kill + resume"
        );
    }
    let _ = std::fs::remove_dir_all(&full);
    let _ = std::fs::remove_dir_all(&cut);
}

#[test]
fn optimize_over_slopes_runs_on_the_gpu_engine() {
    // lavapipe in CI; every slope of a generation in one GPU job
    if common::gpu_engine().is_none() {
        return;
    }
    let out = fresh_dir("gpu");
    let o = sawtooth()
        .args(OPTIMIZE)
        .args(["--generations", "3", "--engine", "gpu", "--out", out.to_str().unwrap()])
        .env("XDG_RUNTIME_DIR", std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_front(&out);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn when_no_design_can_meet_them_the_front_says_what_binds() {
    // on Earth over 0-40 deg nothing in the listing's bounds meets Table 2.2 (README): the
    // run still ends with a front, every design on it marked non-compliant with its reason
    let out = fresh_dir("earth");
    let o = sawtooth()
        .args(OPTIMIZE)
        .args(["--env", "earth", "--generations", "6", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("note: no front design meets the requirements (failing: "), "{stdout}");
    let front = pareto(&out);
    assert!(!front.is_empty(), "{stdout}");
    assert!(front.iter().all(|r| r["compliant"] == "false" && !r["binding_requirement"].is_empty()));
    check_front(&out);
    let _ = std::fs::remove_dir_all(&out);
}
