//! Records shared with the kernels. Keep in sync with shaders/shared/types.wgsl (checked field
//! by field against naga's layout of the WGSL by tests/shaders.rs): the same
//! field order, every field a 4-byte scalar (so #[repr(C)] and WGSL layouts coincide), and
//! each record a multiple of 16 bytes with any padding spelled out as fields, so no implicit
//! rounding of a struct's size (or array stride) can make the two sides differ.

use bytemuck::{Pod, Zeroable};

use crate::engine::kernel::{KDesign, KParticle, KPhysics};
use crate::model::collision::TANGENTIAL_NODES;

/// What a whole dispatch shares (the kernel's uniform). The physics a calibration varies per
/// candidate is in [`GpuDesign`]; two groups whose `GpuPhysics` bytes agree can share a
/// dispatch (`GpuEngine::evaluate_groups`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPhysics {
    pub g: f32,
    pub randomise: u32,
    pub band: f32,
    pub seed: u32,
    pub rest_threshold: f32,
    pub min_hop: f32,
    pub min_hop_horizontal: u32,
    pub per_particle_rest: u32,
    pub max_bounces: u32,
    pub n_particles: u32,
    pub n_designs: u32,
    pub teeth_hist: u32,
}

/// One design: its geometry and its own physics (restitution and effect parameters).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuDesign {
    pub pitch: [f32; 2],
    pub p2: [f32; 2],
    pub p4: [f32; 2],
    pub n_base: [f32; 2],
    pub n_ramp: [f32; 2],
    pub n_catch: [f32; 2],
    pub t_base: [f32; 2],
    pub pitch_len: f32,
    pub base_length: f32,
    pub ext_min: f32,
    pub ext_max: f32,
    pub teeth: i32,
    pub launch_angle: f32,
    pub v0: f32,
    // this design's physics
    pub k_elastic: f32,
    pub mu_friction: f32,
    pub tangential_factor: f32,
    pub plastic: u32,
    pub v_limit: f32,
    pub clamp_tangential: u32,
    pub scatter_sigma: f32,
    pub launch_speed_spread: f32,
    pub launch_angle_sigma: f32,
    /// 1: the DEM's restitution law, k_t from `tangential_table` (`ContactLaw::Dem`).
    pub dem_law: u32,
    pub _pad: u32,
    pub tangential_table: [f32; TANGENTIAL_NODES],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuParticle {
    pub tooth: i32,
    pub pos: [f32; 2],
    pub vel: [f32; 2],
    pub surface: u32,
    pub state: u32,
    pub bounces: u32,
    pub hop: f32,
    pub first: [f32; 2],
    pub k_drag: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuOutcome {
    pub iterations: u32,
    pub lost: u32,
    pub flying: u32,
    pub bounce_sum: u32,
    pub advance_teeth: u32,
    pub distance_sum: f32,
    pub _pad: [u32; 2],
}

impl GpuPhysics {
    /// The batch-wide part of `k`. Its per-design part goes into [`GpuDesign::new`]; the
    /// Stokes k_drag (and the polydisperse size law) into each particle's k_drag
    /// (`init_particle`), so neither is here.
    pub fn from_kernel(k: &KPhysics<f32>, max_bounces: u32, n_particles: u32, n_designs: u32, teeth: u32) -> Self {
        GpuPhysics {
            g: k.g,
            randomise: k.randomise,
            band: k.band,
            seed: k.seed,
            rest_threshold: k.rest_threshold,
            min_hop: k.min_hop,
            min_hop_horizontal: k.min_hop_horizontal as u32,
            per_particle_rest: k.per_particle_rest as u32,
            max_bounces,
            n_particles,
            n_designs,
            teeth_hist: teeth,
        }
    }
}

impl GpuDesign {
    /// Design `d` with its own physics `k` (the per-design part of `KPhysics`).
    pub fn new(d: &KDesign<f32>, k: &KPhysics<f32>) -> Self {
        let r = &k.restitution;
        GpuDesign {
            pitch: d.pitch,
            p2: d.p2,
            p4: d.p4,
            n_base: d.n_base,
            n_ramp: d.n_ramp,
            n_catch: d.n_catch,
            t_base: d.t_base,
            pitch_len: d.pitch_len,
            base_length: d.base_length,
            ext_min: d.ext_min,
            ext_max: d.ext_max,
            teeth: d.teeth,
            launch_angle: d.launch_angle,
            v0: d.v0,
            k_elastic: r.k_elastic,
            mu_friction: r.mu_friction,
            tangential_factor: r.tangential_factor,
            plastic: r.plastic as u32,
            v_limit: r.v_limit,
            clamp_tangential: r.clamp_tangential as u32,
            scatter_sigma: k.scatter_sigma,
            launch_speed_spread: k.launch_speed_spread,
            launch_angle_sigma: k.launch_angle_sigma,
            dem_law: r.dem as u32,
            _pad: 0,
            tangential_table: r.tangential_table,
        }
    }
}

impl From<&KParticle<f32>> for GpuParticle {
    fn from(p: &KParticle<f32>) -> Self {
        GpuParticle {
            tooth: p.tooth,
            pos: p.pos,
            vel: p.vel,
            surface: p.surface,
            state: p.state,
            bounces: p.bounces,
            hop: p.hop,
            first: p.first,
            k_drag: p.k_drag,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_match_the_wgsl_structs() {
        // 12, 32, 12 and 8 four-byte fields in shaders/shared/types.wgsl (tests/shaders.rs
        // checks every field's offset and size against naga's layout of the WGSL structs)
        assert_eq!(std::mem::size_of::<GpuPhysics>(), 48);
        assert_eq!(std::mem::size_of::<GpuDesign>(), 176);
        assert_eq!(std::mem::size_of::<GpuParticle>(), 48);
        assert_eq!(std::mem::size_of::<GpuOutcome>(), 32);
    }
}
