// Closed-form flights and their line crossings. Twin of src/model/flight.rs (f32): each
// function here has a Rust function of the same name and arguments there (`relax`,
// `push_root`, `quadratic_roots`, `stokes_f`, `bracketed_newton`, `stokes_horizon`) or a
// `Flight` method (`flight_pos` = Flight::pos, `flight_vel` = Flight::vel, `flight_drag` =
// Flight::drag, `time_at_x`,
// `y_at_x`, `line_crossings`); `expm1_`/`log1p_` stand in for Rust's exp_m1/ln_1p.
// `Roots` is Rust's `Roots<T>` = [Option<T>; 2]. `kln` is the kernels' own logarithm
// (shared/klog.wgsl): the builtin's error near 1 is absolute.

#import shared/klog.wgsl

struct Flight {
    p0: vec2<f32>,
    v0: vec2<f32>,
    g: f32,
    k: f32,
}

struct Roots {
    n: u32,
    t0: f32,
    t1: f32,
}

// e^x - 1 without cancellation near 0 (WGSL has no expm1).
fn expm1_(x: f32) -> f32 {
    if (abs(x) < 0.1) {
        return x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0 + x * (1.0 / 720.0))))));
    }
    return exp(x) - 1.0;
}

// ln(1 + x) without cancellation near 0 (WGSL has no log1p): a series near 0, else the
// kernels' own `kln` with the rounding of 1 + x repaired (Goldberg's ln u · x / (u - 1)).
// Twin: src/model/real.rs `klog::ln_1p`.
fn log1p_(x: f32) -> f32 {
    if (abs(x) < 0.01) {
        return x * (1.0 - x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * 0.2))));
    }
    let u = 1.0 + x;
    if (u > 16777216.0) { return kln(u); }
    return kln(u) * (x / (u - 1.0));
}

// Whether a flight has Stokes drag. The path switches (shared/constants.wgsl) answer without
// looking when the pipeline was built for one kind of flight only, which compiles the other
// kind's code out. Rust twin: `Flight::drag`.
fn flight_drag(f: Flight) -> bool {
    if (!VACUUM_FLIGHTS) { return true; }
    if (!DRAG_FLIGHTS) { return false; }
    return f.k > 0.0;
}

fn relax(k: f32, t: f32) -> f32 {
    return -expm1_(-k * t) / k;
}

fn flight_pos(f: Flight, t: f32) -> vec2<f32> {
    if (flight_drag(f)) {
        let e = relax(f.k, t);
        let vinf = -f.g / f.k;
        return vec2<f32>(f.p0.x + f.v0.x * e, f.p0.y + vinf * t + (f.v0.y - vinf) * e);
    }
    return vec2<f32>(f.p0.x + f.v0.x * t, f.p0.y + f.v0.y * t - 0.5 * f.g * t * t);
}

fn flight_vel(f: Flight, t: f32) -> vec2<f32> {
    if (flight_drag(f)) {
        let e = exp(-f.k * t);
        let vinf = -f.g / f.k;
        return vec2<f32>(f.v0.x * e, vinf + (f.v0.y - vinf) * e);
    }
    return vec2<f32>(f.v0.x, f.v0.y - f.g * t);
}

fn time_at_x(f: Flight, x: f32) -> f32 {
    let dx = x - f.p0.x;
    let vx = f.v0.x;
    if (vx == 0.0 || (dx / vx) < 0.0) {
        if (dx == 0.0) { return 0.0; }
        return INF;
    }
    if (flight_drag(f)) {
        let q = 1.0 - f.k * dx / vx;
        if (q <= 0.0) { return INF; }
        return -kln(q) / f.k;
    }
    return dx / vx;
}

// Height at horizontal position x; returns INF's negative when unreachable (flag in .y).
fn y_at_x(f: Flight, x: f32) -> vec2<f32> {
    let vx = f.v0.x;
    if (vx == 0.0) { return vec2<f32>(0.0, 0.0); }
    let e = (x - f.p0.x) / vx;
    if (e < 0.0) { return vec2<f32>(0.0, 0.0); }
    if (flight_drag(f)) {
        let q = 1.0 - f.k * e;
        if (q <= 0.0) { return vec2<f32>(0.0, 0.0); }
        let t = -kln(q) / f.k;
        let vinf = -f.g / f.k;
        return vec2<f32>(f.p0.y + vinf * t + (f.v0.y - vinf) * e, 1.0);
    }
    return vec2<f32>(f.p0.y + f.v0.y * e - 0.5 * f.g * e * e, 1.0);
}

fn push_root(r: ptr<function, Roots>, t: f32, t_min: f32, t_max: f32) {
    if (t > 0.0 && t >= t_min && t <= t_max) {
        if ((*r).n == 0u) { (*r).t0 = t; } else { (*r).t1 = t; }
        (*r).n += 1u;
    }
}

fn quadratic_roots(c2: f32, c1: f32, c0: f32, t_min: f32, t_max: f32) -> Roots {
    var r = Roots(0u, 0.0, 0.0);
    if (c2 == 0.0) {
        if (c1 != 0.0) { push_root(&r, -c0 / c1, t_min, t_max); }
        return r;
    }
    let disc = c1 * c1 - 4.0 * c2 * c0;
    if (disc < 0.0) { return r; }
    let sq = sqrt(disc);
    var q: f32;
    if (c1 >= 0.0) { q = -0.5 * (c1 + sq); } else { q = -0.5 * (c1 - sq); }
    if (q == 0.0) { return r; }
    var a = q / c2;
    var b = c0 / q;
    if (b < a) { let tmp = a; a = b; b = tmp; }
    push_root(&r, a, t_min, t_max);
    push_root(&r, b, t_min, t_max);
    return r;
}

fn stokes_f(c0: f32, ca: f32, cb: f32, k: f32, t: f32) -> f32 {
    return c0 + ca * t + cb * relax(k, t);
}

// Safeguarded Newton on a monotone bracket, started at the regula-falsi point.
fn bracketed_newton(c0: f32, ca: f32, cb: f32, k: f32, lo_in: f32, hi_in: f32, f_lo: f32, f_hi: f32) -> f32 {
    var lo = lo_in;
    var hi = hi_in;
    let lo_positive = f_lo > 0.0;
    // start: the root of f's second-order expansion, else regula falsi, else the midpoint
    let q = quadratic_roots(-0.5 * k * cb, ca + cb, c0, lo, hi);
    var t = lo;
    if (q.n > 0u) { t = q.t0; }
    if (!(t > lo && t < hi)) {
        t = 0.5 * (lo + hi);
        if (f_hi != f_lo) { t = lo - f_lo * (hi - lo) / (f_hi - f_lo); }
    }
    if (!(t > lo && t < hi)) { t = 0.5 * (lo + hi); }
    for (var i = 0; i < 48; i++) {
        let m = expm1_(-k * t);
        let ft = c0 + ca * t - cb * m / k;
        let d = ca + cb * (1.0 + m);
        if (ft == 0.0) { return t; }
        if ((ft > 0.0) == lo_positive) { lo = t; } else { hi = t; }
        // Halley: f'' = -k b e^{-kt}, f''' = -k f''
        let d2 = -k * cb * (1.0 + m);
        let den = 2.0 * d * d - ft * d2;
        var halley = lo - 1.0;
        if (den != 0.0) { halley = t - 2.0 * ft * d / den; }
        let tol = EPS * 4.0 * max(abs(t), 1.0e-30);
        if (halley > lo && halley < hi) {
            // the step's error is C δ³ (C at t, so for short steps only): final once below
            // the tolerance
            let step = abs(halley - t);
            let c = abs(d2 * d2 / (4.0 * d * d) + k * d2 / (6.0 * d));
            if (step <= tol || (step <= 1.0e-3 * abs(t) && c * step * step * step <= tol)) { return halley; }
            t = halley;
        } else {
            let next = 0.5 * (lo + hi);
            if (abs(next - t) <= tol) { return next; }
            t = next;
        }
    }
    return t;
}

fn stokes_horizon(c0: f32, a: f32, b: f32, k: f32) -> f32 {
    let span = 40.0 / k;
    if (a < 0.0) { return max((c0 + max(b, 0.0) / k) / -a, 0.0); }
    if (a > 0.0) { return max((-c0 - min(b, 0.0) / k) / a, 0.0); }
    return span;
}

// f at the horizon with the sign the bound gives it (that of a): where k t is large the
// exponential has underflowed and the computed f is rounding noise of either sign, with which
// a falling grain's crossing was missed (on an H200 20 of 400 heavily damped grains flew off
// as lost). Twin: src/model/flight.rs `final_sign_at_horizon`.
fn final_sign_at_horizon(f: f32, a: f32) -> f32 {
    if (a < 0.0) { return min(f, 0.0); }
    if (a > 0.0) { return max(f, 1.1754944e-38); }
    return f;
}

// Crossings in (t_min, t_max] (t > 0) of the line through a with normal n; departing
// removes the root at t = 0 analytically.
fn line_crossings(f: Flight, a: vec2<f32>, n: vec2<f32>, departing: bool, t_min: f32, t_max: f32) -> Roots {
    var c0 = 0.0;
    if (!departing) { c0 = dot(n, f.p0 - a); }
    let nv = dot(n, f.v0);
    var r = Roots(0u, 0.0, 0.0);
    if (!flight_drag(f)) {
        let c1 = nv;
        let c2 = -0.5 * f.g * n.y;
        if (departing) {
            if (c2 != 0.0) { push_root(&r, -c1 / c2, t_min, t_max); }
            return r;
        }
        return quadratic_roots(c2, c1, c0, t_min, t_max);
    }
    let k = f.k;
    let ca = -f.g / k * n.y;
    let cb = nv - ca;
    // t* = ln(1 + x)/k with x = n.v/(-a): accurate for near-tangential lift-off.
    var x = 0.0;
    if (ca != 0.0) { x = nv / -ca; }
    var t_star = -1.0;
    if (x > 0.0 && x < INF) { t_star = log1p_(x) / k; }
    let horizon = stokes_horizon(c0, ca, cb, k);
    let t_end = min(t_max, horizon);
    if (t_min > t_end) { return r; }
    var lo = max(t_min, 0.0);
    var f_lo = c0;
    if (lo != 0.0) { f_lo = stokes_f(c0, ca, cb, k, lo); }
    for (var piece = 0; piece < 2; piece++) {
        var hi = t_end;
        if (piece == 0) {
            if (t_star < 0.0) { continue; }
            hi = t_star;
        }
        if (hi <= lo) { continue; }
        hi = min(hi, t_end);
        var f_hi = stokes_f(c0, ca, cb, k, hi);
        if (hi == horizon) { f_hi = final_sign_at_horizon(f_hi, ca); }
        let starts_on_line = lo == 0.0 && (departing || f_lo == 0.0);
        if (departing && lo > 0.0 && f_lo <= 0.0 && r.n == 0u) {
            push_root(&r, lo, t_min, t_max);   // lift-off below rounding: back at t*
        } else if (!starts_on_line && (f_lo > 0.0) != (f_hi > 0.0)) {
            let t = bracketed_newton(c0, ca, cb, k, lo, hi, f_lo, f_hi);
            push_root(&r, t, t_min, t_max);
        }
        lo = hi;
        f_lo = f_hi;
    }
    return r;
}
