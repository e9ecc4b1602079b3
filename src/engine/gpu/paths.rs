//! Which optional paths of the WGSL kernels a dispatch needs (issue 16).
//!
//! The kernels carry code for flights with and without drag and for the launch-spread and
//! impact-scatter effects. Whether a flight has drag is read from its particle, whether an
//! effect is on from its design's record, so to the shader compiler these are branches the
//! lanes of a SIMD group may disagree on, and a SIMD machine executes both sides of such a
//! branch for every lane. On lavapipe that made a lunar generation pay for the whole Stokes
//! root search on every flight (0.205 s instead of 0.085 s at pop 1000, BENCHMARKS.md).
//! Each switch of [`kernel_codes::WGSL_PATH_SWITCHES`](crate::kernel_codes) is a WGSL
//! pipeline-overridable constant; a dispatch's pipeline is built with a switch off exactly
//! when none of the dispatch's records takes that path, by the kernel's own tests on the same
//! records, so no particle follows different physics. The f32 rounding may still move: with a
//! path gone a driver may fuse other multiply-adds (lavapipe does), which changed how 1 grain
//! of 6400 ended on the 64-design listing-mode batch (tests/gpu_conformance.rs
//! `path_switches_change_no_result`).

use super::layout::{GpuDesign, GpuParticle};
use crate::kernel_codes::{DRAG_FLIGHTS, IMPACT_SCATTER, LAUNCH_SPREAD, VACUUM_FLIGHTS};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KernelPaths {
    /// Some particle flies in vacuum (WGSL `flight_drag` false: `k_drag` not > 0).
    pub vacuum_flights: bool,
    /// Some particle has Stokes drag (`k_drag` > 0).
    pub drag_flights: bool,
    /// Some design spreads its launches (`launch_speed_spread` or `launch_angle_sigma` > 0).
    pub launch_spread: bool,
    /// Some design tilts its impacts (`scatter_sigma` > 0).
    pub impact_scatter: bool,
}

impl KernelPaths {
    /// Every path kept: the general kernel (the WGSL defaults).
    pub const ALL: KernelPaths =
        KernelPaths { vacuum_flights: true, drag_flights: true, launch_spread: true, impact_scatter: true };

    /// The paths these records can take, decided by the kernel's own tests on them.
    pub fn of(designs: &[GpuDesign], particles: &[GpuParticle]) -> KernelPaths {
        // `flight_drag` is `k > 0`: a NaN k flies in vacuum, so the vacuum test is its negation
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let vacuum = |p: &GpuParticle| !(p.k_drag > 0.0);
        KernelPaths {
            vacuum_flights: particles.iter().any(vacuum),
            drag_flights: particles.iter().any(|p| p.k_drag > 0.0),
            launch_spread: designs.iter().any(|d| d.launch_speed_spread > 0.0 || d.launch_angle_sigma > 0.0),
            impact_scatter: designs.iter().any(|d| d.scatter_sigma > 0.0),
        }
    }

    /// The pipeline-overridable constants that build this variant (WGSL `bool`s as 0/1).
    pub fn constants(&self) -> [(&'static str, f64); 4] {
        let b = |on: bool| if on { 1.0 } else { 0.0 };
        [
            (VACUUM_FLIGHTS, b(self.vacuum_flights)),
            (DRAG_FLIGHTS, b(self.drag_flights)),
            (LAUNCH_SPREAD, b(self.launch_spread)),
            (IMPACT_SCATTER, b(self.impact_scatter)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel_codes::WGSL_PATH_SWITCHES;

    #[test]
    fn every_switch_is_set_and_all_means_the_wgsl_defaults() {
        let names: Vec<&str> = KernelPaths::ALL.constants().iter().map(|(n, _)| *n).collect();
        assert_eq!(names, WGSL_PATH_SWITCHES);
        assert!(KernelPaths::ALL.constants().iter().all(|(_, v)| *v == 1.0));
    }

    #[test]
    fn paths_follow_the_records() {
        let vacuum = GpuParticle { k_drag: 0.0, ..Default::default() };
        let drag = GpuParticle { k_drag: 5.3, ..Default::default() };
        let plain = GpuDesign::default();
        let p = KernelPaths::of(&[plain], &[vacuum, vacuum]);
        assert_eq!(
            p,
            KernelPaths { vacuum_flights: true, drag_flights: false, launch_spread: false, impact_scatter: false }
        );
        let p = KernelPaths::of(&[plain], &[drag, vacuum]);
        assert!(p.vacuum_flights && p.drag_flights);
        let spread = GpuDesign { launch_angle_sigma: 0.1, ..Default::default() };
        let scatter = GpuDesign { scatter_sigma: 0.2, ..Default::default() };
        let p = KernelPaths::of(&[plain, spread], &[drag]);
        assert!(!p.vacuum_flights && p.drag_flights && p.launch_spread && !p.impact_scatter);
        assert!(KernelPaths::of(&[scatter], &[drag]).impact_scatter);
    }
}
