//! Grains placed in tooth 0's fill polygon (4.2.3, Eq. 4.29-4.36, `model::fill`), on a
//! staggered lattice with a seeded jitter, deepest first (a small count lines the catch; the
//! full count fills the polygon). They settle under gravity in the case before the stroke.
//!
//! The fill's mass is the model's: fill area × slab depth × loose bulk density (3.4.3,
//! D.7). Without a stated grain diameter, the diameter is the one at which `n` grains of the
//! particle density carry that mass in a slab `depth_grains` diameters deep:
//! n ρ_p π d³/6 = A k d ρ_bulk, so d² = 6 A k ρ_bulk / (n π ρ_p).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::model::fill::{in_polygon, Fill};
use crate::model::geometry::V2;

/// One grain: position (global x, y; z in the slab), diameter, m.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Grain {
    pub pos: [f64; 3],
    pub diameter_m: f64,
}

/// Where the grains are and what they weigh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Placement {
    pub grains: Vec<Grain>,
    pub diameter_m: f64,
    /// Periodic depth of the slab, m.
    pub depth_m: f64,
    /// Mass of one grain, kg.
    pub grain_mass_kg: f64,
    /// The model's fill mass over the slab (A × depth × ρ_bulk), kg.
    pub fill_mass_kg: f64,
    /// The grains' mass over the model's fill mass.
    pub fill_fraction: f64,
}

/// The diameter at which `n` grains of density `rho_p` hold the fill's mass (module docs).
pub fn mass_matching_diameter(area_m2: f64, n: u32, depth_grains: f64, rho_bulk: f64, rho_p: f64) -> f64 {
    (6.0 * area_m2 * depth_grains * rho_bulk / (n as f64 * std::f64::consts::PI * rho_p)).sqrt()
}

fn segment_distance(p: V2, a: V2, b: V2) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// Distance from `p` to the polygon's walls: every edge but the free surface (the edge
/// from vertex `surface`, if any), which grains may overhang.
fn wall_distance(p: V2, poly: &[V2], surface: Option<usize>) -> f64 {
    let n = poly.len();
    (0..n)
        .filter(|i| Some(*i) != surface)
        .map(|i| segment_distance(p, poly[i], poly[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

/// Lattice sites inside the polygon at least `clearance` from its walls: rows `spacing`
/// apart, alternate rows shifted by half a spacing (a hexagonal-like lattice).
fn sites(poly: &[V2], surface: Option<usize>, spacing: f64, clearance: f64, shift: f64) -> Vec<V2> {
    let xs = poly.iter().map(|p| p[0]);
    let ys = poly.iter().map(|p| p[1]);
    let (x0, x1) = (xs.clone().fold(f64::INFINITY, f64::min), xs.fold(f64::NEG_INFINITY, f64::max));
    let (y0, y1) = (ys.clone().fold(f64::INFINITY, f64::min), ys.fold(f64::NEG_INFINITY, f64::max));
    let row = spacing * 3f64.sqrt() / 2.0;
    let mut out = Vec::new();
    let mut i = 0;
    let mut y = y0 + clearance;
    while y <= y1 - clearance {
        let offset = if i % 2 == 1 { spacing / 2.0 } else { 0.0 } + shift * spacing;
        let mut x = x0 + clearance + offset;
        while x <= x1 - clearance {
            let p = [x, y];
            if in_polygon(p, poly) && wall_distance(p, poly, surface) >= clearance {
                out.push(p);
            }
            x += spacing;
        }
        y += row;
        i += 1;
    }
    out
}

/// Place `n` grains of diameter `d` in `fill` over a slab `depth_grains · d` deep, deepest
/// first, each jittered by up to a quarter of the free gap (seeded). Errors when the polygon
/// cannot seat `n` grains of that size at the loose bulk density or denser.
pub fn place(
    fill: &Fill,
    n: u32,
    d: f64,
    depth_grains: f64,
    rho_p: f64,
    rho_bulk: f64,
    seed: u64,
) -> Result<Placement, String> {
    let depth = depth_grains * d;
    let layers = (depth_grains.floor() as usize).max(1);
    let per_layer = (n as usize).div_ceil(layers);
    let grain_mass = rho_p * std::f64::consts::PI * d.powi(3) / 6.0;
    let fill_mass = fill.area * depth * rho_bulk;
    // Start from the spacing at which the fill's area holds the layer's grains loosely and
    // tighten until they fit; the grains must not touch (2 % gap at least).
    let area_spacing = (fill.area / per_layer as f64 / (3f64.sqrt() / 2.0)).sqrt();
    let mut spacing = area_spacing.max(1.02 * d) * 1.3;
    let clearance = 0.51 * d;
    // the polygon's free surface runs from p_fill to p2 (`model::fill::build_fill`)
    let surface = fill.polygon.iter().position(|v| *v == fill.p_fill);
    let mut layer_sites = Vec::new();
    while spacing >= 1.02 * d {
        layer_sites = sites(&fill.polygon, surface, spacing, clearance, 0.0);
        if layer_sites.len() >= per_layer {
            break;
        }
        spacing *= 0.97;
    }
    if layer_sites.len() < per_layer {
        return Err(format!(
            "tooth 0's fill ({:.1} mm^2) cannot seat {n} grains of {:.0} um in {layers} layer(s): it holds {} per layer; lower --particles or [dem] grain_diameter_m",
            fill.area * 1e6,
            d * 1e6,
            layer_sites.len() * layers
        ));
    }
    // deepest below the fill's free surface first: a partial fill lines the catch
    layer_sites.sort_by(|a, b| fill.depth(*b).total_cmp(&fill.depth(*a)).then(a[0].total_cmp(&b[0])));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let jitter = 0.25 * (spacing - d);
    let mut grains = Vec::with_capacity(n as usize);
    'fill: for s in layer_sites.iter().take(per_layer) {
        for l in 0..layers {
            if grains.len() == n as usize {
                break 'fill;
            }
            let z = (l as f64 + 0.5) * depth / layers as f64;
            let (jx, jy) = (rng.random_range(-1.0..=1.0) * jitter, rng.random_range(-1.0..=1.0) * jitter);
            // a site by the free surface (no clearance there) keeps its centre in the fill
            let p = [s[0] + jx, s[1] + jy];
            let p = if in_polygon(p, &fill.polygon) { p } else { *s };
            grains.push(Grain { pos: [p[0], p[1], z], diameter_m: d });
        }
    }
    let mass = grains.len() as f64 * grain_mass;
    Ok(Placement {
        grains,
        diameter_m: d,
        depth_m: depth,
        grain_mass_kg: grain_mass,
        fill_mass_kg: fill_mass,
        fill_fraction: mass / fill_mass,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{prepare, Design, Scenario};

    fn rig_fill() -> (Scenario, Fill) {
        let mut s = Scenario::earth();
        s.sim.teeth = 20;
        let p = prepare(&s, &Design::validation_rig()).unwrap();
        (s, p.fill)
    }

    #[test]
    fn the_mass_matching_diameter_carries_the_fill_mass() {
        let (s, fill) = rig_fill();
        let rho_p = s.material.particle.density;
        let d = mass_matching_diameter(fill.area, 150, 4.0, s.material.bulk_density, rho_p);
        let p = place(&fill, 150, d, 4.0, rho_p, s.material.bulk_density, 1).unwrap();
        assert_eq!(p.grains.len(), 150);
        assert!((p.fill_fraction - 1.0).abs() < 1e-9, "{}", p.fill_fraction);
    }

    #[test]
    fn grains_lie_inside_the_fill_without_touching_and_the_seed_moves_them() {
        let (s, fill) = rig_fill();
        let rho_p = s.material.particle.density;
        let d = mass_matching_diameter(fill.area, 150, 4.0, s.material.bulk_density, rho_p);
        let p = place(&fill, 150, d, 4.0, rho_p, s.material.bulk_density, 1).unwrap();
        for g in &p.grains {
            assert!(in_polygon([g.pos[0], g.pos[1]], &fill.polygon), "{g:?}");
            assert!(g.pos[2] > 0.0 && g.pos[2] < p.depth_m);
        }
        for (i, a) in p.grains.iter().enumerate() {
            for b in &p.grains[i + 1..] {
                let dist =
                    ((a.pos[0] - b.pos[0]).powi(2) + (a.pos[1] - b.pos[1]).powi(2) + (a.pos[2] - b.pos[2]).powi(2))
                        .sqrt();
                assert!(dist >= d, "grains overlap: {dist} < {d}");
            }
        }
        let q = place(&fill, 150, d, 4.0, rho_p, s.material.bulk_density, 2).unwrap();
        assert_ne!(p.grains, q.grains);
        assert_eq!(p, place(&fill, 150, d, 4.0, rho_p, s.material.bulk_density, 1).unwrap());
    }

    #[test]
    fn too_many_grains_of_a_stated_size_are_refused() {
        let (s, fill) = rig_fill();
        let e = place(&fill, 5000, 1e-3, 4.0, s.material.particle.density, s.material.bulk_density, 0).unwrap_err();
        assert!(e.contains("cannot seat 5000 grains"), "{e}");
    }
}
