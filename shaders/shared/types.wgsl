// Records shared by the Rust host and the kernels.
// Keep in sync with src/engine/gpu/layout.rs (field order, scalar types; no vec3, no padding
// surprises: every field is a 4-byte scalar so the WGSL and #[repr(C)] layouts coincide;
// tests/shaders.rs checks every field's offset and size against naga's layout).
// The SURFACE_*, STATE_*, RANDOMISE_*, DRAW_* and PER_PARTICLE codes are not written here:
// build.rs generates them from src/engine/shared.rs (their one declaration).

#import shared/constants.wgsl

// Batch-wide constants: one uniform per dispatch. Everything a calibration varies between
// candidates (restitution, the effects' parameters) lives in `Design` instead, so groups
// that differ only in those run as one dispatch (GpuEngine::evaluate_groups keys its merge
// on this record's bytes). Stokes k_drag is not here either: it reaches the kernel as each
// particle's k_drag, set on the host from the design's own physics (init_particle).
struct Physics {
    g: f32,
    randomise: u32,          // 0 off, 1 first launch, 2 every launch
    band: f32,
    seed: u32,
    rest_threshold: f32,     // m
    min_hop: f32,            // m
    min_hop_horizontal: u32,
    per_particle_rest: u32,
    max_bounces: u32,
    n_particles: u32,
    n_designs: u32,          // designs in this dispatch
    teeth_hist: u32,         // histogram bins per design (= teeth)
}

struct Design {
    pitch_x: f32, pitch_y: f32,
    p2_x: f32, p2_y: f32,
    p4_x: f32, p4_y: f32,
    n_base_x: f32, n_base_y: f32,
    n_ramp_x: f32, n_ramp_y: f32,
    n_catch_x: f32, n_catch_y: f32,
    t_base_x: f32, t_base_y: f32,
    pitch_len: f32,
    base_length: f32,
    ext_min: f32,
    ext_max: f32,
    teeth: i32,
    launch_angle: f32,
    v0: f32,
    // This design's physics (per design so that one dispatch can carry the candidates of a
    // calibration): the restitution law (Eq. 4.9, 4.14, 4.47-4.49) ...
    k_elastic: f32,
    mu_friction: f32,
    tangential_factor: f32,  // 3.5 (Eq. 4.14) or 1/3.5 (listing D.1 l.316)
    plastic: u32,            // 1: k_plastic above v_limit (Eq. 4.9)
    v_limit: f32,            // m/s
    clamp_tangential: u32,   // 1: k_tang clamped to [0, 1]
    // ... and the effects (issue 5; 0 = off); polydispersity arrives as each particle's k_drag
    scatter_sigma: f32,      // impact normal tilt sigma, rad
    launch_speed_spread: f32,
    launch_angle_sigma: f32, // rad
    dem_law: u32,            // 1: the DEM's restitution law (ContactLaw::Dem), k_t from the table
    _pad0: u32,
    tangential_table: array<f32, 12>, // the DEM law's k_t at each TANGENTIAL_PSI
}

struct Particle {
    tooth: i32,
    pos_x: f32, pos_y: f32,
    vel_x: f32, vel_y: f32,
    surface: u32,
    state: u32,
    bounces: u32,
    hop: f32,
    first_x: f32, first_y: f32,
    k_drag: f32,             // this grain's Stokes k_drag, 1/s (polydisperse effect)
}

struct Outcome {
    iterations: u32,
    lost: u32,
    flying: u32,
    bounce_sum: u32,
    advance_teeth: u32,      // sum over binned particles of (tooth - 1)
    distance_sum: f32,       // sum of credited distances, m (listing semantics)
    _pad0: u32, _pad1: u32,
}

const INF: f32 = 3.0e38;
const PI: f32 = 3.14159265358979;
const EPS: f32 = 1.1920929e-7;
