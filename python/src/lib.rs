//! Python bindings of the sawtooth engine (module `sawtooth._sawtooth`, re-exported by the
//! pure-Python package `sawtooth`). Thin by design: every setting goes through the library's
//! scenario resolution (`scenario_request::ScenarioRequest::resolve`, as the CLI's flags do),
//! every design through the library's
//! engines, `fit` and `diagnose` through the library's requests (`fit::request`,
//! `diagnose::request`, which the CLI's commands build too), so the numbers are the CLI's.
//! Errors become `ValueError` with the library's message, naming the keyword.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use anyhow::Context as _;
use clap::ValueEnum;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use sawtooth::calibrate::{parse_assignments, parse_params, EffortSettings, Spelling};
use sawtooth::diagnose::diagnose::parse_effects;
use sawtooth::diagnose::request::{self as diagnose_request, DiagnoseRequest};
use sawtooth::engine::summary::simulation_json;
use sawtooth::engine::{cpu_only_effects, evaluate_detailed, make_engine, make_engine_for, Engine, EngineKind};
use sawtooth::fit::request::{self as fit_request, FitRequest};
use sawtooth::io::config::load_requirements;
use sawtooth::model::design::{DesignRow, LOWER_BOUND_CLI, UPPER_BOUND_CLI, VARIABLES};
use sawtooth::model::requirements::REQUIREMENT_TOLERANCE;
use sawtooth::model::scenario::EnvPreset;
use sawtooth::model::Design;
use sawtooth::optim::nsga2::BatchProblem;
use sawtooth::optim::sawtooth::{
    nonlinear_constraints, objectives, violation, Logged, SawtoothProblem, CONSTRAINT_TOLERANCE, UNSIMULATED_VIOLATION,
};
use sawtooth::scenario_request::{Compat, ScenarioRequest, MAX_ALPHA_POINTS};

fn value_error(e: anyhow::Error) -> PyErr {
    // the CLI prints `error: {e:#}`: the whole context chain on one line
    PyValueError::new_err(format!("{e:#}").trim_end().to_string())
}

fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| value_error(e.into()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A complete problem statement apart from the design: the CLI's preset, config file and
/// overrides, validated exactly as `sawtooth simulate` validates them (ValueError with the
/// CLI's message).
///
/// Scenario(env=None, config=None, *, compat=None, alpha_deg=None, k_elastic=None,
/// mu_fric=None, k_drag_per_s=None, aor_deg=None, material=None, particles=None, teeth=None,
/// max_bounces=None, seed=None, launch_offset_deg=None, randomise=True, effects=None)
///
/// env: "lunar" (g 1.625 m/s^2, vacuum, lunar regolith) or "earth" (g 9.81 m/s^2, Stokes drag
/// 5.439 1/s, quartz sand); config: TOML path (flags override it); compat: "listing";
/// alpha_deg: conveyor angle, degrees; k_elastic: elastic normal COR (-); mu_fric: friction
/// coefficient (-); k_drag_per_s: Stokes drag, 1/s (0 = vacuum); aor_deg: angle of repose,
/// degrees; material: "lunar-regolith" | "quartz-sand" | "glass-beads"; particles per design;
/// teeth; max_bounces; seed of the particle streams; launch_offset_deg: degrees; randomise:
/// launch randomisation; effects: CLI specs such as ["impact-scatter=8"].
#[pyclass(module = "sawtooth._sawtooth", name = "Scenario", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyScenario {
    inner: sawtooth::model::Scenario,
    design: Option<Design>,
}

#[pymethods]
impl PyScenario {
    #[new]
    #[pyo3(signature = (env=None, config=None, *, compat=None, alpha_deg=None, k_elastic=None, mu_fric=None,
        k_drag_per_s=None, aor_deg=None, material=None, particles=None, teeth=None, max_bounces=None, seed=None,
        launch_offset_deg=None, randomise=true, effects=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        env: Option<&str>,
        config: Option<PathBuf>,
        compat: Option<&str>,
        alpha_deg: Option<f64>,
        k_elastic: Option<f64>,
        mu_fric: Option<f64>,
        k_drag_per_s: Option<f64>,
        aor_deg: Option<f64>,
        material: Option<String>,
        particles: Option<i64>,
        teeth: Option<i64>,
        max_bounces: Option<i64>,
        seed: Option<i64>,
        launch_offset_deg: Option<f64>,
        randomise: bool,
        effects: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let env =
            match env {
                None => None,
                Some(e) => Some(EnvPreset::from_str(e, true).map_err(|_| {
                    PyValueError::new_err(format!("env: unknown environment `{e}` (known: lunar, earth)"))
                })?),
            };
        let compat = match compat {
            None | Some("physical") => None,
            Some("listing") => Some(Compat::Listing),
            Some(c) => return Err(PyValueError::new_err(format!("compat: unknown mode `{c}` (known: listing)"))),
        };
        // within u32 the scenario's validation applies the schema's bound with the CLI's
        // message; beyond it, the same rule (sawtooth::schema) under the argument's name
        let count = |name: &str, v: Option<i64>, bound: &sawtooth::schema::Count| -> PyResult<Option<u32>> {
            match v {
                None => Ok(None),
                Some(n) => u32::try_from(n)
                    .map(Some)
                    .map_err(|_| PyValueError::new_err(format!("{name} {}, got {n}", bound.rule()))),
            }
        };
        // the scenario's validation names `environment.alpha_deg`; the argument's own name here
        if let Some(a) = alpha_deg {
            sawtooth::schema::ENV_ALPHA.check("alpha_deg", a).map_err(PyValueError::new_err)?;
        }
        let seed = match seed {
            None => None,
            Some(s) if s >= 0 => Some(s as u64),
            Some(s) => return Err(PyValueError::new_err(format!("seed must be >= 0, got {s}"))),
        };
        let request = ScenarioRequest {
            config,
            env,
            alpha: alpha_deg.map(|a| (a, a)),
            k_elastic,
            mu_fric,
            k_drag: k_drag_per_s,
            aor: aor_deg,
            material,
            particles: count("particles", particles, &sawtooth::schema::SIM_PARTICLES)?,
            teeth: count("teeth", teeth, &sawtooth::schema::SIM_TEETH)?,
            bounces: count("max_bounces", max_bounces, &sawtooth::schema::SIM_MAX_BOUNCES)?,
            seed,
            launch_offset: launch_offset_deg,
            no_randomise: !randomise,
            compat,
            effects: effects.unwrap_or_default(),
        };
        let (inner, design) = request.resolve().map_err(value_error)?;
        Ok(PyScenario { inner, design })
    }

    /// Particles per design.
    #[getter]
    fn particles(&self) -> u32 {
        self.inner.sim.particles
    }
    /// Seed of the counter-based particle streams.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.sim.seed
    }
    /// Simulated teeth.
    #[getter]
    fn teeth(&self) -> u32 {
        self.inner.sim.teeth
    }
    /// The config file's [design] as the 8 variables (mm, mm, mm, mm, deg, deg, m/s, m/s^2), or None.
    #[getter]
    fn design<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.design.map(|d| d.to_cli_units().to_vec().into_pyarray(py))
    }
    /// Every setting as a dict (the library's field names; lengths in m, angles in degrees).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.inner).map_err(|e| value_error(e.into()))?;
        json_to_py(py, &v)
    }
    /// A copy with other particle count and/or seed (validated like the constructor).
    #[pyo3(signature = (*, particles=None, seed=None))]
    fn replace(&self, particles: Option<u32>, seed: Option<u64>) -> PyResult<Self> {
        let mut s = self.clone();
        if let Some(p) = particles {
            s.inner.sim.particles = p;
        }
        if let Some(v) = seed {
            s.inner.sim.seed = v;
        }
        s.inner.validate().map_err(|e| PyValueError::new_err(format!("invalid setting: {e}")))?;
        Ok(s)
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Scenario(mode={:?}, g_m_s2={}, alpha_deg={}, k_drag_per_s={}, material={:?}, particles={}, teeth={}, seed={}, effects=[{}])",
            s.mode,
            s.environment.g,
            s.environment.alpha_deg,
            s.environment.k_drag.unwrap_or(0.0),
            s.material.name,
            s.sim.particles,
            s.sim.teeth,
            s.sim.seed,
            s.effects.active().join(", ")
        )
    }
}

fn engine_kind(name: &str) -> PyResult<EngineKind> {
    EngineKind::from_str(name, true)
        .map_err(|_| PyValueError::new_err(format!("engine: unknown engine `{name}` (known: listing, cpu, gpu, auto)")))
}

/// GPU adapters take a while to open: one engine per kind per process. The CPU engines and
/// the effect checks go through `make_engine_for` every call, as in the CLI.
fn engine_for(kind: EngineKind, scenario: &sawtooth::model::Scenario) -> anyhow::Result<Arc<dyn Engine>> {
    type Cache = Mutex<Vec<(EngineKind, Arc<dyn Engine>)>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    if matches!(kind, EngineKind::Cpu | EngineKind::Listing) || !cpu_only_effects(&scenario.effects).is_empty() {
        return Ok(Arc::from(make_engine_for(kind, scenario)?));
    }
    let mut cache = CACHE.get_or_init(Default::default).lock().unwrap_or_else(|p| p.into_inner());
    if let Some((_, e)) = cache.iter().find(|(k, _)| *k == kind) {
        return Ok(e.clone());
    }
    let e: Arc<dyn Engine> = Arc::from(make_engine(kind)?);
    cache.push((kind, e.clone()));
    Ok(e)
}

/// `x` as float64 rows of 8: a float64 array as it is; a list of rows, an int64 or float32
/// array converted as `numpy.asarray(x, dtype="float64")` converts them; anything else is a
/// ValueError naming `x` (it was a bare `TypeError: type mismatch`).
fn designs_from(x: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 8]>> {
    let x: PyReadonlyArray2<f64> = match x.extract() {
        Ok(a) => a,
        Err(_) => {
            let py = x.py();
            let kwargs = PyDict::new(py);
            kwargs.set_item("dtype", "float64")?;
            let a = py
                .import("numpy")?
                .call_method("asarray", (x,), Some(&kwargs))
                .map_err(|e| PyValueError::new_err(format!("x: not an array of numbers of shape (n, 8): {e}")))?;
            let ndim: usize = a.getattr("ndim")?.extract()?;
            if ndim != 2 {
                return Err(PyValueError::new_err(format!(
                    "x must have shape (n, 8) (one design per row), got an array of {ndim} dimension(s)"
                )));
            }
            a.extract().map_err(|e: PyErr| PyValueError::new_err(format!("x: {e}")))?
        }
    };
    let a = x.as_array();
    if a.ncols() != 8 {
        return Err(PyValueError::new_err(format!(
            "X must have shape (n, 8): columns {}; got {} columns",
            DesignRow::COLUMNS.join(", "),
            a.ncols()
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (i, row) in a.rows().into_iter().enumerate() {
        let mut v = [0.0; 8];
        for (j, x) in row.iter().enumerate() {
            if !x.is_finite() {
                let (name, unit) = VARIABLES[j];
                return Err(PyValueError::new_err(format!(
                    "X[{i}, {j}]: design field `{name}` ({unit}) must be a finite number, got {x}"
                )));
            }
            v[j] = *x;
        }
        out.push(v);
    }
    Ok(out)
}

/// evaluate(scenario, x, *, engine="cpu", seed=None, particles=None, feasible_only=False) -> dict
///
/// Evaluate the rows of x (float64, shape (n, 8): l_c_mm, l_a_mm, l_b_mm, r_mm, omega_deg,
/// delta_deg, v0_m_s, a_m_s2) as one engine batch, the GIL released; every design sees the same
/// particle streams (common random numbers). engine: "cpu" | "gpu" | "auto" | "listing".
///
/// Returns numpy arrays of length n (NaN where not simulated or invalid): f_stroke_hz,
/// f_dynamic_hz (Hz), w_spec_j_kg (J/kg), m_dot_kg_s (kg/s), p_avg_w (W), stroke_m, d_avg_m,
/// advance_m (m), n_wire, lost_fraction, unsettled_fraction, distribution (n, teeth: fraction
/// of launched particles per tooth), valid, simulated, invalid_rule, invalid_message,
/// constraints_mm (n, 7: CONSTRAINT_NAMES, met when <= CONSTRAINT_TOLERANCE mm), violation
/// (mm, 0 = feasible), objectives (n, 2: the built-in optimiser's penalised f_stroke, W_spec);
/// and engine, seed, particles. feasible_only: do not simulate designs with violation > 0.
#[pyfunction]
#[pyo3(signature = (scenario, x, *, engine="cpu", seed=None, particles=None, feasible_only=false))]
fn evaluate<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    x: &Bound<'py, PyAny>,
    engine: &str,
    seed: Option<u64>,
    particles: Option<u32>,
    feasible_only: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = engine_kind(engine)?;
    let xs = designs_from(x)?;
    let scenario = scenario.replace(particles, seed)?.inner;
    let n = xs.len();
    let teeth = scenario.sim.teeth as usize;
    let violations: Vec<f64> = xs.iter().map(|v| violation(v)).collect();
    let constraints: Vec<[f64; 7]> = xs.iter().map(geometric_constraints).collect();
    let simulate: Vec<usize> = (0..n).filter(|&i| !feasible_only || violations[i] == 0.0).collect();
    let designs: Vec<Design> = simulate.iter().map(|&i| Design::from_cli_units(xs[i])).collect();
    let eng = engine_for(kind, &scenario).map_err(value_error)?;
    let results = py.detach(|| eng.evaluate(&scenario, &designs));

    let nan = f64::NAN;
    let (mut f_stroke, mut f_dyn, mut w_spec, mut m_dot, mut p_avg) =
        (vec![nan; n], vec![nan; n], vec![nan; n], vec![nan; n], vec![nan; n]);
    let (mut d_avg, mut lost, mut advance, mut stroke, mut n_wire) =
        (vec![nan; n], vec![nan; n], vec![nan; n], vec![nan; n], vec![-1i64; n]);
    let mut unsettled = vec![nan; n];
    let mut dist = vec![nan; n * teeth];
    let mut valid = vec![false; n];
    let mut simulated = vec![false; n];
    let mut objs = vec![nan; n * 2];
    let mut rule = vec![String::new(); n];
    let mut message = vec![String::new(); n];
    for (k, r) in simulate.iter().zip(results) {
        let i = *k;
        simulated[i] = true;
        let o = objectives(&r);
        objs[2 * i] = o[0];
        objs[2 * i + 1] = o[1];
        match r {
            Ok(e) => {
                valid[i] = true;
                let p = &e.performance;
                f_stroke[i] = p.f_stroke_hz;
                f_dyn[i] = p.f_dynamic_hz;
                w_spec[i] = p.w_spec_j_kg.unwrap_or(nan);
                m_dot[i] = p.m_dot_kg_s;
                p_avg[i] = p.p_avg_w;
                stroke[i] = p.stroke_m;
                n_wire[i] = p.n_wire as i64;
                d_avg[i] = e.sim.d_avg_m;
                lost[i] = e.sim.lost_fraction;
                advance[i] = e.sim.advance_m;
                unsettled[i] = e.sim.unsettled_fraction;
                dist[i * teeth..(i + 1) * teeth].copy_from_slice(&e.sim.distribution);
            }
            Err(invalid) => {
                rule[i] = invalid.rule().to_string();
                message[i] = invalid.to_string();
            }
        }
    }
    for i in 0..n {
        if !simulated[i] {
            rule[i] = "infeasible_not_simulated".to_string();
            message[i] = format!("constraint violation {:.6} (sum of excesses beyond the tolerance {CONSTRAINT_TOLERANCE}); not simulated", violations[i]);
        }
    }
    let arr2 = |v: Vec<f64>, cols: usize| {
        PyArray2::from_owned_array(py, numpy::ndarray::Array2::from_shape_vec((n, cols), v).expect("shape"))
    };
    let d = PyDict::new(py);
    d.set_item("f_stroke_hz", f_stroke.into_pyarray(py))?;
    d.set_item("f_dynamic_hz", f_dyn.into_pyarray(py))?;
    d.set_item("w_spec_j_kg", w_spec.into_pyarray(py))?;
    d.set_item("m_dot_kg_s", m_dot.into_pyarray(py))?;
    d.set_item("p_avg_w", p_avg.into_pyarray(py))?;
    d.set_item("stroke_m", stroke.into_pyarray(py))?;
    d.set_item("n_wire", n_wire.into_pyarray(py))?;
    d.set_item("d_avg_m", d_avg.into_pyarray(py))?;
    d.set_item("advance_m", advance.into_pyarray(py))?;
    d.set_item("lost_fraction", lost.into_pyarray(py))?;
    d.set_item("unsettled_fraction", unsettled.into_pyarray(py))?;
    d.set_item("distribution", arr2(dist, teeth))?;
    d.set_item("valid", valid.into_pyarray(py))?;
    d.set_item("simulated", simulated.into_pyarray(py))?;
    d.set_item("invalid_rule", PyList::new(py, rule)?)?;
    d.set_item("invalid_message", PyList::new(py, message)?)?;
    let flat: Vec<f64> = constraints.iter().flatten().copied().collect();
    d.set_item("constraints_mm", arr2(flat, 7))?;
    d.set_item("violation", violations.into_pyarray(py))?;
    d.set_item("objectives", arr2(objs, 2))?;
    d.set_item("engine", eng.backend())?;
    d.set_item("seed", scenario.sim.seed)?;
    d.set_item("particles", scenario.sim.particles)?;
    Ok(d)
}

/// The seven geometric constraint values of one design, mm (CONSTRAINT_NAMES' order).
fn geometric_constraints(v: &[f64; 8]) -> [f64; 7] {
    let c = nonlinear_constraints(v);
    [v[2] - v[3], v[3] - v[1], v[1] - v[0], c[0], c[1], c[2], c[3]]
}

/// evaluate_problem(scenario, x, *, engine="cpu", generation=0, requirements=None, slopes_deg=None) -> dict
///
/// One generation of the built-in optimiser's problem (`sawtooth optimize`'s own code,
/// `optim::sawtooth::SawtoothProblem::evaluate_batch`): the rows of x (shape (n, 8), VARIABLES'
/// units) on the particle streams of `generation` (seed = scenario.seed + generation *
/// 0x9E3779B97F4A7C15 mod 2^64), every slope of slopes_deg (degrees; default: the scenario's
/// alpha) in one engine job, designs that violate a geometric constraint not simulated.
/// requirements: "table-2.2" or a TOML file with a [requirements] table (`optimize
/// --requirements`).
///
/// Returns: objectives (n, 2: the penalised f_stroke (Hz) and W_spec (J/kg), worst over the
/// slopes; 1e12 where not simulated), violation (n: what Deb's rules rank by: geometric excess
/// in mm, plus the requirements' relative shortfalls, plus UNSIMULATED_VIOLATION for a design
/// not simulated when there are requirements), simulated (n), constraints_mm (n, 7),
/// requirement_constraints (n, 3: REQUIREMENT_NAMES' worst relative shortfalls over the
/// slopes, <= 0 met; NaN where not simulated or without requirements), compliant (n),
/// binding_requirement and operating_limit (lists of str, "" where none), m_dot_op_kg_h,
/// p_op_w (operating point at the slope shown), alpha_deg (n: the slope shown: the one failing
/// the requirements worst, else the highest W_spec), and at that slope f_stroke_hz, w_spec_j_kg,
/// m_dot_kg_s, p_avg_w, d_avg_m, lost_fraction, distribution (n, teeth), invalid_rule; and
/// engine, seed, particles, slopes_deg.
#[pyfunction]
#[pyo3(signature = (scenario, x, *, engine="cpu", generation=0, requirements=None, slopes_deg=None))]
#[allow(clippy::too_many_arguments)]
fn evaluate_problem<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    x: &Bound<'py, PyAny>,
    engine: &str,
    generation: u64,
    requirements: Option<String>,
    slopes_deg: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = engine_kind(engine)?;
    let xs = designs_from(x)?;
    let scenario = scenario.inner.clone();
    let requirements = requirements.map(|spec| load_requirements(&spec)).transpose().map_err(value_error)?;
    let slopes = checked_slopes(&scenario, slopes_deg)?;
    let eng = engine_for(kind, &scenario).map_err(value_error)?;
    let rows: Vec<Vec<f64>> = xs.iter().map(|v| v.to_vec()).collect();
    let base_seed = scenario.sim.seed;
    let has_requirements = requirements.is_some();
    let (seed, logged) = py.detach(|| {
        let mut logged: Vec<Logged> = Vec::new();
        let mut problem = SawtoothProblem {
            scenario: scenario.clone(),
            engine: eng.as_ref(),
            base_seed,
            log: Some(Box::new(|l: &[Logged]| logged.extend_from_slice(l))),
            requirements,
            slopes_deg: slopes.clone(),
        };
        let seed = problem.seed_for(generation);
        if !rows.is_empty() {
            problem.evaluate_batch(&rows, generation);
        }
        drop(problem);
        (seed, logged)
    });

    let n = xs.len();
    let teeth = scenario.sim.teeth as usize;
    let nan = f64::NAN;
    let mut objs = Vec::with_capacity(2 * n);
    let mut req = Vec::with_capacity(3 * n);
    let mut geo = Vec::with_capacity(7 * n);
    let (mut viol, mut alpha, mut m_op, mut p_op) = (vec![], vec![], vec![], vec![]);
    let (mut f_stroke, mut w_spec, mut m_dot, mut p_avg, mut d_avg, mut lost) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut simulated, mut compliant) = (vec![], vec![]);
    let (mut binding, mut limit, mut rule) = (vec![], vec![], vec![]);
    let mut dist = vec![nan; n * teeth];
    for (i, (l, x)) in logged.iter().zip(&xs).enumerate() {
        objs.extend_from_slice(&l.objectives);
        viol.push(l.violation);
        geo.extend_from_slice(&geometric_constraints(x));
        let sim = violation(x) == 0.0;
        simulated.push(sim);
        req.extend_from_slice(&l.requirement_constraints.unwrap_or([nan; 3]));
        alpha.push(if sim { l.alpha_deg } else { nan });
        let a = l.assessment.as_ref();
        compliant.push(a.is_some_and(|a| a.compliant()));
        binding.push(a.and_then(|a| a.binding()).unwrap_or(""));
        limit.push(a.map(|a| a.operating_point.limit.as_str()).unwrap_or(""));
        m_op.push(a.map_or(nan, |a| a.operating_point.m_dot_kg_h));
        p_op.push(a.map_or(nan, |a| a.operating_point.p_avg_w));
        let e = l.evaluation.as_ref();
        f_stroke.push(e.map_or(nan, |e| e.performance.f_stroke_hz));
        w_spec.push(e.and_then(|e| e.performance.w_spec_j_kg).unwrap_or(nan));
        m_dot.push(e.map_or(nan, |e| e.performance.m_dot_kg_s));
        p_avg.push(e.map_or(nan, |e| e.performance.p_avg_w));
        d_avg.push(e.map_or(nan, |e| e.sim.d_avg_m));
        lost.push(e.map_or(nan, |e| e.sim.lost_fraction));
        if let Some(e) = e {
            dist[i * teeth..(i + 1) * teeth].copy_from_slice(&e.sim.distribution);
        }
        rule.push(match (&l.invalid, sim) {
            (Some(r), _) => r.clone(),
            (None, false) => "infeasible_not_simulated".to_string(),
            (None, true) => String::new(),
        });
    }
    let arr2 = |v: Vec<f64>, cols: usize| {
        PyArray2::from_owned_array(py, numpy::ndarray::Array2::from_shape_vec((n, cols), v).expect("shape"))
    };
    let d = PyDict::new(py);
    d.set_item("objectives", arr2(objs, 2))?;
    d.set_item("violation", viol.into_pyarray(py))?;
    d.set_item("simulated", simulated.into_pyarray(py))?;
    d.set_item("constraints_mm", arr2(geo, 7))?;
    d.set_item("requirement_constraints", arr2(req, 3))?;
    d.set_item("compliant", compliant.into_pyarray(py))?;
    d.set_item("binding_requirement", PyList::new(py, binding)?)?;
    d.set_item("operating_limit", PyList::new(py, limit)?)?;
    d.set_item("m_dot_op_kg_h", m_op.into_pyarray(py))?;
    d.set_item("p_op_w", p_op.into_pyarray(py))?;
    d.set_item("alpha_deg", alpha.into_pyarray(py))?;
    d.set_item("f_stroke_hz", f_stroke.into_pyarray(py))?;
    d.set_item("w_spec_j_kg", w_spec.into_pyarray(py))?;
    d.set_item("m_dot_kg_s", m_dot.into_pyarray(py))?;
    d.set_item("p_avg_w", p_avg.into_pyarray(py))?;
    d.set_item("d_avg_m", d_avg.into_pyarray(py))?;
    d.set_item("lost_fraction", lost.into_pyarray(py))?;
    d.set_item("distribution", arr2(dist, teeth))?;
    d.set_item("invalid_rule", PyList::new(py, rule)?)?;
    d.set_item("requirements", has_requirements)?;
    d.set_item("engine", eng.backend())?;
    d.set_item("seed", seed)?;
    d.set_item("particles", scenario.sim.particles)?;
    d.set_item("slopes_deg", if slopes.is_empty() { vec![scenario.environment.alpha_deg] } else { slopes })?;
    Ok(d)
}

/// `slopes_deg` checked as `evaluate_problem` and `simulate` take it: at most
/// MAX_ALPHA_POINTS slopes, each a valid conveyor angle of `scenario`.
fn checked_slopes(scenario: &sawtooth::model::Scenario, slopes_deg: Option<Vec<f64>>) -> PyResult<Vec<f64>> {
    let slopes = slopes_deg.unwrap_or_default();
    if slopes.len() > MAX_ALPHA_POINTS as usize {
        return Err(PyValueError::new_err(format!(
            "slopes_deg: at most {MAX_ALPHA_POINTS} slopes (each is one more simulation per design), got {}",
            slopes.len()
        )));
    }
    for &alpha in &slopes {
        let mut s = scenario.clone();
        s.environment.alpha_deg = alpha;
        s.validate().map_err(|e| PyValueError::new_err(format!("slopes_deg: slope {alpha}: {e}")))?;
    }
    Ok(slopes)
}

/// simulate(scenario, design=None, *, engine="cpu", trajectories=False, slopes_deg=None,
/// requirements=None) -> dict
///
/// One design (8 values in VARIABLES' units; default: the config's [design]): `sawtooth
/// simulate --json`'s object (distribution, d_avg_m, lost_fraction, fill_area_mm2, performance
/// {f_stroke_hz, m_dot_kg_s, w_spec_j_kg, p_avg_w, stroke_m, ...}) plus "particles" {state,
/// x_m, y_m, bounces} and, with trajectories=True, "flights" {particle, bounce, x_m, y_m,
/// vx_m_s, vy_m_s, t_s, state}: each flight's start (global m) and velocity (m/s).
/// requirements: "table-2.2" or a TOML file with a [requirements] table; the verdicts come
/// as "requirements" (`simulate --requirements`). slopes_deg (degrees, at most
/// MAX_ALPHA_POINTS): the design at every slope instead, `simulate --alpha FROM..TO --json`'s
/// object: engine, mode, scenario, design, "slopes" [{alpha_deg, distribution, d_avg_m,
/// lost_fraction, performance} or {alpha_deg, invalid, reason}] and, with requirements, their
/// verdict at the worst slope.
#[pyfunction]
#[pyo3(signature = (scenario, design=None, *, engine="cpu", trajectories=false, slopes_deg=None, requirements=None))]
fn simulate<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    design: Option<Vec<f64>>,
    engine: &str,
    trajectories: bool,
    slopes_deg: Option<Vec<f64>>,
    requirements: Option<String>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = engine_kind(engine)?;
    let design = match (design, scenario.design) {
        (Some(v), _) => {
            let text = v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(",");
            Design::parse_cli(&text).map_err(PyValueError::new_err)?
        }
        (None, Some(d)) => d,
        (None, None) => {
            return Err(PyValueError::new_err(format!(
                "no design: pass design=[{}] or a config file with [design]",
                DesignRow::COLUMNS.join(", ")
            )))
        }
    };
    let s = scenario.inner.clone();
    let requirements = requirements.map(|spec| load_requirements(&spec)).transpose().map_err(value_error)?;
    if let Some(slopes) = slopes_deg {
        if trajectories {
            return Err(PyValueError::new_err(
                "trajectories draw one slope: give slopes_deg or trajectories, not both",
            ));
        }
        let slopes = checked_slopes(&s, Some(slopes))?;
        let eng = engine_for(kind, &s).map_err(value_error)?;
        let v = py.detach(|| {
            let rows = sawtooth::engine::slopes::over_slopes(eng.as_ref(), &s, &design, &slopes, requirements.as_ref());
            sawtooth::engine::slopes::slopes_json(eng.name(), &s, &design, &rows, requirements.as_ref())
        });
        return json_to_py(py, &v);
    }
    if trajectories && (s.effects.sled_motion.is_some() || s.effects.quadratic_drag.is_some()) {
        return Err(PyValueError::new_err("trajectories redraw each flight as one closed-form arc; with the sled-motion or quadratic-drag effects that would be wrong, so they are not offered"));
    }
    if trajectories && matches!(kind, EngineKind::Gpu | EngineKind::Auto) {
        return Err(PyValueError::new_err(
            "trajectories record every flight, which only the CPU engines do: use engine=\"cpu\" or \"listing\"",
        ));
    }
    let eng = engine_for(kind, &s).map_err(value_error)?;
    let det = py
        .detach(|| evaluate_detailed(eng.as_ref(), &s, &design, trajectories))
        .map_err(|invalid| PyValueError::new_err(format!("invalid design ({}): {invalid}", invalid.rule())))?;
    let mut v = simulation_json(&s, &design, eng.name(), &det);
    if let Some(r) = &requirements {
        let e = &det.evaluation;
        let x = r.assess(&e.performance, &s.performance, e.sim.lost_fraction);
        v["requirements"] = sawtooth::engine::slopes::requirements_json(r, &[(s.environment.alpha_deg, x)]);
    }
    let out = json_to_py(py, &v)?;
    let d = out.cast::<PyDict>()?;
    let ps = &det.particles;
    let state = |st: sawtooth::model::ParticleState| match st {
        sawtooth::model::ParticleState::Flying => "flying",
        sawtooth::model::ParticleState::Resting => "resting",
        sawtooth::model::ParticleState::Lost => "lost",
    };
    let pd = PyDict::new(py);
    pd.set_item("state", PyList::new(py, ps.iter().map(|p| state(p.state)))?)?;
    pd.set_item("x_m", ps.iter().map(|p| p.end[0]).collect::<Vec<_>>().into_pyarray(py))?;
    pd.set_item("y_m", ps.iter().map(|p| p.end[1]).collect::<Vec<_>>().into_pyarray(py))?;
    pd.set_item("bounces", ps.iter().map(|p| p.bounces as i64).collect::<Vec<_>>().into_pyarray(py))?;
    d.set_item("particles", pd)?;
    if trajectories {
        let f = &det.flights;
        let fd = PyDict::new(py);
        fd.set_item("particle", f.iter().map(|r| r.particle as i64).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("bounce", f.iter().map(|r| r.bounce as i64).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("x_m", f.iter().map(|r| r.from[0]).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("y_m", f.iter().map(|r| r.from[1]).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("vx_m_s", f.iter().map(|r| r.vel[0]).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("vy_m_s", f.iter().map(|r| r.vel[1]).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("t_s", f.iter().map(|r| r.t).collect::<Vec<_>>().into_pyarray(py))?;
        fd.set_item("state", PyList::new(py, f.iter().map(|r| state(r.state)))?)?;
        d.set_item("flights", fd)?;
    }
    Ok(out)
}

/// load_measured(path) -> dict
///
/// Measured tooth masses (data/validation/testN.csv format), checked by the library: path,
/// provenance, teeth, run (ids), masses_g (runs, teeth; grams), input_mass_g (grams, NaN if not
/// recorded), fractions (runs, teeth), mean_fractions, std_fractions, centre_of_mass_teeth,
/// dispersion_teeth, recovery.
#[pyfunction]
fn load_measured<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let m = sawtooth::io::measured::load(&path).map_err(value_error)?;
    let d = PyDict::new(py);
    let n = m.runs.len();
    let masses: Vec<f64> = m.runs.iter().flat_map(|r| r.teeth_g.iter().copied()).collect();
    d.set_item("path", &m.path)?;
    d.set_item("provenance", PyList::new(py, &m.provenance)?)?;
    d.set_item("teeth", m.teeth)?;
    d.set_item("run", PyList::new(py, m.runs.iter().map(|r| r.id.clone()))?)?;
    d.set_item(
        "masses_g",
        PyArray2::from_owned_array(py, numpy::ndarray::Array2::from_shape_vec((n, m.teeth), masses).expect("shape")),
    )?;
    d.set_item(
        "input_mass_g",
        m.runs.iter().map(|r| r.input_mass_g.unwrap_or(f64::NAN)).collect::<Vec<_>>().into_pyarray(py),
    )?;
    let fr: Vec<f64> = m.fractions().into_iter().flatten().collect();
    d.set_item(
        "fractions",
        PyArray2::from_owned_array(py, numpy::ndarray::Array2::from_shape_vec((n, m.teeth), fr).expect("shape")),
    )?;
    d.set_item("mean_fractions", m.mean_fractions().into_pyarray(py))?;
    d.set_item("std_fractions", m.std_fractions().into_pyarray(py))?;
    let (ex, sx) = m.centre_and_dispersion();
    d.set_item("centre_of_mass_teeth", ex)?;
    d.set_item("dispersion_teeth", sx)?;
    d.set_item("recovery", m.recovery())?;
    Ok(d)
}

/// A choice by name (`objective="sse"`), as the CLI's flag takes it; the error names the
/// keyword and the choices.
fn choice<T: ValueEnum>(field: &str, name: &str) -> PyResult<T> {
    T::from_str(name, false).map_err(|_| {
        let known: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|p| p.get_name().to_string())
            .collect();
        PyValueError::new_err(format!("{field}: unknown value `{name}` (known: {})", known.join(", ")))
    })
}

/// The effort keywords shared by fit and diagnose, over the library's defaults.
fn effort_settings(
    d: EffortSettings,
    particles: Option<u32>,
    max_particles: Option<u32>,
    pop: Option<usize>,
    generations: Option<usize>,
    polish: Option<usize>,
) -> EffortSettings {
    EffortSettings {
        particles,
        max_particles: max_particles.unwrap_or(d.max_particles),
        pop: pop.unwrap_or(d.pop),
        generations: generations.unwrap_or(d.generations),
        polish: polish.unwrap_or(d.polish),
    }
}

/// The library's fit (`fit::request`, the request `sawtooth fit` builds from its flags),
/// GIL released; returns fit.json's object. `params` and `at` come as the CLI's lists
/// (`sawtooth.fit` joins Python's list and dict); errors name the keywords.
#[pyfunction]
#[pyo3(signature = (data, setup, *, params=None, objective="sse", particles=None, max_particles=None, pop=None,
    generations=None, polish=None, normalise=None, seed=None, engine="cpu", holdout=None, bootstrap=None, at=None,
    out=None))]
#[allow(clippy::too_many_arguments)]
fn _fit<'py>(
    py: Python<'py>,
    data: PathBuf,
    setup: PathBuf,
    params: Option<String>,
    objective: &str,
    particles: Option<u32>,
    max_particles: Option<u32>,
    pop: Option<usize>,
    generations: Option<usize>,
    polish: Option<usize>,
    normalise: Option<String>,
    seed: Option<u64>,
    engine: &str,
    holdout: Option<usize>,
    bootstrap: Option<usize>,
    at: Option<String>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut r = FitRequest::new(data, setup, Spelling::Keywords);
    r.params = params.map(|p| parse_params(&p).context("params")).transpose().map_err(value_error)?;
    r.at = at.map(|a| parse_assignments(&a).context("at")).transpose().map_err(value_error)?;
    r.objective = choice("objective", objective)?;
    r.effort = effort_settings(EffortSettings::default(), particles, max_particles, pop, generations, polish);
    r.normalise = normalise.map(|n| choice("normalise", &n)).transpose()?;
    r.seed = seed;
    r.engine = engine_kind(engine)?;
    r.holdout = holdout;
    r.bootstrap = bootstrap.unwrap_or(r.bootstrap);
    r.out = out;
    let outcome = py.detach(|| fit_request::run(&r, &mut |line| eprintln!("{line}"))).map_err(value_error)?;
    json_to_py(py, &outcome.json)
}

/// The library's diagnosis (`diagnose::request`, the request `sawtooth diagnose` builds from
/// its flags), GIL released; returns diagnosis.json's object, and writes report.md and the
/// figures into `out` (`sawtooth.diagnose` makes a temporary one when none is given).
#[pyfunction]
#[pyo3(signature = (data, setup, out, *, effects="all", seed=None, engine="cpu", particles=None, max_particles=None,
    pop=None, generations=None, polish=None, normalise=None, rescore_streams=None, bootstrap=None,
    detection_limits=true, suggest=false, params=None))]
#[allow(clippy::too_many_arguments)]
fn _diagnose<'py>(
    py: Python<'py>,
    data: Vec<PathBuf>,
    setup: Vec<PathBuf>,
    out: PathBuf,
    effects: &str,
    seed: Option<u64>,
    engine: &str,
    particles: Option<u32>,
    max_particles: Option<u32>,
    pop: Option<usize>,
    generations: Option<usize>,
    polish: Option<usize>,
    normalise: Option<String>,
    rescore_streams: Option<usize>,
    bootstrap: Option<usize>,
    detection_limits: bool,
    suggest: bool,
    params: Option<String>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut r = DiagnoseRequest::new(data, setup, out, Spelling::Keywords);
    r.effects = parse_effects(effects).context("effects").map_err(value_error)?;
    r.seed = seed;
    r.engine = engine_kind(engine)?;
    r.effort = effort_settings(DiagnoseRequest::DEFAULT_EFFORT, particles, max_particles, pop, generations, polish);
    r.normalise = normalise.map(|n| choice("normalise", &n)).transpose()?;
    r.rescore_streams = rescore_streams.unwrap_or(r.rescore_streams);
    r.bootstrap = bootstrap.unwrap_or(r.bootstrap);
    r.detection_limits = detection_limits;
    r.suggest = suggest;
    r.params = params.map(|p| parse_params(&p).context("params")).transpose().map_err(value_error)?;
    let (_, json) = py.detach(|| diagnose_request::run(&r, &mut |line| eprintln!("{line}"))).map_err(value_error)?;
    json_to_py(py, &json)
}

#[pymodule]
fn _sawtooth(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenario>()?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_problem, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(load_measured, m)?)?;
    m.add_function(wrap_pyfunction!(_fit, m)?)?;
    m.add_function(wrap_pyfunction!(_diagnose, m)?)?;
    m.add("VARIABLES", DesignRow::COLUMNS)?;
    m.add("LOWER_BOUNDS", LOWER_BOUND_CLI.to_vec())?;
    m.add("UPPER_BOUNDS", UPPER_BOUND_CLI.to_vec())?;
    m.add("CONSTRAINT_TOLERANCE", CONSTRAINT_TOLERANCE)?;
    m.add("REQUIREMENT_TOLERANCE", REQUIREMENT_TOLERANCE)?;
    m.add("UNSIMULATED_VIOLATION", UNSIMULATED_VIOLATION)?;
    m.add("REQUIREMENT_NAMES", ["feed_rate", "power", "wire_length"])?;
    m.add(
        "CONSTRAINT_NAMES",
        [
            "l_b_le_r",
            "r_le_l_a",
            "l_a_le_l_c",
            "c1_catch_reaches_peak",
            "c2_foot_within_pitch",
            "c3_foot_after_start",
            "c4_ramp_cut",
        ],
    )?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
