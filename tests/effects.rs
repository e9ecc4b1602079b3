//! The optional effects of issue 5: off by default (the thesis's model unchanged), each one
//! changes what it should, deterministic per seed, and refused by engines that lack it.

use std::process::Command;

use sawtooth::engine::{evaluate_detailed, particle_engine, EngineKind};
use sawtooth::io::config::ConfigFile;
use sawtooth::model::effects::{Effects, ImpactScatter, LaunchSpread, Polydisperse};
use sawtooth::model::{Design, Scenario, SimOutcome};

fn rig() -> (Scenario, Design) {
    let c = ConfigFile::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/data/validation/test3.toml"))).unwrap();
    let mut s = c.scenario().unwrap();
    s.sim.particles = 400;
    (s, c.design().unwrap())
}

fn sim(s: &Scenario, d: &Design) -> SimOutcome {
    evaluate_detailed(particle_engine(EngineKind::Cpu).as_ref(), s, d, false).unwrap().evaluation.sim
}

fn l1(a: &SimOutcome, b: &SimOutcome) -> f64 {
    a.distribution.iter().zip(&b.distribution).map(|(x, y)| (x - y).abs()).sum::<f64>() + (a.lost_fraction - b.lost_fraction).abs()
}

#[test]
fn effects_are_off_by_default_and_each_one_moves_the_distribution() {
    let (s, d) = rig();
    assert!(!s.effects.any());
    let base = sim(&s, &d);
    let cases = [
        Effects { impact_scatter: Some(ImpactScatter { sigma_deg: 10.0 }), ..Default::default() },
        Effects { launch_spread: Some(LaunchSpread { speed_spread: 0.4, angle_sigma_deg: 5.0 }), ..Default::default() },
        Effects { polydisperse: Some(Polydisperse { sigma_ln: 0.5 }), ..Default::default() },
    ];
    for e in cases {
        let mut s2 = s.clone();
        s2.effects = e;
        let with = sim(&s2, &d);
        assert!(l1(&base, &with) > 0.05, "{:?} changed the distribution by only {}", e.active(), l1(&base, &with));
        assert_eq!(with.distribution, sim(&s2, &d).distribution, "deterministic per seed");
    }
}

#[test]
fn polydispersity_does_nothing_in_vacuum() {
    let mut s = Scenario::lunar();
    s.sim.particles = 200;
    let d = Design::lunar_solution_c();
    let base = sim(&s, &d);
    s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.5 });
    assert_eq!(base.distribution, sim(&s, &d).distribution);
}

#[test]
fn launch_spread_slows_the_transport() {
    // slower, earlier departures cannot carry grains further on average
    let (s, d) = rig();
    let base = sim(&s, &d);
    let mut s2 = s.clone();
    s2.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.5, angle_sigma_deg: 0.0 });
    assert!(sim(&s2, &d).advance_m < base.advance_m);
}

#[test]
fn config_files_and_flags_carry_effects_and_other_engines_refuse_them() {
    let c = ConfigFile::parse("[effects.impact_scatter]\nsigma_deg = 4\n[effects.polydisperse]\nsigma_ln = 0.3\n").unwrap();
    let s = c.scenario().unwrap();
    assert_eq!(s.effects.active(), vec!["impact-scatter", "polydisperse"]);
    assert!(ConfigFile::parse("[effects.impact_scatter]\nsigma = 4\n").is_err());
    let bin = env!("CARGO_BIN_EXE_sawtooth");
    let setup = concat!(env!("CARGO_MANIFEST_DIR"), "/data/validation/test3.toml");
    let o = Command::new(bin).args(["simulate", "--config", setup, "--effect", "impact-scatter=5", "--engine", "listing"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("in the cpu and gpu engines only"));
    let o = Command::new(bin).args(["simulate", "--config", setup, "--effect", "wobble=1"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown effect"));
    let o = Command::new(bin).args(["simulate", "--config", setup, "--effect", "impact-scatter=3", "--json"]).output().unwrap();
    assert!(o.status.success());
}
