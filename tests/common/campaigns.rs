//! Synthetic measurement campaigns diagnosed by the CLI (tests/diagnose.rs,
//! tests/diagnose_beyond.rs): conditions made by `sawtooth synth` on the validation rig
//! (`data/validation`) or the practice campaigns' rig (`data/campaign_rig`), then
//! `sawtooth diagnose` with every candidate at a CI-sized budget.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::sawtooth;

/// The default solver budget with fewer particles than the data call for (12 000 by
/// default), so the suite stays CI-sized.
pub const CI_BUDGET: [&str; 2] = ["--max-particles", "6000"];

/// The rig of the independent practice campaigns (`data/campaign_rig`): glass beads on the
/// Table-4.3 rig at v0 1.1 and 1.4 m/s on a 30° incline and 1.1 m/s on 15°.
pub const RIG: [&str; 3] = ["slow", "fast", "shallow"];

/// A setup of the practice campaigns' rig (`slow`, `fast`, `shallow`).
pub fn rig_setup(name: &str) -> String {
    format!("{}/data/campaign_rig/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// A setup of the validation rig (`test1`..`test3`, Table 4.3).
pub fn validation_setup(name: &str) -> String {
    format!("{}/data/validation/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// Ten synthetic runs of `setup` (with `effect` withheld from the model, if any) into `out`.
pub fn synth(setup: &str, effect: Option<&str>, seed: u64, out: &Path) {
    let mut c = sawtooth();
    c.args(["synth", "--setup", setup, "--runs", "10", "--seed", &seed.to_string(), "--resolution-g", "0.01"]);
    if let Some(e) = effect {
        c.args(["--effect", e]);
    }
    let o = c.arg("--out").arg(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Diagnose the (data, setup) pairs with every candidate effect (the default `all`: the
/// diagnosis is not told which one made the data) at the CI budget; the printed JSON is
/// diagnosis.json's and report.md states its verdict. Returns diagnosis.json.
pub fn diagnose(pairs: &[(impl AsRef<Path>, impl AsRef<str>)], out: &Path) -> Value {
    diagnose_with(pairs, out, &[])
}

/// [`diagnose`] with `extra` flags (`--suggest`).
pub fn diagnose_with(pairs: &[(impl AsRef<Path>, impl AsRef<str>)], out: &Path, extra: &[&str]) -> Value {
    let mut c = sawtooth();
    c.arg("diagnose");
    for (data, setup) in pairs {
        c.arg("--data").arg(data.as_ref()).args(["--setup", setup.as_ref()]);
    }
    let o = c.args(CI_BUDGET).args(extra).arg("--json").arg("--out").arg(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let file: Value = serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap()).unwrap();
    assert_eq!(v, file, "--json prints diagnosis.json");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains(&format!("## Verdict: {}", v["verdict"].as_str().unwrap())),
        "report.md states the verdict"
    );
    v
}

/// A committed DEM campaign of `data/dem` (made by `sawtooth dem run`): its data and setup.
pub fn dem_campaign(name: &str) -> (PathBuf, PathBuf) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/dem").join(name);
    (dir.join("dem.csv"), dir.join("setup.toml"))
}

/// The ranking entry of `effect` in a diagnosis.json.
pub fn ranked<'a>(v: &'a Value, effect: &str) -> &'a Value {
    v["ranking"].as_array().unwrap().iter().find(|m| m["effect"] == effect).expect(effect)
}

/// A diagnosis.json in one line, for assertion messages: the baseline's gap, each candidate's
/// gap, interval, reduction and fitted parameters, best, the indistinguishable set, the
/// combined model and the verdict.
pub fn summary(v: &Value) -> String {
    let r: Vec<String> = v["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            format!(
                "{} {:.1} {} ({:.0} %) {}",
                m["effect"],
                m["gap"],
                m["interval"],
                100.0 * m["reduction"].as_f64().unwrap(),
                m["params"]
            )
        })
        .collect();
    format!(
        "baseline {:.1} {}; {}; best {}; indistinguishable {}; combined {} {:.1} {}; verdict {}: {}",
        v["baseline"]["gap"],
        v["baseline"]["interval"],
        r.join("; "),
        v["best"],
        v["indistinguishable"],
        v["combined"]["effects"],
        v["combined"]["gap"],
        v["combined"]["improvement_over_singles"],
        v["verdict"],
        v["verdict_detail"]["text"]
    )
}
