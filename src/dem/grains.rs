//! Grains placed in tooth 0's fill polygon (4.2.3, Eq. 4.29-4.36, `model::fill`), on a
//! staggered lattice with a seeded jitter, deepest first (a small count lines the catch; the
//! full count fills the polygon). They settle under gravity in the case before the stroke.
//!
//! The fill's mass is the model's: fill area × slab depth × loose bulk density (3.4.3,
//! D.7). Without a stated grain diameter, the diameter is the one at which `n` grains of the
//! particle density carry that mass in a slab `depth_grains` diameters deep:
//! n ρ_p π d³/6 = A k d ρ_bulk, so d² = 6 A k ρ_bulk / (n π ρ_p).
//!
//! Grains of several sizes (the polydisperse law's classes, `super::sizes`) cannot share one
//! lattice: [`place_sized`] seats them one by one, in a seeded order that mixes the sizes,
//! each at the deepest point of a fine candidate grid where it touches neither a wall nor a
//! grain already seated (a sequential deposition; the grains settle in the case anyway).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::sizes::{grain_mass, SizeClass};
use crate::model::fill::{in_polygon, Fill};
use crate::model::geometry::V2;

/// One grain: position (global x, y; z in the slab), diameter, m.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Grain {
    pub pos: [f64; 3],
    pub diameter_m: f64,
    /// Its size class (index into [`Placement::classes`]; 0 with one size).
    pub class: usize,
}

/// Where the grains are and what they weigh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// The grains, class by class (their LIGGGHTS ids 1, 2, ... are contiguous per class).
    pub grains: Vec<Grain>,
    /// The grain diameter, or the size law's mass median d_ref, m.
    pub diameter_m: f64,
    /// Periodic depth of the slab, m.
    pub depth_m: f64,
    /// Mass of one grain of `diameter_m`, kg.
    pub grain_mass_kg: f64,
    /// The grains' mass, kg.
    pub mass_kg: f64,
    /// Size classes (one for one size); a class's drag is set by the case.
    pub classes: Vec<SizeClass>,
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
            grains.push(Grain { pos: [p[0], p[1], z], diameter_m: d, class: 0 });
        }
    }
    let mass = grains.len() as f64 * grain_mass;
    let classes =
        vec![SizeClass { diameter_m: d, grains: grains.len() as u32, mass_fraction: 1.0, drag_gamma_kg_s: None }];
    Ok(Placement {
        grains,
        diameter_m: d,
        depth_m: depth,
        grain_mass_kg: grain_mass,
        mass_kg: mass,
        classes,
        fill_mass_kg: fill_mass,
        fill_fraction: mass / fill_mass,
    })
}

/// Seat the grains of `classes` (diameters around the mass median `d_ref`) in `fill` over a
/// slab `depth_m` deep, periodic in z (module docs). Candidate points lie on a grid of a
/// third of the smallest diameter, deepest below the fill's surface first; each grain, in a
/// seeded shuffled order, takes the first point at which it keeps 0.51 d from the walls (the
/// free surface excepted, as in [`place`]) and 1 % of a gap to every seated grain. Errors
/// when the fill has no room left for a grain.
pub fn place_sized(
    fill: &Fill,
    classes: &[SizeClass],
    d_ref: f64,
    depth_m: f64,
    rho_p: f64,
    rho_bulk: f64,
    seed: u64,
) -> Result<Placement, String> {
    let d_min = classes.iter().map(|c| c.diameter_m).fold(f64::INFINITY, f64::min);
    let d_max = classes.iter().map(|c| c.diameter_m).fold(0.0, f64::max);
    let surface = fill.polygon.iter().position(|v| *v == fill.p_fill);
    let h = d_min / 3.0;
    // the grid in the cross-section, each point with its room to the walls; z levels over
    // the periodic depth
    let mut points: Vec<(V2, f64)> = sites(&fill.polygon, surface, h, 0.5 * d_min, 0.0)
        .into_iter()
        .map(|p| (p, wall_distance(p, &fill.polygon, surface)))
        .collect();
    points.sort_by(|a, b| fill.depth(b.0).total_cmp(&fill.depth(a.0)).then(a.0[0].total_cmp(&b.0[0])));
    let levels = ((depth_m / h).floor() as usize).max(1);
    // the grains to seat, class by class, then in a seeded order that mixes the sizes
    let mut todo: Vec<(usize, f64)> = Vec::new();
    for (k, c) in classes.iter().enumerate() {
        todo.extend(std::iter::repeat_n((k, c.diameter_m), c.grains as usize));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in (1..todo.len()).rev() {
        todo.swap(i, rng.random_range(0..=i));
    }
    let z_jitter = rng.random_range(0.0..1.0) * depth_m / levels as f64;
    // seated grains hashed by cross-section cell (side: the largest diameter)
    let cell = 1.01 * d_max;
    let key = |p: V2| ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64);
    let mut cells: std::collections::HashMap<(i64, i64), Vec<usize>> = std::collections::HashMap::new();
    let mut seated: Vec<Grain> = Vec::with_capacity(todo.len());
    for &(class, d) in &todo {
        let free = |p: V2, z: f64, seated: &[Grain], cells: &std::collections::HashMap<(i64, i64), Vec<usize>>| {
            let (cx, cy) = key(p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &j in cells.get(&(cx + dx, cy + dy)).map_or(&[][..], |v| v.as_slice()) {
                        let g = &seated[j];
                        let dz = (g.pos[2] - z).abs();
                        let dz = dz.min(depth_m - dz);
                        let gap = 1.01 * 0.5 * (d + g.diameter_m);
                        if (g.pos[0] - p[0]).powi(2) + (g.pos[1] - p[1]).powi(2) + dz * dz < gap * gap {
                            return false;
                        }
                    }
                }
            }
            true
        };
        let spot = points.iter().filter(|(_, room)| *room >= 0.51 * d).find_map(|(p, _)| {
            (0..levels)
                .map(|l| (l as f64 * depth_m / levels as f64 + z_jitter) % depth_m)
                .find_map(|z| free(*p, z, &seated, &cells).then_some([p[0], p[1], z]))
        });
        let Some(pos) = spot else {
            return Err(format!(
                "tooth 0's fill ({:.1} mm^2) has no room left for a grain of {:.0} um after {} of {} grains of the size law; lower --particles or the size law's sigma_ln",
                fill.area * 1e6,
                d * 1e6,
                seated.len(),
                todo.len()
            ));
        };
        cells.entry(key([pos[0], pos[1]])).or_default().push(seated.len());
        seated.push(Grain { pos, diameter_m: d, class });
    }
    // class by class, so that each class's LIGGGHTS ids are one range
    seated.sort_by_key(|g| g.class);
    let mass: f64 = seated.iter().map(|g| grain_mass(g.diameter_m, rho_p)).sum();
    let fill_mass = fill.area * depth_m * rho_bulk;
    Ok(Placement {
        grains: seated,
        diameter_m: d_ref,
        depth_m,
        grain_mass_kg: grain_mass(d_ref, rho_p),
        mass_kg: mass,
        classes: classes.to_vec(),
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

#[cfg(test)]
mod sized_tests {
    use super::*;
    use crate::dem::sizes::{reference_diameter, size_classes};
    use crate::model::effects::{Polydisperse, SizeForm};
    use crate::model::{prepare, Design, Scenario};

    /// The rig's fill with the classes of a log-normal law of sd 0.3 around 150 grains' size.
    fn rig_classes(seed: u64) -> (Fill, Placement) {
        let mut s = Scenario::earth();
        s.sim.teeth = 20;
        let fill = prepare(&s, &Design::validation_rig()).unwrap().fill;
        let (rho_p, rho_b) = (s.material.particle.density, s.material.bulk_density);
        let law = Polydisperse { sigma_ln: 0.3, form: SizeForm::Lognormal };
        let d_ref = reference_diameter(&law, mass_matching_diameter(fill.area, 150, 4.0, rho_b, rho_p));
        let depth = 4.0 * d_ref;
        let classes = size_classes(&law, d_ref, fill.area * depth * rho_b, rho_p, Some(5.0));
        let p = place_sized(&fill, &classes, d_ref, depth, rho_p, rho_b, seed).unwrap();
        (fill, p)
    }

    #[test]
    fn grains_of_every_class_are_seated_in_the_fill_without_touching_and_carry_its_mass() {
        let (fill, p) = rig_classes(3);
        let wanted: u32 = p.classes.iter().map(|c| c.grains).sum();
        assert_eq!(p.grains.len(), wanted as usize);
        assert!((p.fill_fraction - 1.0).abs() < 0.03, "{}", p.fill_fraction);
        // ids class by class: each class one contiguous range, in class order
        assert!(p.grains.windows(2).all(|w| w[0].class <= w[1].class));
        for (k, c) in p.classes.iter().enumerate() {
            assert_eq!(p.grains.iter().filter(|g| g.class == k).count(), c.grains as usize);
            assert!(p.grains.iter().filter(|g| g.class == k).all(|g| g.diameter_m == c.diameter_m));
        }
        for (i, a) in p.grains.iter().enumerate() {
            assert!(in_polygon([a.pos[0], a.pos[1]], &fill.polygon), "{a:?}");
            assert!(a.pos[2] >= 0.0 && a.pos[2] < p.depth_m);
            for b in &p.grains[i + 1..] {
                let dz = (a.pos[2] - b.pos[2]).abs();
                let dz = dz.min(p.depth_m - dz); // periodic in z
                let dist = ((a.pos[0] - b.pos[0]).powi(2) + (a.pos[1] - b.pos[1]).powi(2) + dz * dz).sqrt();
                assert!(dist >= 0.5 * (a.diameter_m + b.diameter_m), "grains overlap: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn the_seed_mixes_the_sizes_differently_and_the_same_seed_places_the_same() {
        let (_, p) = rig_classes(1);
        let (_, q) = rig_classes(2);
        assert_ne!(p.grains, q.grains);
        assert_eq!(p, rig_classes(1).1);
        // sizes are mixed: the deepest tenth of the grains is not all of one class
        let mut by_height = p.grains.clone();
        by_height.sort_by(|a, b| a.pos[1].total_cmp(&b.pos[1]));
        let low = &by_height[..by_height.len() / 10];
        assert!(low.iter().any(|g| g.class != low[0].class), "{low:?}");
    }

    #[test]
    fn a_fill_too_small_for_the_law_is_refused_with_the_rule() {
        let (fill, p) = rig_classes(0);
        let mut classes = p.classes.clone();
        for c in &mut classes {
            c.grains *= 4;
        }
        let e = place_sized(&fill, &classes, p.diameter_m, p.depth_m, 2500.0, 1500.0, 0).unwrap_err();
        assert!(e.contains("no room left") && e.contains("sigma_ln"), "{e}");
    }
}
