//! The regolith fill area under acceleration and the launch points inside it
//! (4.2.3, Eq. 4.29-4.37, listing D.1 lines 109-210), and the spill check of 5.3.1.

use super::design::Design;
use super::geometry::{Profile, V2};
use super::rng::{seed_word, uniform01, DRAW_LAUNCH_POINT, PER_PARTICLE};
use super::scenario::{LaunchPoints, PhysicsMode};
use super::validity::Invalid;

/// The Halton caps are declared in `schema` (they bound a loop, and `validity`'s message names
/// them without depending on this module).
pub use crate::schema::{LISTING_HALTON_POINTS, MAX_HALTON_POINTS};
/// Arc points of the physical fill polygon (the listing keeps 10 of 1000, erratum 20).
const PHYSICAL_ARC_POINTS: usize = 512;

#[derive(Clone, Debug, PartialEq)]
pub struct Fill {
    /// Angle of the fill surface, radians from the global horizontal (listing line 115).
    pub surface_angle: f64,
    /// Where the fill surface meets ramp 2 or the base (p_fill,2 of Figure 4.6).
    pub p_fill: V2,
    /// Polygon vertices (global, tooth 0's p1 at the origin).
    pub polygon: Vec<V2>,
    /// Cross-section A_regolith, m² (polyarea, listing line 340).
    pub area: f64,
    /// The exact boundary for membership tests: straight part (from p4 round to p2) and the
    /// catch arc (centre, radius, start and end angle) back from p2 to p4. `None` in listing
    /// mode, whose polygon (10 arc points) is the boundary the listing tested against.
    pub exact: Option<ExactBoundary>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ExactBoundary {
    /// p4, [p1_2], p_fill, p2: the straight edges between consecutive points.
    pub straight: Vec<V2>,
    pub centre: V2,
    pub radius: f64,
    /// Arc from angle a2 (at p2) counter-clockwise to a4 (at p4), a4 > a2.
    pub a2: f64,
    pub a4: f64,
    /// The arc's end directions from the centre, p2 - p3 and p4 - p3 (the vectors a2 and a4
    /// are the angles of): membership is decided by their cross products, not by an `atan2`
    /// per candidate point (which was a fifth of the preparation).
    pub to_p2: V2,
    pub to_p4: V2,
}

fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

impl ExactBoundary {
    /// Crossing-number test of the closed curve: straight edges plus the arc, counting
    /// crossings of the ray from `p` towards +x (O(1) per point instead of O(arc points)).
    #[inline(always)]
    pub fn contains(&self, p: V2) -> bool {
        self.contains_lanes(&[p[0]], &[p[1]])[0]
    }

    /// [`ExactBoundary::contains`] for `L` points at once, with the same operations per
    /// point: the loops over the points are innermost, so the compiler runs them on SIMD
    /// lanes (`launch_points` tests its candidates eight at a time).
    ///
    /// Written without data-dependent branches (`&` and `^` on the tests, not `if`): Halton
    /// candidates fall in and out at random, so branches on them mispredicted about half the
    /// time. An edge the ray misses still computes its crossing x, unused (a horizontal
    /// edge's is ±inf or NaN, which no test takes).
    #[inline(always)]
    pub fn contains_lanes<const L: usize>(&self, px: &[f64; L], py: &[f64; L]) -> [bool; L] {
        let mut inside = [false; L];
        for e in self.straight.windows(2) {
            let (a, b) = (e[0], e[1]);
            for l in 0..L {
                let x = a[0] + (py[l] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
                inside[l] ^= ((a[1] > py[l]) != (b[1] > py[l])) & (px[l] < x);
            }
        }
        for l in 0..L {
            let dy = py[l] - self.centre[1];
            let h2 = self.radius * self.radius - dy * dy;
            let h = h2.max(0.0).sqrt();
            for x in [self.centre[0] - h, self.centre[0] + h] {
                // a ray through an arc end point is measure-zero for Halton points
                inside[l] ^= (h2 > 0.0) & (x > px[l]) & self.on_arc([x - self.centre[0], dy]);
            }
        }
        inside
    }

    /// Whether direction `u` from the centre lies on the arc, angle in [a2, a4): for an arc
    /// of at most half a turn, u is counter-clockwise of p2's direction and clockwise of
    /// p4's; a longer arc is everything but the complementary arc [a4, a2 + 2π).
    #[inline(always)]
    fn on_arc(&self, u: V2) -> bool {
        if self.a4 - self.a2 <= std::f64::consts::PI {
            (cross(self.to_p2, u) >= 0.0) & (cross(u, self.to_p4) > 0.0)
        } else {
            !((cross(self.to_p4, u) >= 0.0) & (cross(u, self.to_p2) > 0.0))
        }
    }

    /// The same membership by the arc's angles (one `atan2` per crossing): the definition
    /// [`ExactBoundary::on_arc`] is checked against.
    #[cfg(test)]
    fn on_arc_by_angle(&self, u: V2) -> bool {
        let mut ang = u[1].atan2(u[0]);
        while ang < self.a2 {
            ang += 2.0 * std::f64::consts::PI;
        }
        ang < self.a4
    }
}

impl Fill {
    /// Signed distance of `p` from the line of the fill's free surface (through `p_fill` at
    /// `surface_angle`, Figure 4.6), m; the fill lies on one side of it.
    pub fn signed_surface_distance(&self, p: V2) -> f64 {
        let (s, c) = self.surface_angle.sin_cos();
        (p[0] - self.p_fill[0]) * s - (p[1] - self.p_fill[1]) * c
    }

    /// How deep `p` lies below the free surface, m: its distance from the surface line (the
    /// fill is bounded by that line, so every point of it is on the same side).
    pub fn depth(&self, p: V2) -> f64 {
        self.signed_surface_distance(p).abs()
    }
}

/// Fill-surface angle: direction of the effective acceleration + 90° + AOR (erratum 21,
/// listing lines 111-115; Eq. 4.29-4.31 for the vectors). `launch_angle` is the global
/// direction of the sled's acceleration, α + offset + δ (listing line 112).
pub fn fill_surface_angle(g: f64, a: f64, launch_angle: f64, aor_deg: f64) -> f64 {
    let g_eff = [-a * launch_angle.cos(), -a * launch_angle.sin() - g]; // Eq. 4.31
    let beta = g_eff[1].atan2(g_eff[0]) + std::f64::consts::FRAC_PI_2;
    beta + aor_deg.to_radians()
}

/// The spill check of listing D.6 lines 61-69, kept verbatim for compatibility mode
/// (erratum 9: fixed g and (α - δ) where the simulation uses (α + δ)).
pub fn listing_spill_check(alpha_deg: f64, aor_deg: f64, g: f64, offset_deg: f64, d: &Design) -> Result<(), Invalid> {
    let alpha_c = alpha_deg.to_radians();
    let mu_s = aor_deg.to_radians().tan();
    let dr = offset_deg.to_radians();
    let a = d.a;
    let num = a * ((alpha_c - dr).cos() - (alpha_c - dr).sin() * mu_s) - g * mu_s;
    let den = a * ((alpha_c - dr).cos() * mu_s + (alpha_c - dr).sin()) + g;
    let delta_check = -(num / den).atan();
    if delta_check > alpha_c {
        return Err(Invalid::FillSpills {
            detail: format!(
                "listing D.6 check: surface angle {:.3} deg exceeds conveyor angle {:.3} deg",
                delta_check.to_degrees(),
                alpha_deg
            ),
        });
    }
    Ok(())
}

/// Intersection of the line through `p` with direction angle `ang` and the line through
/// `a`-`b`; returns the parameter along `a`-`b` and the point.
fn line_cross(p: V2, ang: f64, a: V2, b: V2) -> Option<(f64, V2)> {
    let d = [ang.cos(), ang.sin()];
    let e = [b[0] - a[0], b[1] - a[1]];
    let den = d[0] * e[1] - d[1] * e[0];
    if den.abs() < 1e-300 {
        return None;
    }
    let w = [a[0] - p[0], a[1] - p[1]];
    let s = -(d[0] * w[1] - d[1] * w[0]) / den; // along a-b
    Some((s, [a[0] + s * e[0], a[1] + s * e[1]]))
}

/// Build the fill polygon. `alpha_sim` is the conveyor angle the simulation uses (the listing
/// forces 35°, erratum 4), `launch_angle` the sled's acceleration direction.
pub fn build_fill(
    profile: &Profile,
    g: f64,
    d: &Design,
    launch_angle: f64,
    aor_deg: f64,
    mode: PhysicsMode,
) -> Result<Fill, Invalid> {
    let surface_angle = fill_surface_angle(g, d.a, launch_angle, aor_deg);
    let p2_1 = profile.p2;
    let p1_2 = profile.p1_of(1);
    let p2_2 = profile.point_of(1, profile.p2);
    let p4_1 = profile.p4;
    let spill = |detail: String| Invalid::FillSpills { detail };

    let p_fill = match mode {
        PhysicsMode::Physical => {
            // 5.3.1: the fill spills into the next tooth when its surface is steeper than the
            // conveyor: then it leaves p2 rising relative to the base and passes over tooth 2.
            if surface_angle >= profile.alpha {
                return Err(spill(format!(
                    "fill surface angle {:.3} deg is not below the conveyor angle {:.3} deg",
                    surface_angle.to_degrees(),
                    profile.alpha.to_degrees()
                )));
            }
            let on_ramp = line_cross(p2_1, surface_angle, p1_2, p2_2).filter(|(s, _)| (0.0..=1.0).contains(s));
            let end = profile.point_of(profile.teeth - 1, profile.p4);
            let on_base =
                line_cross(p2_1, surface_angle, [0.0, 0.0], end).filter(|(_, p)| p[0] >= p2_1[0].min(p4_1[0]));
            match (on_ramp, on_base) {
                (Some((_, r)), Some((_, b))) => {
                    if r[0] <= b[0] {
                        r
                    } else {
                        b
                    }
                }
                (Some((_, r)), None) => r,
                (None, Some((_, b))) => b,
                (None, None) => return Err(spill("fill surface meets neither ramp 2 nor the base".into())),
            }
        }
        PhysicsMode::Listing => {
            // Listing lines 117-162: sign changes of (fill - ramp_2) on [p2_1.x, p2_2.x] and of
            // (fill - base) on [p2_1.x, p1_end.x]; both must exist; the smaller x wins.
            let slope = surface_angle.tan();
            let fill = |x: f64| p2_1[1] + slope * (x - p2_1[0]);
            let ra = (p2_2[1] - p1_2[1]) / (p2_2[0] - p1_2[0]);
            let ramp2 = |x: f64| p1_2[1] + ra * (x - p1_2[0]);
            let base = |x: f64| profile.alpha.tan() * x;
            let x_end = profile.p1_of(profile.teeth - 1)[0];
            let fr = |x: f64| fill(x) - ramp2(x);
            let fb = |x: f64| fill(x) - base(x);
            if fr(p2_1[0]).signum() == fr(p2_2[0]).signum() {
                return Err(spill(
                    "listing fill construction: fill surface does not cross ramp 2 before its peak".into(),
                ));
            }
            if fb(p2_1[0]).signum() == fb(x_end).signum() {
                return Err(spill("listing fill construction: fill surface does not cross the base".into()));
            }
            // Both are straight lines: the root fzero brackets is the line-line crossing.
            let xr = (ramp2(0.0) - fill(0.0)) / (slope - ra);
            let xb = (base(0.0) - fill(0.0)) / (slope - profile.alpha.tan());
            if xr <= xb {
                [xr, fill(xr)]
            } else {
                [xb, fill(xb)]
            }
        }
    };

    let (a2, a4) = profile.catch_arc_angles();
    // the arc's point in the direction with this sine and cosine
    let arc_point = |(s, c): (f64, f64)| [profile.p3[0] + profile.radius * c, profile.p3[1] + profile.radius * s];
    // p4, [p1_2], p_fill, then the arc
    let mut polygon = Vec::with_capacity(3 + PHYSICAL_ARC_POINTS.max(10));
    polygon.push(p4_1);
    if p_fill[0] > p1_2[0] {
        polygon.push(p1_2);
    }
    polygon.push(p_fill);
    match mode {
        PhysicsMode::Physical => {
            // the kernel's own sines and cosines (`lane_math`), the same on every libm
            let angles: Vec<f64> = (0..PHYSICAL_ARC_POINTS)
                .map(|k| a2 + (k as f64 / (PHYSICAL_ARC_POINTS - 1) as f64) * (a4 - a2))
                .collect();
            let (sin, cos) = arc_sin_cos(&angles);
            polygon.extend(sin.into_iter().zip(cos).map(arc_point));
        }
        PhysicsMode::Listing => {
            // Listing lines 165-183: linspace(a2, a4 - 0.05, 1000), every 100th point.
            let n = 1000;
            for k in (0..n).step_by(100) {
                let f = k as f64 / (n - 1) as f64;
                let angle = a2 + f * (a4 - 0.05 - a2);
                polygon.push(arc_point((angle.sin(), angle.cos())));
            }
        }
    }
    let area = polygon_area(&polygon);
    let exact = (mode == PhysicsMode::Physical).then(|| {
        let mut straight = vec![p4_1];
        if p_fill[0] > p1_2[0] {
            straight.push(p1_2);
        }
        straight.push(p_fill);
        straight.push(p2_1);
        let from_centre = |q: V2| [q[0] - profile.p3[0], q[1] - profile.p3[1]];
        ExactBoundary {
            straight,
            centre: profile.p3,
            radius: profile.radius,
            a2,
            a4,
            to_p2: from_centre(profile.p2),
            to_p4: from_centre(profile.p4),
        }
    });
    Ok(Fill { surface_angle, p_fill, polygon, area, exact })
}

/// The sines and cosines of the fill arc's angles (`lane_math::sin_cos`), in the x86-64-v3
/// build where the cpu engine's path takes it: there the compiler runs the loop four angles
/// at a time (the function has no branch), to the same bits.
fn arc_sin_cos(angles: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (mut sin, mut cos) = (vec![0.0; angles.len()], vec![0.0; angles.len()]);
    #[cfg(target_arch = "x86_64")]
    if crate::simd::selected().x86_64_v3() {
        // SAFETY: the CPU has every feature the function is compiled for (the path is one
        // this CPU has).
        unsafe { x86_64_v3_arc_sin_cos(angles, &mut sin, &mut cos) };
        return (sin, cos);
    }
    arc_sin_cos_inlined(angles, &mut sin, &mut cos);
    (sin, cos)
}

/// [`arc_sin_cos`]'s loop, into slices (a loop that writes pairs was left scalar).
#[inline(always)]
fn arc_sin_cos_inlined(angles: &[f64], sin: &mut [f64], cos: &mut [f64]) {
    for ((&a, s), c) in angles.iter().zip(sin.iter_mut()).zip(cos.iter_mut()) {
        (*s, *c) = crate::lane_math::sin_cos(a);
    }
}

/// [`arc_sin_cos_inlined`] compiled for x86-64-v3 ([`crate::simd`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]
fn x86_64_v3_arc_sin_cos(angles: &[f64], sin: &mut [f64], cos: &mut [f64]) {
    arc_sin_cos_inlined(angles, sin, cos)
}

/// Shoelace area (MATLAB polyarea).
pub fn polygon_area(poly: &[V2]) -> f64 {
    let n = poly.len();
    let mut s = 0.0;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        s += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * s.abs()
}

/// Even-odd point-in-polygon test; points on an edge count as inside (MATLAB inpolygon).
pub fn in_polygon(p: V2, poly: &[V2]) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        // on-edge test
        let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let within =
            p[0] >= a[0].min(b[0]) && p[0] <= a[0].max(b[0]) && p[1] >= a[1].min(b[1]) && p[1] <= a[1].max(b[1]);
        if cross.abs() <= 1e-18 && within {
            return true;
        }
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Van der Corput radical inverse of `i` in `base`. Inlined so that the launch points' bases
/// 2 and 3 are constants: the digit loop's `%` and `/` then compile to shifts and multiplies
/// instead of 64-bit divisions (same digits, same sum, in the same order).
#[inline(always)]
pub fn radical_inverse(mut i: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut r = 0.0;
    while i > 0 {
        r += f * (i % base) as f64;
        i /= base;
        f *= inv;
    }
    r
}

/// [`radical_inverse`] of `first`, `first + 1`, … (`L` of them) in `base`, to the same bits:
/// every lane runs as many digit steps as the largest index has digits, and a step past a
/// lane's last digit adds `f * 0.0 = +0.0`, which leaves a non-negative sum unchanged. The
/// common trip count lets the compiler run the lanes as SIMD.
#[inline(always)]
pub fn radical_inverse_lanes<const L: usize>(first: u32, base: u32) -> [f64; L] {
    let inv = 1.0 / base as f64;
    let mut digits = 0;
    let mut last = first as u64 + L as u64 - 1;
    while last > 0 {
        last /= base as u64;
        digits += 1;
    }
    let mut i: [u32; L] = std::array::from_fn(|l| first + l as u32);
    let mut f = inv;
    let mut r = [0.0; L];
    for _ in 0..digits {
        for l in 0..L {
            r[l] += f * (i[l] % base) as f64;
            i[l] /= base;
        }
        f *= inv;
    }
    r
}

/// [`radical_inverse`] in base 2 by reversing the bits: its digits' weights are powers of
/// two, so for i < 2^53 the loop's sum is exact and equals the reversed bits scaled by 2^-64.
#[inline(always)]
pub fn radical_inverse_2(i: u64) -> f64 {
    debug_assert!(i < 1 << 53);
    i.reverse_bits() as f64 * (-64f64).exp2()
}

/// Launch points (Eq. 4.37, listing lines 185-209): Halton bases 2 and 3 with the first
/// point skipped, scaled to the polygon's bounding box, the first `n` inside it. The
/// listing stops after 2000 candidates; the physical mode keeps drawing (deviation: the
/// thesis's 2000 cannot seat 10 000 particles). `LaunchPoints::Random` replaces the Halton
/// candidates by independent uniform ones keyed by (seed, candidate).
pub fn launch_points(
    fill: &Fill,
    n: usize,
    mode: PhysicsMode,
    sampling: LaunchPoints,
    seed: u64,
) -> Result<Vec<V2>, Invalid> {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::selected().x86_64_v3() {
        // SAFETY: the CPU has every feature the function is compiled for (the path is one
        // this CPU has).
        return unsafe { x86_64_v3_launch_points(fill, n, mode, sampling, seed) };
    }
    launch_points_inlined(fill, n, mode, sampling, seed)
}

/// [`launch_points`] compiled for x86-64-v3 ([`crate::simd`]): the candidate tests run
/// on four f64 lanes instead of two (preparation 14–16 % faster, `cargo bench -p
/// sawtooth-benches --bench engines -- prepare`), to the same bits (tested below).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]
fn x86_64_v3_launch_points(
    fill: &Fill,
    n: usize,
    mode: PhysicsMode,
    sampling: LaunchPoints,
    seed: u64,
) -> Result<Vec<V2>, Invalid> {
    launch_points_inlined(fill, n, mode, sampling, seed)
}

#[inline(always)]
fn launch_points_inlined(
    fill: &Fill,
    n: usize,
    mode: PhysicsMode,
    sampling: LaunchPoints,
    seed: u64,
) -> Result<Vec<V2>, Invalid> {
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in &fill.polygon {
        xmin = xmin.min(p[0]);
        xmax = xmax.max(p[0]);
        ymin = ymin.min(p[1]);
        ymax = ymax.max(p[1]);
    }
    let limit = match mode {
        PhysicsMode::Listing => LISTING_HALTON_POINTS,
        PhysicsMode::Physical => MAX_HALTON_POINTS.max(LISTING_HALTON_POINTS),
    };
    // Candidates are drawn and tested eight at a time (SIMD lanes), then taken in order as
    // the one-at-a-time loop would: a batch may test a few candidates past the last one
    // needed, and those are dropped. (Preparation −35 % with the x86-64-v3 build.)
    const LANES: usize = 8;
    const _: () = assert!(MAX_HALTON_POINTS + LANES as u64 <= u32::MAX as u64, "candidate indices fit u32");
    let w = seed_word(seed); // the random candidates' key
    let mut out = Vec::with_capacity(n);
    let mut i = 1u64;
    'candidates: while out.len() < n && i <= limit {
        let (u, v): ([f64; LANES], [f64; LANES]) = match sampling {
            LaunchPoints::Halton => {
                (std::array::from_fn(|l| radical_inverse_2(i + l as u64)), radical_inverse_lanes(i as u32, 3))
            }
            LaunchPoints::Random => {
                let at = |l: usize, draw: u32| uniform01(w, (i + l as u64) as u32, PER_PARTICLE, draw);
                (
                    std::array::from_fn(|l| at(l, DRAW_LAUNCH_POINT)),
                    std::array::from_fn(|l| at(l, DRAW_LAUNCH_POINT + 1)),
                )
            }
        };
        let px: [f64; LANES] = std::array::from_fn(|l| xmin + (xmax - xmin) * u[l]);
        let py: [f64; LANES] = std::array::from_fn(|l| ymin + (ymax - ymin) * v[l]);
        let inside: [bool; LANES] = match &fill.exact {
            Some(b) => b.contains_lanes(&px, &py),
            None => std::array::from_fn(|l| in_polygon([px[l], py[l]], &fill.polygon)),
        };
        for l in 0..LANES {
            if !(out.len() < n && i <= limit) {
                break 'candidates;
            }
            if inside[l] {
                out.push([px[l], py[l]]);
            }
            i += 1;
            // A fill that seats fewer than 1 in 1000 candidates is degenerate (a sliver): stop
            // early instead of drawing millions of points; a usable fill seats ~20 % or more.
            if i == 20_000 && out.len() < 20 {
                break 'candidates;
            }
        }
    }
    if out.len() < n {
        return Err(Invalid::FillTooSmall { found: out.len(), needed: n, candidates: i - 1 });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_matches_known_values() {
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(2, 2), 0.25);
        assert_eq!(radical_inverse(3, 2), 0.75);
        assert!((radical_inverse(1, 3) - 1.0 / 3.0).abs() < 1e-15);
        assert!((radical_inverse(5, 3) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-15);
    }

    /// The launch points as the one-at-a-time loop drew them before candidates were tested
    /// in batches: the specification [`launch_points`] keeps to the bit.
    fn launch_points_one_at_a_time(
        fill: &Fill,
        n: usize,
        mode: PhysicsMode,
        sampling: LaunchPoints,
        seed: u64,
    ) -> Result<Vec<V2>, Invalid> {
        let xs = fill.polygon.iter().map(|p| p[0]);
        let ys = fill.polygon.iter().map(|p| p[1]);
        let (xmin, xmax) = (xs.clone().fold(f64::INFINITY, f64::min), xs.fold(f64::NEG_INFINITY, f64::max));
        let (ymin, ymax) = (ys.clone().fold(f64::INFINITY, f64::min), ys.fold(f64::NEG_INFINITY, f64::max));
        let limit = if mode == PhysicsMode::Listing { LISTING_HALTON_POINTS } else { MAX_HALTON_POINTS };
        let mut out = Vec::new();
        let mut i = 1u64;
        while out.len() < n && i <= limit {
            let (u, v) = match sampling {
                LaunchPoints::Halton => (radical_inverse(i, 2), radical_inverse(i, 3)),
                LaunchPoints::Random => {
                    let w = seed_word(seed);
                    (
                        uniform01(w, i as u32, PER_PARTICLE, DRAW_LAUNCH_POINT),
                        uniform01(w, i as u32, PER_PARTICLE, DRAW_LAUNCH_POINT + 1),
                    )
                }
            };
            let p = [xmin + (xmax - xmin) * u, ymin + (ymax - ymin) * v];
            let inside = match &fill.exact {
                Some(b) => b.contains(p),
                None => in_polygon(p, &fill.polygon),
            };
            if inside {
                out.push(p);
            }
            i += 1;
            if i == 20_000 && out.len() < 20 {
                break;
            }
        }
        if out.len() < n {
            return Err(Invalid::FillTooSmall { found: out.len(), needed: n, candidates: i - 1 });
        }
        Ok(out)
    }

    /// Batched candidates (eight per step, both compilations) seat the same points, to the
    /// bit, and fail with the same count as one candidate at a time: fills of random valid
    /// designs of both environments in both modes, Halton and random candidates, counts on
    /// and off a batch's edge, the listing's 2000-candidate limit, and a sliver that stops
    /// early.
    #[test]
    fn batched_candidates_seat_the_one_at_a_time_points() {
        use crate::model::{prepare, sampling::random_valid_designs, Scenario};
        let mut fills = Vec::new();
        for scenario in [Scenario::lunar(), Scenario::earth()] {
            for mode in [PhysicsMode::Physical, PhysicsMode::Listing] {
                let s = Scenario { mode, ..scenario.clone() };
                for d in random_valid_designs(&s, 3, 11) {
                    fills.push((prepare(&s, &d).expect("a valid design").fill, mode));
                }
            }
        }
        // a sliver: seats fewer than 20 of the first 20 000 candidates
        let sliver = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 1.0001]];
        let polygon_fill = |polygon: Vec<V2>| Fill {
            surface_angle: 0.0,
            p_fill: [0.0; 2],
            area: polygon_area(&polygon),
            polygon,
            exact: None,
        };
        fills.push((polygon_fill(sliver), PhysicsMode::Physical));
        // a square seats every candidate: the listing's limit decides at exactly 2000 points
        fills.push((polygon_fill(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), PhysicsMode::Listing));
        let (mut seated, mut refused) = (0, 0);
        for (fill, mode) in &fills {
            for sampling in [LaunchPoints::Halton, LaunchPoints::Random] {
                for n in [1, 7, 8, 9, 100, 333, 1500, 2000, 2001] {
                    let expected = launch_points_one_at_a_time(fill, n, *mode, sampling, 5);
                    let bits = |r: &Result<Vec<V2>, Invalid>| match r {
                        Ok(ps) => Ok(ps.iter().map(|p| [p[0].to_bits(), p[1].to_bits()]).collect::<Vec<_>>()),
                        Err(e) => Err(e.to_string()),
                    };
                    #[allow(unused_mut)] // the x86-64-v3 build joins it on x86-64 only
                    let mut builds = vec![("baseline", launch_points_inlined(fill, n, *mode, sampling, 5))];
                    #[cfg(target_arch = "x86_64")]
                    if crate::simd::Simd::Avx2.supported() {
                        // SAFETY: the CPU has x86-64-v3 (checked above).
                        builds.push(("x86-64-v3", unsafe { x86_64_v3_launch_points(fill, n, *mode, sampling, 5) }));
                    }
                    for (build, got) in builds {
                        assert_eq!(bits(&got), bits(&expected), "{build}, {mode:?}, {sampling:?}, n {n}");
                    }
                    match expected {
                        Ok(_) => seated += 1,
                        Err(_) => refused += 1,
                    }
                }
            }
        }
        assert!(seated > 50 && refused >= 4, "{seated} seated, {refused} refused");
    }

    /// The fill arc's sines and cosines in the x86-64-v3 build (vectorised by the compiler)
    /// are the scalar `lane_math::sin_cos`'s to the bit, over the arcs' angles and beyond.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_arcs_sines_and_cosines_are_the_same_in_both_builds() {
        if !crate::simd::Simd::Avx2.supported() {
            eprintln!("skipped: this CPU lacks x86-64-v3, so only the baseline build runs here");
            return;
        }
        for n in [1, 3, 4, 5, 512, 1003] {
            let angles: Vec<f64> = (0..n).map(|k| -7.0 + 14.0 * ((k as f64 * 0.618_033_988_749_895) % 1.0)).collect();
            let (mut s, mut c) = (vec![0.0; n], vec![0.0; n]);
            // SAFETY: the CPU has x86-64-v3 (checked above).
            unsafe { x86_64_v3_arc_sin_cos(&angles, &mut s, &mut c) };
            for (k, &a) in angles.iter().enumerate() {
                let (ws, wc) = crate::lane_math::sin_cos(a);
                assert_eq!((s[k].to_bits(), c[k].to_bits()), (ws.to_bits(), wc.to_bits()), "sin_cos({a})");
            }
        }
    }

    /// Every lane of [`radical_inverse_lanes`] is [`radical_inverse`] to the bit, also where
    /// a batch crosses into one more digit.
    #[test]
    fn radical_inverse_lanes_are_the_digit_loop_to_the_bit() {
        for first in (1..3000u32).chain([6555, 6558, 59_045, 19_999_990]) {
            let lanes: [f64; 8] = radical_inverse_lanes(first, 3);
            for (l, r) in lanes.iter().enumerate() {
                assert_eq!(
                    r.to_bits(),
                    radical_inverse(first as u64 + l as u64, 3).to_bits(),
                    "{}",
                    first as usize + l
                );
            }
        }
    }

    #[test]
    fn base_2_by_bit_reversal_is_the_digit_loop_to_the_bit() {
        for i in (0..100_000u64).chain([(1 << 53) - 1, 123_456_789_012_345]) {
            assert_eq!(radical_inverse_2(i).to_bits(), radical_inverse(i, 2).to_bits(), "{i}");
        }
    }

    /// Membership by cross products with the arc's end directions decides as the angle form
    /// does, over circle points of fills at every slope of the rig (all but points within
    /// rounding of an end ray, which Halton candidates do not meet).
    #[test]
    fn arc_membership_by_cross_products_matches_the_angles() {
        use crate::model::{
            geometry::{check_design, Profile},
            Design,
        };
        let d = Design::lunar_solution_c();
        let mut fills = 0;
        for alpha in [0.0, 10.0, 20.0, 35.0, 40.0] {
            let prof = Profile::new(&d, check_design(&d).unwrap(), alpha, 10);
            let ang = (alpha + 18.434 + d.delta_deg).to_radians();
            let Ok(f) = build_fill(&prof, 1.625, &d, ang, 58.0, PhysicsMode::Physical) else { continue };
            let b = f.exact.unwrap();
            for i in 1..20_000u64 {
                let phi = 2.0 * std::f64::consts::PI * radical_inverse(i, 3);
                let u = [b.radius * phi.cos(), b.radius * phi.sin()];
                assert_eq!(b.on_arc(u), b.on_arc_by_angle(u), "alpha {alpha}, direction {phi}");
            }
            fills += 1;
        }
        assert!(fills >= 2, "{fills}"); // solution C spills at some of these slopes
                                        // arcs shorter and longer than half a turn (the two branches), and one across ±π
        for (a2, a4) in [(-0.5f64, 2.0f64), (-1.0, 3.5), (2.0, 6.0)] {
            let b = ExactBoundary {
                straight: vec![],
                centre: [0.0, 0.0],
                radius: 1.0,
                a2,
                a4,
                to_p2: [a2.cos(), a2.sin()],
                to_p4: [a4.cos(), a4.sin()],
            };
            for i in 1..20_000u64 {
                let phi = 2.0 * std::f64::consts::PI * radical_inverse(i, 3);
                let u = [phi.cos(), phi.sin()];
                assert_eq!(b.on_arc(u), b.on_arc_by_angle(u), "arc [{a2}, {a4}), direction {phi}");
            }
        }
    }

    #[test]
    fn square_area_and_membership() {
        let sq = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(polygon_area(&sq), 1.0);
        assert!(in_polygon([0.5, 0.5], &sq));
        assert!(in_polygon([1.0, 0.5], &sq));
        assert!(!in_polygon([1.5, 0.5], &sq));
    }

    #[test]
    fn line_cross_finds_the_middle_of_a_crossing_segment() {
        let (s, p) = line_cross([0.0, 0.0], 0.0, [1.0, -1.0], [1.0, 1.0]).unwrap();
        assert!((s - 0.5).abs() < 1e-15 && (p[0] - 1.0).abs() < 1e-15 && p[1].abs() < 1e-15);
    }

    /// The physical fill of lunar solution C (α 35°, launch offset 18.434°, AOR 58°).
    fn solution_c_fill() -> Fill {
        use crate::model::{
            geometry::{check_design, Profile},
            Design,
        };
        let d = Design::lunar_solution_c();
        let prof = Profile::new(&d, check_design(&d).unwrap(), 35.0, 10);
        let ang = (35.0f64 + 18.434 + d.delta_deg).to_radians();
        build_fill(&prof, 1.625, &d, ang, 58.0, PhysicsMode::Physical).unwrap()
    }

    #[test]
    fn exact_boundary_agrees_with_a_fine_polygon() {
        let f = solution_c_fill();
        let b = f.exact.as_ref().unwrap();
        let (mut disagree, mut inside) = (0, 0);
        for i in 1..20_000u64 {
            let p = [-0.01 + 0.09 * radical_inverse(i, 2), -0.01 + 0.1 * radical_inverse(i, 3)];
            let e = b.contains(p);
            inside += e as u32;
            if e != in_polygon(p, &f.polygon) {
                disagree += 1;
            }
        }
        assert!(inside > 1000, "{inside}");
        // only points in the slivers between the arc and its 512-point chords may differ
        assert!(disagree <= 3, "{disagree}");
    }

    #[test]
    fn the_fill_lies_below_its_surface_line() {
        let f = solution_c_fill();
        assert!(f.depth(f.p_fill) < 1e-15);
        // every vertex on one side (the surface is an edge of the fill), some well below it
        let signed: Vec<f64> = f.polygon.iter().map(|v| f.signed_surface_distance(*v)).collect();
        let (lo, hi) = signed.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        assert!(lo > -1e-12 || hi < 1e-12, "vertices on both sides: [{lo}, {hi}]");
        let deepest = lo.abs().max(hi.abs());
        assert!(deepest > 1e-3, "{deepest}");
        for l in launch_points(&f, 200, PhysicsMode::Physical, LaunchPoints::Halton, 0).unwrap() {
            let dd = f.depth(l);
            assert!(dd <= deepest + 1e-12, "{dd} > {deepest}");
        }
    }

    #[test]
    fn surface_at_rest_is_the_angle_of_repose() {
        // erratum 21: with a = 0 the surface angle reduces to the AOR.
        let ang = fill_surface_angle(9.81, 0.0, 1.0, 34.0);
        assert!((ang.to_degrees() - 34.0).abs() < 1e-9);
    }
}
