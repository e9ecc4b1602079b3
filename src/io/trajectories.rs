//! Trajectory CSV: launch and impact points of every traced flight (global metres).

use std::path::Path;

use anyhow::{Context as _, Result};

use crate::engine::{Detailed, FlightRecord};
use crate::model::flight::Flight;
use crate::model::ParticleState;

/// One CSV row: a point a particle passed through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajPoint {
    pub particle: u32,
    pub bounce: u32,
    pub pos: [f64; 2],
    pub state: ParticleState,
}

/// Lower-case name of a state, as the CSV writes it.
pub fn state_name(s: ParticleState) -> &'static str {
    match s {
        ParticleState::Flying => "flying",
        ParticleState::Resting => "resting",
        ParticleState::Lost => "lost",
    }
}

/// Where a flight ends; None when it hit nothing (lost with t = 0).
pub fn impact_point(r: &FlightRecord, g: f64, k_drag: f64) -> Option<[f64; 2]> {
    if r.state == ParticleState::Lost && r.t == 0.0 {
        return None;
    }
    Some(Flight { p0: r.from, v0: r.vel, g, k: k_drag, drift: [0.0; 2] }.pos(r.t))
}

/// The launch (bounce 0 only) and impact points of every flight, in record order.
pub fn trajectory_points(det: &Detailed, g: f64, k_drag: f64) -> Vec<TrajPoint> {
    let mut out = Vec::with_capacity(det.flights.len() + det.particles.len());
    for r in &det.flights {
        if r.bounce == 0 {
            out.push(TrajPoint { particle: r.particle, bounce: 0, pos: r.from, state: ParticleState::Flying });
        }
        if let Some(pos) = impact_point(r, g, k_drag) {
            out.push(TrajPoint { particle: r.particle, bounce: r.bounce + 1, pos, state: r.state });
        }
    }
    out
}

/// Write the trajectory CSV `particle,bounce,x_m,y_m,state` atomically.
pub fn write_trajectories(path: &Path, det: &Detailed, g: f64, k_drag: f64) -> Result<()> {
    let ctx = || format!("writing trajectories to {}", path.display());
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["particle", "bounce", "x_m", "y_m", "state"]).with_context(ctx)?;
    for p in trajectory_points(det, g, k_drag) {
        let row = [
            p.particle.to_string(),
            p.bounce.to_string(),
            p.pos[0].to_string(),
            p.pos[1].to_string(),
            state_name(p.state).to_string(),
        ];
        w.write_record(&row).with_context(ctx)?;
    }
    let bytes = w.into_inner().map_err(|e| anyhow::anyhow!("{}", e.error())).with_context(ctx)?;
    super::atomic::write_atomic(path, &bytes).with_context(ctx)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::collections::HashMap;
    use std::path::PathBuf;

    use super::*;
    use crate::engine::{evaluate_detailed, particle_engine, EngineKind};
    use crate::model::{Design, Scenario};

    /// Solution C on the Moon with five traced particles.
    pub(crate) fn small_lunar() -> (Scenario, Detailed) {
        let mut scenario = Scenario::lunar();
        scenario.sim.particles = 5;
        let engine = particle_engine(EngineKind::Cpu);
        let det = evaluate_detailed(engine.as_ref(), &scenario, &Design::lunar_solution_c(), true).unwrap();
        (scenario, det)
    }

    /// A fresh, unique directory under the system temp dir.
    pub(crate) fn temp_dir(tag: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
        let dir = std::env::temp_dir().join(format!("sawtooth-{tag}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn csv_round_trip_has_launches_and_consistent_impacts() {
        let (s, det) = small_lunar();
        let (g, k) = (s.environment.g, s.environment.k_drag.unwrap_or(0.0));
        let dir = temp_dir("traj");
        let path = dir.join("traj.csv");
        write_trajectories(&path, &det, g, k).unwrap();

        let mut rd = csv::Reader::from_path(&path).unwrap();
        assert_eq!(rd.headers().unwrap(), vec!["particle", "bounce", "x_m", "y_m", "state"]);
        let mut rows: HashMap<(u32, u32), [f64; 2]> = HashMap::new();
        for rec in rd.records() {
            let rec = rec.unwrap();
            let key = (rec[0].parse().unwrap(), rec[1].parse().unwrap());
            assert!(["flying", "resting", "lost"].contains(&&rec[4]), "{rec:?}");
            assert!(
                rows.insert(key, [rec[2].parse().unwrap(), rec[3].parse().unwrap()]).is_none(),
                "duplicate {key:?}"
            );
        }
        for p in 0..5 {
            assert!(rows.contains_key(&(p, 0)), "particle {p} has no launch row");
        }
        // Each impact is where the particle's next flight starts.
        let mut checked = 0;
        for next in det.flights.iter().filter(|r| r.bounce > 0) {
            let hit = rows[&(next.particle, next.bounce)];
            let err = (hit[0] - next.from[0]).hypot(hit[1] - next.from[1]);
            assert!(err < 1e-9, "particle {} bounce {}: {err:e} m", next.particle, next.bounce);
            checked += 1;
        }
        assert!(checked > 0, "no multi-bounce flights traced");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
