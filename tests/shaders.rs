//! The WGSL kernels against their Rust side, without a GPU: every kernel validates with naga
//! (build.rs does this too, so this mostly checks that the validation catches breakage), the
//! shared records agree field by field with naga's layout, and the generated constants are
//! the Rust ones.

use sawtooth::engine::gpu::compose::FILES as COMPOSED_FILES;
use sawtooth::engine::gpu::shaders::{compose, FILES, KERNELS};
use sawtooth::engine::gpu::validate::validate_wgsl;

#[test]
fn every_kernel_parses_and_validates() {
    for k in KERNELS {
        let src = compose(k).unwrap();
        validate_wgsl(k, &src).unwrap_or_else(|e| panic!("{e}"));
    }
}

/// What build.rs runs on every kernel rejects broken shaders, with naga's message: a parse
/// error (a missing semicolon), a type error (an f32 returned as u32) and an unknown name.
#[test]
fn broken_shaders_are_rejected_with_naga_s_message() {
    let src = compose("particles.wgsl").unwrap();
    let cases = [
        (
            "fn to_index(x: f32) -> i32 {\n    return i32(clamp(x, -1.0e9, 1.0e9));",
            "return i32(clamp(x, -1.0e9, 1.0e9))",
        ),
        (
            "fn to_index(x: f32) -> i32 {\n    return i32(clamp(x, -1.0e9, 1.0e9));",
            "return u32(clamp(x, -1.0e9, 1.0e9));",
        ),
        ("atomicAdd(&wg_hop_n, 1u);", "atomicAdd(&wg_hop_n, NOT_A_CONSTANT);"),
    ];
    for (anchor, broken) in cases {
        assert!(src.contains(anchor), "anchor {anchor:?} not in the kernel");
        let bad = src.replacen(anchor.lines().last().unwrap().trim(), broken, 1);
        assert_ne!(bad, src);
        let err = validate_wgsl("particles.wgsl", &bad).expect_err(broken);
        assert!(err.starts_with("particles.wgsl: WGSL"), "{err}");
        assert!(err.contains("particles.wgsl:"), "naga's report names the place: {err}");
    }
}

#[test]
fn every_shared_file_is_imported_by_some_kernel() {
    let composed: String = KERNELS.iter().map(|k| compose(k).unwrap()).collect();
    for (path, text) in FILES {
        let first = text.lines().find(|l| l.starts_with("fn ") || l.starts_with("struct ") || l.starts_with("const "));
        assert!(composed.contains(first.unwrap_or("")), "{path} is never imported");
    }
    assert_eq!(FILES.iter().map(|(p, _)| *p).collect::<Vec<_>>(), COMPOSED_FILES);
}

/// Every constant generated from src/kernel_codes.rs has the Rust value in the composed
/// kernel, read back by naga (not by matching text).
#[test]
fn shared_constants_have_the_rust_values_in_the_kernel() {
    let src = compose("particles.wgsl").unwrap();
    let module = validate_wgsl("particles.wgsl", &src).unwrap();
    for (name, value) in sawtooth::kernel_codes::WGSL_U32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("const {name} missing from the kernel"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => assert_eq!(v, *value, "{name}"),
            ref e => panic!("{name}: not a u32 literal: {e:?}"),
        }
    }
}

/// (WGSL member name, byte offset, byte size) of every field of a Rust record, a `[f32; 2]`
/// field standing for its two WGSL scalars `<name>_x`, `<name>_y` (or `_pad0`, `_pad1`).
macro_rules! rust_members {
    ($ty:ty { $($field:ident => [$($wgsl:literal),+]),* $(,)? }) => {{
        let zero = <$ty as bytemuck::Zeroable>::zeroed();
        let mut v: Vec<(&str, usize, usize)> = Vec::new();
        $({
            let names = [$($wgsl),+];
            let size = std::mem::size_of_val(&zero.$field) / names.len();
            for (i, n) in names.iter().enumerate() {
                v.push((n, std::mem::offset_of!($ty, $field) + i * size, size));
            }
        })*
        let total: usize = v.iter().map(|m| m.2).sum();
        assert_eq!(total, std::mem::size_of::<$ty>(), "{}: a field is missing from the list", stringify!($ty));
        v
    }};
}

/// The records shared with the host (shaders/shared/types.wgsl) against their Rust twins
/// (src/engine/gpu/layout.rs): each WGSL member's offset (from naga's front end) and size
/// (naga's `Layouter`) equal the Rust field's `offset_of!` and size, member by member, and
/// the struct sizes agree.
#[test]
fn shared_records_match_their_rust_twins_field_by_field() {
    use sawtooth::engine::gpu::layout::{GpuDesign, GpuOutcome, GpuParticle, GpuPhysics};
    let src = compose("particles.wgsl").unwrap();
    let module = validate_wgsl("particles.wgsl", &src).unwrap();
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let records = [
        (
            "Physics",
            std::mem::size_of::<GpuPhysics>(),
            rust_members!(GpuPhysics {
                g => ["g"], randomise => ["randomise"], band => ["band"], seed => ["seed"],
                rest_threshold => ["rest_threshold"], min_hop => ["min_hop"],
                min_hop_horizontal => ["min_hop_horizontal"], per_particle_rest => ["per_particle_rest"],
                max_bounces => ["max_bounces"], n_particles => ["n_particles"], n_designs => ["n_designs"],
                teeth_hist => ["teeth_hist"],
            }),
        ),
        (
            "Design",
            std::mem::size_of::<GpuDesign>(),
            rust_members!(GpuDesign {
                pitch => ["pitch_x", "pitch_y"], p2 => ["p2_x", "p2_y"], p4 => ["p4_x", "p4_y"],
                n_base => ["n_base_x", "n_base_y"], n_ramp => ["n_ramp_x", "n_ramp_y"],
                n_catch => ["n_catch_x", "n_catch_y"], t_base => ["t_base_x", "t_base_y"],
                pitch_len => ["pitch_len"], base_length => ["base_length"], ext_min => ["ext_min"],
                ext_max => ["ext_max"], teeth => ["teeth"], launch_angle => ["launch_angle"], v0 => ["v0"],
                k_elastic => ["k_elastic"], mu_friction => ["mu_friction"],
                tangential_factor => ["tangential_factor"], plastic => ["plastic"], v_limit => ["v_limit"],
                clamp_tangential => ["clamp_tangential"], scatter_sigma => ["scatter_sigma"],
                launch_speed_spread => ["launch_speed_spread"], launch_angle_sigma => ["launch_angle_sigma"],
                dem_law => ["dem_law"], _pad => ["_pad0"], tangential_table => ["tangential_table"],
            }),
        ),
        (
            "Particle",
            std::mem::size_of::<GpuParticle>(),
            rust_members!(GpuParticle {
                tooth => ["tooth"], pos => ["pos_x", "pos_y"], vel => ["vel_x", "vel_y"], surface => ["surface"],
                state => ["state"], bounces => ["bounces"], hop => ["hop"], first => ["first_x", "first_y"],
                k_drag => ["k_drag"],
            }),
        ),
        (
            "Outcome",
            std::mem::size_of::<GpuOutcome>(),
            rust_members!(GpuOutcome {
                iterations => ["iterations"], lost => ["lost"], flying => ["flying"], bounce_sum => ["bounce_sum"],
                advance_teeth => ["advance_teeth"], distance_sum => ["distance_sum"], _pad => ["_pad0", "_pad1"],
            }),
        ),
    ];
    for (name, rust_size, rust) in records {
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("struct {name} not found"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("{name} is not a struct") };
        assert_eq!(layouter[handle].size as usize, rust_size, "{name}: WGSL {} bytes, Rust {rust_size}", span);
        assert_eq!(*span as usize, rust_size, "{name}: span");
        let wgsl: Vec<(&str, usize, usize)> = members
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize, layouter[m.ty].size as usize))
            .collect();
        assert_eq!(wgsl, rust, "{name}: (member, offset, size) differ between WGSL and Rust");
        // no implicit rounding of a struct's size or array stride can make the sides differ
        assert_eq!(rust_size % 16, 0, "{name}: pad to a multiple of 16 bytes");
    }
}

/// Every WGSL function has a Rust twin (issue 16): a `fn` of the same name in the Rust twin
/// files, or the named stand-in where the Rust form differs (a method, a field, std).
#[test]
fn every_wgsl_function_has_a_rust_twin() {
    let src = compose("particles.wgsl").unwrap();
    let module = validate_wgsl("particles.wgsl", &src).unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let rust: String = [
        "src/engine/kernel.rs",
        "src/engine/cpu.rs",
        "src/model/flight.rs",
        "src/model/rng.rs",
        "src/model/real.rs",
        "src/model/collision.rs",
    ]
    .iter()
    .map(|p| std::fs::read_to_string(format!("{root}/{p}")).unwrap())
    .collect();
    // WGSL name -> what the Rust side has instead of `fn <same name>`
    let stand_ins = [
        ("flight_pos", "fn pos("),             // Flight::pos
        ("flight_vel", "fn vel("),             // Flight::vel
        ("flight_drag", "fn drag("),           // Flight::drag (the path switches are GPU-only)
        ("expm1_", ".exp_m1()"),               // num_traits::Float::exp_m1 (WGSL has none)
        ("log1p_", ".ln_1p()"),                // num_traits::Float::ln_1p (WGSL has none)
        ("bounce_velocity", "fn bounce("),     // Restitution::bounce
        ("ksin_cos", "fn sin_cos("),           // ktrig::sin_cos
        ("katan_unit", "fn atan_unit("),       // ktrig::atan_unit
        ("katan2", "fn atan2("),               // ktrig::atan2
        ("pitch", "pub pitch: [T; 2]"),        // KDesign::pitch (a field)
        ("simulate", "pub fn run_particles<"), // its bounce loop; the reduction is `reduce`
        // one thread per particle: `follow_particle` for each (tests/twins.rs)
        ("simulate_particles", "pub fn follow_particle<"),
        ("reduce_designs", "pub fn particle_steps<"), // the max of particle_steps, then `reduce`
        ("reduce_design", "pub fn reduce<"),
    ];
    let names = module.functions.iter().filter_map(|(_, f)| f.name.clone());
    let entries = module.entry_points.iter().map(|e| e.name.clone());
    let mut missing = Vec::new();
    for name in names.chain(entries) {
        let needle = match stand_ins.iter().find(|(w, _)| *w == name) {
            Some((_, r)) => r.to_string(),
            None => format!("fn {name}"),
        };
        let found = rust.match_indices(&needle).any(|(i, _)| {
            // `fn name(` or `fn name<`, not a longer name
            stand_ins.iter().any(|(w, _)| *w == name)
                || matches!(rust[i + needle.len()..].chars().next(), Some('(') | Some('<'))
        });
        if !found {
            missing.push(name);
        }
    }
    assert!(missing.is_empty(), "WGSL functions without a Rust twin: {missing:?}");
    assert!(rust.contains("pub fn reduce<"), "the reduction's twin");
}
