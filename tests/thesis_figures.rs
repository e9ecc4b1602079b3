//! The published figures the spec's README lists, held against both particle engines.

use sawtooth::engine::{evaluate_detailed, particle_engine, EngineKind, Evaluation};
use sawtooth::model::{Design, Scenario};

fn eval(kind: EngineKind, s: &Scenario, d: &Design) -> Evaluation {
    evaluate_detailed(particle_engine(kind).as_ref(), s, d, false).expect("valid design").evaluation
}

const ENGINES: [EngineKind; 2] = [EngineKind::Cpu, EngineKind::Listing];

#[test]
fn lunar_solution_c_stroke_frequency_and_cooling_in_every_mode() {
    for s in [Scenario::lunar(), Scenario::lunar().into_listing_compat()] {
        let p = eval(EngineKind::Cpu, &s, &Design::lunar_solution_c()).performance;
        assert!((p.t_cool_s - 27.54).abs() < 0.005, "t_cool {}", p.t_cool_s);
        assert!((p.stroke_m * 1e3 - 11.01).abs() < 0.01, "stroke {}", p.stroke_m);
        assert!((p.f_stroke_hz - 0.03598).abs() < 0.000005, "f_stroke {}", p.f_stroke_hz);
    }
}

#[test]
fn compat_lunar_solution_c_reproduces_table_c6() {
    let s = Scenario::lunar().into_listing_compat();
    for kind in ENGINES {
        let e = eval(kind, &s, &Design::lunar_solution_c());
        // erratum 13: fill ≈ 1154 mm² with the listing's 10-point arc
        assert!((e.sim.fill_area_mm2 - 1154.0).abs() < 3.0, "{kind:?} fill {}", e.sim.fill_area_mm2);
        assert_eq!(e.performance.n_wire, 35, "{kind:?}");
        assert!((0.15..=0.19).contains(&e.sim.d_avg_m), "{kind:?} d_avg {}", e.sim.d_avg_m);
        assert!((0.017..=0.022).contains(&e.performance.m_dot_kg_s), "{kind:?} m_dot {}", e.performance.m_dot_kg_s);
    }
}

#[test]
fn compat_terrestrial_solution_c_reproduces_table_5_2() {
    let s = Scenario::earth().into_listing_compat();
    for kind in ENGINES {
        let e = eval(kind, &s, &Design::earth_solution_c());
        assert!((e.sim.fill_area_mm2 - 693.0).abs() < 6.0, "{kind:?} fill {}", e.sim.fill_area_mm2);
        assert!((51..=53).contains(&e.performance.n_wire), "{kind:?} n_wire {}", e.performance.n_wire);
        assert!((0.06..=0.08).contains(&e.sim.d_avg_m), "{kind:?} d_avg {}", e.sim.d_avg_m);
        let stroke_mm = e.performance.stroke_m * 1e3;
        assert!((stroke_mm - 14.4).abs() < 0.05, "stroke {stroke_mm}");
        assert!((e.performance.f_stroke_hz - 0.03590).abs() < 0.00001);
    }
}

#[test]
fn physical_mode_moves_lunar_solution_c_further_than_the_listing() {
    // README (spec): the text's physics gives d_avg ≈ 0.21 m where the listing gives ≈ 0.17 m.
    let phys = eval(EngineKind::Cpu, &Scenario::lunar(), &Design::lunar_solution_c());
    let list = eval(EngineKind::Cpu, &Scenario::lunar().into_listing_compat(), &Design::lunar_solution_c());
    assert!((0.19..=0.24).contains(&phys.sim.d_avg_m), "physical d_avg {}", phys.sim.d_avg_m);
    assert!(phys.sim.d_avg_m > list.sim.d_avg_m);
    // the text's width (0.16 m) and the same tooth count give the physical fill mass
    assert!((phys.sim.fill_area_mm2 - 1154.0).abs() < 3.0);
    assert_eq!(phys.sim.lost_fraction, 0.0);
}

#[test]
fn validation_rig_simulates_with_both_launch_angles() {
    // Table 4.3 with the fitted parameters of 4.3.5, 20 teeth; launch at α + 18.434° and at α.
    for offset in [18.434, 0.0] {
        let mut s = Scenario::earth();
        s.material = sawtooth::model::scenario::Material::glass_beads();
        s.collision.k_elastic = 0.854;
        s.collision.mu_friction = 0.133;
        s.environment.k_drag = Some(5.347);
        s.sim.teeth = 20;
        s.sim.launch_offset_deg = offset;
        for s in [s.clone(), s.into_listing_compat()] {
            let e = eval(EngineKind::Cpu, &s, &Design::validation_rig());
            let total: f64 = e.sim.distribution.iter().sum::<f64>() + e.sim.lost_fraction;
            assert!((total - 1.0).abs() < 1e-12);
        }
    }
}
