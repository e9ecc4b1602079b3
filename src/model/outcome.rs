//! Per-particle end states and the per-design metrics of 4.2.6 (Eq. 4.56-4.59).

use serde::Serialize;

use super::geometry::Profile;

/// Where a particle is when the bounce loop ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ParticleState {
    /// Still hopping when the loop stopped (max bounces, or the listing's mean-hop rule).
    Flying,
    /// Its last hop was shorter than the rest threshold; it keeps its last impact point.
    Resting,
    /// No surface ahead: it left past the last tooth or behind the first.
    Lost,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ParticleEnd {
    pub state: ParticleState,
    /// Final global position (last impact point), m; NaN when lost.
    pub end: [f64; 2],
    /// First impact point, global, m; None when the first flight found nothing.
    pub first_impact: Option<[f64; 2]>,
    /// Impacts the particle made.
    pub bounces: u32,
}

/// Per-design result of the particle simulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SimOutcome {
    /// Fraction of launched particles ending in each tooth (Eq. 4.56), index 0 = tooth 1.
    pub distribution: Vec<f64>,
    pub lost_fraction: f64,
    /// Fraction still flying at the end (part of `distribution`, binned at their last impact).
    pub unsettled_fraction: f64,
    /// Average transport distance, m (listing D.1 lines 343-361: global x of the resting
    /// tooth's p4, 0 for tooth 1 and for lost particles, over all launched particles).
    pub d_avg_m: f64,
    /// Mean number of teeth advanced times the pitch, m: the distance along the conveyor
    /// (reported beside d_avg, which is horizontal and p4-based, erratum 16).
    pub advance_m: f64,
    pub fill_area_mm2: f64,
    /// Bounce iterations the loop ran.
    pub bounces: u32,
    /// Mean impacts per particle.
    pub mean_bounces: f64,
}

/// 1-based tooth a particle ends in, clamped to the profile (Eq. 4.56; positions behind
/// tooth 1's peak count as tooth 1, as the listing credits them distance 0).
pub fn end_tooth(profile: &Profile, end: [f64; 2]) -> u32 {
    profile.tooth_of_x(end[0]).clamp(1, profile.teeth as i64) as u32
}

pub fn summarise(profile: &Profile, fill_area_m2: f64, particles: &[ParticleEnd], iterations: u32) -> SimOutcome {
    let mut counts = vec![0u32; profile.teeth as usize];
    let (mut lost, mut flying, mut dist, mut advance, mut bounces) = (0usize, 0usize, 0.0, 0u64, 0u64);
    for p in particles {
        bounces += p.bounces as u64;
        match p.state {
            ParticleState::Lost => {
                lost += 1;
                continue;
            }
            ParticleState::Flying => flying += 1,
            ParticleState::Resting => {}
        }
        let j = end_tooth(profile, p.end);
        counts[(j - 1) as usize] += 1;
        dist += profile.credited_distance(j as i64);
        advance += (j - 1) as u64;
    }
    let advance_m = advance as f64 * profile.pitch_len;
    from_counts(&counts, particles.len(), lost, flying, dist, advance_m, fill_area_m2, iterations, bounces)
}

/// The per-design outcome from the reduced counts (what the GPU kernel reduces, too):
/// per-tooth counts, lost and still-flying counts, the sum of credited distances (m), the
/// sum of advances (m), impacts.
#[allow(clippy::too_many_arguments)]
pub fn from_counts(
    counts: &[u32],
    n: usize,
    lost: usize,
    flying: usize,
    distance_sum_m: f64,
    advance_sum_m: f64,
    fill_area_m2: f64,
    iterations: u32,
    bounce_sum: u64,
) -> SimOutcome {
    let n = n.max(1) as f64;
    SimOutcome {
        distribution: counts.iter().map(|c| *c as f64 / n).collect(),
        lost_fraction: lost as f64 / n,
        unsettled_fraction: flying as f64 / n,
        d_avg_m: distance_sum_m / n,
        advance_m: advance_sum_m / n,
        fill_area_mm2: fill_area_m2 * 1e6,
        bounces: iterations,
        mean_bounces: bounce_sum as f64 / n,
    }
}

/// Centre of mass E_x and dispersion σ_x of a tooth distribution (Eq. 4.58-4.59), over the
/// fractions given (normalised to their sum, as App. B normalises to recovered mass).
pub fn centre_and_dispersion(fractions: &[f64]) -> (f64, f64) {
    let total: f64 = fractions.iter().sum();
    if total <= 0.0 {
        return (f64::NAN, f64::NAN);
    }
    let ex: f64 = fractions.iter().enumerate().map(|(j, p)| (j + 1) as f64 * p / total).sum();
    let var: f64 = fractions.iter().enumerate().map(|(j, p)| p / total * ((j + 1) as f64 - ex).powi(2)).sum();
    (ex, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_4_metrics_of_test_3() {
        // App. B means of Test 3: 0.83/0.66/0.41/0.07 g -> E_x 1.85, σ_x 0.87 (Table 4.4)
        let (ex, sx) = centre_and_dispersion(&[0.83, 0.66, 0.41, 0.07]);
        assert!((ex - 1.85).abs() < 0.01, "{ex}");
        assert!((sx - 0.87).abs() < 0.01, "{sx}");
    }

    #[test]
    fn uniform_spread_over_four_teeth_has_dispersion_1_118() {
        let (_, sx) = centre_and_dispersion(&[1.0, 1.0, 1.0, 1.0]);
        assert!((sx - 1.118).abs() < 1e-3);
    }
}
