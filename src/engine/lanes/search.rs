//! The flight search, the launch randomisation and the restitution on lanes, written once
//! over [`Lane`]: `kernel::first_hit_in` with `model::flight`'s crossings, step by step,
//! each branch a select of both sides (a branch no lane takes is skipped), whole numbers
//! (teeth, surface codes) riding as f64. Each function names the scalar function it
//! follows; the scalar functions are the reference (`tests.rs` compares every lane with
//! them, to the bit).

use super::{LaneFlights, MAX_LANES};
use crate::engine::kernel::{
    Hit, KDesign, KParticle, KPhysics, SURFACE_BASE, SURFACE_CATCH, SURFACE_NONE, SURFACE_RAMP,
};
use crate::lane::{F64Lane, Lane, LaneMask};
use crate::lane_math::{atan2, exp_m1, ln, ln_1p, sin_cos};
use crate::model::collision::Restitution;
use crate::model::rng::pcg4d_keys;

/// Up to two crossing times per lane: how many (as f64), the first and the second
/// (`flight::Roots`).
#[derive(Clone, Copy)]
struct Roots<L> {
    n: L,
    r0: L,
    r1: L,
}

/// `flight::push_root` in the lanes of `mask`.
#[inline(always)]
fn push<L: Lane>(r: &mut Roots<L>, mask: L::Mask, t: L, t_min: L, t_max: L) {
    let ok = mask & kept(t, t_min, t_max);
    let first = r.n.eq(L::splat(0.0));
    r.r0 = L::select(ok & first, t, r.r0);
    r.r1 = L::select(ok & !first, t, r.r1);
    r.n = L::select(ok, r.n + L::splat(1.0), r.n);
}

/// A flight's start, launch velocity and drag in every lane (`flight::Flight`).
#[derive(Clone, Copy)]
struct Fl<L: Lane> {
    px: L,
    py: L,
    vx: L,
    vy: L,
    /// 0.5 g, as the scalar position multiplies it.
    half_g: L,
    /// Stokes k_drag (1/s; 0 in vacuum) and the terminal velocity -g/k of a drag flight.
    k: L,
    vinf: L,
    /// The sled-motion drift added to the position (zero but where a piece drifts) and the
    /// lanes whose piece drifts (`Flight::drift` not zero).
    wx: L,
    wy: L,
    drifting: L::Mask,
}

/// `flight::relax`, (1 - e^{-kt})/k.
#[inline(always)]
fn relax<L: F64Lane>(f: &Fl<L>, t: L) -> L {
    -exp_m1(-f.k * t) / f.k
}

/// `Flight::pos`.
#[inline(always)]
fn pos_at<L: F64Lane, const DRAG: bool>(f: &Fl<L>, t: L) -> (L, L) {
    let (x, y) = if DRAG {
        // Eq. 4.53-4.54
        let e = relax(f, t);
        (f.px + f.vx * e, f.py + f.vinf * t + (f.vy - f.vinf) * e)
    } else {
        (f.px + f.vx * t, f.py + f.vy * t - f.half_g * t * t)
    };
    if !f.drifting.any() {
        return (x, y);
    }
    // the drift adds to the position where there is one
    (L::select(f.drifting, x + f.wx * t, x), L::select(f.drifting, y + f.wy * t, y))
}

/// `Flight::time_at_x`.
#[inline(always)]
fn time_at_x<L: F64Lane, const DRAG: bool>(f: &Fl<L>, x: L) -> L {
    let (zero, inf) = (L::splat(0.0), L::splat(f64::INFINITY));
    let dx = x - f.px;
    let t = dx / f.vx;
    let never = f.vx.eq(zero) | t.lt(zero);
    let behind = L::select(dx.eq(zero), zero, inf);
    if DRAG {
        // beyond the drag asymptote x0 + vx/k when q <= 0
        let q = L::splat(1.0) - f.k * dx / f.vx;
        let t = -ln(q) / f.k;
        return L::select(never, behind, L::select(q.le(zero), inf, t));
    }
    L::select(never, behind, t)
}

/// `Flight::y_at_x`: whether it gets there, and the height.
#[inline(always)]
fn y_at_x<L: F64Lane, const DRAG: bool>(f: &Fl<L>, x: L) -> (L::Mask, L) {
    let zero = L::splat(0.0);
    let e = (x - f.px) / f.vx;
    let reaches = f.vx.ne(zero) & !e.lt(zero);
    if DRAG {
        // Eq. 4.55
        let q = L::splat(1.0) - f.k * e;
        let t = -ln(q) / f.k;
        return (reaches & !q.le(zero), f.py + f.vinf * t + (f.vy - f.vinf) * e);
    }
    (reaches, f.py + f.vy * e - f.half_g * e * e)
}

/// The coefficients of f(t) = n·(P(t) - a) of a flight against the line through `a` with
/// normal `n` (`Flight::line_crossings`' first lines): c0 (zero for a flight departing the
/// line), n·v and n·drift.
#[inline(always)]
fn line_coefficients<L: Lane>(f: &Fl<L>, (ax, ay): (L, L), (nx, ny): (L, L), departing: L::Mask) -> (L, L, L) {
    let c0 = L::select(departing, L::splat(0.0), nx * (f.px - ax) + ny * (f.py - ay));
    let nv = nx * f.vx + ny * f.vy;
    let nw = nx * f.wx + ny * f.wy; // drift adds to the linear term
    (c0, nv, nw)
}

/// The roots of c2 t² + c1 t + c0 by the stable form (`flight::quadratic_roots` where c2 is
/// not zero): the smaller and the larger, and the lanes that have two (a negative
/// discriminant or the double root t = 0 have none).
#[inline(always)]
fn quadratic_pair<L: Lane>(c2: L, c1: L, c0: L) -> (L::Mask, L, L) {
    let zero = L::splat(0.0);
    let disc = c1 * c1 - L::splat(4.0) * c2 * c0;
    let sq = disc.sqrt();
    let q = L::select(c1.ge(zero), L::splat(-0.5) * (c1 + sq), L::splat(-0.5) * (c1 - sq));
    let (x, y) = (q / c2, c0 / q);
    let swap = y.lt(x);
    (!disc.lt(zero) & !q.eq(zero), L::select(swap, y, x), L::select(swap, x, y))
}

/// `Flight::line_crossings` of vacuum flights, in the lanes of `mask` (no roots elsewhere).
/// `c2_g` is -0.5 g.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn vacuum_crossings<L: Lane>(
    mask: L::Mask,
    f: &Fl<L>,
    c2_g: f64,
    a: (L, L),
    n: (L, L),
    departing: L::Mask,
    t_min: L,
    t_max: L,
) -> Roots<L> {
    let zero = L::splat(0.0);
    let (c0, nv, nw) = line_coefficients(f, a, n, departing);
    let c1 = nv + nw;
    let c2 = L::splat(c2_g) * n.1;
    let mut r = Roots { n: zero, r0: zero, r1: zero };
    // departing: f(t) = t (c1 + c2 t)
    let dep = mask & departing & c2.ne(zero);
    if dep.any() {
        push(&mut r, dep, -c1 / c2, t_min, t_max);
    }
    // quadratic_roots: the linear case, then both roots of the stable form
    let solve = mask & !departing;
    if !solve.any() {
        return r;
    }
    let linear = solve & c2.eq(zero) & c1.ne(zero);
    if linear.any() {
        push(&mut r, linear, -c0 / c1, t_min, t_max);
    }
    let (two, small, large) = quadratic_pair(c2, c1, c0);
    let quad = solve & c2.ne(zero) & two;
    push(&mut r, quad, small, t_min, t_max);
    push(&mut r, quad, large, t_min, t_max);
    r
}

/// `flight::stokes_f`, f(t) = c0 + a t + b E(t).
#[inline(always)]
fn stokes_f<L: F64Lane>(f: &Fl<L>, (c0, ca, cb): (L, L, L), t: L) -> L {
    c0 + ca * t + cb * relax(f, t)
}

/// `flight::stokes_horizon`: a time by which f has its final sign.
#[inline(always)]
fn stokes_horizon<L: Lane>((c0, a, b): (L, L, L), k: L) -> L {
    let zero = L::splat(0.0);
    let falling = ((c0 + b.max(zero) / k) / -a).max(zero);
    let rising = ((-c0 - b.min(zero) / k) / a).max(zero);
    L::select(a.lt(zero), falling, L::select(a.gt(zero), rising, L::splat(40.0) / k))
}

/// `flight::final_sign_at_horizon`: f at the horizon with the sign the bound gives it.
#[inline(always)]
fn final_sign_at_horizon<L: Lane>(f: L, a: L) -> L {
    let zero = L::splat(0.0);
    L::select(a.lt(zero), f.min(zero), L::select(a.gt(zero), f.max(L::splat(f64::MIN_POSITIVE)), f))
}

/// Where `flight::push_root` keeps a root: in (0, ∞) ∩ [t_min, t_max].
#[inline(always)]
fn kept<L: Lane>(t: L, t_min: L, t_max: L) -> L::Mask {
    t.gt(L::splat(0.0)) & t.ge(t_min) & t.le(t_max)
}

/// The first root `flight::quadratic_roots` keeps in (0, ∞) ∩ [t_min, t_max], and the lanes
/// that have one.
#[inline(always)]
fn first_quadratic_root<L: Lane>(c2: L, c1: L, c0: L, t_min: L, t_max: L) -> (L::Mask, L) {
    let zero = L::splat(0.0);
    let linear = c2.eq(zero);
    let t_lin = -c0 / c1;
    let lin_ok = linear & c1.ne(zero) & kept(t_lin, t_min, t_max);
    let (two, small, large) = quadratic_pair(c2, c1, c0);
    let quad = !linear & two;
    let (ok_small, ok_large) = (quad & kept(small, t_min, t_max), quad & kept(large, t_min, t_max));
    (lin_ok | ok_small | ok_large, L::select(lin_ok, t_lin, L::select(ok_small, small, large)))
}

/// `flight::bracketed_newton` in the lanes of `mask`: each lane takes the scalar function's
/// steps and stops where it returns; the group runs as many steps as its slowest lane.
#[inline(always)]
fn bracketed_newton<L: F64Lane>(
    f: &Fl<L>,
    mask: L::Mask,
    (c0, ca, cb): (L, L, L),
    (mut lo, mut hi): (L, L),
    (f_lo, f_hi): (L, L),
) -> L {
    let (zero, one, k) = (L::splat(0.0), L::splat(1.0), f.k);
    let lo_positive = f_lo.gt(zero);
    let (has, root) = first_quadratic_root(L::splat(-0.5) * k * cb, ca + cb, c0, lo, hi);
    let mut t = L::select(has, root, lo);
    let regula = L::select(f_hi.ne(f_lo), lo - f_lo * (hi - lo) / (f_hi - f_lo), L::splat(0.5) * (lo + hi));
    t = L::select(t.gt(lo) & t.lt(hi), t, regula);
    t = L::select(t.gt(lo) & t.lt(hi), t, L::splat(0.5) * (lo + hi));
    let (mut active, mut result) = (mask, t);
    for _ in 0..48 {
        if !active.any() {
            break;
        }
        // f and its derivatives share e^{-kt}: one expm1 per step
        let m = exp_m1(-k * t);
        let ft = c0 + ca * t - cb * m / k;
        let d = ca + cb * (one + m);
        let on_root = active & ft.eq(zero);
        result = L::select(on_root, t, result);
        active = active & !on_root;
        let same_side = !(ft.gt(zero) ^ lo_positive);
        lo = L::select(active & same_side, t, lo);
        hi = L::select(active & !same_side, t, hi);
        let d2 = -k * cb * (one + m);
        let den = L::splat(2.0) * d * d - ft * d2;
        let halley = L::select(den.ne(zero), t - L::splat(2.0) * ft * d / den, lo - one);
        let tol = L::splat(f64::EPSILON * 4.0) * t.abs().max(L::splat(f64::MIN_POSITIVE));
        let inside = halley.gt(lo) & halley.lt(hi);
        let step = (halley - t).abs();
        let c = (d2 * d2 / (L::splat(4.0) * d * d) + k * d2 / (L::splat(6.0) * d)).abs();
        let short = step.le(L::splat(1e-3) * t.abs()) & (c * step * step * step).le(tol);
        let halley_final = active & inside & (step.le(tol) | short);
        let next = L::splat(0.5) * (lo + hi);
        let bisection_final = active & !inside & (next - t).abs().le(tol);
        result = L::select(halley_final, halley, L::select(bisection_final, next, result));
        active = active & !(halley_final | bisection_final);
        t = L::select(inside, halley, next);
    }
    L::select(active, t, result)
}

/// `Flight::line_crossings` of Stokes flights (the second half of the scalar function: at
/// most two roots, each bracketed on a monotone interval), in the lanes of `mask`.
#[inline(always)]
fn stokes_crossings<L: F64Lane>(
    mask: L::Mask,
    f: &Fl<L>,
    a: (L, L),
    n: (L, L),
    departing: L::Mask,
    t_min: L,
    t_max: L,
) -> Roots<L> {
    let (zero, inf) = (L::splat(0.0), L::splat(f64::INFINITY));
    let (c0, nv, nw) = line_coefficients(f, a, n, departing);
    let mut r = Roots { n: zero, r0: zero, r1: zero };
    let vinf_n = f.vinf * n.1;
    let (ca, cb) = (vinf_n + nw, nv - vinf_n);
    let coef = (c0, ca, cb);
    // the extremum t* = ln(1 + x)/k, where x = n·v/(-a) > 0
    let x = L::select(ca.ne(zero), (nv + nw) / -ca, zero);
    let has_star = mask & x.gt(zero) & x.abs().lt(inf);
    // (each function of the lanes below is taken only where some lane needs it)
    let t_star = if has_star.any() { ln_1p(x) / f.k } else { zero };
    let horizon = stokes_horizon(coef, f.k);
    let t_end = t_max.min(horizon);
    let active = mask & !t_min.gt(t_end);
    if !active.any() {
        return r;
    }
    let mut lo = t_min.max(zero);
    let from_zero = lo.eq(zero);
    let mut f_lo = if (active & !from_zero).any() { L::select(from_zero, c0, stokes_f(f, coef, lo)) } else { c0 };
    for (present, hi) in [(has_star, t_star), (L::Mask::splat(true), t_end)] {
        let go = active & present & !hi.le(lo);
        if !go.any() {
            continue;
        }
        let hi = hi.min(t_end);
        let f_hi = stokes_f(f, coef, hi);
        let f_hi = L::select(hi.eq(horizon), final_sign_at_horizon(f_hi, ca), f_hi);
        let starts_on_line = lo.eq(zero) & (departing | f_lo.eq(zero));
        // lift-off below rounding: the flight is back on its surface at t*
        let lift_off = go & departing & lo.gt(zero) & f_lo.le(zero) & r.n.eq(zero);
        push(&mut r, lift_off, lo, t_min, t_max);
        let bracket = go & !lift_off & !starts_on_line & (f_lo.gt(zero) ^ f_hi.gt(zero));
        if bracket.any() {
            let t = bracketed_newton(f, bracket, coef, (lo, hi), (f_lo, f_hi));
            push(&mut r, bracket, t, t_min, t_max);
        }
        lo = L::select(go, hi, lo);
        f_lo = L::select(go, f_hi, f_lo);
    }
    r
}

/// `Flight::line_crossings` in the lanes of `mask`, for vacuum or Stokes flights.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn crossings<L: F64Lane, const DRAG: bool>(
    mask: L::Mask,
    f: &Fl<L>,
    c2_g: f64,
    a: (L, L),
    n: (L, L),
    departing: L::Mask,
    t_min: L,
    t_max: L,
) -> Roots<L> {
    if DRAG {
        stokes_crossings(mask, f, a, n, departing, t_min, t_max)
    } else {
        vacuum_crossings(mask, f, c2_g, a, n, departing, t_min, t_max)
    }
}

/// `kernel::contact`: the lanes whose particle lies on the segment a-b's line (to rounding),
/// inside its extent, moving into it.
#[inline(always)]
fn contact<L: Lane>(
    pitch_len: f64,
    f: &Fl<L>,
    (vx, vy): (L, L),
    (ax, ay): (L, L),
    (bx, by): (L, L),
    (nx, ny): (L, L),
) -> L::Mask {
    let zero = L::splat(0.0);
    let (dx, dy) = (f.px - ax, f.py - ay);
    let c0 = dx * nx + dy * ny;
    let tol = L::splat(64.0 * f64::EPSILON) * L::splat(pitch_len).max(f.px.abs()).max(f.py.abs());
    let near = !(c0.abs().gt(tol) | (vx * nx + vy * ny).ge(zero));
    if !near.any() {
        return near; // the usual case: no lane lies on the line
    }
    let (ex, ey) = (bx - ax, by - ay);
    let s = (dx * ex + dy * ey) / (ex * ex + ey * ey);
    near & s.ge(zero) & s.le(L::splat(1.0))
}

/// Whether the point `q` lies on the segment from `a` along `e` (`ee` = e·e), as
/// `first_hit_in` asks of a crossing: 0 <= s <= 1 for its position s along it.
#[inline(always)]
fn on_segment<L: Lane>(q: (L, L), (ax, ay): (L, L), (ex, ey): (L, L), ee: L) -> L::Mask {
    let s = ((q.0 - ax) * ex + (q.1 - ay) * ey) / ee;
    s.ge(L::splat(0.0)) & s.le(L::splat(1.0))
}

/// `kernel::to_index`: a position's index clamped to ±1e9, kept as a whole f64.
#[inline(always)]
fn to_index<L: Lane>(x: L) -> L {
    x.max(L::splat(-1e9)).min(L::splat(1e9))
}

/// The first impact of each lane's flight: `kernel::first_hit_in` step by step. `DRAG`:
/// every lane's grain has Stokes drag (k_drag > 0), else none has. `PIECES`: the lanes'
/// flights are pieces, with a time limit and perhaps a drift; else flights in one piece,
/// whose code is the search's without either (the lunar batches ran 7 % slower through the
/// pieces' selects). The hits of lanes beyond the width are left empty.
#[inline(always)]
pub(super) fn first_hits<L: F64Lane, const DRAG: bool, const PIECES: bool>(
    d: &KDesign<f64>,
    ph: &KPhysics<f64>,
    lanes: &LaneFlights,
    bounce: u32,
) -> [Hit<f64>; MAX_LANES] {
    let a = &lanes.0;
    let (zero, one, inf) = (L::splat(0.0), L::splat(1.0), L::splat(f64::INFINITY));
    let k = if DRAG { L::load(&a[LaneFlights::K]) } else { zero };
    // how long each lane's search looks (`first_hit_in`'s t_limit: a piece's length,
    // infinite for a flight in one piece), and each lane's drift
    let limit = if PIECES { L::load(&a[LaneFlights::LIMIT]) } else { inf };
    let (wx, wy) =
        if PIECES { (L::load(&a[LaneFlights::DRIFT]), L::load(&a[LaneFlights::DRIFT + 1])) } else { (zero, zero) };
    let drifting = if PIECES { wx.ne(zero) | wy.ne(zero) } else { L::Mask::splat(false) };
    let (px, py) = (L::load(&a[LaneFlights::POS]), L::load(&a[LaneFlights::POS + 1]));
    let (vx, vy) = (L::load(&a[LaneFlights::VEL]), L::load(&a[LaneFlights::VEL + 1]));
    // the terminal velocity as `Flight` computes it, -g / k
    let vinf = if DRAG { -L::splat(ph.g) / k } else { zero };
    let f = Fl { px, py, vx, vy, half_g: L::splat(0.5 * ph.g), k, vinf, wx, wy, drifting };
    let (surface, kf) = (L::load(&a[LaneFlights::SURFACE]), L::load(&a[LaneFlights::TOOTH]));
    let c2_g = -0.5 * ph.g;
    // `rel_vel` of the scalar search: the velocity plus the drift
    let rel_vel = (f.vx + wx, f.vy + wy);

    // The base line through every p1; its crossing bounds the flight.
    let n_base = (L::splat(d.n_base[0]), L::splat(d.n_base[1]));
    let departing_base = surface.eq(L::splat(SURFACE_BASE as f64));
    let all = L::Mask::splat(true);
    let mut roots = crossings::<L, DRAG>(all, &f, c2_g, (zero, zero), n_base, departing_base, zero, limit);
    let s0 = -kf * L::splat(d.pitch_len);
    let s1 = s0 + L::splat(d.base_length);
    let (tb0, tb1) = (L::splat(d.t_base[0]), L::splat(d.t_base[1]));
    let ends = ((s0 * tb0, s0 * tb1), (s1 * tb0, s1 * tb1));
    let over = !departing_base & contact(d.pitch_len, &f, rel_vel, ends.0, ends.1, n_base);
    roots.n = L::select(over, one, roots.n);
    roots.r0 = L::select(over, zero, roots.r0);
    // every hop counts, so the first root is the base crossing
    let has = roots.n.ge(one);
    let t = roots.r0;
    let (qx, qy) = pos_at::<L, DRAG>(&f, t);
    let s = qx * tb0 + qy * tb1;
    let mut found = has & s.ge(s0) & s.le(L::splat(d.base_length) + s0);
    let horizon = if PIECES { L::select(has, t, inf).min(limit) } else { L::select(has, t, inf) };
    let teeth_last = L::splat((d.teeth - 1) as f64);
    let j = (to_index((s / L::splat(d.pitch_len)).floor()) + kf).max(zero).min(teeth_last);
    let mut best_t = L::select(found, t, inf);
    let (mut best_x, mut best_y) = (L::select(found, qx, zero), L::select(found, qy, zero));
    let mut best_tooth = L::select(found, j, zero);
    let mut best_surface = L::select(found, L::splat(SURFACE_BASE as f64), zero);

    // The teeth whose x-extent overlaps the flight's x-range before the horizon.
    let finite = horizon.abs().lt(inf);
    let x_end =
        L::select(finite, pos_at::<L, DRAG>(&f, horizon).0, L::select(f.vx.ge(zero), inf, L::splat(f64::NEG_INFINITY)));
    // with drift x(t) need not be monotone: |x(t) - x0| <= (|vx| + |wx|) t bounds the range
    // instead
    let (x_end, x_start) = if drifting.any() {
        let reach = (f.vx.abs() + wx.abs()) * horizon;
        (L::select(drifting, f.px + reach, x_end), L::select(drifting, f.px - reach, f.px))
    } else {
        (x_end, f.px)
    };
    let forward = x_end.ge(x_start);
    let (xmin, xmax) = (L::select(forward, x_start, x_end), L::select(forward, x_end, x_start));
    let lo = to_index(((xmin - L::splat(d.ext_max)) / L::splat(d.pitch[0])).ceil()) + kf;
    let hi = to_index(((xmax - L::splat(d.ext_min)) / L::splat(d.pitch[0])).floor()) + kf;
    let j_lo = lo.max(zero).min(teeth_last);
    let j_hi = hi.max(zero).min(teeth_last);
    let none = lo.gt(teeth_last) | hi.lt(zero);
    let count = L::select(none, zero, (j_hi - j_lo + one).max(zero));
    let x_far = L::select(found, best_x, x_end);
    let mut counts = [0.0; MAX_LANES];
    count.store(&mut counts);
    let steps = counts[..L::WIDTH].iter().fold(0.0f64, |m, &c| m.max(c)) as usize;
    let top_rel = L::splat(d.p2[1].max(d.p4[1]).max(0.0));
    let margin = L::splat(64.0 * f64::EPSILON * d.pitch_len);
    for step in 0..steps {
        // `flies_over`: a lane whose flight stays above this tooth's peak skips it (the
        // scalar scan passes the same teeth, in runs)
        let stepf = L::splat(step as f64);
        let j = j_lo + stepf;
        let dj = j - kf;
        let ahead = x_far.ge(f.px);
        let (lo, hi) = (L::select(ahead, f.px, x_far), L::select(ahead, x_far, f.px));
        let base = dj * L::splat(d.pitch[0]);
        let xa = (base + L::splat(d.ext_min)).max(lo);
        let xb = (base + L::splat(d.ext_max)).min(hi);
        let top = dj * L::splat(d.pitch[1]) + top_rel;
        let (sa, ya) = y_at_x::<L, DRAG>(&f, xa);
        let (sb, yb) = y_at_x::<L, DRAG>(&f, xb);
        // (a drifting lane's x(t) is not monotone: it searches every tooth of its range)
        let flies_over = (xa.gt(xb) | (sa & sb & ya.gt(top) & yb.gt(top))) & !drifting;
        let live = stepf.lt(count) & !flies_over;
        if !live.any() {
            continue;
        }
        for surface_kind in [SURFACE_RAMP, SURFACE_CATCH] {
            // the first tooth's catch is ignored on the first flight
            let on = if surface_kind == SURFACE_CATCH && bounce == 0 { live & !j.eq(zero) } else { live };
            if !on.any() {
                continue;
            }
            let (from, to, normal) =
                if surface_kind == SURFACE_RAMP { ([0.0, 0.0], d.p2, d.n_ramp) } else { (d.p2, d.p4, d.n_catch) };
            let (ox, oy) = (dj * L::splat(d.pitch[0]), dj * L::splat(d.pitch[1]));
            let (ax, ay) = (ox + L::splat(from[0]), oy + L::splat(from[1]));
            let (bx, by) = (ox + L::splat(to[0]), oy + L::splat(to[1]));
            let n = (L::splat(normal[0]), L::splat(normal[1]));
            let departing = surface.eq(L::splat(surface_kind as f64)) & dj.eq(zero);
            let t_max = L::select(found, best_t, horizon);
            // only while the flight is within the segment's x-extent can it hit the segment
            // (x(t) is monotone without drift): search that time window only
            let (xa, xb) = (ax.min(bx) - margin, ax.max(bx) + margin);
            let backward = f.vx.lt(zero);
            let x_in = L::select(backward, xb.min(f.px), xa.max(f.px));
            let x_out = L::select(backward, xa, xb);
            let moving = f.vx.gt(zero) | f.vx.lt(zero);
            let inside = f.px.ge(xa) & f.px.le(xb);
            let t_lo = L::select(moving, time_at_x::<L, DRAG>(&f, x_in), L::select(inside, zero, inf));
            let t_hi = L::select(moving, time_at_x::<L, DRAG>(&f, x_out), inf);
            // a drifting lane searches the whole time (`first_hit_in`: no x-window)
            let (t_lo, t_hi) = if drifting.any() {
                (L::select(drifting, zero, t_lo), L::select(drifting, inf, t_hi))
            } else {
                (t_lo, t_hi)
            };
            let search = on & !t_lo.gt(t_max);
            let mut roots = crossings::<L, DRAG>(search, &f, c2_g, (ax, ay), n, departing, t_lo, t_max.min(t_hi));
            let over = on & !departing & contact(d.pitch_len, &f, rel_vel, (ax, ay), (bx, by), n);
            roots.n = L::select(over, one, roots.n);
            roots.r0 = L::select(over, zero, roots.r0);
            // the first root on the segment itself (0 <= s <= 1) is this segment's hit
            let e = (bx - ax, by - ay);
            let ee = e.0 * e.0 + e.1 * e.1;
            let q0 = pos_at::<L, DRAG>(&f, roots.r0);
            let ok0 = on & roots.n.ge(one) & on_segment(q0, (ax, ay), e, ee);
            let second = on & roots.n.ge(L::splat(2.0)) & !ok0;
            let (q1, ok1) = if second.any() {
                let q1 = pos_at::<L, DRAG>(&f, roots.r1);
                (q1, second & on_segment(q1, (ax, ay), e, ee))
            } else {
                (q0, L::Mask::splat(false))
            };
            let t = L::select(ok0, roots.r0, roots.r1);
            let better = (ok0 | ok1) & t.lt(best_t);
            found = found | better;
            best_t = L::select(better, t, best_t);
            best_x = L::select(better, L::select(ok0, q0.0, q1.0), best_x);
            best_y = L::select(better, L::select(ok0, q0.1, q1.1), best_y);
            best_tooth = L::select(better, j, best_tooth);
            best_surface = L::select(better, L::splat(surface_kind as f64), best_surface);
        }
    }
    let mut out = [[0.0; MAX_LANES]; 5];
    for (row, v) in out.iter_mut().zip([best_t, best_x, best_y, best_tooth, best_surface]) {
        v.store(row);
    }
    let [t, x, y, tooth, surface] = out;
    let found = found.bits();
    let mut hits = [Hit::default(); MAX_LANES];
    for (l, h) in hits.iter_mut().enumerate().take(L::WIDTH) {
        *h = Hit {
            found: found >> l & 1 != 0,
            t: t[l],
            pos: [x[l], y[l]],
            tooth: tooth[l] as i32,
            surface: surface[l] as u32,
        };
    }
    hits
}

/// `Restitution::bounce` of the lanes' impact velocities `v` on surfaces with normals `n`:
/// the law's one code (`Restitution::bounce_on`) on lanes of `L`.
#[inline(always)]
pub(super) fn bounce<L: Lane<Scalar = f64>>(
    r: &Restitution<f64>,
    v: &[[f64; MAX_LANES]; 2],
    n: &[[f64; MAX_LANES]; 2],
) -> [[f64; MAX_LANES]; 2] {
    let out = r.bounce_on([L::load(&v[0]), L::load(&v[1])], [L::load(&n[0]), L::load(&n[1])]);
    let mut rows = [[0.0; MAX_LANES]; 2];
    out[0].store(&mut rows[0]);
    out[1].store(&mut rows[1]);
    rows
}

/// `kernel::randomise_launch_drawn` with the launch factors drawn (`draws`: the angle's and
/// the speed's uniform numbers, lane by lane) and no launch spread, operation for operation.
#[allow(clippy::needless_range_loop)] // lane l of five rows at once
#[inline(always)]
pub(super) fn randomise<L: F64Lane>(
    d: &KDesign<f64>,
    ph: &KPhysics<f64>,
    parts: &mut [KParticle<f64>],
    idx: &[u32],
    [angle, speed]: [&[f64]; 2],
) {
    let mut a = [[0.0; MAX_LANES]; 5];
    for l in 0..L::WIDTH {
        let j = LaneFlights::source(l, idx.len());
        let p = &parts[idx[j] as usize];
        (a[0][l], a[1][l], a[2][l]) = (p.vel[0], p.vel[1], p.surface as f64);
        (a[3][l], a[4][l]) = (angle[j], speed[j]);
    }
    let (vx, vy, surface) = (L::load(&a[0]), L::load(&a[1]), L::load(&a[2]));
    let (one_less_band, two_band) = (L::splat(1.0 - ph.band), L::splat(2.0 * ph.band));
    let fa = one_less_band + two_band * L::load(&a[3]);
    let fs = one_less_band + two_band * L::load(&a[4]);
    let speed = (vx * vx + vy * vy).sqrt() * fs;
    // one atan2 and one sincos for both kinds of launch, as the scalar function
    let first = surface.eq(L::splat(SURFACE_NONE as f64));
    // `kernel::normal_of` the surface left
    let (ramp, catch) = (surface.eq(L::splat(SURFACE_RAMP as f64)), surface.eq(L::splat(SURFACE_CATCH as f64)));
    let nx = L::select(ramp, L::splat(d.n_ramp[0]), L::select(catch, L::splat(d.n_catch[0]), L::splat(d.n_base[0])));
    let ny = L::select(ramp, L::splat(d.n_ramp[1]), L::select(catch, L::splat(d.n_catch[1]), L::splat(d.n_base[1])));
    let (tx, ty) = (ny, -nx);
    let y = L::select(first, vy, vx * nx + vy * ny);
    let x = L::select(first, vx, vx * tx + vy * ty);
    let ang = atan2(y, x);
    // the first launch's angle kept in [0, 2π), a rebound's inside (0, π)
    let zero = L::splat(0.0);
    let global = L::select(ang.lt(zero), ang + L::splat(2.0 * std::f64::consts::PI), ang) * fa;
    let eps = 1e-6;
    let rebound = (ang * fa).max(L::splat(eps)).min(L::splat(std::f64::consts::PI - eps));
    let (s, c) = sin_cos(L::select(first, global, rebound));
    let out_x = L::select(first, speed * c, speed * (c * tx + s * nx));
    let out_y = L::select(first, speed * s, speed * (c * ty + s * ny));
    let mut out = [[0.0; MAX_LANES]; 2];
    out_x.store(&mut out[0]);
    out_y.store(&mut out[1]);
    for (l, &i) in idx.iter().enumerate() {
        parts[i as usize].vel = [out[0][l], out[1][l]];
    }
}

/// The first word of `pcg4d(pcg4d([particle, bounce, draw, seed_word]))` for sixteen
/// particles, as `rng::uniform01` hashes its key: the hash's one code (`rng::pcg4d_keys`) on
/// sixteen keys side by side, inlined here so that it is compiled for these lanes'
/// instruction set (integer arithmetic, so the same words on any).
#[inline(always)]
pub(super) fn uniform_bits(seed_word: u32, ids: &[u32; 16], bounce: u32, draw: u32) -> [u32; 16] {
    pcg4d_keys(pcg4d_keys([*ids, [bounce; 16], [draw; 16], [seed_word; 16]]))[0]
}
