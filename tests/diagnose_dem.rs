//! `sawtooth diagnose` on the committed DEM campaigns of `data/dem/` (issue 32, item 1): data
//! made by a real discrete-element engine (LIGGGHTS; grain–grain collisions, rolling, spin,
//! Hertz contacts), not by a simulator of the thesis's model. The DEM contains none of the
//! candidate effects except where one was put in (the sled's return, the polydisperse size
//! law), so the tool must not call a gap "explained" by a candidate the DEM does not contain,
//! and must find the stated sled return when it is in the data.
//!
//! The campaigns are read from `data/dem/` (made by `scripts/dem-campaigns.sh`, see its
//! README), so no LIGGGHTS is needed here. Three conditions each (the campaign rig's slow,
//! fast and shallow), diagnosed with every candidate at a CI-sized particle budget.

mod common;
use common::campaigns::{dem_campaign as campaign, ranked, summary};

use serde_json::Value;

/// The default solver budget with fewer particles, so the suite stays CI-sized. The data's
/// own noise (3 runs of 150 grains) dominates the floor at this budget.
const CI_BUDGET: [&str; 2] = ["--max-particles", "2000"];

/// Whether this heavy test runs (a three-condition diagnosis each, a minute or two on 2 cores).
fn heavy(test: &str) -> bool {
    common::full_tier(test, "a three-condition diagnosis of DEM data with every candidate")
}

/// Diagnose the named campaigns (one condition each) with every candidate; diagnosis.json.
fn diagnose(campaigns: &[&str], tag: &str) -> Value {
    let mut c = common::sawtooth();
    c.arg("diagnose");
    for name in campaigns {
        let (data, setup) = campaign(name);
        c.arg("--data").arg(data).arg("--setup").arg(setup);
    }
    let out = common::scratch(&format!("diagnose-dem-{tag}"));
    let o = c.args(CI_BUDGET).args(["--json", "--out"]).arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    v
}

/// What the tool may say about a DEM campaign that contains the candidate effects `contained`
/// and physics outside the candidates' family: a candidate it does not contain is never the
/// explanation; it may close a part of the gap (`partly-explained`), as out-of-family physics
/// can look partly like a candidate; otherwise the answer is "none of these".
fn assert_names_only_what_the_dem_contains(v: &Value, contained: &[&str]) {
    let s = summary(v);
    let verdict = v["verdict"].as_str().unwrap();
    let best = v["best"].as_str();
    if verdict == "explained" {
        assert!(best.is_some_and(|b| contained.contains(&b)), "explained by a candidate the DEM lacks: {s}");
    }
    if let Some(b) = best {
        assert!(contained.contains(&b) || verdict == "partly-explained", "{b} named as the cause: {s}");
    }
}

/// Effects that the DEM campaigns without a return or a size law lack altogether: one grain
/// size, linear (Stokes) drag, a sled that does not move after the stroke.
const ABSENT: [&str; 3] = ["polydisperse", "quadratic-drag", "sled-motion"];

/// The deep fill (150 grains carrying the model's fill mass) at the rig's three conditions:
/// the gap is real (the DEM's grain–grain collisions, rolling and spin are not the model's)
/// and no candidate is its cause.
#[test]
fn a_deep_dem_fill_is_not_explained_by_a_candidate_it_does_not_contain() {
    if !heavy("diagnose_dem::a_deep_dem_fill_is_not_explained_by_a_candidate_it_does_not_contain") {
        return;
    }
    let v = diagnose(&["earth-deep-slow", "earth-deep-fast", "earth-deep-shallow"], "deep");
    let s = summary(&v);
    let over = v["verdict_detail"]["baseline"]["gap_over_floor"].as_f64().unwrap();
    assert!(over > 3.0, "the DEM's gap is well above the data's noise: {over}x; {s}");
    assert_names_only_what_the_dem_contains(&v, &[]);
    assert!(
        ["unexplained", "partly-explained"].contains(&v["verdict"].as_str().unwrap()),
        "out-of-family physics: {s}"
    );
    assert!(v["best"].as_str().is_none_or(|b| !ABSENT.contains(&b)), "{s}");
}

/// The slow condition with the sled returning at once at 0.3 m/s while the grains fly (a real
/// movement of the DEM's mesh, stated in the setup), beside the resting fast and shallow
/// conditions: the sled-motion candidate is the best and removes most of the gap; what it
/// leaves is the DEM's out-of-family rest.
#[test]
fn a_stated_sled_return_in_the_dem_is_found() {
    if !heavy("diagnose_dem::a_stated_sled_return_in_the_dem_is_found") {
        return;
    }
    let v = diagnose(&["earth-deep-slow-return", "earth-deep-fast", "earth-deep-shallow"], "return");
    let s = summary(&v);
    assert_eq!(v["best"], "sled-motion", "{s}");
    let reduction = ranked(&v, "sled-motion")["reduction"].as_f64().unwrap();
    assert!(reduction > 0.5, "the return is most of this gap: {reduction}; {s}");
    assert_names_only_what_the_dem_contains(&v, &["sled-motion"]);
}

/// The monolayer (40 grains of the deep fill's size lining the catch, a quarter of its mass):
/// fewer grain–grain collisions than the deep fill, still none of the candidates.
#[test]
fn a_dem_monolayer_is_not_explained_by_a_candidate_it_does_not_contain() {
    if !heavy("diagnose_dem::a_dem_monolayer_is_not_explained_by_a_candidate_it_does_not_contain") {
        return;
    }
    let v = diagnose(&["earth-mono-slow", "earth-mono-fast", "earth-mono-shallow"], "mono");
    let s = summary(&v);
    assert_names_only_what_the_dem_contains(&v, &[]);
    assert!(v["best"].as_str().is_none_or(|b| !ABSENT.contains(&b)), "{s}");
}

/// The deep fill with the polydisperse size law (log-normal, σ 0.3 of ln d; five size classes,
/// each with its own Stokes drag): the size law is the only candidate the DEM contains; a
/// Schiller–Naumann drag or a moving sled is not in it.
#[test]
fn a_polydisperse_dem_fill_names_at_most_the_size_law() {
    if !heavy("diagnose_dem::a_polydisperse_dem_fill_names_at_most_the_size_law") {
        return;
    }
    let v = diagnose(&["earth-poly-slow", "earth-poly-fast", "earth-poly-shallow"], "poly");
    let s = summary(&v);
    assert_names_only_what_the_dem_contains(&v, &["polydisperse"]);
    assert!(v["best"].as_str().is_none_or(|b| !["quadratic-drag", "sled-motion"].contains(&b)), "{s}");
}
