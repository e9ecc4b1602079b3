//! Why a design cannot be simulated: a typed reason, never a silent zero.

use thiserror::Error;

#[derive(Clone, Debug, PartialEq, Error)]
pub enum Invalid {
    #[error("design field `{field}` must be a finite number, got {value}")]
    NotFinite { field: &'static str, value: f64 },
    #[error("design field `{field}` must be > 0, got {value}")]
    NotPositive { field: &'static str, value: f64 },
    #[error("design field `omega_deg` must lie in (0, 180) degrees, got {0}")]
    OmegaRange(f64),
    #[error("design field `delta_deg` must lie in (-90, 90) degrees, got {0}")]
    DeltaRange(f64),
    #[error("linear constraint {rule} violated (5.2, Eq. 5.2): {lhs_mm:.4} mm > {rhs_mm:.4} mm")]
    Chain { rule: &'static str, lhs_mm: f64, rhs_mm: f64 },
    #[error("constraint c1 (Eq. 5.4): catch arc of radius r does not reach p2 (|y2-y3| - r = {excess_mm:.4} mm > 0)")]
    CatchMissesPeak { excess_mm: f64 },
    #[error("constraint c2 (Eq. 5.5): catch foot p4 lies beyond the pitch (x4 - l_c = {excess_mm:.4} mm > 0)")]
    CatchOverlapsNextTooth { excess_mm: f64 },
    #[error("constraint c3 (Eq. 5.6): catch foot p4 lies behind the tooth start (x4 = {x4_mm:.4} mm < 0)")]
    CatchBehindToothStart { x4_mm: f64 },
    #[error("viability check (Eq. 5.8-5.9): catch arc cuts the ramp a second time at {t2_mm:.4} mm along it")]
    CatchCutsRamp { t2_mm: f64 },
    #[error("spill check (5.3.1): {detail}")]
    FillSpills { detail: String },
    /// `candidates`: the points drawn before giving up; at the cap (`schema::MAX_HALTON_POINTS`,
    /// the listing's 2000) it is the particle count, not the fill, that is too large.
    #[error("fill area too small: {found} of {needed} launch points fall inside it among the {candidates} candidate points drawn (4.2.3; at most {} are drawn in the physical mode, {} in the listing's: fewer particles would seat)", crate::schema::MAX_HALTON_POINTS, crate::schema::LISTING_HALTON_POINTS)]
    FillTooSmall { found: usize, needed: usize, candidates: u64 },
}

impl Invalid {
    /// Short machine-readable name of the rule.
    pub fn rule(&self) -> &'static str {
        match self {
            Invalid::NotFinite { .. } => "not_finite",
            Invalid::NotPositive { .. } => "not_positive",
            Invalid::OmegaRange(_) => "omega_range",
            Invalid::DeltaRange(_) => "delta_range",
            Invalid::Chain { .. } => "linear_chain",
            Invalid::CatchMissesPeak { .. } => "c1_catch_misses_peak",
            Invalid::CatchOverlapsNextTooth { .. } => "c2_catch_overlaps_next_tooth",
            Invalid::CatchBehindToothStart { .. } => "c3_catch_behind_tooth_start",
            Invalid::CatchCutsRamp { .. } => "catch_cuts_ramp",
            Invalid::FillSpills { .. } => "fill_spills",
            Invalid::FillTooSmall { .. } => "fill_too_small",
        }
    }
}
