use sawtooth::engine::*;
use sawtooth::model::*;
fn main() {
    for (name, sc, d) in [
        ("lunar phys", Scenario::lunar(), Design::lunar_solution_c()),
        ("lunar compat", Scenario::lunar().into_listing_compat(), Design::lunar_solution_c()),
        ("earth phys", Scenario::earth(), Design::earth_solution_c()),
        ("earth compat", Scenario::earth().into_listing_compat(), Design::earth_solution_c()),
    ] {
        for kind in [EngineKind::Cpu, EngineKind::Listing] {
            let e = particle_engine(kind);
            let t = std::time::Instant::now();
            let r = evaluate_detailed(e.as_ref(), &sc, &d, false);
            let el = t.elapsed();
            match r {
                Ok(det) => {
                    let s = &det.evaluation.sim; let p = &det.evaluation.performance;
                    let nz: Vec<String> = s.distribution.iter().enumerate().filter(|(_, v)| **v > 0.0).map(|(i, v)| format!("{}:{:.2}", i + 1, v)).collect();
                    println!("{name:13} {:8} d_avg {:.4} lost {:.2} unset {:.2} area {:.1} it {} mb {:.1} n_wire {} mdot {:.4} W {:?} {:?} [{}]", e.name(), s.d_avg_m, s.lost_fraction, s.unsettled_fraction, s.fill_area_mm2, s.bounces, s.mean_bounces, p.n_wire, p.m_dot_kg_s, p.w_spec_j_kg, el, nz.join(" "));
                }
                Err(e) => println!("{name} invalid: {e}"),
            }
        }
    }
}
