//! A user program on the library: simulate one design and print where the grains come to
//! rest, tooth by tooth, with the performance figures `sawtooth simulate` prints.
//!
//! cargo run --release --example simulate_design                       # lunar solution C
//! cargo run --release --example simulate_design -- earth 47.376,45.884,34.375,36.916,62.853,17.552,1.299,58.595
//!
//! The design is the eight variables in the command line's units: l_c, l_a, l_b, r (mm),
//! omega, delta (deg), v0 (m/s), a (m/s^2). The scenario is the thesis's preset for the
//! environment (listing D.5) with 1000 particles; the `cpu` engine runs it.

use sawtooth::engine::cpu::CpuEngine;
use sawtooth::engine::BatchEvaluator;
use sawtooth::model::{Design, Scenario};

fn main() {
    let mut args = std::env::args().skip(1);
    let env = args.next().unwrap_or_else(|| "lunar".to_string());
    let mut scenario = match env.as_str() {
        "lunar" => Scenario::lunar(),
        "earth" => Scenario::earth(),
        other => usage(&format!("environment `{other}`: expected lunar or earth")),
    };
    let design = match args.next() {
        None if env == "lunar" => Design::lunar_solution_c(),
        None => Design::earth_solution_c(),
        Some(list) => {
            let values: Vec<f64> = list
                .split(',')
                .map(|v| v.trim().parse().unwrap_or_else(|_| usage(&format!("design value `{v}` is not a number"))))
                .collect();
            let Ok(values) = <[f64; 8]>::try_from(values) else {
                usage("the design needs eight comma-separated values")
            };
            Design::from_cli_units(values)
        }
    };
    scenario.sim.particles = 1000;

    // One design is a batch of one; an optimiser hands the engine a whole generation at once.
    let result = CpuEngine::default().evaluate(&scenario, &[design]).remove(0);
    let evaluation = match result {
        Ok(e) => e,
        Err(invalid) => {
            // a design the model rejects (a violated constraint, an empty fill area) is an
            // answer, not a crash: say which rule it broke
            eprintln!("the design is invalid: {invalid}");
            std::process::exit(2);
        }
    };

    let sim = &evaluation.sim;
    println!("{env}, {} particles, seed {}", scenario.sim.particles, scenario.sim.seed);
    println!("tooth  share of the launched grains");
    for (tooth, share) in sim.distribution.iter().enumerate().filter(|(_, s)| **s > 0.0) {
        println!("{:>5}  {:>5.1} %  {}", tooth + 1, 100.0 * share, "#".repeat((60.0 * share).round() as usize));
    }
    println!("lost: {:.1} %, mean transport distance d_avg: {:.1} mm", 100.0 * sim.lost_fraction, 1e3 * sim.d_avg_m);
    let p = &evaluation.performance;
    println!(
        "mass flow {:.1} kg/h at {:.4} Hz, {} SMA wires, specific work {}",
        p.m_dot_kg_s * 3600.0,
        p.f_stroke_hz,
        p.n_wire,
        p.w_spec_j_kg.map_or("- (no mass flow)".to_string(), |w| format!("{w:.0} J/kg"))
    );
}

fn usage(problem: &str) -> ! {
    eprintln!("{problem}\nusage: simulate_design [lunar|earth] [l_c,l_a,l_b,r,omega,delta,v0,a]");
    std::process::exit(2);
}
