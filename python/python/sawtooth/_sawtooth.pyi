"""Type stubs of the compiled module (the Rust engine). Units: SI unless a name says otherwise."""

from os import PathLike
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, "PathLike[str]"]
_Engine = Literal["cpu", "gpu", "auto", "listing"]

#: Column names of a design row: mm, mm, mm, mm, deg, deg, m/s, m/s^2 (Table 5.3).
VARIABLES: List[str]
#: Listing D.5's bounds of the eight variables (erratum 2), in VARIABLES' units.
LOWER_BOUNDS: List[float]
UPPER_BOUNDS: List[float]
#: MATLAB's ConstraintTolerance (mm); a constraint c is met when c <= this.
CONSTRAINT_TOLERANCE: float
#: Names of the seven columns of ``constraints_mm``: the chain of Eq. 5.2 and c1-c4 of D.5.
CONSTRAINT_NAMES: List[str]
#: Names of the three columns of ``requirement_constraints``: 1.1 feed rate, 1.4 power and
#: 5.5 wire length of Table 2.2, each a relative shortfall (<= 0 met).
REQUIREMENT_NAMES: List[str]
#: Rounding-only tolerance of the requirement verdicts (a requirement c is met when c <= this).
REQUIREMENT_TOLERANCE: float
#: Added to the violation of a design not simulated when a run has requirements.
UNSIMULATED_VIOLATION: float
__version__: str

class Scenario:
    """A problem statement apart from the design: preset, config file, then keyword overrides,
    validated exactly like ``sawtooth simulate``'s flags (ValueError with the CLI's message).

    env: "lunar" (g 1.625 m/s^2, vacuum, regolith) or "earth" (g 9.81, Stokes drag 5.439 1/s,
    quartz sand); config: a TOML file (README's format); compat: "listing" reproduces the
    listing's physics; alpha_deg: conveyor angle (deg); k_elastic: elastic normal COR; mu_fric:
    friction coefficient; k_drag_per_s: Stokes drag (1/s, 0 = vacuum); aor_deg: angle of repose
    (deg); material: "lunar-regolith" | "quartz-sand" | "glass-beads"; particles: per design;
    teeth; max_bounces; seed: of the counter-based particle streams; launch_offset_deg (deg);
    randomise: launch randomisation on/off; effects: CLI effect specs such as
    ["impact-scatter=8", "polydisperse=0.5"].
    """

    def __init__(
        self,
        env: Optional[Literal["lunar", "earth"]] = None,
        config: Optional[_Path] = None,
        *,
        compat: Optional[Literal["listing", "physical"]] = None,
        alpha_deg: Optional[float] = None,
        k_elastic: Optional[float] = None,
        mu_fric: Optional[float] = None,
        k_drag_per_s: Optional[float] = None,
        aor_deg: Optional[float] = None,
        material: Optional[str] = None,
        particles: Optional[int] = None,
        teeth: Optional[int] = None,
        max_bounces: Optional[int] = None,
        seed: Optional[int] = None,
        launch_offset_deg: Optional[float] = None,
        randomise: bool = True,
        effects: Optional[Sequence[str]] = None,
    ) -> None: ...
    @property
    def particles(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def teeth(self) -> int: ...
    @property
    def design(self) -> Optional[npt.NDArray[np.float64]]:
        """The config file's [design] in VARIABLES' units, or None."""
    def to_dict(self) -> Dict[str, Any]:
        """Every setting (library field names: g in m/s^2, lengths in m, angles in deg)."""
    def replace(self, *, particles: Optional[int] = None, seed: Optional[int] = None) -> "Scenario": ...

def evaluate(
    scenario: Scenario,
    x: npt.NDArray[np.float64],
    *,
    engine: _Engine = "cpu",
    seed: Optional[int] = None,
    particles: Optional[int] = None,
    feasible_only: bool = False,
) -> Dict[str, Any]:
    """Evaluate the rows of ``x`` (shape (n, 8), VARIABLES' units) as one engine batch, the GIL
    released. Every design of the batch sees the same particle streams (common random numbers).

    Returns arrays of length n (NaN where a design was not simulated or is invalid):
    f_stroke_hz, f_dynamic_hz (Hz), w_spec_j_kg (J/kg, NaN without mass flow), m_dot_kg_s (kg/s),
    p_avg_w (W), stroke_m (m), n_wire (-1 if invalid), d_avg_m, advance_m (m), lost_fraction,
    unsettled_fraction, distribution (n, teeth; fraction of launched particles per tooth),
    valid / simulated (bool), invalid_rule / invalid_message (lists of str, "" when valid),
    constraints_mm (n, 7; CONSTRAINT_NAMES, <= CONSTRAINT_TOLERANCE is met), violation (sum of
    the excesses, 0 = feasible), objectives (n, 2; the built-in optimiser's f_stroke and W_spec
    with its penalties), and engine, seed, particles. ``feasible_only`` skips the simulation of
    designs whose violation is > 0 (as the optimiser does).
    """

def evaluate_problem(
    scenario: Scenario,
    x: npt.NDArray[np.float64],
    *,
    engine: _Engine = "cpu",
    generation: int = 0,
    requirements: Optional[_Path] = None,
    slopes_deg: Optional[Sequence[float]] = None,
) -> Dict[str, Any]:
    """One generation of ``sawtooth optimize``'s problem, by its own code: the rows of ``x`` on
    the particle streams of ``generation`` (seed + generation * 0x9E3779B97F4A7C15 mod 2^64),
    at every slope of ``slopes_deg`` (deg; default: the scenario's alpha) in one engine job,
    designs violating a geometric constraint not simulated. ``requirements``: "table-2.2" or a
    TOML file with a [requirements] table.

    Returns: objectives (n, 2; penalised f_stroke in Hz and W_spec in J/kg, worst over the
    slopes, 1e12 where not simulated), violation (what Deb's rules rank by), simulated,
    constraints_mm (n, 7), requirement_constraints (n, 3; REQUIREMENT_NAMES, worst over the
    slopes, NaN where not simulated or without requirements), compliant, binding_requirement,
    operating_limit (lists of str), m_dot_op_kg_h (kg/h), p_op_w (W), alpha_deg (the slope
    shown: failing the requirements worst, else highest W_spec) and at that slope f_stroke_hz,
    w_spec_j_kg, m_dot_kg_s, p_avg_w, d_avg_m, lost_fraction, distribution (n, teeth),
    invalid_rule; and requirements (bool), engine, seed, particles, slopes_deg.
    """

def simulate(
    scenario: Scenario,
    design: Optional[Sequence[float]] = None,
    *,
    engine: _Engine = "cpu",
    trajectories: bool = False,
    slopes_deg: Optional[Sequence[float]] = None,
    requirements: Optional[str] = None,
) -> Dict[str, Any]:
    """One design (default: the config's [design]): ``sawtooth simulate --json``'s object plus
    ``particles`` {state, x_m, y_m, bounces} and, with trajectories=True, ``flights``
    {particle, bounce, x_m, y_m, vx_m_s, vy_m_s, t_s, state} (each flight's start, global m).
    ``requirements`` ("table-2.2" or a TOML file) adds their verdicts. ``slopes_deg``: the
    design at every slope instead (``simulate --alpha FROM..TO --json``'s object: ``slopes``,
    and with requirements their verdict at the worst slope)."""

def load_measured(path: _Path) -> Dict[str, Any]:
    """Measured tooth masses (data/validation format): path, provenance, teeth, run,
    masses_g (runs, teeth), input_mass_g (NaN if not recorded), fractions (runs, teeth),
    mean_fractions, std_fractions, centre_of_mass_teeth, dispersion_teeth, recovery."""

def _fit(data: _Path, setup: _Path, **options: Any) -> Dict[str, Any]: ...
def _diagnose(data: List[_Path], setup: List[_Path], out: _Path, **options: Any) -> Dict[str, Any]: ...
