//! `sawtooth diagnose` beyond its own family (issue 32): data whose shape no candidate can
//! produce comes out `unexplained` ("none of these") with the residual no candidate removes;
//! a sled motion that no setup states is found from the data (two motions, one between the
//! motion screen's grid points); a subtle effect (an impact scatter of 11°, 300 µm beads'
//! quadratic drag, a narrow spread of grain sizes, each well above the noise floor) is named
//! or narrowed to at most three.
//!
//! Three conditions per campaign on the practice campaigns' rig (`data/campaign_rig`), made
//! by `synth` (10 runs each) and diagnosed with every candidate at a CI-sized budget.

use std::path::Path;

use crate::common;
use common::campaigns::{diagnose, diagnose_with, rig_setup, summary, synth, RIG};
use common::scratch;

/// Whether a heavy test runs: each is a three-condition diagnosis with every candidate (the
/// unstated-motion ones with the motion screen besides), minutes on 2 cores.
fn heavy(test: &str) -> bool {
    common::full_tier(test, "a three-condition diagnosis with every candidate")
}

/// A run's masses with `share` of its loaded mass moved from its modal tooth to tooth 1
/// (grains that never launch) and `tail` to the tooth after the mode (a fast tail): a
/// shape the thesis's model and its candidate effects do not make.
fn reshape(csv: &str, share: f64, tail: f64) -> String {
    let mut out = String::new();
    let mut header = true;
    for line in csv.lines() {
        if line.starts_with('#') || header {
            header &= line.starts_with('#');
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let (run, teeth, input) = (cells[0], &cells[1..cells.len() - 1], cells[cells.len() - 1]);
        let mut m = teeth.to_vec();
        let k = (0..m.len()).max_by(|a, b| m[*a].total_cmp(&m[*b])).unwrap();
        let to_first = (share * input * 100.0).round() / 100.0;
        let to_next = if k + 1 < m.len() { (tail * input * 100.0).round() / 100.0 } else { 0.0 };
        m[k] -= to_first + to_next;
        m[0] += to_first;
        if to_next > 0.0 {
            m[k + 1] += to_next;
        }
        let cells: Vec<String> = m.iter().map(|x| format!("{x:.2}")).collect();
        out.push_str(&format!("{run},{},{input:.2}\n", cells.join(",")));
    }
    out
}

#[test]
fn reshape_moves_the_stated_shares_and_keeps_the_mass() {
    let csv = "# c\nrun,tooth_1,tooth_2,tooth_3,input_mass\n1,0.00,0.50,1.50,2.00\n";
    let r = reshape(csv, 0.1, 0.05);
    assert_eq!(r, "# c\nrun,tooth_1,tooth_2,tooth_3,input_mass\n1,0.20,0.50,1.30,2.00\n");
    let csv = "run,tooth_1,tooth_2,input_mass\n1,0.20,1.70,2.00\n";
    assert_eq!(
        reshape(csv, 0.1, 0.05),
        "run,tooth_1,tooth_2,input_mass\n1,0.40,1.50,2.00\n",
        "no tooth after the mode"
    );
}

/// 12 % of every run's mass stays in tooth 1 and 8 % goes one tooth further than the rest:
/// no candidate makes that shape. The verdict says "none of these", the baseline's gap is
/// well above its floor, no effect is named the cause, and the tooth-1 excess is the
/// residual that every model leaves, in every condition.
#[test]
fn data_whose_shape_no_candidate_makes_is_unexplained() {
    if !heavy("diagnose_beyond::data_whose_shape_no_candidate_makes_is_unexplained") {
        return;
    }
    let d = scratch("oof");
    let mut pairs = Vec::new();
    for (i, n) in RIG.iter().enumerate() {
        let plain = d.join(format!("{n}-plain.csv"));
        synth(&rig_setup(n), None, 400 + i as u64, &plain);
        let data = d.join(format!("{n}.csv"));
        std::fs::write(&data, reshape(&std::fs::read_to_string(&plain).unwrap(), 0.12, 0.08)).unwrap();
        pairs.push((data, rig_setup(n)));
    }
    let v = diagnose(&pairs, &d.join("out"));
    let s = summary(&v);
    eprintln!("out of family: {s}");
    assert_eq!(v["verdict"], "unexplained", "{s}");
    assert!(v["best"].is_null(), "{s}");
    let detail = &v["verdict_detail"];
    assert!(detail["remaining"]["gap_over_floor"].as_f64().unwrap() > detail["floor_factor"].as_f64().unwrap(), "{s}");
    assert!(detail["text"].as_str().unwrap().starts_with("none of these"), "{s}");
    for c in detail["not_removed"].as_array().unwrap() {
        // tooth 1 (the grains that stayed) is missed by every model beyond the noise, on
        // one side or the other (a fit may overshoot it to serve the other teeth)
        let t1 = &c["bins"][0];
        assert_eq!(t1["bin"], "tooth 1", "{c}");
        assert!(t1["residual"].as_f64().unwrap().abs() > 1.0 && t1["flag"] == true, "{c}");
        assert!(c["sse"].as_f64().unwrap() > c["floor"].as_f64().unwrap(), "{c}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The rig's three setups without their `motion_*` lines, written into `d`.
fn unstated_setups(d: &Path) -> Vec<String> {
    RIG.iter()
        .map(|n| {
            let text = std::fs::read_to_string(rig_setup(n)).unwrap();
            assert!(text.contains("motion_delay_s"), "the rig's setups state the motion; this test removes it");
            let unstated: String =
                text.lines().filter(|l| !l.starts_with("motion_")).map(|l| format!("{l}\n")).collect();
            let setup = d.join(format!("{n}.toml"));
            std::fs::write(&setup, unstated).unwrap();
            setup.to_str().unwrap().to_string()
        })
        .collect()
}

/// Every condition's sled moves after the launch as `effect` says (`sled-motion=DELAY,SPEED`)
/// and no setup says so: the sled-motion candidate searches the delay and the return speed,
/// and is named, with its fitted motion returned for the caller to check.
fn unstated_motion_is_found(tag: &str, effect: &str, seed: u64) -> (f64, f64, String) {
    let d = scratch(tag);
    let mut pairs = Vec::new();
    for (i, (n, setup)) in RIG.iter().zip(unstated_setups(&d)).enumerate() {
        let data = d.join(format!("{n}.csv"));
        synth(&setup, Some(effect), seed + i as u64, &data);
        pairs.push((data, setup));
    }
    let v = diagnose(&pairs, &d.join("out"));
    let s = summary(&v);
    eprintln!("unstated motion {effect}: {s}");
    assert_eq!(v["best"], "sled-motion", "{s}");
    assert_ne!(v["verdict"], "unexplained", "{s}");
    // the screen's whole grid comes with the diagnosis: 2 delays × 6 speeds × both
    // directions, the best of them among those that fit about as well
    let screen = &v["motion_screen"]["points"];
    assert_eq!(screen.as_array().map(Vec::len), Some(24), "{s}");
    assert_eq!(screen[0]["about_as_well"], true, "{s}");
    let m = v["ranking"].as_array().unwrap().iter().find(|m| m["effect"] == "sled-motion").unwrap();
    let (delay, speed) = (m["params"]["delay_s"].as_f64().unwrap(), m["params"]["return_speed_m_s"].as_f64().unwrap());
    std::fs::remove_dir_all(&d).ok();
    (delay, speed, s)
}

/// Every condition's sled returns at once at 0.3 m/s and no setup says so: found, with
/// about that motion (the baseline, fitted without a motion, has bent k_elastic to mimic it;
/// the motion screen searches the shared parameters at every point of its grid).
#[test]
fn sled_motion_that_no_setup_states_is_found() {
    if !heavy("diagnose_beyond::sled_motion_that_no_setup_states_is_found") {
        return;
    }
    let (delay, speed, s) = unstated_motion_is_found("unstated", "sled-motion=0,0.3", 200);
    assert!(delay < 0.03 && (0.15..=0.6).contains(&speed), "fitted motion {delay} s, {speed} m/s: {s}");
}

/// A sled that rests 0.05 s, then returns at 0.5 m/s, and no setup says so: found, with
/// about that motion. A grid point of the motion screen, but not an easy one: a short DE
/// leaves its shared parameters unconverged, and on raw SSEs a slow return at once fits
/// about as well (the handling spill; docs/diagnosis-report.md), so the screen must rank
/// its grid at the full budget on the loss-adjusted gap.
#[test]
fn a_delayed_unstated_sled_motion_is_found() {
    if !heavy("diagnose_beyond::a_delayed_unstated_sled_motion_is_found") {
        return;
    }
    let (delay, speed, s) = unstated_motion_is_found("unstated-delayed", "sled-motion=0.05,0.5", 210);
    assert!(
        (0.02..=0.09).contains(&delay) && (0.3..=0.8).contains(&speed),
        "fitted motion {delay} s, {speed} m/s: {s}"
    );
}

/// `effect` in every condition of the rig (seeds `seed`, +1, +2): where the true model
/// halves the baseline's gap and the noise floor is far below it, the effect is named, or
/// narrowed to at most three candidates with it among them (the practice campaigns'
/// grading).
fn subtle_effect_is_resolved(tag: &str, effect: &str, seed: u64) {
    let d = scratch(tag);
    let mut pairs = Vec::new();
    for (i, n) in RIG.iter().enumerate() {
        let data = d.join(format!("{n}.csv"));
        synth(&rig_setup(n), Some(effect), seed + i as u64, &data);
        pairs.push((data, rig_setup(n)));
    }
    let v = diagnose(&pairs, &d.join("out"));
    let s = summary(&v);
    eprintln!("{effect}: {s}");
    let name = effect.split('=').next().unwrap();
    let together: Vec<&str> = v["indistinguishable"].as_array().unwrap().iter().map(|e| e.as_str().unwrap()).collect();
    let named = v["best"] == name || (!v["best"].is_null() && together.contains(&name) && together.len() <= 3);
    assert!(named, "{s}");
    std::fs::remove_dir_all(&d).ok();
}

/// An impact scatter of 11° at every impact: the true model removes four fifths of the
/// baseline's gap.
#[test]
fn a_subtle_impact_scatter_is_resolved() {
    if !heavy("diagnose_beyond::a_subtle_impact_scatter_is_resolved") {
        return;
    }
    subtle_effect_is_resolved("subtle", "impact-scatter=11", 300);
}

/// The Schiller–Naumann drag of 300 µm glass beads: on this rig most of the baseline's raw
/// gap is the runs' spill; once that is allowed, the true model more than halves it.
#[test]
fn a_subtle_quadratic_drag_is_resolved() {
    if !heavy("diagnose_beyond::a_subtle_quadratic_drag_is_resolved") {
        return;
    }
    subtle_effect_is_resolved("subtle-qd", "quadratic-drag=300e-6,2500", 310);
}

/// Grain sizes log-normal with σ_ln 0.08 about the nominal (σ_ln 0.2 is no subtle effect on
/// this rig: the baseline misses by 170 %²): the true model halves a baseline gap of about
/// 10 %², 8× its noise floor.
#[test]
fn a_subtle_polydispersity_is_resolved() {
    if !heavy("diagnose_beyond::a_subtle_polydispersity_is_resolved") {
        return;
    }
    subtle_effect_is_resolved("subtle-poly", "polydisperse=0.08", 320);
}

/// The names in a diagnosis.json's indistinguishable set.
fn together(v: &serde_json::Value) -> Vec<String> {
    v["indistinguishable"].as_array().unwrap().iter().map(|e| e.as_str().unwrap().to_string()).collect()
}

/// Three conditions that differ only in their runs (the rig's fast setup three times) leave
/// an impact scatter of 10° in a set with a candidate that widens the landings alike (10° is
/// below what they resolve, 13.9°; at 11° the candidate's profile starts already tell it
/// apart, and on the slow setup no strength up to 30° is resolved at all);
/// `--suggest` names an additional condition that would separate them, and with that
/// condition measured (synthesised with the same effect) and added, the diagnosis no longer
/// leaves the others beside it (issue 46, item 3).
#[test]
fn the_suggested_condition_separates_what_three_could_not() {
    if !heavy("diagnose_beyond::the_suggested_condition_separates_what_three_could_not") {
        return;
    }
    let d = scratch("suggest");
    let truth = "impact-scatter";
    let fast = rig_setup("fast");
    let mut pairs: Vec<(std::path::PathBuf, String)> = Vec::new();
    for i in 0..3u64 {
        let data = d.join(format!("fast{i}.csv"));
        synth(&fast, Some("impact-scatter=10"), 600 + i, &data);
        pairs.push((data, fast.clone()));
    }
    let v = diagnose_with(&pairs, &d.join("three"), &["--suggest"]);
    let s = summary(&v);
    eprintln!("three alike: {s}");
    let before = together(&v);
    assert!(before.len() >= 2 && before.iter().any(|e| e == truth), "three alike conditions tell it apart: {s}");
    let top = &v["suggestions"]["proposals"][0];
    eprintln!("suggested: {top}");
    assert_eq!(top["separates"], true, "{top}");
    // the suggested condition, measured: the rig's setup with the change made
    let (var, value) = top["change"].as_object().unwrap().iter().next().unwrap();
    let value = value.as_f64().unwrap();
    let base = std::fs::read_to_string(&fast).unwrap();
    let key = match var.as_str() {
        "v0_m_s" => Some("v0_m_s"),
        "a_m_s2" => Some("a_m_s2"),
        "alpha_deg" => Some("alpha_deg"),
        "runs" => None,
        other => panic!("unknown change {other}"),
    };
    let text: String = base
        .lines()
        .map(|l| match key {
            Some(k) if l.starts_with(&format!("{k} =")) => format!("{k} = {value}\n"),
            _ => format!("{l}\n"),
        })
        .collect();
    let setup = d.join("suggested.toml");
    std::fs::write(&setup, text).unwrap();
    let data = d.join("suggested.csv");
    synth(setup.to_str().unwrap(), Some("impact-scatter=10"), 610, &data);
    pairs.push((data, setup.to_str().unwrap().to_string()));
    let w = diagnose(&pairs, &d.join("four"));
    let s = summary(&w);
    eprintln!("with the suggested condition: {s}");
    assert_eq!(w["best"], truth, "{s}");
    // every candidate the suggestion said it would tell from the truth is told apart
    let after = together(&w);
    let claimed: Vec<&str> = top["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["separation"].as_f64().unwrap() > 3.0 && (p["a"] == truth || p["b"] == truth))
        .map(|p| if p["a"] == truth { p["b"].as_str().unwrap() } else { p["a"].as_str().unwrap() })
        .collect();
    assert!(!claimed.is_empty(), "{top}");
    for other in claimed {
        assert!(!after.iter().any(|e| e == other), "`{other}` still beside {truth}: {s}");
    }
    std::fs::remove_dir_all(&d).ok();
}
