//! Optional physical effects the thesis's model leaves out (issue 5), each off by default and
//! with at most two parameters. The `cpu` and `gpu` kernels apply them; the `listing` port of
//! the thesis's algorithm refuses a scenario that switches one on (`engine::make_engine_for`).

use serde::{Deserialize, Serialize};

use super::real::Real;

/// The surface normal is tilted by a random angle at each impact (rough printed surfaces,
/// non-spherical grains): tilt ~ N(0, sigma) (`form = "normal"`, the default), or uniform
/// on [−√3 sigma, √3 sigma], the same standard deviation (`form = "uniform"`; cpu only: a
/// form for synthetic data that differs from the diagnosis's candidate).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpactScatter {
    pub sigma_deg: f64,
    #[serde(default, skip_serializing_if = "TiltForm::is_normal")]
    pub form: TiltForm,
}

/// The tilt law of [`ImpactScatter`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TiltForm {
    #[default]
    Normal,
    Uniform,
}

impl TiltForm {
    fn is_normal(&self) -> bool {
        *self == TiltForm::Normal
    }
}

/// Grains leave at different times of the acceleration phase: a grain that leaves early is
/// slower, speed factor 1 - speed_spread·u with u ~ U(0, 1); its direction is jittered by
/// N(0, angle_sigma). Applied to the first launch, before the ±band randomisation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaunchSpread {
    pub speed_spread: f64,
    pub angle_sigma_deg: f64,
}

/// Grains at the fill's free surface leave slower than the body of the fill: a grain at depth
/// z below the free surface (`Fill::depth`, Figure 4.6) leaves with speed factor
/// 1 − speed_loss · exp(−z / decay_depth_m), so the top layer loses up to `speed_loss` and
/// grains a few `decay_depth_m` down leave as the thesis's ideal launch. Applied to the first
/// launch velocity (`init_particle`), before the ±band randomisation and any launch spread.
///
/// **Designed from DEM evidence, not from the thesis** (issue 32, item 3; docs/physics.md):
/// in a LIGGGHTS run of the validation rig (150 grains, Earth), the grains of the fill's top
/// third ended 34 mm from tooth 0 (sd 7 mm), those below it 44-45 mm (sd 2-3 mm); their speeds
/// parted within ~30 ms of the launch (top fifth 17 % slower than the deepest fifth), while
/// the model's end positions hardly depend on depth (correlation 0.13 vs the DEM's 0.67).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FillSurfaceLoss {
    pub speed_loss: f64,
    pub decay_depth_m: f64,
}

/// Particle diameters vary, and the measurement weighs grains (a tooth's mass counts each
/// grain by its mass ∝ d³). Stokes b/m ∝ 1/d² (Eq. 4.16, 4.20), so each grain's k_drag is
/// k_drag (d_ref/d)². Only matters with drag.
///
/// **Each simulated grain stands for an equal mass.** The simulated diameters are drawn
/// from the *mass-weighted* size law q₃(d) ∝ d³ q₀(d) (importance sampling with equal
/// weights), so the engines count grains and the counts are mass fractions — no weight
/// variance, and the GPU reduction stays a count. `form` is the number-weighted law q₀:
/// - `lognormal` (default): d/d_ref = exp(sigma_ln z), z ~ N(0, 1). A log-normal q₀ with
///   median d₀ has a log-normal q₃ with the same σ and median d₀ e^{3σ²}; `d_ref` is that
///   mass-median size, the one k_drag describes.
/// - `uniform`: q₀ uniform on [d_ref e^{-√3 σ}, d_ref e^{√3 σ}] (the same log-sd for small
///   σ); q₃ ∝ d³ on that range, drawn by inverting its CDF: d⁴ = a⁴ + u (b⁴ − a⁴).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Polydisperse {
    pub sigma_ln: f64,
    #[serde(default, skip_serializing_if = "SizeForm::is_lognormal")]
    pub form: SizeForm,
}

/// The number-weighted size law of [`Polydisperse`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SizeForm {
    #[default]
    Lognormal,
    Uniform,
}

impl SizeForm {
    fn is_lognormal(&self) -> bool {
        *self == SizeForm::Lognormal
    }
}

/// The sled keeps moving after the launch (the thesis assumes it stops): it rests for
/// `delay_s`, then returns down the slope at `return_speed_m_s` until it has travelled back
/// the stroke v0²/(2a) (the POC profile vs the delayed profile of Tests 1 and 2). Impacts are
/// computed against the moving profile, restitution on the velocity relative to it.
/// `direction = "launch"` moves it back along the launch direction instead of the slope
/// (cpu only: a form for synthetic data that differs from the diagnosis's candidate).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SledMotion {
    pub delay_s: f64,
    pub return_speed_m_s: f64,
    #[serde(default, skip_serializing_if = "MotionDirection::is_slope")]
    pub direction: MotionDirection,
}

/// Along what the sled of [`SledMotion`] returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MotionDirection {
    /// Down the slope (the rig's guide).
    #[default]
    Slope,
    /// Back along the launch direction.
    Launch,
}

impl MotionDirection {
    fn is_slope(&self) -> bool {
        *self == MotionDirection::Slope
    }
    /// The name a setup's `[measurement] motion_direction` and a report use.
    pub fn name(self) -> &'static str {
        match self {
            MotionDirection::Slope => "slope",
            MotionDirection::Launch => "launch",
        }
    }
}

/// Non-linear air drag with the Schiller-Naumann coefficient (Eq. 4.15, 4.17, 4.18) instead
/// of the fitted linear k_drag: per unit mass the drag over speed is
/// k(v) = 18 μ / (ρ_p d²) · (1 + 0.15 Re^0.687), Re = ρ_air |v| d / μ, for a sphere of
/// diameter `diameter_m` and density `density_kg_m3` in sea-level air (4.1.3). Integrated as
/// Stokes flights whose k is refreshed every `QUADRATIC_DRAG_STEP_S`. Only where the
/// environment has air (drag on).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadraticDrag {
    pub diameter_m: f64,
    pub density_kg_m3: f64,
}

/// The Schiller-Naumann drag force per unit mass and speed, 1/s:
/// `stokes` (18 μ/(ρ_p d²)) · (1 + 0.15 Re^0.687), Re = `re_per_speed` · `speed` (Eq. 4.17-4.18).
/// Generic, so that the cpu kernel's flights ([`QuadraticDrag`] pieces) and the host's
/// matching ([`QuadraticDrag::equivalent_diameter`]) share one formula.
#[inline(always)]
pub fn schiller_naumann_rate<T: Real>(stokes: T, re_per_speed: T, speed: T) -> T {
    stokes * (T::one() + T::c(0.15) * (re_per_speed * speed).powf(T::c(0.687)))
}

/// Sea-level air (4.1.3): density, kg/m³, and dynamic viscosity, Pa s.
pub const AIR_DENSITY: f64 = 1.225;
pub const AIR_VISCOSITY: f64 = 1.81e-5;
/// Length of the piecewise-Stokes steps of the quadratic-drag integration, s.
pub const QUADRATIC_DRAG_STEP_S: f64 = 0.02;

impl QuadraticDrag {
    /// The diameter, m, of grains of `density_kg_m3` whose drag over speed at `speed_m_s`,
    /// 18 μ / (ρ_p d²) · (1 + 0.15 Re^0.687) (Eq. 4.17), is `k_drag` (1/s): the quadratic
    /// drag that matches a linear drag at that speed. Clamped to [1 µm, 1 m]; the drag falls
    /// monotonically with the diameter, so bisection in log d finds it.
    pub fn equivalent_diameter(k_drag: f64, density_kg_m3: f64, speed_m_s: f64) -> f64 {
        let drag = |d: f64| QuadraticDrag { diameter_m: d, density_kg_m3 }.drag_over_speed(speed_m_s);
        let (mut lo, mut hi) = (1e-6_f64.ln(), 0.0_f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if drag(mid.exp()) > k_drag {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).exp()
    }

    /// The drag over speed, 1/s, at `speed_m_s` (Eq. 4.17 with Eq. 4.18's Re).
    pub fn drag_over_speed(&self, speed_m_s: f64) -> f64 {
        let (stokes, re_per_speed) = self.coefficients();
        schiller_naumann_rate(stokes, re_per_speed, speed_m_s.abs())
    }

    /// Stokes part 18 μ / (ρ_p d²), 1/s, and Re per unit speed ρ_air d / μ, s/m.
    pub fn coefficients(&self) -> (f64, f64) {
        (
            18.0 * AIR_VISCOSITY / (self.density_kg_m3 * self.diameter_m.powi(2)),
            AIR_DENSITY * self.diameter_m / AIR_VISCOSITY,
        )
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadratic_drag: Option<QuadraticDrag>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sled_motion: Option<SledMotion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impact_scatter: Option<ImpactScatter>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub launch_spread: Option<LaunchSpread>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polydisperse: Option<Polydisperse>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill_surface_loss: Option<FillSurfaceLoss>,
}

/// One optional effect, described once: its name (CLI, configs, outputs), its parameters
/// (config keys, the bounds `validate` enforces, the narrower bounds a calibration searches,
/// the values at which it does nothing) and how it is switched on in [`Effects`]. Every list
/// of effects in the crate (CLI parsing, validation, the engines' support checks, the
/// diagnosis's candidates) is derived from [`EffectKind::ALL`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectKind {
    ImpactScatter,
    LaunchSpread,
    Polydisperse,
    SledMotion,
    QuadraticDrag,
    FillSurfaceLoss,
}

impl EffectKind {
    pub const ALL: [EffectKind; 6] = [
        EffectKind::ImpactScatter,
        EffectKind::LaunchSpread,
        EffectKind::Polydisperse,
        EffectKind::SledMotion,
        EffectKind::QuadraticDrag,
        EffectKind::FillSurfaceLoss,
    ];

    /// The name on the command line and in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::ImpactScatter => "impact-scatter",
            EffectKind::LaunchSpread => "launch-spread",
            EffectKind::Polydisperse => "polydisperse",
            EffectKind::SledMotion => "sled-motion",
            EffectKind::QuadraticDrag => "quadratic-drag",
            EffectKind::FillSurfaceLoss => "fill-surface-loss",
        }
    }

    /// The config table's name (`[effects.<key>]`).
    pub fn key(self) -> &'static str {
        match self {
            EffectKind::ImpactScatter => "impact_scatter",
            EffectKind::LaunchSpread => "launch_spread",
            EffectKind::Polydisperse => "polydisperse",
            EffectKind::SledMotion => "sled_motion",
            EffectKind::QuadraticDrag => "quadratic_drag",
            EffectKind::FillSurfaceLoss => "fill_surface_loss",
        }
    }

    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.iter().copied().find(|e| e.name() == name)
    }

    /// The effect's parameters, as the config file names them.
    pub fn param_names(self) -> &'static [&'static str] {
        match self {
            EffectKind::ImpactScatter => &["sigma_deg"],
            EffectKind::LaunchSpread => &["speed_spread", "angle_sigma_deg"],
            EffectKind::Polydisperse => &["sigma_ln"],
            EffectKind::SledMotion => &["delay_s", "return_speed_m_s"],
            EffectKind::QuadraticDrag => &["diameter_m", "density_kg_m3"],
            EffectKind::FillSurfaceLoss => &["speed_loss", "decay_depth_m"],
        }
    }

    /// The range every value must lie in (`Effects::validate`).
    pub fn valid_bounds(self) -> &'static [(f64, f64)] {
        match self {
            EffectKind::ImpactScatter => &[(0.0, 45.0)],
            EffectKind::LaunchSpread => &[(0.0, 0.95), (0.0, 45.0)],
            EffectKind::Polydisperse => &[(0.0, 1.5)],
            EffectKind::SledMotion => &[(0.0, 100.0), (1e-6, 10.0)],
            EffectKind::QuadraticDrag => &[(1e-6, 0.01), (100.0, 20_000.0)],
            EffectKind::FillSurfaceLoss => &[(0.0, 0.95), (1e-6, 0.1)],
        }
    }

    /// The range a calibration searches (inside `valid_bounds`).
    pub fn search_bounds(self) -> &'static [(f64, f64)] {
        match self {
            EffectKind::ImpactScatter => &[(0.0, 30.0)],
            EffectKind::LaunchSpread => &[(0.0, 0.9), (0.0, 30.0)],
            EffectKind::Polydisperse => &[(0.0, 1.2)],
            // a delay beyond the flights is the same as no motion; the POC's v_d is 0.05 m/s
            EffectKind::SledMotion => &[(0.0, 0.3), (0.01, 1.0)],
            // glass beads 100-200 µm, quartz sand 125-500 µm (4.3.6); soda-lime to quartz
            EffectKind::QuadraticDrag => &[(50e-6, 600e-6), (2000.0, 2700.0)],
            // the DEM's loss sat within a grain diameter or two of the surface (0.5 mm grains,
            // a 2.6 mm deep fill); beyond a few mm the loss reaches the whole rig fill alike,
            // a uniform slow-down the shared parameters already trade against (a wider box
            // of 10 mm left an in-family synthetic campaign's truth unfound)
            EffectKind::FillSurfaceLoss => &[(0.0, 0.6), (1e-4, 4e-3)],
        }
    }

    /// Parameters at which the effect does nothing (a nested baseline), where they exist:
    /// quadratic drag replaces the linear drag law, so no setting of it is the baseline; a
    /// sled-motion delay at its search bound outlasts the rig's flights.
    pub fn neutral(self) -> Option<&'static [f64]> {
        match self {
            EffectKind::ImpactScatter => Some(&[0.0]),
            EffectKind::LaunchSpread => Some(&[0.0, 0.0]),
            EffectKind::Polydisperse => Some(&[0.0]),
            EffectKind::SledMotion => Some(&[0.3, 0.05]),
            EffectKind::QuadraticDrag => None,
            EffectKind::FillSurfaceLoss => Some(&[0.0, 1e-3]),
        }
    }

    /// Only changes drag: nothing to see in vacuum.
    pub fn needs_air(self) -> bool {
        matches!(self, EffectKind::Polydisperse | EffectKind::QuadraticDrag)
    }

    /// Switch the effect on in `e` with parameters `v` (one per `param_names`).
    pub fn apply(self, e: &mut Effects, v: &[f64]) {
        match self {
            EffectKind::ImpactScatter => {
                // keep a form set by a config (the calibration fits only sigma_deg)
                let form = e.impact_scatter.map(|x| x.form).unwrap_or_default();
                e.impact_scatter = Some(ImpactScatter { sigma_deg: v[0], form })
            }
            EffectKind::LaunchSpread => {
                e.launch_spread = Some(LaunchSpread { speed_spread: v[0], angle_sigma_deg: v[1] })
            }
            EffectKind::Polydisperse => {
                // keep a size law set by a config (the calibration fits only sigma_ln)
                let form = e.polydisperse.map(|p| p.form).unwrap_or_default();
                e.polydisperse = Some(Polydisperse { sigma_ln: v[0], form })
            }
            EffectKind::SledMotion => {
                let direction = e.sled_motion.map(|x| x.direction).unwrap_or_default();
                e.sled_motion = Some(SledMotion { delay_s: v[0], return_speed_m_s: v[1], direction })
            }
            EffectKind::QuadraticDrag => {
                e.quadratic_drag = Some(QuadraticDrag { diameter_m: v[0], density_kg_m3: v[1] })
            }
            EffectKind::FillSurfaceLoss => {
                e.fill_surface_loss = Some(FillSurfaceLoss { speed_loss: v[0], decay_depth_m: v[1] })
            }
        }
    }

    /// The effect's parameters in `e`, None when it is off.
    pub fn values(self, e: &Effects) -> Option<Vec<f64>> {
        match self {
            EffectKind::ImpactScatter => e.impact_scatter.map(|x| vec![x.sigma_deg]),
            EffectKind::LaunchSpread => e.launch_spread.map(|x| vec![x.speed_spread, x.angle_sigma_deg]),
            EffectKind::Polydisperse => e.polydisperse.map(|x| vec![x.sigma_ln]),
            EffectKind::SledMotion => e.sled_motion.map(|x| vec![x.delay_s, x.return_speed_m_s]),
            EffectKind::QuadraticDrag => e.quadratic_drag.map(|x| vec![x.diameter_m, x.density_kg_m3]),
            EffectKind::FillSurfaceLoss => e.fill_surface_loss.map(|x| vec![x.speed_loss, x.decay_depth_m]),
        }
    }

    /// What the effect does, its parameters with their units, and where it acts (for --help).
    pub fn describe(self) -> &'static str {
        match self {
            EffectKind::ImpactScatter => "each impact's surface normal tilted by a random angle of sd SIGMA_DEG (deg): rough surfaces, non-spherical grains",
            EffectKind::LaunchSpread => "grains leave early and slower, speed x (1 - SPEED_SPREAD u), u ~ U(0,1), direction jittered by sd ANGLE_SIGMA_DEG (deg)",
            EffectKind::Polydisperse => "log-normal grain sizes, sd SIGMA_LN of ln d; Stokes drag per grain ∝ 1/d² (with drag only)",
            EffectKind::SledMotion => "the sled rests DELAY_S (s) after the launch, then returns at RETURN_SPEED_M_S (m/s) over the stroke (cpu engine only)",
            EffectKind::QuadraticDrag => "Schiller-Naumann drag of spheres of DIAMETER_M (m) and DENSITY_KG_M3 (kg/m³) instead of the linear k_drag (with drag only; cpu engine only)",
            EffectKind::FillSurfaceLoss => "grains at the fill's free surface leave slower: speed x (1 - SPEED_LOSS exp(-depth / DECAY_DEPTH_M)), depth below the surface in m (from DEM evidence, not the thesis)",
        }
    }

    /// The CLI's `NAME=p1[,p2]` form of the parameters, for messages.
    pub fn cli_form(self) -> String {
        format!("{}={}", self.name(), self.param_names().iter().map(|p| p.to_uppercase()).collect::<Vec<_>>().join(","))
    }
}

/// Every effect as `--help` lists it: `NAME=PARAMS: what it does`, one per line.
pub fn effects_help() -> String {
    EffectKind::ALL.map(|e| format!("  {}: {}", e.cli_form(), e.describe())).join("\n")
}

/// The effects' names, comma-separated (for messages).
pub fn known_effects() -> String {
    EffectKind::ALL.map(|e| e.name()).join(", ")
}

impl Effects {
    pub fn is_default(&self) -> bool {
        *self == Effects::default()
    }

    pub fn any(&self) -> bool {
        !self.active_kinds().is_empty()
    }

    pub fn is_on(&self, kind: EffectKind) -> bool {
        kind.values(self).is_some()
    }

    /// The effects switched on.
    pub fn active_kinds(&self) -> Vec<EffectKind> {
        EffectKind::ALL.into_iter().filter(|k| self.is_on(*k)).collect()
    }

    /// Names of the effects switched on.
    pub fn active(&self) -> Vec<&'static str> {
        self.active_kinds().into_iter().map(EffectKind::name).collect()
    }

    /// Parse `NAME=p1[,p2]` (the CLI's and config's text form; errors name the effect, the
    /// caller names where the text came from): impact-scatter=SIGMA_DEG, launch-spread=SPEED,ANGLE_DEG,
    /// polydisperse=SIGMA_LN, sled-motion=DELAY_S,RETURN_SPEED_M_S,
    /// quadratic-drag=DIAMETER_M,DENSITY_KG_M3, fill-surface-loss=SPEED_LOSS,DECAY_DEPTH_M.
    pub fn set_from_cli(&mut self, spec: &str) -> Result<(), String> {
        let (name, params) =
            spec.split_once('=').ok_or_else(|| format!("`{spec}`: expected NAME=PARAMS, e.g. impact-scatter=5"))?;
        let kind = EffectKind::from_name(name)
            .ok_or_else(|| format!("unknown effect `{name}` (known: {})", known_effects()))?;
        let values: Vec<f64> = params
            .split(',')
            .map(|p| p.trim().parse::<f64>().map_err(|_| format!("effect {name}: `{p}` is not a number")))
            .collect::<Result<_, _>>()?;
        let n = kind.param_names().len();
        if values.len() != n {
            return Err(format!("effect {name} takes {n} value(s) ({}), got {}", kind.cli_form(), values.len()));
        }
        // checked before it is applied: a refused spec leaves the effects as they were
        check_values(kind, &values)?;
        kind.apply(self, &values);
        Ok(())
    }

    pub fn validate(&self) -> Result<(), String> {
        for kind in EffectKind::ALL {
            if let Some(values) = kind.values(self) {
                check_values(kind, &values)?;
            }
        }
        Ok(())
    }
}

/// Whether `values` lie in `kind`'s valid bounds; the error names the config key.
fn check_values(kind: EffectKind, values: &[f64]) -> Result<(), String> {
    for ((v, (lo, hi)), name) in values.iter().zip(kind.valid_bounds()).zip(kind.param_names()) {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(format!("`effects.{}.{name}` must lie in [{lo}, {hi}], got {v}", kind.key()));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_specs_parse_and_reject() {
        let mut e = Effects::default();
        e.set_from_cli("impact-scatter=5").unwrap();
        e.set_from_cli("launch-spread=0.3,4").unwrap();
        e.set_from_cli("polydisperse=0.4").unwrap();
        assert_eq!(e.active(), vec!["impact-scatter", "launch-spread", "polydisperse"]);
        assert!(e.set_from_cli("rotation=1").unwrap_err().contains("unknown effect"));
        assert!(e.set_from_cli("launch-spread=0.3").unwrap_err().contains("takes 2"));
        assert!(e.set_from_cli("polydisperse=-0.1").unwrap_err().contains("effects.polydisperse.sigma_ln"));
        assert!(e.set_from_cli("impact-scatter=90").unwrap_err().contains("sigma_deg"));
        let mut e = Effects::default();
        e.set_from_cli("fill-surface-loss=0.2,0.0005").unwrap();
        assert_eq!(e.fill_surface_loss, Some(FillSurfaceLoss { speed_loss: 0.2, decay_depth_m: 0.0005 }));
        assert!(e
            .set_from_cli("fill-surface-loss=0.2,0")
            .unwrap_err()
            .contains("effects.fill_surface_loss.decay_depth_m"));
        assert!(e.set_from_cli("fill-surface-loss=1.2,0.001").unwrap_err().contains("speed_loss"));
    }

    /// A value outside its effect's bounds is refused before it is applied: the effects
    /// keep what they held (an effect already on keeps its values, one that was off stays
    /// off), so a caller that reports the error and goes on holds no invalid effect.
    #[test]
    fn a_refused_spec_leaves_the_effects_unchanged() {
        let mut e = Effects::default();
        e.set_from_cli("impact-scatter=5").unwrap();
        let before = e;
        assert!(e.set_from_cli("impact-scatter=90").unwrap_err().contains("effects.impact_scatter.sigma_deg"));
        assert!(e.set_from_cli("polydisperse=-0.1").unwrap_err().contains("effects.polydisperse.sigma_ln"));
        assert!(e.set_from_cli("fill-surface-loss=0.2,0").unwrap_err().contains("decay_depth_m"));
        assert!(e.set_from_cli("sled-motion=0,NaN").is_err());
        assert_eq!(e, before);
        assert!(e.validate().is_ok());
    }
}
