// The particle kernels (4.2.4) and the per-design reduction (Eq. 4.56-4.57): in physical mode
// one thread per particle (`simulate_particles`, then `reduce_designs`); in listing mode one
// workgroup per design, its threads striding over the particles bounce by bounce (`simulate`).
// CPU twin: src/engine/kernel.rs (same function names and arguments; its header lists the
// pairs), driven by src/engine/cpu.rs `run_particles` (the bounce loop of `simulate`) and
// `kernel::reduce` (the reduction of `simulate`). Positions are relative to a tooth's p1 so f32 suffices.
// The uniform `ph` holds what the whole dispatch shares; each design's own physics
// (restitution, effect parameters) is read from its `Design` record, so one dispatch may
// carry designs of different physics (e.g. a calibration's candidates).

#import shared/types.wgsl
#import shared/rng.wgsl
#import shared/trig.wgsl
#import shared/flight.wgsl

@group(0) @binding(0) var<uniform> ph: Physics;
@group(0) @binding(1) var<storage, read> designs: array<Design>;
@group(0) @binding(2) var<storage, read_write> particles: array<Particle>;
@group(0) @binding(3) var<storage, read_write> outcomes: array<Outcome>;
@group(0) @binding(4) var<storage, read_write> histogram: array<atomic<u32>>;

const WG: u32 = 64u; // Rust twin: kernel.rs `WG` (the reduction's lanes)

var<workgroup> wg_flying: atomic<u32>;
var<workgroup> wg_hop_n: atomic<u32>;
var<workgroup> wg_sum: array<f32, 64>;
var<workgroup> wg_go: u32;

struct Hit {
    found: bool,
    t: f32,
    pos: vec2<f32>,
    tooth: i32,
    surface: u32,
}

fn pitch(d: Design) -> vec2<f32> { return vec2<f32>(d.pitch_x, d.pitch_y); }

fn offset(d: Design, dj: i32, p: vec2<f32>) -> vec2<f32> {
    return f32(dj) * pitch(d) + p;
}

fn normal_of(d: Design, surface: u32) -> vec2<f32> {
    if (surface == SURFACE_RAMP) { return vec2<f32>(d.n_ramp_x, d.n_ramp_y); }
    if (surface == SURFACE_CATCH) { return vec2<f32>(d.n_catch_x, d.n_catch_y); }
    return vec2<f32>(d.n_base_x, d.n_base_y);
}

fn randomise_launch(d: Design, p: ptr<function, Particle>, index: u32, bounce: u32) {
    var apply = false;
    if (ph.randomise == RANDOMISE_FIRST_LAUNCH) { apply = bounce == 0u; }
    if (ph.randomise == RANDOMISE_EVERY_LAUNCH) { apply = true; }
    let spread = LAUNCH_SPREAD && (*p).surface == SURFACE_NONE && (d.launch_speed_spread > 0.0 || d.launch_angle_sigma > 0.0);
    if (!apply && !spread) { return; }
    var fa = 1.0;
    var fs = 1.0;
    if (apply) {
        fa = 1.0 - ph.band + 2.0 * ph.band * uniform01(ph.seed, index, bounce, DRAW_ANGLE);
        fs = 1.0 - ph.band + 2.0 * ph.band * uniform01(ph.seed, index, bounce, DRAW_SPEED);
    }
    let v = vec2<f32>((*p).vel_x, (*p).vel_y);
    var speed = sqrt(v.x * v.x + v.y * v.y) * fs;
    // One katan2 and one ksin_cos serve both kinds of launch (lanes that disagree run both
    // sides of a branch); the first launch's angle is global, a rebound's from the departed
    // surface's tangent.
    let first = (*p).surface == SURFACE_NONE;
    let n = normal_of(d, (*p).surface);
    let t = vec2<f32>(n.y, -n.x);
    var y = dot(v, n);
    var x = dot(v, t);
    if (first) {
        y = v.y;
        x = v.x;
    }
    var ang = katan2(y, x);
    if (first) {
        if (ang < 0.0) { ang += 2.0 * PI; }
        if (spread) {
            // launch-spread effect: earlier (slower) departures and a jittered direction
            speed *= 1.0 - d.launch_speed_spread * uniform01(ph.seed, index, bounce, DRAW_LAUNCH_SPEED);
            ang += d.launch_angle_sigma * normal01(ph.seed, index, bounce, DRAW_LAUNCH_ANGLE);
        }
        ang = ang * fa;
    } else {
        let eps = 1.0e-6;
        ang = clamp(ang * fa, eps, PI - eps);
    }
    let sc = ksin_cos(ang);
    let s = sc.x;
    let c = sc.y;
    if (first) {
        (*p).vel_x = speed * c;
        (*p).vel_y = speed * s;
    } else {
        (*p).vel_x = speed * (c * t.x + s * n.x);
        (*p).vel_y = speed * (c * t.y + s * n.y);
    }
}

fn hop_ok(start: vec2<f32>, to: vec2<f32>) -> bool {
    if (ph.min_hop == 0.0) { return true; }
    let dx = to.x - start.x;
    if (ph.min_hop_horizontal != 0u) { return abs(dx) > ph.min_hop; }
    let dy = to.y - start.y;
    return dx * dx + dy * dy > ph.min_hop * ph.min_hop;
}

fn contact(d: Design, pos: vec2<f32>, vel: vec2<f32>, a: vec2<f32>, b: vec2<f32>, n: vec2<f32>) -> bool {
    let c0 = dot(pos - a, n);
    let tol = 64.0 * EPS * max(max(d.pitch_len, abs(pos.x)), abs(pos.y));
    if (abs(c0) > tol || dot(vel, n) >= 0.0) { return false; }
    let e = b - a;
    let s = dot(pos - a, e) / dot(e, e);
    return s >= 0.0 && s <= 1.0;
}

// The x-interval from tooth dj_first's left end to tooth dj_last's right end, clipped to
// [lo, hi] (empty, x.x > x.y, when they do not meet). Rust twin: kernel.rs `teeth_span`.
fn teeth_span(d: Design, dj_first: i32, dj_last: i32, lo: f32, hi: f32) -> vec2<f32> {
    return vec2<f32>(max(f32(dj_first) * d.pitch_x + d.ext_min, lo), min(f32(dj_last) * d.pitch_x + d.ext_max, hi));
}

// Whether the flight is higher than need_a at x = xa and than need_b at x = xb (true when
// xa > xb: it is not there at all). The trajectory is concave in x, so above a line at both
// ends of an interval is above it over the whole interval. Rust twin: kernel.rs `above_at_ends`.
fn above_at_ends(fl: Flight, xa: f32, xb: f32, need_a: f32, need_b: f32) -> bool {
    if (xa > xb) { return true; }
    let ya = y_at_x(fl, xa);
    let yb = y_at_x(fl, xb);
    if (ya.y == 0.0 || yb.y == 0.0) { return false; }
    return ya.x > need_a && yb.x > need_b;
}

// The run test's line, at least as high as each tooth's peak over that tooth's extent: it
// rises with the teeth (slope) and has tooth 0's peak height at the left end of its extent
// (x_ref; uphill, the right end downhill); the run test asks for `clearance` above it. Rust
// twin: kernel.rs `run_line`.
struct RunLine {
    peak: f32,
    slope: f32,
    x_ref: f32,
    clearance: f32,
}

fn run_line(d: Design) -> RunLine {
    let slope = d.pitch_y / d.pitch_x;
    var x_ref = d.ext_min;
    if (slope < 0.0) { x_ref = d.ext_max; }
    return RunLine(max(max(d.p2_y, d.p4_y), 0.0), slope, x_ref, RUN_CLEARANCE_PITCHES * d.pitch_len);
}

// How many teeth from j on a vacuum flight clears by the run test, worked out instead of
// searched for: the parabola minus the run test's line is a quadratic in time, so the flight
// is above the line between its two roots, and every tooth from j to the last one ending
// before the later root (in x) is cleared when tooth j starts after the earlier one. 1 (the
// doubling's first run) when tooth j does not start inside, 0 when the interval ends within
// tooth j. Rounding may make the count one too many: the run is still tested, and halved when
// the test fails. `line` is the design's `run_line`, [lo, hi] the flight's x-range as the scan
// clips it. Rust twin: kernel.rs `vacuum_run`.
fn vacuum_run(d: Design, fl: Flight, line: RunLine, j: i32, j_hi: i32, k: i32, lo: f32, hi: f32) -> i32 {
    // y(t) - line(x(t)) = -g/2 t^2 + b t + c
    let vx = fl.v0.x;
    let b = fl.v0.y - line.slope * vx;
    let c = fl.p0.y - line.peak - line.slope * (fl.p0.x - line.x_ref) - line.clearance;
    let disc = b * b + 2.0 * fl.g * c;
    if (!(disc > 0.0) || !(fl.g > 0.0) || vx == 0.0) { return 1; }
    let sq = sqrt(disc);
    let x1 = fl.p0.x + vx * ((b - sq) / fl.g);
    let x2 = fl.p0.x + vx * ((b + sq) / fl.g);
    let xl = min(x1, x2);
    let xr = max(x1, x2);
    let xa = max(f32(j - k) * d.pitch_x + d.ext_min, lo);
    if (!(xa > xl)) { return 1; }
    if (xr >= hi) { return max(j_hi - j + 1, 0); }
    let last = to_index(floor((xr - d.ext_max) / d.pitch_x)) + k;
    return max(min(last, j_hi) - j + 1, 0);
}

// The first tooth from j_from on that the flight does not fly over (j_hi + 1 when none): a
// tooth is flown over when the flight stays above its peak over the tooth's x-extent
// (clipped to the part of the flight before x_far; no point of a tooth is higher than its
// peak). In few passes where the flight clears many teeth: after a tooth it clears, a run of
// the next teeth is passed at once when the flight is above the line over the run's peaks by
// RUN_CLEARANCE_PITCHES (far more than rounding, so the one-tooth test would say the same of
// each tooth); the run doubles while that holds and halves when not, down to one tooth
// tested exactly. A vacuum flight's run is worked out instead (`vacuum_run`), and after it
// passes the next tooth is tested alone. A pass computes either test's inputs and runs one
// test (lanes in different modes would otherwise run both), and on a SIMD machine the scan
// lasts as long as its slowest lane's. Rust twin: kernel.rs `next_tooth_to_search` (the
// same passes; its one-tooth test is `flies_over`, its run test `clears_run`).
fn next_tooth_to_search(d: Design, fl: Flight, j_from: i32, j_hi: i32, k: i32, x0: f32, x_far: f32) -> i32 {
    let lo = min(x0, x_far);
    let hi = max(x0, x_far);
    let line = run_line(d);
    var j = j_from;
    var run = 0;
    loop {
        if (j > j_hi) { break; }
        var last = j;
        if (run > 0) { last = min(j + run - 1, j_hi); }
        let x = teeth_span(d, j - k, last - k, lo, hi);
        var need_a = f32(j - k) * d.pitch_y + line.peak; // tooth j's peak (kernel.rs flies_over)
        var need_b = need_a;
        if (run > 0) {
            need_a = line.peak + line.slope * (x.x - line.x_ref) + line.clearance;
            need_b = line.peak + line.slope * (x.y - line.x_ref) + line.clearance;
        }
        if (above_at_ends(fl, x.x, x.y, need_a, need_b)) {
            j = last + 1;
            if (flight_drag(fl)) {
                run = max(2 * run, 1);
            } else if (run == 0) {
                run = vacuum_run(d, fl, line, j, j_hi, k, lo, hi);
            } else {
                run = 0;
            }
        } else {
            if (run == 0) { break; }
            run = run / 2;
        }
    }
    return j;
}

fn to_index(x: f32) -> i32 {
    return i32(clamp(x, -1.0e9, 1.0e9));
}

fn first_hit(d: Design, p: Particle, bounce: u32) -> Hit {
    let pos = vec2<f32>(p.pos_x, p.pos_y);
    let vel = vec2<f32>(p.vel_x, p.vel_y);
    let fl = Flight(pos, vel, ph.g, p.k_drag);
    var best = Hit(false, INF, vec2<f32>(0.0), 0, SURFACE_NONE);
    let k = p.tooth;
    let kf = f32(k);
    let n_base = vec2<f32>(d.n_base_x, d.n_base_y);
    let t_base = vec2<f32>(d.t_base_x, d.t_base_y);

    // Base: one line through every p1.
    var horizon = INF;
    let departing_base = p.surface == SURFACE_BASE;
    var roots = line_crossings(fl, vec2<f32>(0.0), n_base, departing_base, 0.0, INF);
    if (!departing_base && hop_ok(pos, pos)) {
        let s0 = -kf * d.pitch_len;
        let a = s0 * t_base;
        let b = (s0 + d.base_length) * t_base;
        if (contact(d, pos, vel, a, b, n_base)) { roots = Roots(1u, 0.0, 0.0); }
    }
    for (var i = 0u; i < roots.n; i++) {
        var t = roots.t0;
        if (i == 1u) { t = roots.t1; }
        let q = flight_pos(fl, t);
        if (!hop_ok(pos, q)) { continue; }
        horizon = t;
        let s = dot(q, t_base);
        let s_lo = -kf * d.pitch_len;
        if (s >= s_lo && s <= d.base_length + s_lo) {
            let j = clamp(to_index(floor(s / d.pitch_len)) + k, 0, d.teeth - 1);
            best = Hit(true, t, q, j, SURFACE_BASE);
        }
        break;
    }

    // Teeth whose x-extent overlaps the flight before the horizon.
    var x_end: f32;
    if (horizon < INF) { x_end = flight_pos(fl, horizon).x; } else if (vel.x >= 0.0) { x_end = INF; } else { x_end = -INF; }
    let xmin = min(pos.x, x_end);
    let xmax = max(pos.x, x_end);
    let lo = to_index(ceil((xmin - d.ext_max) / d.pitch_x));
    let hi = to_index(floor((xmax - d.ext_min) / d.pitch_x));
    if (lo + k > d.teeth - 1 || hi + k < 0) { return best; }
    let j_lo = clamp(lo + k, 0, d.teeth - 1);
    let j_hi = clamp(hi + k, 0, d.teeth - 1);
    var x_far = x_end;
    if (best.found) { x_far = best.pos.x; }
    let p2 = vec2<f32>(d.p2_x, d.p2_y);
    let p4 = vec2<f32>(d.p4_x, d.p4_y);
    let margin = 64.0 * EPS * d.pitch_len;
    // Tooth by tooth, each lane first passes the teeth its flight clears (a cheap test) and
    // then searches one it may hit: lanes that disagree on a branch run both sides, so with
    // `continue` every lane would pay the search of each tooth in the range of the lane with
    // the longest flight; this way they pay for the most teeth any lane searches.
    var j = j_lo;
    loop {
        j = next_tooth_to_search(d, fl, j, j_hi, k, pos.x, x_far);
        if (j > j_hi) { break; }
        let dj = j - k;
        for (var si = 0u; si < 2u; si++) {
            var surface = SURFACE_RAMP;
            if (si == 1u) { surface = SURFACE_CATCH; }
            if (surface == SURFACE_CATCH && bounce == 0u && j == 0) { continue; }
            var a: vec2<f32>;
            var b: vec2<f32>;
            var n: vec2<f32>;
            if (surface == SURFACE_RAMP) {
                a = offset(d, dj, vec2<f32>(0.0));
                b = offset(d, dj, p2);
                n = vec2<f32>(d.n_ramp_x, d.n_ramp_y);
            } else {
                a = offset(d, dj, p2);
                b = offset(d, dj, p4);
                n = vec2<f32>(d.n_catch_x, d.n_catch_y);
            }
            let departing = p.surface == surface && dj == 0;
            var t_max = horizon;
            if (best.found) { t_max = best.t; }
            let xa = min(a.x, b.x) - margin;
            let xb = max(a.x, b.x) + margin;
            var t_lo = INF;
            var t_hi = INF;
            if (vel.x > 0.0 || vel.x < 0.0) {
                // the window's ends in the direction of flight, then one time_at_x for each
                // (lanes flying both ways would otherwise run both pairs)
                var x_in = max(xa, pos.x);
                var x_out = xb;
                if (vel.x < 0.0) {
                    x_in = min(xb, pos.x);
                    x_out = xa;
                }
                t_lo = time_at_x(fl, x_in);
                t_hi = time_at_x(fl, x_out);
            } else if (pos.x >= xa && pos.x <= xb) {
                t_lo = 0.0;
            }
            var rs = Roots(0u, 0.0, 0.0);
            if (!(t_lo > t_max)) { rs = line_crossings(fl, a, n, departing, t_lo, min(t_max, t_hi)); }
            if (!departing && hop_ok(pos, pos) && contact(d, pos, vel, a, b, n)) { rs = Roots(1u, 0.0, 0.0); }
            // the first root on the segment; both are tested side by side, without branches (a
            // loop over them ran both passes for every lane anyway, one after the other), and
            // not at all where no lane has a root (a lavapipe that skips a block no lane
            // enters then skips it: 3 % of the lunar kernel on Mesa 25)
            if (rs.n > 0u) {
                let e = b - a;
                let ee = dot(e, e);
                let q0 = flight_pos(fl, rs.t0);
                let q1 = flight_pos(fl, rs.t1);
                let s0 = dot(q0 - a, e) / ee;
                let s1 = dot(q1 - a, e) / ee;
                let on0 = (rs.n >= 1u) & !((s0 < 0.0) | (s0 > 1.0) | !hop_ok(pos, q0));
                let on1 = (rs.n >= 2u) & !((s1 < 0.0) | (s1 > 1.0) | !hop_ok(pos, q1));
                var t = rs.t1;
                var q = q1;
                if (on0) {
                    t = rs.t0;
                    q = q0;
                }
                if ((on0 | on1) & (t < best.t)) { best = Hit(true, t, q, j, surface); }
            }
        }
        j++;
    }
    return best;
}

// CPU twin: Restitution::bounce (src/model/collision.rs), with this design's restitution law.
fn bounce_velocity(d: Design, v: vec2<f32>, n: vec2<f32>) -> vec2<f32> {
    let vn_s = dot(v, n);                      // Eq. 4.47
    let vn = vn_s * n;
    let vt = v - vn;                           // Eq. 4.48
    let vn_abs = abs(vn_s);
    let vt_abs = sqrt(dot(vt, vt));
    var k_norm = d.k_elastic;                  // Eq. 4.9 above v_limit
    if (d.plastic != 0u && vn_abs > d.v_limit) { k_norm = d.k_elastic * sqrt(sqrt(d.v_limit / vn_abs)); }
    var k_tang = 0.0;                          // Eq. 4.14
    if (d.dem_law != 0u) {
        // the DEM's measured k_t(psi); a zero friction impulse makes psi infinite
        let impulse = d.mu_friction * (k_norm + 1.0) * vn_abs;
        var psi = bitcast<f32>(0x7f800000u);
        if (impulse > 0.0) { psi = vt_abs / impulse; }
        k_tang = dem_tangential(d, psi);
    } else if (vt_abs > 0.0) {
        k_tang = 1.0 - d.tangential_factor * d.mu_friction * (k_norm + 1.0) * vn_abs / vt_abs;
    }
    if (d.clamp_tangential != 0u && d.dem_law == 0u) { k_tang = clamp(k_tang, 0.0, 1.0); }
    return k_tang * vt - k_norm * vn;          // Eq. 4.49
}

// CPU twin: Restitution::dem_tangential (src/model/collision.rs): linear between the table's
// nodes, Coulomb's 1 - c/psi through the last node past it.
fn dem_tangential(d: Design, psi: f32) -> f32 {
    let last = 11u;
    let psi_last = TANGENTIAL_PSI[last];
    if (!(psi < psi_last)) { return 1.0 - (1.0 - d.tangential_table[last]) * psi_last / psi; }
    var i = 0u;
    while (i + 1u < last && !(psi < TANGENTIAL_PSI[i + 1u])) { i++; }
    let p0 = TANGENTIAL_PSI[i];
    let p1 = TANGENTIAL_PSI[i + 1u];
    let k0 = d.tangential_table[i];
    let k1 = d.tangential_table[i + 1u];
    return k0 + (k1 - k0) * (psi - p0) / (p1 - p0);
}

fn step_particle(d: Design, p: ptr<function, Particle>, index: u32, bounce: u32) {
    randomise_launch(d, p, index, bounce);
    fly_particle(d, p, index, bounce);
}

// The flight from the (randomised) launch velocity to the next impact, and the bounce there.
// Rust twin: kernel.rs `fly_particle` (the cpu engine randomises a whole bounce's launches
// before flying any of them).
fn fly_particle(d: Design, p: ptr<function, Particle>, index: u32, bounce: u32) {
    let hit = first_hit(d, *p, bounce);
    if (!hit.found) {
        (*p).state = STATE_LOST;
        return;
    }
    let pos = vec2<f32>((*p).pos_x, (*p).pos_y);
    let fl = Flight(pos, vec2<f32>((*p).vel_x, (*p).vel_y), ph.g, (*p).k_drag);
    let v_in = flight_vel(fl, hit.t);
    let n_true = normal_of(d, hit.surface);
    var v_out = bounce_velocity(d, v_in, n_true);
    if (IMPACT_SCATTER && d.scatter_sigma > 0.0) {
        // impact-scatter effect (CPU twin: kernel.rs `land`): a tilt is admissible when the
        // grain arrives against the tilted facet and leaves the true surface; one it cannot
        // meet is drawn again (the shadow rule), up to TILT_DRAWS times
        for (var k = 0u; k < TILT_DRAWS; k += 1u) {
            var draw = DRAW_SCATTER;
            if (k > 0u) { draw = DRAW_SCATTER_AGAIN + 2u * (k - 1u); }
            let sc = ksin_cos(d.scatter_sigma * normal01(ph.seed, index, bounce, draw));
            let tilted = vec2<f32>(sc.y * n_true.x - sc.x * n_true.y, sc.x * n_true.x + sc.y * n_true.y);
            if (dot(v_in, tilted) < 0.0) {
                let out = bounce_velocity(d, v_in, tilted);
                if (dot(out, n_true) > 0.0) {
                    v_out = out;
                    break;
                }
            }
        }
    }
    (*p).hop = abs(hit.pos.x - pos.x);         // Eq. 4.50 per particle
    let back = offset(d, hit.tooth - (*p).tooth, vec2<f32>(0.0));
    (*p).pos_x = hit.pos.x - back.x;
    (*p).pos_y = hit.pos.y - back.y;
    (*p).tooth = hit.tooth;
    (*p).vel_x = v_out.x;
    (*p).vel_y = v_out.y;
    (*p).surface = hit.surface;
    (*p).bounces += 1u;
    if ((*p).bounces == 1u) {
        let g = offset(d, (*p).tooth, vec2<f32>((*p).pos_x, (*p).pos_y));
        (*p).first_x = g.x;
        (*p).first_y = g.y;
    }
    if (ph.per_particle_rest != 0u && (*p).hop < ph.rest_threshold) {
        (*p).state = STATE_RESTING;
    }
}

// Eq. 4.56 (1-based tooth, clamped) for a final position. Rust twin: kernel.rs `end_tooth`.
fn end_tooth(d: Design, p: Particle) -> i32 {
    let j = p.tooth + to_index(floor((p.pos_x - d.p2_x) / d.pitch_x)) + 1;
    return clamp(j, 1, d.teeth);
}

// Listing mode: the bounce loop of all of a design's particles together, because the
// listing's stop (Eq. 4.50, D.1 l.328-336) is on the mean hop of the whole bounce; one
// workgroup per design, a barrier per bounce, then the reduction. CPU twin: cpu.rs
// `run_particles`, then kernel.rs `reduce`.
@compute @workgroup_size(64)
fn simulate(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let design = wid.x;
    let d = designs[design];
    let first = design * ph.n_particles;
    var iterations = 0u;
    for (var bounce = 0u; bounce < ph.max_bounces; bounce++) {
        if (lid == 0u) {
            atomicStore(&wg_flying, 0u);
            atomicStore(&wg_hop_n, 0u);
        }
        workgroupBarrier();
        var hop_sum = 0.0;
        for (var i = lid; i < ph.n_particles; i += WG) {
            var p = particles[first + i];
            if (p.state != STATE_FLYING) { continue; }
            step_particle(d, &p, i, bounce);
            particles[first + i] = p;
            if (p.state != STATE_LOST) {
                hop_sum += p.hop;
                atomicAdd(&wg_hop_n, 1u);
            }
            if (p.state == STATE_FLYING) { atomicAdd(&wg_flying, 1u); }
        }
        wg_sum[lid] = hop_sum;
        workgroupBarrier();
        iterations = bounce + 1u;
        if (lid == 0u) {
            var go = 1u;
            if (ph.per_particle_rest != 0u) {
                if (atomicLoad(&wg_flying) == 0u) { go = 0u; }
            } else {
                // listing D.1 l.328-336: all gone, or mean hop below l_limit (Eq. 4.50)
                var total = 0.0;
                for (var i = 0u; i < WG; i++) { total += wg_sum[i]; }
                let n = atomicLoad(&wg_hop_n);
                if (n == 0u || total / f32(n) < ph.rest_threshold) { go = 0u; }
            }
            wg_go = go;
        }
        if (workgroupUniformLoad(&wg_go) == 0u) { break; }
    }
    // the reduction reads every lane's particles
    storageBarrier();
    if (lid == 0u) { reduce_design(design, iterations); }
}

// Physical mode: each particle's rest rule is its own (4.2.4, erratum 15), so one thread
// follows one particle to rest with no barrier, and threads map to particles, not designs
// (issue 16: a workgroup no longer waits for its slowest particle at every bounce). Returns
// the steps taken. Rust twin: kernel.rs `follow_particle`.
fn follow_particle(d: Design, p: ptr<function, Particle>, index: u32) -> u32 {
    var steps = 0u;
    for (var bounce = 0u; bounce < ph.max_bounces; bounce++) {
        if ((*p).state != STATE_FLYING) { break; }
        step_particle(d, p, index, bounce);
        steps = bounce + 1u;
    }
    return steps;
}

// One thread per particle of every design in the dispatch (a 2-D grid of workgroups when
// there are more than one dimension holds); `reduce_designs` runs after it.
@compute @workgroup_size(64)
fn simulate_particles(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                      @builtin(local_invocation_index) lid: u32) {
    let flat = (wid.y * nwg.x + wid.x) * WG + lid;
    if (flat >= ph.n_designs * ph.n_particles) { return; }
    let design = flat / ph.n_particles;
    let i = flat % ph.n_particles;
    var p = particles[flat];
    follow_particle(designs[design], &p, i);
    particles[flat] = p;
}

// Steps a particle took in `follow_particle`, from what it left: one per impact, plus the
// flight that lost it. Rust twin: kernel.rs `particle_steps`.
fn particle_steps(p: Particle) -> u32 {
    return p.bounces + select(0u, 1u, p.state == STATE_LOST);
}

// The per-design reduction after `simulate_particles`, one thread per design; its
// iterations are the bounce loop's (as `run_particles` counts them: until no particle flies,
// at least one). Rust twin: the max of kernel.rs `particle_steps`, then `reduce`.
@compute @workgroup_size(64)
fn reduce_designs(@builtin(global_invocation_id) gid: vec3<u32>) {
    let design = gid.x;
    if (design >= ph.n_designs) { return; }
    let first = design * ph.n_particles;
    var iterations = 1u;
    for (var i = 0u; i < ph.n_particles; i++) {
        iterations = max(iterations, min(particle_steps(particles[first + i]), ph.max_bounces));
    }
    reduce_design(design, iterations);
}

// Reduction of one design in one thread: tooth histogram, lost and still-flying counts,
// impacts, distances. Rust twin: kernel.rs `reduce`, the same loops in the same order: lane l
// of WG sums particles l, l + WG, ..., then the lanes' sums are added in lane order (the
// order of the workgroup that did this before, kept so the f32 sums keep their bits). One
// thread needs no barrier or workgroup atomic, and on lavapipe it is as fast.
fn reduce_design(design: u32, iterations: u32) {
    let d = designs[design];
    let first = design * ph.n_particles;
    var out = Outcome(iterations, 0u, 0u, 0u, 0u, 0.0, 0u, 0u);
    for (var lane = 0u; lane < WG; lane++) {
        var dist = 0.0;
        for (var i = lane; i < ph.n_particles; i += WG) {
            var p = particles[first + i];
            out.bounce_sum += p.bounces;
            if (p.state == STATE_LOST) {
                out.lost += 1u;
                continue;
            }
            if (p.state == STATE_FLYING && p.bounces > 0u && p.hop < ph.rest_threshold) {
                p.state = STATE_RESTING; // listing mode: hopping below l_limit when the loop stopped
                particles[first + i] = p;
            }
            if (p.state == STATE_FLYING) { out.flying += 1u; }
            let j = end_tooth(d, p);
            atomicAdd(&histogram[design * ph.teeth_hist + u32(j - 1)], 1u);
            out.advance_teeth += u32(j - 1);
            if (j > 1) { dist += d.pitch_x * f32(j - 1) + d.p4_x; } // listing D.1 l.347-351
        }
        out.distance_sum += dist;
    }
    outcomes[design] = out;
}
