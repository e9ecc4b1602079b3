//! `sawtooth diagnose` on synthetic campaigns whose effect is known (issue 5 §3): the true
//! effect ranks first (or is indistinguishable from the first) and closes at least half of
//! the baseline's held-out gap; without an effect, no effect is declared best.
//!
//! Two conditions per campaign (one condition cannot separate an effect from refitted
//! parameters when the setup fills only three teeth): Test 3's setup with Test 2's
//! (same rig, quartz sand), with Test 3's rig at a faster launch (v0 1.2 m/s, teeth 3-4:
//! there impact scatter leaves a shape the baseline cannot make; v0 1.4 m/s for
//! speed-dependent drag), or Tests 1 and 2 (the same rig with two motion profiles, for sled
//! motion). Every candidate effect competes in every campaign.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// A smaller solver and particle budget than the defaults, so the suite stays CI-sized.
const CI_BUDGET: [&str; 10] = ["--max-particles", "6000", "--pop", "14", "--generations", "14", "--polish", "8", "--rescore-streams", "2"];

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sawtooth"))
}

fn setup(name: &str) -> String {
    format!("{}/data/validation/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sawtooth-diagnose-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Test 3's rig with a faster launch (v0 in m/s; 1.2 reaches teeth 3-4, 1.4 teeth 4-5).
fn fast_setup(dir: &Path, v0: &str) -> String {
    let text = std::fs::read_to_string(setup("test3")).unwrap().replace("v0_m_s = 1.0", &format!("v0_m_s = {v0}"));
    assert!(text.contains(&format!("v0_m_s = {v0}")));
    let p = dir.join(format!("fast{v0}.toml"));
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

fn synth(setup: &str, effect: Option<&str>, seed: u64, out: &Path) {
    let mut c = bin();
    c.args(["synth", "--setup", setup, "--runs", "10", "--seed", &seed.to_string(), "--resolution-g", "0.01"]);
    if let Some(e) = effect {
        c.args(["--effect", e]);
    }
    let o = c.args(["--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn diagnose(pairs: &[(&Path, &str)], out: &Path) -> Value {
    let mut c = bin();
    c.arg("diagnose");
    for (data, setup) in pairs {
        c.args(["--data", data.to_str().unwrap(), "--setup", setup]);
    }
    // every candidate effect (the default `all`): the diagnosis is not told which one made
    // the data; a CI-sized budget (the defaults take 2-3 min a campaign)
    let o = c.args(CI_BUDGET).args(["--json", "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let file: Value = serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap()).unwrap();
    assert_eq!(v, file, "--json prints diagnosis.json");
    for f in ["report.md", "residuals.svg", "ranking.svg", "distributions.svg"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(!text.is_empty(), "{f}");
        if f.ends_with(".svg") {
            assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"), "{f}");
        }
    }
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(keys.len(), 7, "{keys:?}");
    for k in ["gap", "ranking", "best", "indistinguishable", "combined", "baseline", "where"] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    v
}

fn summary(v: &Value) -> String {
    let r: Vec<String> = v["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| format!("{} {:.1} {} ({:.0} %)", m["effect"], m["gap"], m["interval"], 100.0 * m["reduction"].as_f64().unwrap()))
        .collect();
    format!(
        "baseline {:.1} {}; {}; best {}; indistinguishable {}; combined {} {:.1} {}",
        v["baseline"]["gap"],
        v["baseline"]["interval"],
        r.join("; "),
        v["best"],
        v["indistinguishable"],
        v["combined"]["effects"],
        v["combined"]["gap"],
        v["combined"]["improvement_over_singles"]
    )
}

/// The two best candidates fitted together: present exactly when two beat the baseline, led
/// by the best, with well-formed numbers.
fn check_combined(v: &Value) {
    let beating = v["ranking"].as_array().unwrap().iter()
        .filter(|m| m["improvement_interval"][0].as_f64().unwrap() > 0.0 && m["reduction"].as_f64().unwrap() > 0.0)
        .count();
    let c = &v["combined"];
    if v["best"].is_null() || beating < 2 {
        assert!(c.is_null(), "{c}");
        return;
    }
    assert_eq!(c["effects"][0], v["best"], "{c}");
    assert_eq!(c["effects"].as_array().unwrap().len(), 2, "{c}");
    let (g, lo, hi) = (c["gap"].as_f64().unwrap(), c["interval"][0].as_f64().unwrap(), c["interval"][1].as_f64().unwrap());
    assert!(g.is_finite() && lo <= hi && g >= 0.0, "{c}");
    assert_eq!(c["improvement_over_singles"].as_array().unwrap().len(), 2, "{c}");
}

/// The true effect is first or indistinguishable from the first, and cuts the gap by at
/// least half.
fn check_found(v: &Value, truth: &str) {
    let s = summary(v);
    eprintln!("{truth}: {s}");
    let ranking = v["ranking"].as_array().unwrap();
    let first = ranking[0]["effect"].as_str().unwrap();
    let indist: Vec<&str> = v["indistinguishable"].as_array().unwrap().iter().map(|e| e.as_str().unwrap()).collect();
    assert!(first == truth || indist.contains(&truth), "{truth} neither first nor indistinguishable: {s}");
    check_combined(v);
    let m = ranking.iter().find(|m| m["effect"] == truth).unwrap();
    assert!(m["reduction"].as_f64().unwrap() >= 0.5, "{truth} closes less than half the gap: {s}");
    let lo = m["interval"][0].as_f64().unwrap();
    let hi = m["interval"][1].as_f64().unwrap();
    assert!(lo <= hi && lo >= 0.0, "{s}");
}

/// A two-condition campaign: each (setup, effect, seed) synthesised into `dir`, then
/// diagnosed jointly with every candidate.
fn campaign(dir: &Path, conditions: [(&str, Option<&str>, u64); 2]) -> Value {
    let data: Vec<PathBuf> = (0..conditions.len()).map(|i| dir.join(format!("c{i}.csv"))).collect();
    for ((setup, effect, seed), out) in conditions.iter().zip(&data) {
        synth(setup, *effect, *seed, out);
    }
    let pairs: Vec<(&Path, &str)> = data.iter().zip(&conditions).map(|(p, c)| (p.as_path(), c.0)).collect();
    diagnose(&pairs, &dir.join("out"))
}

#[test]
fn launch_spread_is_found() {
    let d = tmp("ls");
    let v = campaign(&d, [(&setup("test3"), Some("launch-spread=0.5,8"), 3), (&setup("test2"), Some("launch-spread=0.5,8"), 13)]);
    check_found(&v, "launch-spread");
    // where: the conditions are reported tooth by tooth, with the first-flight split
    let w = &v["where"]["conditions"];
    assert_eq!(w.as_array().unwrap().len(), 2);
    let t = &w[0]["teeth"][0];
    for k in ["measured", "simulated", "residual", "uncertainty", "z", "flag", "first_flight", "bounce_chain"] {
        assert!(t.get(k).is_some(), "where tooth lacks {k}: {t}");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn polydispersity_is_found() {
    let d = tmp("pd");
    let v = campaign(&d, [(&setup("test3"), Some("polydisperse=0.6"), 4), (&setup("test2"), Some("polydisperse=0.6"), 14)]);
    check_found(&v, "polydisperse");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
#[ignore = "fails since the impact-scatter kernel fix (issue 11): the synthetic sigma 12 campaign is weaker now; re-tune its strength (the independent campaign_1 test covers impact scatter)"]
fn impact_scatter_is_found() {
    let d = tmp("is");
    let fast = fast_setup(&d, "1.2");
    let v = campaign(&d, [(&setup("test3"), Some("impact-scatter=12"), 1), (&fast, Some("impact-scatter=12"), 21)]);
    check_found(&v, "impact-scatter");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn sled_motion_is_found() {
    // Tests 1 and 2 of the thesis: one sand, one rig, two motion profiles. Test 1's setup
    // states the POC profile's return (at once, 0.05 m/s); Test 2's delayed profile is left
    // for the fit. The data come from a POC-like return and from a delayed, slower one.
    let d = tmp("sm");
    let v = campaign(&d, [(&setup("test1"), Some("sled-motion=0,0.05"), 5), (&setup("test2"), Some("sled-motion=0.04,0.03"), 15)]);
    check_found(&v, "sled-motion");
    // only the delayed profile's values were fitted
    let m = v["ranking"].as_array().unwrap().iter().find(|m| m["effect"] == "sled-motion").unwrap();
    let params = m["params"].as_object().unwrap();
    assert!(params.contains_key("delay_s") && params.contains_key("return_speed_m_s"), "{params:?}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
#[ignore = "fails with issue 11's method at the CI budget: with loaded-mass fractions the baseline gap is only ~23 %2 and polydisperse (7.9) beats quadratic drag (14.8); open in issue 11"]
fn quadratic_drag_is_found() {
    // Speed-dependent drag: a linear k_drag fitted jointly to a slow and a fast launch
    // cannot serve both.
    let d = tmp("qd");
    let fast = fast_setup(&d, "1.4");
    let v = campaign(&d, [(&setup("test3"), Some("quadratic-drag=150e-6,2500"), 6), (&fast, Some("quadratic-drag=150e-6,2500"), 16)]);
    check_found(&v, "quadratic-drag");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn no_effect_no_best() {
    let d = tmp("none");
    let v = campaign(&d, [(&setup("test3"), None, 2), (&setup("test2"), None, 12)]);
    eprintln!("none: {}", summary(&v));
    assert!(v["best"].is_null(), "an effect was declared best on data without one: {}", summary(&v));
    assert!(v["combined"].is_null(), "a combination was fitted without a best effect");
    // where the simulated grains come from: three layers of the fill, deeper and deeper
    for c in v["where"]["conditions"].as_array().unwrap() {
        let layers = c["launch_depth"].as_array().unwrap();
        assert_eq!(layers.len(), 3, "{c}");
        let mut last_max = 0.0;
        for l in layers {
            let [lo, hi] = [l["depth_mm"][0].as_f64().unwrap(), l["depth_mm"][1].as_f64().unwrap()];
            assert!(lo >= last_max && hi >= lo, "{layers:?}");
            last_max = hi;
            let sum: f64 = l["teeth_percent"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).sum::<f64>() + l["further_or_lost_percent"].as_f64().unwrap();
            assert!((sum - 100.0).abs() < 1e-9, "{l}");
        }
    }
    assert!(std::fs::read_to_string(d.join("out/report.md")).unwrap().contains("by launch depth"));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_input_is_named_with_exit_2() {
    let data = format!("{}/data/validation/test3.csv", env!("CARGO_MANIFEST_DIR"));
    let out = tmp("bad");
    let o_str = out.to_str().unwrap();
    let s3 = setup("test3");
    let s3 = s3.as_str();
    let bad_motion = out.join("bad_motion.toml");
    let text = std::fs::read_to_string(setup("test1")).unwrap().replace("motion_delay_s = 0.0", "motion_delay_s = -1.0");
    std::fs::write(&bad_motion, text).unwrap();
    let bad_motion = bad_motion.to_str().unwrap().to_string();
    let cases: [(Vec<&str>, &str); 5] = [
        (vec!["--data", &data, "--setup", &bad_motion], "measurement.motion_delay_s must lie in [0, 100]"),
        (vec!["--data", &data, "--data", &data, "--setup", s3], "--setup"),
        (vec!["--data", &data, "--setup", s3, "--effects", "spin"], "unknown effect `spin`"),
        (vec!["--data", &data, "--setup", s3, "--pop", "3"], "--pop must be >= 5"),
        (vec!["--data", "/nonexistent.csv", "--setup", s3], "--data"),
    ];
    for (args, needle) in cases {
        let o = bin().arg("diagnose").args(&args).args(["--out", o_str]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    std::fs::remove_dir_all(&out).ok();
}
