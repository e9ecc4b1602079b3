//! The float type the kernels are written against.
//!
//! The `cpu` engine runs the same arithmetic in `f64` (physics) or `f32` (the precision the
//! WGSL kernels have), so the kernel code is generic over this small trait, as parry does
//! with its `Real` alias.

use num_traits::{Float, FloatConst};

pub trait Real: Float + FloatConst + Default + Send + Sync + std::fmt::Debug + 'static {
    /// Convert a constant (always exactly representable or rounded once).
    fn c(x: f64) -> Self;
    fn f64(self) -> f64;
}

impl Real for f32 {
    #[inline(always)]
    fn c(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    #[inline(always)]
    fn c(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
}
