//! The integer codes the Rust kernel and the WGSL kernels share: particle states, surfaces,
//! randomisation schedules and random-draw ids. Declared here once. The WGSL side is generated
//! from this file at build time (build.rs writes `shared/constants.wgsl` into OUT_DIR and
//! `shaders/shared/types.wgsl` imports it), so the two sides cannot drift apart.
//!
//! build.rs includes this file with `#[path]`: keep it free of `use` and of crate paths.

/// Declares each `u32` constant and lists them all (name, value) in [`WGSL_U32`] for the
/// generated WGSL.
macro_rules! shared_u32 {
    ($($(#[$doc:meta])* $name:ident = $value:expr;)*) => {
        $($(#[$doc])* pub const $name: u32 = $value;)*
        /// Every shared constant as (name, value), in declaration order (build.rs writes
        /// them as WGSL `const NAME: u32 = VALUEu;`).
        pub const WGSL_U32: &[(&str, u32)] = &[$((stringify!($name), $name)),*];
    };
}

shared_u32! {
    /// The surface a particle last touched (`KParticle::surface`, WGSL `Particle.surface`).
    SURFACE_NONE = 0;
    SURFACE_BASE = 1;
    SURFACE_RAMP = 2;
    SURFACE_CATCH = 3;

    /// A particle's state (`KParticle::state`, WGSL `Particle.state`).
    STATE_FLYING = 0;
    STATE_RESTING = 1;
    STATE_LOST = 2;

    /// Randomisation schedule (4.2.4 vs listing D.3, erratum 5).
    RANDOMISE_OFF = 0;
    RANDOMISE_FIRST_LAUNCH = 1;
    RANDOMISE_EVERY_LAUNCH = 2;

    /// Draw ids of the counter-based RNG (`src/model/rng.rs`, `shaders/shared/rng.wgsl`):
    /// the draws a particle makes at each launch (4.2.4: one factor for the angle, one for
    /// the speed).
    DRAW_ANGLE = 0;
    DRAW_SPEED = 1;
    /// Effects (issue 5): a normal deviate for the impact tilt (draws 2 and 3), the launch
    /// spread's speed and angle (5 and 6), and the grain size (7 and 8; keyed with bounce =
    /// `PER_PARTICLE`).
    DRAW_SCATTER = 2;
    DRAW_LAUNCH_SPEED = 4;
    DRAW_LAUNCH_ANGLE = 5;
    DRAW_SIZE = 7;
    /// Random launch points (`LaunchPoints::Random`): x and y (9 and 10) of candidate i,
    /// keyed (i, PER_PARTICLE).
    DRAW_LAUNCH_POINT = 9;
    /// The impact tilt drawn again (impact scatter's shadow rule, `kernel::land`): the k-th
    /// redraw of a bounce is the normal deviate of draws 16 + 2 (k − 1) and the one after.
    DRAW_SCATTER_AGAIN = 16;
    /// The most tilts an impact draws (the first at `DRAW_SCATTER`, the rest at
    /// `DRAW_SCATTER_AGAIN`) before it takes the untilted bounce.
    TILT_DRAWS = 8;
    /// The bounce key of draws made once per particle.
    PER_PARTICLE = u32::MAX;
}

/// Declares each switch of the kernels' optional paths as its own name and lists them in
/// [`WGSL_PATH_SWITCHES`].
macro_rules! path_switches {
    ($($(#[$doc:meta])* $name:ident;)*) => {
        $($(#[$doc])* pub const $name: &str = stringify!($name);)*
        /// Every path switch, in declaration order (build.rs writes them as WGSL
        /// `override NAME: bool = true;`).
        pub const WGSL_PATH_SWITCHES: &[&str] = &[$($name),*];
    };
}

path_switches! {
    /// Switches of the WGSL kernels' optional paths (issue 16): pipeline-overridable
    /// constants, true by default (the general kernel). The gpu engine sets each from a
    /// dispatch's own records (src/engine/gpu/paths.rs), so a path none of its particles can
    /// take is compiled out of that dispatch's pipeline: a SIMD machine (lavapipe; a GPU's
    /// warp, to a lesser degree) otherwise runs both sides of every branch its lanes
    /// disagree on, and from the kernel's point of view a particle's drag or a design's
    /// effect parameters may differ from lane to lane. The Rust kernel has no such switch: it
    /// branches per flight, which is what a pipeline with the path kept does.
    ///
    /// Some particle flies in vacuum (`k_drag` = 0).
    VACUUM_FLIGHTS;
    /// Some particle has Stokes drag (`k_drag` > 0).
    DRAG_FLIGHTS;
    /// Some design has the launch-spread effect on.
    LAUNCH_SPREAD;
    /// Some design has the impact-scatter effect on.
    IMPACT_SCATTER;
}

/// In `next_tooth_to_search` (kernel.rs, particles.wgsl): a run of teeth is passed at once
/// only when the flight is higher than the line over their peaks by this many pitch lengths,
/// far more than rounding moves a height, so `flies_over` would say the same of each tooth.
pub const RUN_CLEARANCE_PITCHES: f64 = 1e-3;

/// The nodes ψ of the DEM restitution law's tangential table (`model::collision`,
/// `ContactLaw::Dem`): ψ = |v_t| / (μ (1 + k_n) |v_n|), the tangential speed over the most a
/// Coulomb contact can take from it. Dense below 2, where single impacts in LIGGGHTS change
/// from sliding (k_t = 1 − 1/ψ) to sticking and tangential rebound.
pub const TANGENTIAL_PSI: [f64; 12] = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0];

/// The generated WGSL: one `const` per shared constant, one `override` per path switch.
pub fn wgsl_constants() -> String {
    let mut out =
        String::from("// Generated by build.rs from src/kernel_codes.rs: do not edit (edit the Rust side).\n");
    for (name, value) in WGSL_U32 {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out.push_str(&format!("const RUN_CLEARANCE_PITCHES: f32 = {RUN_CLEARANCE_PITCHES:?};\n"));
    let psi: Vec<String> = TANGENTIAL_PSI.iter().map(|p| format!("{p:?}")).collect();
    out.push_str(&format!("const TANGENTIAL_PSI = array<f32, {}>({});\n", TANGENTIAL_PSI.len(), psi.join(", ")));
    for name in WGSL_PATH_SWITCHES {
        out.push_str(&format!("override {name}: bool = true;\n"));
    }
    out
}
