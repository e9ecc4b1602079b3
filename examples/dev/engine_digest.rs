//! A digest of every bit the `cpu` engine leaves: each particle's state, end point, first
//! impact and bounce count, and every flight of a traced design, over random valid designs
//! of both environments, both modes, each effect and both kinds of launch point, in f64 and
//! f32. A change to the kernel or the preparation that claims "the same bits" prints the
//! same digests before and after.
//!
//! cargo run --release --example engine_digest [DESIGNS]

use sawtooth::engine::cpu::{CpuEngine, Precision};
use sawtooth::engine::{Context, ParticleEngine};
use sawtooth::model::effects::{
    ImpactScatter, LaunchSpread, MotionDirection, Polydisperse, QuadraticDrag, SizeForm, SledMotion, TiltForm,
};
use sawtooth::model::sampling::random_valid_designs;
use sawtooth::model::scenario::LaunchPoints;
use sawtooth::model::{prepare, PhysicsMode, Scenario};

/// FNV-1a over 64-bit words.
struct Digest(u64);
impl Digest {
    fn add(&mut self, word: u64) {
        for b in word.to_le_bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

fn main() {
    let designs: usize = std::env::args().nth(1).map_or(60, |s| s.parse().expect("DESIGNS is a count"));
    let mut cases: Vec<(String, Scenario)> = Vec::new();
    for (env, base) in [("lunar", Scenario::lunar()), ("earth", Scenario::earth())] {
        for mode in [PhysicsMode::Physical, PhysicsMode::Listing] {
            let mut s = base.clone();
            s.mode = mode;
            cases.push((format!("{env} {mode:?}"), s.clone()));
            let mut e = s.clone();
            e.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 3.0, form: TiltForm::default() });
            e.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.2, angle_sigma_deg: 5.0 });
            e.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
            cases.push((format!("{env} {mode:?} scatter+spread+polydisperse"), e));
            let mut m = s.clone();
            m.effects.sled_motion =
                Some(SledMotion { delay_s: 0.01, return_speed_m_s: 0.3, direction: MotionDirection::default() });
            if env == "earth" {
                m.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: 150e-6, density_kg_m3: 2500.0 });
            }
            cases.push((
                format!("{env} {mode:?} sled-motion{}", if env == "earth" { "+quadratic-drag" } else { "" }),
                m,
            ));
            let mut r = s.clone();
            r.sim.launch_points = LaunchPoints::Random;
            cases.push((format!("{env} {mode:?} random launch points"), r));
        }
    }
    for (name, s) in cases {
        let ctx = Context::new(&s);
        let mut line = Vec::new();
        for precision in [Precision::F64, Precision::F32] {
            let engine = CpuEngine { precision };
            let mut dig = Digest(0xcbf2_9ce4_8422_2325);
            let mut flights = 0usize;
            for (i, d) in random_valid_designs(&s, designs, 3).iter().enumerate() {
                let prep = prepare(&s, d).expect("valid design");
                let mut trace = Vec::new();
                let run = engine.run(&prep, &ctx, if i % 10 == 0 { Some(&mut trace) } else { None });
                dig.add(run.iterations as u64);
                for p in &run.particles {
                    dig.add(p.state as u64);
                    dig.add(p.end[0].to_bits());
                    dig.add(p.end[1].to_bits());
                    let f = p.first_impact.unwrap_or([0.0; 2]);
                    dig.add(f[0].to_bits());
                    dig.add(f[1].to_bits());
                    dig.add(p.bounces as u64);
                    flights += p.bounces as usize;
                }
                for r in &trace {
                    for w in [r.from[0], r.from[1], r.vel[0], r.vel[1], r.t] {
                        dig.add(w.to_bits());
                    }
                }
            }
            line.push(format!("{:?} {:016x} ({flights} impacts)", precision, dig.0));
        }
        println!("{name:<50} {}", line.join("  "));
    }
}
