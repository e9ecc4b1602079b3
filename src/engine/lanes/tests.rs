//! Every instantiation of the lane search this CPU runs, held to the scalar kernel to the bit.
//! An instantiation this CPU lacks is skipped with a message (on stderr, past the test
//! harness's capture).

use super::*;
use crate::engine::cpu::{kernel_design, kernel_physics};
use crate::engine::kernel::{first_hit, fly_particle, init_particle, randomise_launch, STATE_FLYING, SURFACE_BASE};
use crate::engine::Context;
use crate::lane::F64Lane;
use crate::model::effects::{Effects, FillSurfaceLoss, ImpactScatter, LaunchSpread, Polydisperse, SizeForm, TiltForm};
use crate::model::sampling::random_valid_designs;
use crate::model::scenario::LaunchPoints;
use crate::model::{prepare, Scenario};

type HitBits = (bool, u64, [u64; 2], i32, u32);

fn bits(h: &Hit<f64>) -> HitBits {
    (h.found, h.t.to_bits(), [h.pos[0].to_bits(), h.pos[1].to_bits()], h.tooth, h.surface)
}

/// Every instantiation this CPU runs ([`Lanes::on_this_cpu`]: one f64 always, and the SIMD
/// lanes it has); the SIMD paths of this architecture that it lacks are named on stderr as
/// not run (written past libtest's output capture, so that it shows on a passing run).
fn instantiations(test: &str) -> Vec<Lanes> {
    for simd in Simd::ALL {
        let this_arch = match simd {
            Simd::Scalar => false,
            Simd::Avx2 | Simd::Avx512 => cfg!(target_arch = "x86_64"),
            Simd::Neon => cfg!(target_arch = "aarch64"),
        };
        if this_arch && !simd.supported() {
            use std::io::Write;
            let why = "this CPU lacks their instructions; not run here";
            let _ = writeln!(std::io::stderr(), "SKIPPED {test} on the {} lanes: {why}", simd.name());
        }
    }
    Lanes::on_this_cpu()
}

/// The scenarios the lane tests run: `base` at slopes from 0 to 40°, plain and with the
/// effects that change launches, bounces and (polydisperse) each grain's drag, on Halton
/// and random launch points.
fn cases(base: Scenario, particles: u32) -> Vec<Scenario> {
    let mut cases = Vec::new();
    for alpha in [0.0, 20.0, 35.0, 40.0] {
        let mut s = base.clone();
        s.sim.particles = particles;
        s.environment.alpha_deg = alpha;
        cases.push(s.clone());
        s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 6.0, form: TiltForm::default() });
        s.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.3, angle_sigma_deg: 8.0 });
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
        s.sim.launch_points = LaunchPoints::Random;
        cases.push(s.clone());
        if alpha == 20.0 {
            // the fill-surface loss alone: slower first launches that the lanes'
            // randomisation still takes (no launch spread)
            s.effects = Effects::default();
            s.effects.fill_surface_loss = Some(FillSurfaceLoss { speed_loss: 0.4, decay_depth_m: 2e-3 });
            cases.push(s);
        }
    }
    cases
}

/// Every lane finds the hit the scalar search finds, to the bit, at every bounce of
/// every particle: random valid lunar designs (vacuum flights) in [`cases`], in groups of
/// every size from one to eight.
#[test]
fn each_lane_finds_the_scalar_hit_to_the_bit() {
    for (lanes, (compared, on_teeth)) in
        compare_lane_hits("each_lane_finds_the_scalar_hit_to_the_bit", &cases(Scenario::lunar(), 120))
    {
        assert!(
            compared > 20_000 && on_teeth > compared / 3,
            "{}: {compared} flights compared, {on_teeth} on teeth",
            lanes.name()
        );
    }
}

/// The same for Earth's designs: flights with Stokes drag, whose root search (Halley
/// steps, one `expm1` each) the lanes run to the scalar search's bits.
#[test]
fn each_lane_finds_the_scalar_hit_to_the_bit_with_drag() {
    let test = "each_lane_finds_the_scalar_hit_to_the_bit_with_drag";
    for (lanes, (compared, on_teeth)) in compare_lane_hits(test, &cases(Scenario::earth(), 120)) {
        assert!(
            compared > 10_000 && on_teeth > compared / 3,
            "{}: {compared} flights compared, {on_teeth} on teeth",
            lanes.name()
        );
    }
}

/// Heavily damped grains (lunar gravity with k_drag 8 1/s and polydisperse sizes of sd 0.5
/// in ln d: a grain's k up to ~160 1/s) fall for long after e^{-kt} has underflowed; their
/// crossings just before the horizon are the scalar search's on the lanes too.
#[test]
fn each_lane_finds_the_scalar_hit_for_heavily_damped_grains() {
    let mut damped = Vec::new();
    for alpha in [0.0, 20.0, 35.0] {
        let mut s = Scenario::lunar();
        s.sim.particles = 120;
        s.environment.alpha_deg = alpha;
        s.environment.k_drag = Some(8.0);
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.5, form: SizeForm::default() });
        damped.push(s);
    }
    for (lanes, (compared, _)) in compare_lane_hits("each_lane_finds_the_scalar_hit_for_heavily_damped_grains", &damped)
    {
        assert!(compared > 5_000, "{}: {compared} flights compared", lanes.name());
    }
}

/// Flights in pieces: a sled that returns while grains fly (down the slope or along the
/// launch, at once or after a delay; lunar and Earth) and quadratic drag (alone, with
/// polydisperse sizes, and with a returning sled). Every particle's hit, the piece it lies
/// in and that piece's start are the scalar `first_hit_piecewise`'s to the bit, in lane
/// groups of every size, and the flights compared include ones that end after their first
/// piece and ones that end in a drifting piece.
#[test]
fn each_lane_finds_the_scalar_piecewise_hit_to_the_bit() {
    use crate::engine::kernel::first_hit_piecewise;
    use crate::model::effects::{MotionDirection, QuadraticDrag, SledMotion};
    let sled = |delay_s, return_speed_m_s, direction| SledMotion { delay_s, return_speed_m_s, direction };
    let drag = QuadraticDrag { diameter_m: 300e-6, density_kg_m3: 2500.0 };
    let mut cases = Vec::new();
    for (c, base) in [Scenario::lunar(), Scenario::earth()].into_iter().enumerate() {
        for (m, motion) in [
            sled(0.0, 0.3, MotionDirection::Slope),
            sled(0.05, 0.5, MotionDirection::Slope),
            sled(0.02, 0.06, MotionDirection::Launch),
        ]
        .into_iter()
        .enumerate()
        {
            let mut s = base.clone();
            s.sim.particles = 100;
            s.environment.alpha_deg = [0.0, 20.0, 35.0][(c + m) % 3];
            s.effects.sled_motion = Some(motion);
            cases.push(s);
        }
    }
    for alpha in [0.0, 30.0] {
        let mut s = Scenario::earth();
        s.sim.particles = 100;
        s.environment.alpha_deg = alpha;
        s.effects.quadratic_drag = Some(drag);
        cases.push(s.clone());
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
        cases.push(s.clone());
        s.effects.polydisperse = None;
        s.effects.sled_motion = Some(sled(0.0, 0.25, MotionDirection::Slope));
        cases.push(s);
    }
    for lanes in instantiations("each_lane_finds_the_scalar_piecewise_hit_to_the_bit") {
        let (mut compared, mut drifting, mut pieces) = (0usize, 0usize, 0usize);
        each_bounce(&cases, 3, 70, |c, d, ph, parts, flying, bounce| {
            assert!(applies_piecewise(ph) && !applies(ph), "case {c} flies in pieces");
            // all at once, then in groups of 1, 2, ..., up to one less than the width
            let mut lane_hits = lanes.first_hits_piecewise(d, ph, parts, flying, bounce);
            let sizes = lanes.width().saturating_sub(1).max(1);
            let mut size = 1 + (bounce as usize % sizes);
            let mut rest = flying;
            while !rest.is_empty() {
                let (group, tail) = rest.split_at(size.min(rest.len()));
                lane_hits.extend(lanes.first_hits_piecewise(d, ph, parts, group, bounce));
                rest = tail;
                size = size % sizes + 1;
            }
            for (n, (h, fl, start)) in lane_hits.iter().enumerate() {
                let i = flying[n % flying.len()];
                let (sh, sfl, sstart) = first_hit_piecewise(d, ph, &parts[i as usize], bounce);
                let flight_bits = |f: &Flight<f64>| [f.p0, f.v0, f.drift, [f.k, f.g]].map(|v| v.map(f64::to_bits));
                assert_eq!(
                    (bits(h), flight_bits(fl), start.to_bits()),
                    (bits(&sh), flight_bits(&sfl), sstart.to_bits()),
                    "{}: case {c}, bounce {bounce}, particle {i}",
                    lanes.name()
                );
                compared += 1;
                pieces += usize::from(*start > 0.0);
                drifting += usize::from(fl.drift != [0.0; 2]);
            }
        });
        assert!(
            compared > 20_000 && drifting > compared / 50 && pieces > compared / 20,
            "{}: {compared} flights compared, {drifting} ending in a drifting piece, {pieces} after their first piece",
            lanes.name()
        );
    }
}

/// Every bounce of the particles of `designs` random valid designs per case of `cases`
/// (design seeds from `seed`), as the scalar kernel's loop flies them: `visit` gets the
/// case's index, the design, the physics, the particles with this bounce's launches
/// randomised, the flying ones and the bounce, before they fly.
fn each_bounce(
    cases: &[Scenario],
    designs: usize,
    seed: u64,
    mut visit: impl FnMut(usize, &KDesign<f64>, &KPhysics<f64>, &[KParticle<f64>], &[u32], u32),
) {
    for (c, s) in cases.iter().enumerate() {
        let ctx = Context::new(s);
        let ph = kernel_physics::<f64>(&ctx);
        for design in random_valid_designs(s, designs, seed + c as u64) {
            let prep = prepare(s, &design).unwrap();
            let d = kernel_design::<f64>(&prep);
            let mut parts: Vec<KParticle<f64>> =
                prep.launches.iter().enumerate().map(|(i, l)| init_particle(&d, &ph, *l, i as u32)).collect();
            for bounce in 0..ctx.max_bounces {
                for (i, p) in parts.iter_mut().enumerate().filter(|(_, p)| p.state == STATE_FLYING) {
                    randomise_launch(&d, &ph, p, i as u32, bounce);
                }
                let flying: Vec<u32> =
                    (0..parts.len() as u32).filter(|&i| parts[i as usize].state == STATE_FLYING).collect();
                if flying.is_empty() {
                    break;
                }
                visit(c, &d, &ph, &parts, &flying, bounce);
                for &i in &flying {
                    fly_particle(&d, &ph, &mut parts[i as usize], i, bounce);
                }
            }
        }
    }
}

/// Lane hits against scalar hits over `cases`, for every instantiation of
/// [`instantiations`]: how many flights were compared, and how many of them end on a tooth
/// (not the base line or lost).
fn compare_lane_hits(test: &str, cases: &[Scenario]) -> Vec<(Lanes, (usize, usize))> {
    let mut out = Vec::new();
    for lanes in instantiations(test) {
        let (mut compared, mut on_teeth) = (0usize, 0usize);
        each_bounce(cases, 5, 7, |c, d, ph, parts, flying, bounce| {
            assert!(applies(ph), "case {c} is a one-piece flight of the text's physics");
            // groups of 1, 2, ..., width particles, then again
            let mut rest = flying;
            let mut size = 1 + (bounce as usize % lanes.width());
            while !rest.is_empty() {
                let (group, tail) = rest.split_at(size.min(rest.len()));
                let hits = lanes.first_hits(d, ph, parts, group, bounce);
                for (h, &i) in hits.iter().zip(group) {
                    let scalar = first_hit(d, ph, &parts[i as usize], bounce);
                    assert_eq!(bits(h), bits(&scalar), "{}: case {c}, bounce {bounce}, particle {i}", lanes.name());
                    compared += 1;
                    on_teeth += usize::from(scalar.found && scalar.surface != SURFACE_BASE);
                }
                rest = tail;
                size = size % lanes.width() + 1;
            }
        });
        out.push((lanes, (compared, on_teeth)));
    }
    out
}

/// The launch randomisation on lanes gives `randomise_launch_drawn`'s velocities to the
/// bit, for first launches and rebounds off every surface: the particles of random valid
/// lunar and Earth designs at every bounce, with the same draws.
#[test]
fn lane_launches_are_the_scalar_launches_to_the_bit() {
    use crate::engine::kernel::randomise_launch_drawn;
    use crate::model::rng::{uniform01, DRAW_ANGLE, DRAW_SPEED};
    for lanes in instantiations("lane_launches_are_the_scalar_launches_to_the_bit") {
        let mut compared = [0usize; 4]; // by the surface left: none (first launch), base, ramp, catch
        for base in [Scenario::lunar(), Scenario::earth()] {
            for (c, s) in cases(base, 80).iter().filter(|s| s.effects.launch_spread.is_none()).enumerate() {
                let ctx = Context::new(s);
                let ph = kernel_physics::<f64>(&ctx);
                assert!(randomises(&ph));
                for design in random_valid_designs(s, 3, 50 + c as u64) {
                    let prep = prepare(s, &design).unwrap();
                    let d = kernel_design::<f64>(&prep);
                    let mut parts: Vec<KParticle<f64>> =
                        prep.launches.iter().enumerate().map(|(i, l)| init_particle(&d, &ph, *l, i as u32)).collect();
                    for bounce in 0..ctx.max_bounces {
                        let flying: Vec<u32> =
                            (0..parts.len() as u32).filter(|&i| parts[i as usize].state == STATE_FLYING).collect();
                        if flying.is_empty() {
                            break;
                        }
                        let mut on_lanes = parts.clone();
                        for group in flying.chunks(lanes.width()) {
                            let draw = |k| group.iter().map(|&i| uniform01(ph.seed, i, bounce, k)).collect::<Vec<_>>();
                            lanes.randomise_launches(
                                &d,
                                &ph,
                                &mut on_lanes,
                                group,
                                &draw(DRAW_ANGLE),
                                &draw(DRAW_SPEED),
                            );
                        }
                        for &i in &flying {
                            let p = &mut parts[i as usize];
                            compared[p.surface as usize] += 1;
                            randomise_launch_drawn(&d, &ph, p, i, bounce, None);
                            let b = |v: [f64; 2]| [v[0].to_bits(), v[1].to_bits()];
                            let at = format!("{}: case {c}, bounce {bounce}, particle {i}", lanes.name());
                            assert_eq!(b(on_lanes[i as usize].vel), b(p.vel), "{at}");
                            fly_particle(&d, &ph, p, i, bounce);
                        }
                    }
                }
            }
        }
        assert!(compared.iter().all(|&n| n > 500), "{}: launches compared by surface left: {compared:?}", lanes.name());
    }
}

/// The restitution law on lanes gives the scalar law's bits, over impacts of every speed
/// (both sides of the plastic limit) and angle, in both modes' laws and the DEM's (its
/// tangential table read on every piece and past its end).
#[test]
fn lane_bounces_are_the_scalar_bounces_to_the_bit() {
    use crate::model::collision::TANGENTIAL_NODES;
    use crate::model::scenario::{Collision, ContactLaw, Material, PhysicsMode};
    use rand::{Rng, SeedableRng};
    let material = Material::lunar_regolith();
    let table: Vec<f64> = (0..TANGENTIAL_NODES).map(|i| 0.8 - 1.5 * (i as f64 / 11.0 - 0.4).powi(2)).collect();
    let dem = Collision { law: ContactLaw::Dem, tangential_ratio: table, ..Collision::thesis(0.87, 0.11) };
    let laws = [
        Restitution::new(PhysicsMode::Physical, &Collision::thesis(0.8, 0.3), &material),
        Restitution::new(PhysicsMode::Listing, &Collision::thesis(0.8, 0.3), &material),
        Restitution::new(PhysicsMode::Physical, &dem, &material),
        Restitution::new(PhysicsMode::Physical, &Collision { mu_friction: 0.0, ..dem.clone() }, &material),
    ];
    assert!(laws[2].dem && laws[3].dem);
    for lanes in instantiations("lane_bounces_are_the_scalar_bounces_to_the_bit") {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (law, r) in laws.iter().enumerate() {
            for _ in 0..4000 {
                let (mut v, mut n) = ([[0.0; MAX_LANES]; 2], [[0.0; MAX_LANES]; 2]);
                for l in 0..MAX_LANES {
                    let speed = 10f64.powf(rng.random_range(-4.0..1.0));
                    let (a, b): (f64, f64) = (rng.random_range(0.0..6.3), rng.random_range(0.0..6.3));
                    (v[0][l], v[1][l]) = (speed * a.cos(), speed * a.sin());
                    (n[0][l], n[1][l]) = (b.cos(), b.sin());
                }
                // a grazing, a head-on and a resting impact among them, each in some lane
                let l = rng.random_range(0..lanes.width());
                match rng.random_range(0..8) {
                    0 => (v[0][l], v[1][l], n[0][l], n[1][l]) = (1.0, 0.0, 0.0, 1.0),
                    1 => (v[0][l], v[1][l], n[0][l], n[1][l]) = (0.0, -1.0, 0.0, 1.0),
                    2 => (v[0][l], v[1][l]) = (0.0, 0.0),
                    _ => {}
                }
                let out = lanes.bounce_velocities(r, &v, &n);
                for l in 0..lanes.width() {
                    let s = r.bounce([v[0][l], v[1][l]], [n[0][l], n[1][l]]);
                    assert_eq!(
                        [out[0][l].to_bits(), out[1][l].to_bits()],
                        [s[0].to_bits(), s[1].to_bits()],
                        "{}: law {law}, v {:?}, n {:?}",
                        lanes.name(),
                        [v[0][l], v[1][l]],
                        [n[0][l], n[1][l]]
                    );
                }
            }
        }
    }
}

/// Every operation of a lane type and the elementary functions over it, row by row, for
/// [`Lanes`]' `operations` (each instantiation's entry point runs it with its lane type):
/// the arithmetic, the comparisons and mask operations (as 1 or 0), select, min, max,
/// rounding, the f64 bits `lane_math` reads, and `lane_math`'s functions.
#[inline(always)]
pub(super) fn operations<L: F64Lane>(x: &[f64; MAX_LANES], y: &[f64; MAX_LANES]) -> Vec<[f64; MAX_LANES]> {
    use crate::lane::LaneMask;
    use crate::lane_math::{atan2, exp_m1, ln, ln_1p, sin_cos};
    let (a, b) = (L::load(x), L::load(y));
    let one_zero = |m: L::Mask| L::select(m, L::splat(1.0), L::splat(0.0));
    let (sin, cos) = sin_cos(a);
    let (field, significand) = a.exponent_field_and_significand();
    let k = a.floor().max(L::splat(-1022.0)).min(L::splat(1024.0));
    let (lt, eq) = (a.lt(b), a.eq(b));
    let rows = [
        a + b,
        a - b,
        a * b,
        a / b,
        -a,
        a.abs(),
        a.sqrt(),
        a.floor(),
        a.ceil(),
        a.max(b),
        a.min(b),
        one_zero(lt),
        one_zero(a.le(b)),
        one_zero(a.gt(b)),
        one_zero(a.ge(b)),
        one_zero(eq),
        one_zero(a.ne(b)),
        one_zero(lt & eq),
        one_zero(lt | eq),
        one_zero(lt ^ a.le(b)),
        one_zero(!lt),
        one_zero(L::Mask::splat(lt.any())),
        L::splat(lt.bits() as f64),
        L::select(lt, a, b),
        one_zero(a.sign_negative()),
        a.copysign(b),
        k.pow2i(),
        field,
        significand,
        exp_m1(a),
        sin,
        cos,
        atan2(b, a),
        ln(a),
        ln_1p(a),
    ];
    rows.iter()
        .map(|r| {
            let mut out = [0.0; MAX_LANES];
            r.store(&mut out);
            out
        })
        .collect()
}

/// Every lane operation and `lane_math`'s functions on every instantiation give the scalar
/// f64 code's bits, lane by lane (the mask's `any` and `bits` the lanes' together): over a
/// million arguments, pairs of the special values (signed zeros, infinities, NaN, the
/// functions' edges) and pairs of equal numbers.
#[test]
fn every_lane_operation_is_the_scalar_operation_to_the_bit() {
    let special = [
        0.0,
        -0.0,
        f64::NAN,
        -f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        709.78,
        709.79,
        -40.0,
        524_288.0,
        524_289.0,
        f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        1.0,
        -1.0,
        0.5,
        -2.5,
        1e300,
        std::f64::consts::FRAC_PI_2,
        std::f64::consts::PI,
    ];
    let mut xs: Vec<f64> = (0..1_000_000).map(|i| -12.0 + 24.0 * ((i as f64 * 0.618_033_988_749_895) % 1.0)).collect();
    xs.extend(
        (0..200_000).map(|i| (if i % 2 == 0 { 1.0 } else { -1.0 }) * 10f64.powf(-310.0 + 620.0 * i as f64 / 2e5)),
    );
    let mut pairs: Vec<(f64, f64)> = xs.iter().enumerate().map(|(i, &x)| (x, xs[i * 7919 % xs.len()])).collect();
    pairs.extend(special.iter().flat_map(|&x| special.iter().map(move |&y| (x, y))));
    pairs.extend(xs.iter().take(1000).map(|&x| (x, x)));
    let b = |x: f64| x.to_bits();
    for lanes in instantiations("every_lane_operation_is_the_scalar_operation_to_the_bit") {
        let w = lanes.width();
        for (c, chunk) in pairs.chunks(w).enumerate() {
            let (mut x, mut y) = ([chunk[0].0; MAX_LANES], [chunk[0].1; MAX_LANES]);
            for (l, &(xl, yl)) in chunk.iter().enumerate() {
                (x[l], y[l]) = (xl, yl);
            }
            let got = lanes.operations(&x, &y);
            // the mask's `any` and `bits` (rows 21 and 22) are of all lanes together
            let lt: Vec<bool> = (0..w).map(|l| x[l] < y[l]).collect();
            let bits = lt.iter().enumerate().map(|(l, &t)| u32::from(t) << l).sum::<u32>() as f64;
            for l in 0..w {
                let want = Lanes::ONE.operations(&[x[l]; MAX_LANES], &[y[l]; MAX_LANES]);
                for (row, (g, e)) in got.iter().zip(&want).enumerate() {
                    let e = match row {
                        21 => f64::from(u8::from(lt.iter().any(|&t| t))),
                        22 => bits,
                        _ => e[0],
                    };
                    assert_eq!(b(g[l]), b(e), "{}: row {row} of x {:e}, y {:e} (chunk {c})", lanes.name(), x[l], y[l]);
                }
            }
        }
    }
}

/// The generator drawn through every instantiation draws `uniform01`'s numbers.
#[test]
fn lane_uniforms_are_uniform01() {
    use crate::model::rng::{seed_word, uniform01};
    for lanes in instantiations("lane_uniforms_are_uniform01") {
        for seed in [0u64, 1, 0xdead_beef_1234] {
            let s = seed_word(seed);
            for first in [0u32, 5, 1000, u32::MAX - 20] {
                let ids: Vec<u32> = (0..16).map(|k| first.wrapping_add(3 * k)).collect();
                for (bounce, draw) in [(0, 0), (7, 1), (99, 6)] {
                    for n in [1, 9, 16] {
                        let u = lanes.uniforms(s, &ids[..n], bounce, draw);
                        for (k, id) in ids[..n].iter().enumerate() {
                            assert_eq!(u[k].to_bits(), uniform01(s, *id, bounce, draw).to_bits(), "{}", lanes.name());
                        }
                    }
                }
            }
        }
    }
}

/// The cpu engine on every instantiation leaves every particle as the scalar kernel's
/// bounce loop does (randomise every launch, fly, land, one particle at a time): lunar
/// designs with and without launch randomisation, Earth's (drag), with and without the
/// effects, with flights in pieces (a returning sled; quadratic drag on Earth) and with the
/// DEM's restitution law.
#[test]
fn the_engine_on_lanes_leaves_every_particle_as_the_scalar_loop() {
    use crate::model::effects::{QuadraticDrag, SledMotion};
    use crate::model::scenario::{Collision, ContactLaw};
    let mut cases = Vec::new();
    for (base, randomise) in [(Scenario::lunar(), true), (Scenario::lunar(), false), (Scenario::earth(), true)] {
        let mut s = base;
        s.sim.particles = 150;
        s.sim.randomise = randomise;
        cases.push(s.clone());
        let mut dem = s.clone();
        let table = (0..crate::model::collision::TANGENTIAL_NODES).map(|i| 0.6 - 0.1 * i as f64).collect();
        dem.collision = Collision { law: ContactLaw::Dem, tangential_ratio: table, ..dem.collision };
        cases.push(dem);
        s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 4.0, form: TiltForm::default() });
        s.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.2, angle_sigma_deg: 5.0 });
        s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.3, form: SizeForm::default() });
        cases.push(s.clone());
        // flights in pieces: the sled returning while grains fly, and (in air) quadratic drag
        s.effects.sled_motion =
            Some(SledMotion { delay_s: 0.02, return_speed_m_s: 0.3, direction: Default::default() });
        cases.push(s.clone());
        if s.environment.k_drag.is_some() {
            s.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: 300e-6, density_kg_m3: 2500.0 });
            cases.push(s);
        }
    }
    for lanes in instantiations("the_engine_on_lanes_leaves_every_particle_as_the_scalar_loop") {
        for (c, s) in cases.iter().enumerate() {
            let ctx = Context::new(s);
            let ph = kernel_physics::<f64>(&ctx);
            for design in random_valid_designs(s, 4, 30 + c as u64) {
                let prep = prepare(s, &design).unwrap();
                let d = kernel_design::<f64>(&prep);
                let (engine, _) = crate::engine::cpu::run_particles::<f64>(&prep, &ctx, Some(lanes), None);
                for (i, l) in prep.launches.iter().enumerate() {
                    let mut p = init_particle(&d, &ph, *l, i as u32);
                    for bounce in 0..ctx.max_bounces {
                        if p.state != STATE_FLYING {
                            break;
                        }
                        randomise_launch(&d, &ph, &mut p, i as u32, bounce);
                        fly_particle(&d, &ph, &mut p, i as u32, bounce);
                    }
                    let e = &engine[i];
                    let b = |v: [f64; 2]| [v[0].to_bits(), v[1].to_bits()];
                    assert_eq!(
                        (e.state, e.tooth, b(e.pos), b(e.vel), e.bounces, b(e.first)),
                        (p.state, p.tooth, b(p.pos), b(p.vel), p.bounces, b(p.first)),
                        "{}: case {c}, particle {i}",
                        lanes.name()
                    );
                }
            }
        }
    }
}

/// What the vector search does not cover it says so: a flight in pieces (sled motion,
/// quadratic drag), the listing's minimum hop. Vacuum and Stokes flights it covers.
#[test]
fn the_vector_search_is_only_for_one_piece_flights_of_the_texts_physics() {
    use crate::model::effects::{QuadraticDrag, SledMotion};
    let physics = |s: &Scenario| kernel_physics::<f64>(&Context::new(s));
    assert!(applies(&physics(&Scenario::lunar())));
    assert!(applies(&physics(&Scenario::earth())));
    assert!(!applies(&physics(&Scenario::lunar().into_listing_compat())));
    assert!(!applies(&physics(&Scenario::earth().into_listing_compat())));
    let mut s = Scenario::earth();
    s.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: 1e-4, density_kg_m3: 3100.0 });
    assert!(!applies(&physics(&s)));
    let mut s = Scenario::lunar();
    s.effects.sled_motion = Some(SledMotion { delay_s: 0.01, return_speed_m_s: 0.5, direction: Default::default() });
    assert!(!applies(&physics(&s)));
    // flights in pieces go to the piecewise search, unless the listing's minimum hop applies
    assert!(applies_piecewise(&physics(&s)));
    assert!(!applies_piecewise(&physics(&s.clone().into_listing_compat())));
    assert!(!applies_piecewise(&physics(&Scenario::earth())));
}
