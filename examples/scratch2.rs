use sawtooth::engine::*;
use sawtooth::model::*;
use sawtooth::model::outcome::end_tooth;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let compat = args.get(1).map(|s| s == "compat").unwrap_or(false);
    let earth = args.get(2).map(|s| s == "earth").unwrap_or(false);
    let mut sc = if earth { Scenario::earth() } else { Scenario::lunar() };
    if compat { sc = sc.into_listing_compat(); }
    let d = if earth { Design::earth_solution_c() } else { Design::lunar_solution_c() };
    let a = evaluate_detailed(particle_engine(EngineKind::Cpu).as_ref(), &sc, &d, true).unwrap();
    let b = evaluate_detailed(particle_engine(EngineKind::Listing).as_ref(), &sc, &d, true).unwrap();
    let pr = &a.prepared.profile;
    let mut agree = 0;
    for i in 0..a.particles.len() {
        let (p, q) = (&a.particles[i], &b.particles[i]);
        let tp = if p.state == ParticleState::Lost { 0 } else { end_tooth(pr, p.end) };
        let tq = if q.state == ParticleState::Lost { 0 } else { end_tooth(pr, q.end) };
        if tp == tq { agree += 1; continue; }
        println!("#{i}: cpu {:?} t{} b{} first {:?} | listing {:?} t{} b{} first {:?}", p.state, tp, p.bounces, p.first_impact.map(|f| [f[0]*1e3, f[1]*1e3]), q.state, tq, q.bounces, q.first_impact.map(|f| [f[0]*1e3, f[1]*1e3]));
        if i == args.get(3).and_then(|s| s.parse().ok()).unwrap_or(usize::MAX) {
            for f in a.flights.iter().filter(|f| f.particle as usize == i) { println!("   cpu  b{} from [{:.4} {:.4}] v [{:.4} {:.4}] t {:.5} {:?}", f.bounce, f.from[0]*1e3, f.from[1]*1e3, f.vel[0], f.vel[1], f.t, f.state); }
            for f in b.flights.iter().filter(|f| f.particle as usize == i) { println!("   list b{} from [{:.4} {:.4}] v [{:.4} {:.4}] t {:.5} {:?}", f.bounce, f.from[0]*1e3, f.from[1]*1e3, f.vel[0], f.vel[1], f.t, f.state); }
        }
    }
    println!("agree {agree}/{}", a.particles.len());
}
